"""What the drawings of the lever gears share (pivoted roller, rocking cam, rolling lever, trip
gear): simple solids in the x-z plane, the roller, the valve drives (rocker arm, rod and valve
lever) and the eccentric, the layout that moves the valve group under the gear's valve pin, and
LeverGearView, the base of their views (explorer/view/gear_views.py).

Same conventions as explorer.view.drawing: metres, z up, the gear drawn in the x-z plane (the gear's
plane (x, y) -> world (x, z)), shafts along y; a counter-clockwise turn by a in the gear's plane is
the world rotation quat_about_y(-a). The valve, its spring and seat are the drawing's valve group,
moved so that the valve stem's top sits where the gear's valve pin is at rest (`gear_layout`); the
valve travels along the gear's valve axis (drawn upright: the scenes open their valves downwards).
Linkage parts follow the rigid kinematics; the valve follows the displayed (possibly elastic,
magnified) lift.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import trimesh

from ..effects.lift import build_lift
from . import translating_roller as stock
from .base import GearView
from .drawing import extrude_contour as _extrude_ccw
from .drawing import displayed_valve_lift, looped_roller_rotation, quat_about_y, signed_area, valve_group

TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------------------------
# simple solids in the x-z plane, extruded along y
# --------------------------------------------------------------------------------------------


def extrude_contour(xy: np.ndarray, width: float) -> trimesh.Trimesh:
    """explorer.view.drawing.extrude_contour for a polygon of either orientation (it wants ccw)."""
    xy = np.asarray(xy, dtype=float)
    if signed_area(xy) < 0.0:
        xy = xy[::-1]
    return _extrude_ccw(xy, width)


def bar(length: float, half: float, width: float, sections: int = 16) -> trimesh.Trimesh:
    """Stadium bar from (0, 0) to (length, 0) in x-z with round ends of radius `half`."""
    a = np.linspace(-0.5 * math.pi, 0.5 * math.pi, sections)
    right = np.column_stack([length + half * np.cos(a), half * np.sin(a)])
    left = np.column_stack([-half * np.cos(a), -half * np.sin(a)])
    return extrude_contour(np.vstack([right, left]), width)


def bar_between(p, q, half: float, width: float) -> trimesh.Trimesh:
    """Bar from point p to point q (x-z plane), in the frame of p."""
    dx, dz = q[0] - p[0], q[1] - p[1]
    mesh = bar(math.hypot(dx, dz), half, width)
    angle = math.atan2(dz, dx)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(-angle, [0.0, 1.0, 0.0]))
    return mesh


def disc(radius: float, width: float, centre=(0.0, 0.0), sections: int = 64) -> trimesh.Trimesh:
    a = np.linspace(0.0, TWO_PI, sections, endpoint=False)
    return extrude_contour(np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)]), width)


def pin(x: float, z: float, radius: float, width: float) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=radius, height=width, sections=24)
    m.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2.0, [1.0, 0.0, 0.0]))
    m.apply_translation([x, 0.0, z])
    return m


def sector(points: np.ndarray, width: float) -> trimesh.Trimesh:
    """A lever body: the pivot (origin) joined to a curved face given as points."""
    return extrude_contour(np.vstack([[0.0, 0.0], points]), width)


def concat(parts) -> trimesh.Trimesh:
    return trimesh.util.concatenate([p for p in parts if p is not None])


def world(n, x, z):
    return np.column_stack([np.full(n, x, dtype=float), np.zeros(n), np.full(n, z, dtype=float)])


def ident(n):
    return np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))


# --------------------------------------------------------------------------------------------
# layout: the drawing's valve, spring and seat, moved under the gear's valve pin
# --------------------------------------------------------------------------------------------


def valve_pin_rest(gear_lift) -> tuple[float, float] | None:
    """Rest position (x, y in the gear's plane) of the pin that pushes the valve, or None."""
    gear = getattr(gear_lift, "gear", None)
    if gear is None:
        return None
    drive = getattr(gear, "drive", None) if not hasattr(gear, "valve") else gear.valve
    if hasattr(drive, "valve_pivot"):  # rod and lever
        beta0 = float(drive.valve_lever_angle(np.array(drive.rest)))
        e = drive.valve_pivot
        return (e[0] + drive.arm_out * math.cos(beta0 + drive.bend), e[1] + drive.arm_out * math.sin(beta0 + drive.bend))
    p = drive.pivot
    return (p[0] + drive.arm * math.cos(drive.rest + drive.angle), p[1] + drive.arm * math.sin(drive.rest + drive.angle))


def gear_layout(scene, result=None, lift=None, at_linkage_scale: bool = False):
    """explorer.view.parts.Layout sized for the gear's lift, its valve group moved under the gear's
    valve pin (the trip gear keeps the stock position, its latch is drawn beside the spindle)."""
    lift = lift if lift is not None else build_lift(scene)
    lay = stock.layout(drawing_scene(scene, lift, at_linkage_scale), result)
    pin = valve_pin_rest(lift)
    if pin is None:
        return lay
    dx, dz = pin[0] - lay.valve_x, pin[1] - lay.stem_top_rest
    return replace(lay, valve_x=lay.valve_x + dx, stem_top_rest=lay.stem_top_rest + dz, seat_z=lay.seat_z + dz,
                   spring_seat_z=lay.spring_seat_z + dz, pivot=(lay.pivot[0] + dx, lay.pivot[1], lay.pivot[2] + dz))


# The translating roller's drawing (explorer.view.translating_roller) proportions its drawing (valve, spring, bar thickness) from the cam's base
# circle and roller. The eccentric-driven gears have no rotating cam: their follower section keeps
# the defaults, and the valve group came out a few centimetres tall under a linkage of most of a
# metre, a speck in the picture, its bars hairlines. They are drawn at the scale of the
# eccentric's lever instead (DRAWING_SCALE of its arm: a 150 mm arm gives the valve group the
# size a 90 mm cam would), which keeps the stock rules (valve about three times its lift across,
# capped by the drawing's size) and so a valve that still fits its lift.
DRAWING_SCALE = 0.6


def drawing_scene(scene, lift, at_linkage_scale: bool):
    """The scene as the translating roller's drawing sizes it (at the linkage's scale for the
    eccentric gears, whose follower section keeps the defaults)."""
    arm = getattr(getattr(getattr(lift, "gear", None), "drive", None), "arm", None)
    if not at_linkage_scale or not arm:
        return scene
    f = scene.follower
    size = DRAWING_SCALE * float(arm)
    if f.base_radius + f.roller_radius >= size:
        return scene
    return scene.with_changes(follower=replace(f, base_radius=size - f.roller_radius))


def valve_poses(scene, result, lay, magnification, axis: float = -0.5 * math.pi):
    s = displayed_valve_lift(result, magnification)
    n = s.size
    ux, uz = math.cos(axis), math.sin(axis)
    # the translating roller's drawing moves the stem top down by s; along another axis the drawing keeps the
    # valve upright and moves it along that axis
    pos = np.column_stack([lay.valve_x + s * ux, np.zeros(n), lay.stem_top_rest + s * uz])
    return {
        "valve": (pos, ident(n)),
        "spring": (world(n, lay.valve_x, lay.spring_seat_z), ident(n)),
        "seat": (world(n, 0.0, 0.0), ident(n)),
    }


# --------------------------------------------------------------------------------------------
# parts the gears share
# --------------------------------------------------------------------------------------------


def sizes(lay):
    w = lay.cam_width
    half = max(0.5 * lay.lever_half_thickness, 0.04 * (lay.base_radius + lay.roller_radius))
    return w, half


def roller(lay, radius):
    r, w = radius, lay.roller_width
    rim = disc(r, w)
    marks = [pin(0.62 * r * math.cos(a), 0.62 * r * math.sin(a), 0.12 * r, 1.04 * w) for a in (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi)]
    return concat([rim, *marks, pin(0.0, 0.0, 0.28 * r, 1.15 * w)])


def valve_drive_parts(drive, lay, w, half, roller_arm_angle=0.0):
    """Rocker arm (in the lever's frame) or rod + valve lever parts."""
    out = {}
    if hasattr(drive, "valve_pivot"):  # rod and lever (Fig. 3)
        out["rod"] = bar((drive.rod), 0.6 * half, 0.5 * w)
        d_local = (drive.arm_in, 0.0)
        f_local = (drive.arm_out * math.cos(drive.bend), drive.arm_out * math.sin(drive.bend))
        out["valve_lever"] = concat([bar_between((0.0, 0.0), d_local, half, 0.6 * w),
                                      bar_between((0.0, 0.0), f_local, half, 0.6 * w), pin(0.0, 0.0, 1.2 * half, 0.8 * w)])
        e = drive.valve_pivot
        out["valve_lever_pivot"] = pin(e[0], e[1], 0.7 * half, 1.4 * w)
    return out


def roller_spin(theta, centre, contact, normal_ground, centre_rate, r):
    """Roller angle for rolling without slip on the cam: Omega = -((omega x C - v_R) . t) / r per
    unit omega, t = z x n, integrated by the trapezoid rule (a drawing, not a result)."""
    tx, ty = -normal_ground[:, 1], normal_ground[:, 0]
    cam_vx, cam_vy = -contact[:, 1], contact[:, 0]
    rate = -((cam_vx - centre_rate[:, 0]) * tx + (cam_vy - centre_rate[:, 1]) * ty) / r
    steps = np.diff(theta)
    return np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * steps)])


def drive_poses(drive, psi, roller_centre, n):
    if not hasattr(drive, "valve_pivot"):
        return {}
    beta = np.asarray(drive.valve_lever_angle(np.asarray(psi)), dtype=float)
    e = drive.valve_pivot
    dx = e[0] + drive.arm_in * np.cos(beta)
    dz = e[1] + drive.arm_in * np.sin(beta)
    rod_angle = np.arctan2(dz - roller_centre[:, 1], dx - roller_centre[:, 0])
    return {
        "rod": (np.column_stack([roller_centre[:, 0], np.zeros(n), roller_centre[:, 1]]), quat_about_y(-rod_angle)),
        "valve_lever": (world(n, *e), quat_about_y(-beta)),
        "valve_lever_pivot": (world(n, 0.0, 0.0), ident(n)),
    }


def eccentric_parts(drive, lay, w, half):
    e = drive.radius
    sheave = disc(1.6 * e + 0.2 * e, 0.8 * w, centre=(e * math.cos(drive.phase), e * math.sin(drive.phase)))
    shaft = concat([disc(0.5 * e, 3.0 * w), pin(0.0, 0.5 * e, 0.15 * e, 3.0 * w)])
    strap = disc(1.6 * e + 0.35 * e, 0.5 * w)  # the rod's strap round the sheave, drawn as a ring disc
    rod = concat([bar(drive.rod, 0.6 * half, 0.5 * w), strap])
    return {"eccentric": sheave, "camshaft": shaft, "eccentric_rod": rod}


def eccentric_poses(drive, theta):
    n = theta.size
    ex, ez = drive.centre(theta)
    bx, bz = drive.pin(theta)
    q = quat_about_y(-theta)
    return {
        "eccentric": (world(n, 0.0, 0.0), q),
        "camshaft": (world(n, 0.0, 0.0), q),
        "eccentric_rod": (np.column_stack([ex, np.zeros(n), ez]), quat_about_y(-np.arctan2(bz - ez, bx - ex))),
    }


class LeverGearView(GearView):
    """The drawing of a gear whose lift curve carries its geometry (`.gear`): the gear's own parts
    (`gear_parts`, `gear_poses`: its levers, links, cams and rollers), coloured from `colors`, and
    the valve group moved under the gear's valve pin, travelling along the gear's valve axis."""

    parts_follow_cam = True  # the levers are drawn from the gear's geometry
    at_linkage_scale = False  # drawn at the scale of an eccentric's lever (drawing_scene)

    def gear_parts(self, scene, lift, lay) -> dict:
        raise NotImplementedError

    def gear_poses(self, scene, lift, lay, theta) -> dict:
        raise NotImplementedError

    def layout(self, scene, result=None, lift=None):
        return gear_layout(scene, result, lift, self.at_linkage_scale)

    def parts(self, scene, result=None, lay=None, lift=None, contour_samples: int = 720, only=None) -> dict:
        lift = lift if lift is not None else build_lift(scene)
        lay = lay or self.layout(scene, result, lift)
        parts = self.gear_parts(scene, lift, lay)
        for name, mesh in parts.items():  # rerun takes a part's colour from its mesh when the table lacks it
            if name in self.colors:
                mesh.visual.face_colors = (*self.colors[name], 255)
        parts.update(valve_group(lay))
        return {k: v for k, v in parts.items() if only is None or k in only}

    def poses(self, scene, result, magnification: float = 1.0, lay=None, lift=None) -> dict:
        lift = lift if lift is not None else build_lift(scene)
        lay = lay or self.layout(scene, result, lift)
        theta = np.radians(np.asarray(result.columns["cam_angle_deg"], dtype=float))
        poses = self.gear_poses(scene, lift, lay, theta)
        axis = -0.5 * math.pi
        gear = getattr(lift, "gear", None)
        valve = getattr(gear, "valve", None) or getattr(gear, "drive", None)
        if valve is not None and hasattr(valve, "axis"):
            axis = valve.axis
        poses.update(valve_poses(scene, result, lay, magnification, axis))
        if "roller" in poses:
            poses["roller"] = (poses["roller"][0], looped_roller_rotation(poses["roller"][1]))
        return poses
