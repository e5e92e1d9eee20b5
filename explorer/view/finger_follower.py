"""The drawing of the end-pivot finger follower (explorer.gears.finger_follower): the synthesised
cam, the finger with its roller (or pad) and valve pad, the lash adjuster's body and ball, the
contact markers and the valve group (explorer.view.arm_train)."""

from __future__ import annotations

from .arm_train import ArmTrainView

VIEW = ArmTrainView()
