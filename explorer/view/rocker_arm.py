"""The drawing of the centre-pivot rocker arm (explorer.gears.rocker_arm): the synthesised cam, the
lifter (flat or roller) and the pushrod with its ball ends when the train has them, the rocker
with its valve pad, the contact markers and the valve group (explorer.view.arm_train)."""

from __future__ import annotations

from .arm_train import ArmTrainView

VIEW = ArmTrainView()
