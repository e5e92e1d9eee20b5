"""The drawing of the pivoted roller lever (explorer.gears.pivoted_roller): the synthesised cam and
its shaft, the roller on its lever about the fixed pivot, and the valve drive (a rocker arm on
the same lever, or Fig. 3's rod and valve lever)."""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from .drawing import quat_about_y
from .gear_parts import (TWO_PI, LeverGearView, bar, bar_between, concat, disc, drive_poses, extrude_contour, ident,
                         pin, roller, roller_spin, sizes, valve_drive_parts, world)

COLORS = MappingProxyType({
    "roller_lever": (90, 170, 110),
    "rod": (150, 160, 175),
    "valve_lever": (70, 150, 95),
    "valve_lever_pivot": (95, 100, 110),
})


def pivoted_parts(scene, lift, lay):
    gear = lift.gear
    w, half = sizes(lay)
    theta = np.linspace(0.0, TWO_PI, 720, endpoint=False)
    contour = gear.geometry(theta).contour
    r = gear.roller_radius
    lever = [bar(gear.arm, half, 0.6 * w), pin(0.0, 0.0, 1.3 * half, 0.8 * w)]
    drive = gear.drive
    if not hasattr(drive, "valve_pivot"):  # rocker: the valve arm on the same lever
        lever.append(bar_between((0.0, 0.0), (drive.arm * math.cos(drive.angle), drive.arm * math.sin(drive.angle)),
                                  half, 0.6 * w))
    parts = {
        "cam": extrude_contour(contour, w),
        "camshaft": concat([disc(0.32 * gear.base_radius, 3.2 * w), pin(0.0, 0.32 * gear.base_radius, 0.1 * gear.base_radius, 3.2 * w)]),
        "roller": roller(lay, r),
        "roller_lever": concat(lever),
        "lever_pivot": pin(gear.pivot[0], gear.pivot[1], 0.7 * half, 1.4 * w),
    }
    parts.update(valve_drive_parts(drive, lay, w, half))
    return parts


def pivoted_poses(scene, lift, lay, theta):
    gear = lift.gear
    n = theta.size
    g = gear.geometry(theta)
    psi = g.lever_angle
    centre = g.roller_centre
    rate = np.column_stack([-gear.arm * np.sin(psi) * g.lever_rate, gear.arm * np.cos(psi) * g.lever_rate])
    spin = roller_spin(theta, centre, g.contact, g.normal_ground, rate, gear.roller_radius)
    cam_q = quat_about_y(-theta)
    poses = {
        "cam": (world(n, 0.0, 0.0), cam_q),
        "camshaft": (world(n, 0.0, 0.0), cam_q),
        "roller": (np.column_stack([centre[:, 0], np.zeros(n), centre[:, 1]]), quat_about_y(-spin)),
        "roller_lever": (world(n, *gear.pivot), quat_about_y(-psi)),
        "lever_pivot": (world(n, 0.0, 0.0), ident(n)),
    }
    poses.update(drive_poses(gear.drive, psi, centre, n))
    return poses


class PivotedRollerView(LeverGearView):
    colors = COLORS

    def gear_parts(self, scene, lift, lay) -> dict:
        return pivoted_parts(scene, lift, lay)

    def gear_poses(self, scene, lift, lay, theta) -> dict:
        return pivoted_poses(scene, lift, lay, theta)


VIEW = PivotedRollerView()
