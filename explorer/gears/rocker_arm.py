"""The centre-pivot rocker arm (issue #24), follower.type "rocker-arm": with [gear.lifter] the OHV
pushrod train (cam -> flat or roller lifter -> pushrod between ball ends -> rocker -> pad on the
valve tip: trucks, V8s, industrial engines); without it the OHC rocker driven directly from an
overhead cam by a roller or a pad (the finger follower's arm with the pivot between the ends).

(The type is not "rocker": that word already is the 1902 gears' [gear.valve] type = "rocker", a
valve drive, and the plug-in check keeps a follower type out of the modules other gears share.)

with [gear.lifter]     [gear.lifter] type ("flat": face_radius; "roller": roller_radius, offset),
                       socket_height, width; [gear.rocker] pivot, cup (the pushrod's upper ball with
                       the valve closed)
without                [gear.rocker] as the finger's [gear.finger]
both                   [gear.valve_pad] arm, angle, radius; [gear.valve] axis, axis_point, tip_radius;
                       [contact] sliding_friction (a flat lifter or a pad on the cam), tip_friction
[lift]                 the wanted valve lift (a closed form: the cam is synthesised) or law = "contour"
                       with a [cam] contour (arcs or points: the rocker, or the lifter, analysed over it)
The geometry is explorer.gears.pushrod (PushrodTrain) and explorer.gears.arm (ArmGear), built by
explorer.gears.modern_spec; the gear hooks are explorer.gears.arm_train's.
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from .arm_train import CONTACT_COLUMNS, KINEMATICS_COLUMNS, ArmTrainGear
from .flat_face import crown_stress
from .modern_spec import _arm, _lifter, _valve, _valve_pad

PUSHROD_KINEMATICS = ("lifter_lift_m", "lifter_velocity_per_rad", "pushrod_angle_deg", "rocker_lever_ratio")


def _pushrod(train) -> bool:
    return hasattr(train, "lifter")


class RockerArm(ArmTrainGear):
    type = "rocker-arm"
    description = "centre-pivot rocker on the valve tip, with [gear.lifter] the OHV lifter and pushrod train"
    arm_kind = "rocker"
    # [gear.rocker] is the pushrod's cup and the pivot with [gear.lifter], an arm on the cam without it
    # (modern_spec.parse_parts reads it so; `parse` is the base's through it)
    parts = MappingProxyType({"lifter": _lifter, "rocker": _arm, "valve_pad": _valve_pad, "valve": _valve})
    optional_parts = frozenset({"lifter", "valve"})
    columns = MappingProxyType({"kinematics": KINEMATICS_COLUMNS + PUSHROD_KINEMATICS,
                                "contact": CONTACT_COLUMNS + ("hertz_stress_Pa", "pushrod_force_N")})

    def side_stiffness(self, spec):
        part = spec.part("lifter") if "lifter" in spec.parts else spec.part("rocker")
        return part.get("stiffness")

    def arm_angle(self, k) -> np.ndarray:
        return k.rocker_angle[0] if hasattr(k, "rocker_angle") else k.arm_angle[0]

    def extra_kinematics(self, k) -> dict:
        if not hasattr(k, "lifter_lift"):
            return {}
        return {"lifter_lift_m": k.lifter_lift[0], "lifter_velocity_per_rad": k.lifter_lift[1],
                "pushrod_angle_deg": np.degrees(k.pushrod_angle), "rocker_lever_ratio": k.rocker_ratio}

    def roller_radius(self, train) -> float:
        if _pushrod(train):
            return train.lifter.radius if train.lifter.kind == "roller" else 0.0
        side = train.arm.cam_side
        return side.radius if side.kind == "roller" else 0.0

    def counter_radius(self, train) -> float:
        return train.lifter.radius if _pushrod(train) else train.arm.cam_side.radius

    def cam_width(self, train):
        return train.lifter.width if _pushrod(train) else train.arm.cam_side.width

    def cam_hertz(self, train, k, normal, e_star: float, width: float) -> np.ndarray:
        """A crowned lifter face touches the lobe in a point (explorer.gears.flat_face.crown_stress);
        a roller, a pad or a flat face in a line."""
        if _pushrod(train) and train.lifter.kind == "flat" and math.isfinite(train.lifter.radius):
            return crown_stress(normal, train.lifter.radius, k.surface.radius, e_star, width)[0]
        return super().cam_hertz(train, k, normal, e_star, width)

    def point_stress(self, train, k):
        if _pushrod(train) and train.lifter.kind == "flat" and math.isfinite(train.lifter.radius):
            width = self.cam_width(train)
            return lambda normal, e_star: self.cam_hertz(train, k, normal, e_star, width)
        return None

    def extra_contact(self, train, k, forces) -> dict:
        return {"pushrod_force_N": train.pushrod_force(k, forces)} if _pushrod(train) else {}

    def oscillating(self, train) -> bool:
        return not _pushrod(train)  # the lifter slides in its bore

    def extra_report(self, train, k) -> dict:
        if not _pushrod(train):
            return {"rocker_pivot_m": list(train.arm.pivot), "valve_pad_arm_m": train.valve.drive.arm}
        return {"lifter": train.lifter.kind, "pushrod_length_m": train.pushrod_length, "rocker_arm_m": train.rocker_arm,
                "valve_pad_arm_m": train.valve.drive.arm, "max_lifter_lift_m": float(np.max(k.lifter_lift[0])),
                "max_pushrod_angle_deg": float(np.degrees(np.max(np.abs(k.pushrod_angle)))),
                "min_rocker_lever_ratio": float(k.rocker_ratio.min()), "max_rocker_lever_ratio": float(k.rocker_ratio.max())}


GEAR = RockerArm()
