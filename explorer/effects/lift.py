"""The lift curve of a scene: the one place that assembles it.

A gear follower asks the gear registry for its builder; a scene whose lift is a table, an
acceleration law or a cam contour names its builder in LIFT_BUILDERS (imported when used); every
other law is a closed-form LawLift.
"""

from __future__ import annotations

from ..core.plugins import resolve
from ..gears.registry import lift_builder
from ..lift.curves import LawLift, LiftCurve


# lift.law -> "module:function" building the lift curve of a scene with that law (imported when
# used); the gears' builders are in explorer.gears.registry, the closed-form laws are LawLift.
LIFT_BUILDERS: dict[str, str] = {
    "table": "explorer.lift.table:build_table_lift",
    "acceleration": "explorer.lift.acceleration:build_acceleration_lift",
    "contour": "explorer.lift.contours.lift_from_contour:build_contour_lift",
    "polydyne": "explorer.lift.polydyne:build_polydyne_lift",
    "spline": "explorer.lift.spline:build_spline_lift",
}


def build_lift(scene) -> LiftCurve:
    """The lift curve a validated scene describes: the one place that assembles it, from the gear
    registry (a gear follower) or LIFT_BUILDERS (dispatch on lift.law), else a LawLift."""
    spec = scene.lift
    gear_lift = lift_builder(scene.follower.type)
    if gear_lift is not None:
        return gear_lift(scene)
    if spec.law in LIFT_BUILDERS:
        return resolve(LIFT_BUILDERS[spec.law])(scene)
    return LawLift(
        height=spec.height,
        start=spec.start,
        rise=spec.rise,
        dwell=spec.dwell,
        ret=spec.ret,
        rise_law=spec.law,
        return_law=spec.return_law or spec.law,
    )
