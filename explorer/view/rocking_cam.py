"""The drawing of the eccentric-driven rocking cam (explorer.gears.rocking_cam): the eccentric, its
rod and the rocking cam about its pivot, the roller on its lever, and the valve drive; drawn at the
scale of the eccentric's lever."""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from .drawing import quat_about_y
from .gear_parts import (LeverGearView, bar, bar_between, concat, drive_poses, eccentric_parts, eccentric_poses, ident,
                         pin, roller, sector, sizes, valve_drive_parts, world)

COLORS = MappingProxyType({
    "roller_lever": (90, 170, 110),
    "rod": (150, 160, 175),
    "valve_lever": (70, 150, 95),
    "valve_lever_pivot": (95, 100, 110),
    "eccentric": (214, 126, 44),
    "eccentric_rod": (150, 160, 175),
    "rocking_cam": (214, 126, 44),
    "cam_pivot": (95, 100, 110),
})


def rocking_parts(scene, lift, lay):
    gear = lift.gear
    w, half = sizes(lay)
    contour, _ = gear.contour.contour_points(gear.roller_radius, n=241, margin=0.25)
    body = sector(contour, w)
    arm = bar(gear.drive.arm, half, 0.6 * w)
    parts = {
        "rocking_cam": concat([body, arm, pin(0.0, 0.0, 1.3 * half, 0.8 * w)]),
        "cam_pivot": pin(gear.cam_pivot[0], gear.cam_pivot[1], 0.7 * half, 1.4 * w),
        "roller": roller(lay, gear.roller_radius),
        "lever_pivot": pin(gear.lever_pivot[0], gear.lever_pivot[1], 0.7 * half, 1.4 * w),
    }
    lever = [bar(gear.lever_arm, half, 0.6 * w), pin(0.0, 0.0, 1.3 * half, 0.8 * w)]
    valve = gear.valve
    if not hasattr(valve, "valve_pivot"):
        lever.append(bar_between((0.0, 0.0), (valve.arm * math.cos(valve.angle), valve.arm * math.sin(valve.angle)), half, 0.6 * w))
    parts["roller_lever"] = concat(lever)
    parts.update(eccentric_parts(gear.drive, lay, w, half))
    parts.update(valve_drive_parts(valve, lay, w, half))
    return parts


def rocking_poses(scene, lift, lay, theta):
    gear = lift.gear
    n = theta.size
    d = gear.contact_details(theta)
    centre = d["roller_centre"]
    psi = d["lever_angle"]
    poses = {
        "rocking_cam": (world(n, *gear.cam_pivot), quat_about_y(-d["rocking_angle"])),
        "cam_pivot": (world(n, 0.0, 0.0), ident(n)),
        "roller": (np.column_stack([centre[:, 0], np.zeros(n), centre[:, 1]]), ident(n)),
        "roller_lever": (world(n, *gear.lever_pivot), quat_about_y(-psi)),
        "lever_pivot": (world(n, 0.0, 0.0), ident(n)),
    }
    poses.update(eccentric_poses(gear.drive, theta))
    poses.update(drive_poses(gear.valve, psi, centre, n))
    return poses


class RockingCamView(LeverGearView):
    colors = COLORS
    at_linkage_scale = True

    def gear_parts(self, scene, lift, lay) -> dict:
        return rocking_parts(scene, lift, lay)

    def gear_poses(self, scene, lift, lay, theta) -> dict:
        return rocking_poses(scene, lift, lay, theta)


VIEW = RockingCamView()
