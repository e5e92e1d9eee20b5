"""The drawing of the eccentric rolling lever (explorer.gears.rolling_lever): the eccentric, its rod
and the rolling lever, rolling on the valve lever, with their rolling faces; drawn at the scale of
the eccentric's lever."""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from .drawing import quat_about_y
from .gear_parts import (LeverGearView, bar, bar_between, concat, eccentric_parts, eccentric_poses, ident, pin, sector,
                         sizes, world)

COLORS = MappingProxyType({
    "valve_lever": (70, 150, 95),
    "valve_lever_pivot": (95, 100, 110),
    "eccentric": (214, 126, 44),
    "eccentric_rod": (150, 160, 175),
    "cam_pivot": (95, 100, 110),
    "rolling_lever": (214, 126, 44),
})


def rolling_parts(scene, lift, lay):
    gear = lift.gear
    w, half = sizes(lay)
    face_a, face_b, _ = gear.faces(120)
    valve = gear.valve
    parts = {
        "rolling_lever": concat([sector(face_a, w), bar(gear.drive.arm, half, 0.6 * w), pin(0.0, 0.0, 1.3 * half, 0.8 * w)]),
        "valve_lever": concat([sector(face_b, w), pin(0.0, 0.0, 1.3 * half, 0.8 * w),
                                bar_between((0.0, 0.0), (valve.arm * math.cos(valve.angle), valve.arm * math.sin(valve.angle)),
                                             half, 0.6 * w)]),
        "cam_pivot": pin(gear.pivot[0], gear.pivot[1], 0.7 * half, 1.4 * w),
        "valve_lever_pivot": pin(gear.valve_pivot[0], gear.valve_pivot[1], 0.7 * half, 1.4 * w),
    }
    parts.update(eccentric_parts(gear.drive, lay, w, half))
    return parts


def rolling_poses(scene, lift, lay, theta):
    gear = lift.gear
    n = theta.size
    alpha = np.asarray(gear.drive.angle(theta), dtype=float)
    w = gear.rolling_swing(theta).c[0]
    beta = np.where(w > 0.0, np.asarray(gear.valve_lever_angle(np.maximum(w, 0.0)), dtype=float), gear.rest)
    poses = {
        "rolling_lever": (world(n, *gear.pivot), quat_about_y(-alpha)),
        "valve_lever": (world(n, *gear.valve_pivot), quat_about_y(-beta)),
        "cam_pivot": (world(n, 0.0, 0.0), ident(n)),
        "valve_lever_pivot": (world(n, 0.0, 0.0), ident(n)),
    }
    poses.update(eccentric_poses(gear.drive, theta))
    return poses


class RollingLeverView(LeverGearView):
    colors = COLORS
    at_linkage_scale = True

    def gear_parts(self, scene, lift, lay) -> dict:
        return rolling_parts(scene, lift, lay)

    def gear_poses(self, scene, lift, lay, theta) -> dict:
        return rolling_poses(scene, lift, lay, theta)


VIEW = RollingLeverView()
