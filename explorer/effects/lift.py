"""The lift curve of a scene: its gear's (explorer.gears.base.Gear.build_lift: the [lift] law's for
most gears, the gear's own geometry for the others). The one place every run, view and study asks."""

from __future__ import annotations

from ..lift.curves import LiftCurve


def build_lift(scene) -> LiftCurve:
    """The lift curve a validated scene describes."""
    return scene.gear_plugin.build_lift(scene)
