"""The lift curve of a scene: the one place that assembles it.

A gear follower asks the gear registry for its builder; any other scene's lift is its [lift]
law's (explorer/lift/registry.py: the law's builder, or a closed-form LawLift).
"""

from __future__ import annotations

from ..gears.registry import lift_builder
from ..lift.curves import LiftCurve, scene_lift


def build_lift(scene) -> LiftCurve:
    """The lift curve a validated scene describes: the one place that assembles it, from the gear
    registry (a gear follower) or the law table."""
    gear_lift = lift_builder(scene.follower.type)
    if gear_lift is not None:
        return gear_lift(scene)
    return scene_lift(scene)
