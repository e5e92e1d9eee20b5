"""What the drawings of the finger follower and the rocker arm (with or without lifter and pushrod)
share: the parts of explorer.view.modern_parts (cam, camshaft, roller, the arm, lash adjuster,
lifter, pushrod, the contact markers) posed by the rigid kinematics, and the stock valve group
(valve, spring, seat) moved so that the stem's top is where the valve pad touches the tip with the
valve closed, travelling along the gear's valve axis at the displayed (possibly elastic, magnified)
lift."""

from __future__ import annotations

import math
from dataclasses import replace
from types import MappingProxyType

import numpy as np

from ..effects.lift import build_lift
from . import translating_roller as stock
from .drawing import looped_roller_rotation, valve_group
from .gear_parts import LeverGearView, valve_poses
from .modern_parts import MODERN_PART_COLORS, arm_drawing, arm_poses, pushrod_drawing, pushrod_poses

COLORS = MappingProxyType({k: v for k, v in MODERN_PART_COLORS.items() if k != "valve"})


def _pushrod(train) -> bool:
    return hasattr(train, "lifter")


class ArmTrainView(LeverGearView):
    """The drawing of an arm train whose lift carries its geometry (explorer.gears.arm_train.TrainLift)."""

    colors = COLORS

    def layout(self, scene, result=None, lift=None):
        lift = lift if lift is not None else build_lift(scene)
        lay = stock.layout(scene, result)
        x, z = lift.gear.valve.rest_contact()
        dx, dz = x - lay.valve_x, z - lay.stem_top_rest
        return replace(lay, valve_x=lay.valve_x + dx, stem_top_rest=lay.stem_top_rest + dz, seat_z=lay.seat_z + dz,
                       spring_seat_z=lay.spring_seat_z + dz, pivot=(lay.pivot[0] + dx, lay.pivot[1], lay.pivot[2] + dz))

    def gear_parts(self, scene, lift, lay) -> dict:
        train = lift.gear
        drawing = pushrod_drawing(train) if _pushrod(train) else arm_drawing(train)
        return {name: mesh for name, mesh in drawing.parts.items() if name != "valve"}

    def gear_poses(self, scene, lift, lay, theta) -> dict:
        train = lift.gear
        poses = pushrod_poses(train, theta) if _pushrod(train) else arm_poses(train, theta)
        poses.pop("valve", None)
        return poses

    def parts(self, scene, result=None, lay=None, lift=None, contour_samples: int = 720, only=None) -> dict:
        lift = lift if lift is not None else build_lift(scene)
        lay = lay or self.layout(scene, result, lift)
        parts = self.gear_parts(scene, lift, lay)
        parts.update(valve_group(lay))
        return {k: v for k, v in parts.items() if only is None or k in only}

    def poses(self, scene, result, magnification: float = 1.0, lay=None, lift=None) -> dict:
        lift = lift if lift is not None else build_lift(scene)
        lay = lay or self.layout(scene, result, lift)
        theta = np.radians(np.asarray(result.columns["cam_angle_deg"], dtype=float))
        poses = self.gear_poses(scene, lift, lay, theta)
        u = lift.gear.valve.axis
        poses.update(valve_poses(scene, result, lay, magnification, math.atan2(u[1], u[0])))
        if "roller" in poses:
            poses["roller"] = (poses["roller"][0], looped_roller_rotation(poses["roller"][1]))
        return poses
