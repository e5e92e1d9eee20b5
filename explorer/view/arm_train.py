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
from .drawing import quat_about_y
from .modern_parts import MODERN_PART_COLORS, arm_drawing, arm_poses, hla_parts, pushrod_drawing, pushrod_poses, to_world
from .train_motion import train_shape

COLORS = MappingProxyType({k: v for k, v in MODERN_PART_COLORS.items() if k != "valve"})


def _pushrod(train) -> bool:
    return hasattr(train, "lifter")


def per_valve_travel(coordinate: np.ndarray, drive: np.ndarray) -> float:
    """d coordinate / d(valve-referred drive) of a part's rigid coordinate (a lifter's travel, an
    arm's angle) over the revolution: the least-squares slope over the steps where the drive is
    above a tenth of its peak (the relation is the gear's ratio, near-constant over a lift; a
    drawing of a magnified deviation needs no better)."""
    open_ = drive > 0.1 * drive.max()
    if open_.sum() < 2:
        return 0.0
    return float(np.polyfit(drive[open_], coordinate[open_], 1)[0])


def _about_y(wxyz: np.ndarray) -> np.ndarray:
    return 2.0 * np.arctan2(wxyz[:, 2], wxyz[:, 0])


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
        parts = {name: mesh for name, mesh in drawing.parts.items() if name != "valve"}
        if "lash_adjuster" in parts and train_shape(scene)[1]:  # [hla]: its plunger moves, carrying the ball
            parts.update(hla_parts(train))
        return parts

    # items 7, 8: the train's masses (explorer.view.train_motion)
    def train_stations(self, scene):
        parts = scene.gear.parts  # the gear's tables ([gear.lifter], [gear.finger] or [gear.rocker])
        if "lifter" in parts:
            return (("lifter", "roller"), ("pushrod",), ("rocker",))
        return (("roller", "finger" if "finger" in parts else "rocker"),)

    def train_poses(self, scene, result, motion, rigid, lay=None, lift=None):
        """Each station's parts moved by its mass's displayed deviation from the drive, turned into
        the part's own coordinate by its rigid ratio (per_valve_travel): a lifter and pushrod
        slide along the lifter's axis, an arm turns about its pivot (the roller with it); a
        finger's pivot rides on the adjuster's plunger, which slides along its axis."""
        lift = lift if lift is not None else build_lift(scene)
        train = lift.gear
        theta = np.radians(np.asarray(result.columns["cam_angle_deg"], dtype=float))
        k = train.kinematics(theta)
        drive = motion.drive
        out = {}
        if _pushrod(train):
            slide = per_valve_travel(k.lifter_lift[0], drive)
            for names, shown in zip((("lifter", "roller"), ("pushrod",)), motion.displayed[:2]):
                dz = slide * (shown - drive)
                for name in names:
                    if name in rigid:  # a flat lifter has no roller
                        pos, q = rigid[name]
                        out[name] = (pos + np.column_stack([np.zeros_like(dz), np.zeros_like(dz), dz]), q)
            turn = per_valve_travel(k.rocker_angle[0], drive) * (motion.displayed[2] - drive)
            pos, q = rigid["rocker"]
            out["rocker"] = (pos, quat_about_y(_about_y(q) - turn))
            return out
        name = train.kind
        psi = k.arm_angle[0]
        pivot = np.asarray(train.arm.pivot, dtype=float)
        shift = np.zeros((len(drive), 3))
        moved = np.zeros(len(drive))  # the pad's travel (valve-referred) the pivot's shift brings
        if motion.plunger is not None and "lash_adjuster" in rigid:  # plunger travel: into the body, along the valve axis
            shift = motion.plunger[:, None] * to_world(np.asarray(train.valve.axis)[None, :], 0.0)
            out["hla_plunger"] = (rigid["hla_plunger"][0] + shift, rigid["hla_plunger"][1])
            moved = motion.plunger
        # the finger's travel holds the adjuster's part (train.py: -g p at the cam joint); the
        # shifted pivot brings the pad p of it, the turn about the pivot the rest (which keeps the
        # roller on the cam: g + 1 = the finger's ratio)
        turn = per_valve_travel(psi, drive) * (motion.displayed[0] - drive - moved)
        pos, q = rigid[name]
        out[name] = (pos + shift, quat_about_y(_about_y(q) - turn))
        if "roller" in rigid:
            c, s_ = np.cos(turn), np.sin(turn)
            rel = np.asarray(k.centre, dtype=float) - pivot
            centre = pivot + np.column_stack([c * rel[:, 0] - s_ * rel[:, 1], s_ * rel[:, 0] + c * rel[:, 1]])
            out["roller"] = (to_world(centre, 0.0) + shift, quat_about_y(_about_y(rigid["roller"][1]) - turn))
        return out

    def gear_poses(self, scene, lift, lay, theta) -> dict:
        train = lift.gear
        poses = pushrod_poses(train, theta) if _pushrod(train) else arm_poses(train, theta)
        poses.pop("valve", None)
        if "lash_adjuster" in poses and train_shape(scene)[1]:
            n = theta.size
            poses["hla_plunger"] = (np.tile(to_world(np.asarray(train.arm.pivot)[None, :], 0.0)[0], (n, 1)),
                                    np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)))
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
