"""The end-pivot roller finger follower (issue #24): the finger rests on the hydraulic lash
adjuster's ball (its pivot) at one end, carries the roller (or a pad) under the cam between the
ends and opens the valve with its curved pad at the other end; most of today's petrol engines.

[gear.finger]         pivot, arm, side, cam_side ("roller": follower.roller_radius; "pad":
                      pad_radius, face_angle), width
[gear.valve_pad]      arm, angle, radius        [gear.valve]  axis, axis_point, tip_radius
[gear.lash_adjuster]  body_diameter, body_length (the drawing)
[lift]                the wanted valve lift (a closed form: the cam is synthesised) or law = "contour"
                      with a [cam] contour (arcs or points: the finger analysed over it)
[contact]             tip_friction (the pad on the valve tip), sliding_friction (a pad on the cam)
Keys, units and ranges: explorer.gears.modern_spec and docs/theory/modern-gears.md; the geometry
is explorer.gears.arm, its gear hooks explorer.gears.arm_train.
"""

from __future__ import annotations

import math
from types import MappingProxyType

from .arm_train import CONTACT_COLUMNS, KINEMATICS_COLUMNS, ArmTrainGear
from .modern_spec import _arm, _lash_adjuster, _valve, _valve_pad


class FingerFollower(ArmTrainGear):
    type = "finger-follower"
    description = "end-pivot finger on a lash adjuster, roller (or pad) on the cam, curved pad on the valve tip"
    arm_kind = "finger"
    parts = MappingProxyType({"finger": _arm, "valve_pad": _valve_pad, "valve": _valve, "lash_adjuster": _lash_adjuster})
    optional_parts = frozenset({"valve", "lash_adjuster"})
    columns = MappingProxyType({"kinematics": KINEMATICS_COLUMNS, "contact": CONTACT_COLUMNS + ("hertz_stress_Pa",)})

    def side_stiffness(self, spec):
        return spec.part("finger").get("stiffness")

    def roller_radius(self, train) -> float:
        side = train.arm.cam_side
        return side.radius if side.kind == "roller" else 0.0

    def counter_radius(self, train) -> float:
        return train.arm.cam_side.radius  # roller, pad, inf for a flat pad

    def cam_width(self, train):
        return train.arm.cam_side.width

    def extra_report(self, train, k) -> dict:
        return {"finger_pivot_m": list(train.arm.pivot), "roller_or_pad_arm_m": train.arm.cam_side.arm,
                "valve_pad_arm_m": train.valve.drive.arm, "valve_axis_deg": math.degrees(train.valve.drive.axis)}


GEAR = FingerFollower()
