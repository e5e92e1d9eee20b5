"""3D parts of the seeds' other gears, for the browser explorer and the rerun recordings.

Same conventions as explorer.view.parts: metres, z up, the gear drawn in the x-z plane (the gear's
plane (x, y) -> world (x, z)), shafts along y; a counter-clockwise turn by a in the gear's plane
is the world rotation quat_about_y(-a). Every part's mesh is in its own frame; `gear_poses`
gives one (positions (N, 3), wxyz (N, 4)) per step of a Result.

The valve, its spring and seat are explorer.view.parts' parts, moved so that the valve stem's top
sits where the gear's valve pin is at rest (`gear_layout`); the valve travels along the gear's
valve axis (drawn upright: the scenes open their valves downwards). Linkage parts follow the rigid
kinematics; the valve follows the displayed (possibly elastic, magnified) lift. The trip gear
keeps the stock valve (opening downwards): a latch cam drives a rod whose latch pushes a catch
collar on the spindle from above and slides off it at the trip; a dashpot sits above the
spindle (see `_trip_geometry`). The eccentric gears are drawn at the scale of their linkage
(`_drawing_scene`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import trimesh

from . import parts as M
from .parts import extrude_contour as _extrude_ccw
from .parts import quat_about_y

TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------------------------
# simple solids in the x-z plane, extruded along y
# --------------------------------------------------------------------------------------------


def extrude_contour(xy: np.ndarray, width: float) -> trimesh.Trimesh:
    """explorer.view.parts.extrude_contour for a polygon of either orientation (it wants ccw)."""
    xy = np.asarray(xy, dtype=float)
    if M._signed_area(xy) < 0.0:
        xy = xy[::-1]
    return _extrude_ccw(xy, width)


def _bar(length: float, half: float, width: float, sections: int = 16) -> trimesh.Trimesh:
    """Stadium bar from (0, 0) to (length, 0) in x-z with round ends of radius `half`."""
    a = np.linspace(-0.5 * math.pi, 0.5 * math.pi, sections)
    right = np.column_stack([length + half * np.cos(a), half * np.sin(a)])
    left = np.column_stack([-half * np.cos(a), -half * np.sin(a)])
    return extrude_contour(np.vstack([right, left]), width)


def _bar_between(p, q, half: float, width: float) -> trimesh.Trimesh:
    """Bar from point p to point q (x-z plane), in the frame of p."""
    dx, dz = q[0] - p[0], q[1] - p[1]
    mesh = _bar(math.hypot(dx, dz), half, width)
    angle = math.atan2(dz, dx)
    mesh.apply_transform(trimesh.transformations.rotation_matrix(-angle, [0.0, 1.0, 0.0]))
    return mesh


def _disc(radius: float, width: float, centre=(0.0, 0.0), sections: int = 64) -> trimesh.Trimesh:
    a = np.linspace(0.0, TWO_PI, sections, endpoint=False)
    return extrude_contour(np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)]), width)


def _pin(x: float, z: float, radius: float, width: float) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=radius, height=width, sections=24)
    m.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2.0, [1.0, 0.0, 0.0]))
    m.apply_translation([x, 0.0, z])
    return m


def _sector(points: np.ndarray, width: float) -> trimesh.Trimesh:
    """A lever body: the pivot (origin) joined to a curved face given as points."""
    return extrude_contour(np.vstack([[0.0, 0.0], points]), width)


def _concat(parts) -> trimesh.Trimesh:
    return trimesh.util.concatenate([p for p in parts if p is not None])


def _world(n, x, z):
    return np.column_stack([np.full(n, x, dtype=float), np.zeros(n), np.full(n, z, dtype=float)])


def _ident(n):
    return np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))


# --------------------------------------------------------------------------------------------
# layout: explorer.view.parts' valve, spring and seat, moved under the gear's valve pin
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


def gear_layout(scene, result=None, lift=None):
    """explorer.view.parts.Layout sized for the gear's lift, its valve group moved under the gear's
    valve pin (the trip gear keeps the stock position, its latch is drawn beside the spindle)."""
    from ..effects.lift import build_lift

    lift = lift if lift is not None else build_lift(scene)
    lay = M.layout(_drawing_scene(scene, lift), result)
    pin = valve_pin_rest(lift)
    if pin is None:
        return lay
    dx, dz = pin[0] - lay.valve_x, pin[1] - lay.stem_top_rest
    return replace(lay, valve_x=lay.valve_x + dx, stem_top_rest=lay.stem_top_rest + dz, seat_z=lay.seat_z + dz,
                   spring_seat_z=lay.spring_seat_z + dz, pivot=(lay.pivot[0] + dx, lay.pivot[1], lay.pivot[2] + dz))


def _stock_scene(scene):
    """The scene as a translating-roller gear: explorer.view.parts' own parts and sizes, without its
    dispatch back to this module."""
    return scene.with_changes(follower=replace(scene.follower, type="translating-roller"))


# explorer.view.parts proportions its drawing (valve, spring, bar thickness) from the cam's base
# circle and roller. The eccentric-driven gears have no rotating cam: their follower section keeps
# the defaults, and the valve group came out a few centimetres tall under a linkage of most of a
# metre, a speck in the picture, its bars hairlines. They are drawn at the scale of the
# eccentric's lever instead (DRAWING_SCALE of its arm: a 150 mm arm gives the valve group the
# size a 90 mm cam would), which keeps the stock rules (valve about three times its lift across,
# capped by the drawing's size) and so a valve that still fits its lift.
DRAWING_SCALE = 0.6


def _drawing_scene(scene, lift):
    stock = _stock_scene(scene)
    arm = getattr(getattr(getattr(lift, "gear", None), "drive", None), "arm", None)
    if scene.follower.type not in ("rocking-cam", "rolling-lever") or not arm:
        return stock
    f = stock.follower
    size = DRAWING_SCALE * float(arm)
    if f.base_radius + f.roller_radius >= size:
        return stock
    return stock.with_changes(follower=replace(f, base_radius=size - f.roller_radius))


def _valve_group(scene, result, lay):
    return M.build_parts(_stock_scene(scene), result, lay=lay, only=("valve", "spring", "seat"))


def _valve_poses(scene, result, lay, magnification, axis: float = -0.5 * math.pi):
    s = M.displayed_valve_lift(result, magnification)
    n = s.size
    ux, uz = math.cos(axis), math.sin(axis)
    # explorer.view.parts moves the stem top down by s; along another axis the drawing keeps the
    # valve upright and moves it along that axis
    pos = np.column_stack([lay.valve_x + s * ux, np.zeros(n), lay.stem_top_rest + s * uz])
    return {
        "valve": (pos, _ident(n)),
        "spring": (_world(n, lay.valve_x, lay.spring_seat_z), _ident(n)),
        "seat": (_world(n, 0.0, 0.0), _ident(n)),
    }


# --------------------------------------------------------------------------------------------
# parts and poses per gear
# --------------------------------------------------------------------------------------------


def gear_parts(scene, result=None, lay=None, lift=None, only=None) -> dict[str, trimesh.Trimesh]:
    from ..effects.lift import build_lift

    lift = lift if lift is not None else build_lift(scene)
    lay = lay or gear_layout(scene, result, lift)
    kind = scene.follower.type
    parts = {"pivoted-roller": _pivoted_parts, "rocking-cam": _rocking_parts, "rolling-lever": _rolling_parts,
             "trip": _trip_parts}[kind](scene, lift, lay)
    from ..gears import GEAR_PART_COLORS

    for name, mesh in parts.items():  # rerun takes a part's colour from its mesh when the table lacks it
        if name in GEAR_PART_COLORS:
            mesh.visual.face_colors = (*GEAR_PART_COLORS[name], 255)
    parts.update(_valve_group(scene, result, lay))
    return {k: v for k, v in parts.items() if only is None or k in only}


def gear_poses(scene, result, magnification: float = 1.0, lay=None, lift=None) -> dict:
    from ..effects.lift import build_lift

    lift = lift if lift is not None else build_lift(scene)
    lay = lay or gear_layout(scene, result, lift)
    theta = np.radians(np.asarray(result.columns["cam_angle_deg"], dtype=float))
    kind = scene.follower.type
    poses = {"pivoted-roller": _pivoted_poses, "rocking-cam": _rocking_poses, "rolling-lever": _rolling_poses,
             "trip": _trip_poses}[kind](scene, lift, lay, theta)
    axis = -0.5 * math.pi
    gear = getattr(lift, "gear", None)
    valve = getattr(gear, "valve", None) or getattr(gear, "drive", None)
    if valve is not None and hasattr(valve, "axis"):
        axis = valve.axis
    poses.update(_valve_poses(scene, result, lay, magnification, axis))
    return poses


def _sizes(lay):
    w = lay.cam_width
    half = max(0.5 * lay.lever_half_thickness, 0.04 * (lay.base_radius + lay.roller_radius))
    return w, half


def _roller(lay, radius):
    r, w = radius, lay.roller_width
    rim = _disc(r, w)
    marks = [_pin(0.62 * r * math.cos(a), 0.62 * r * math.sin(a), 0.12 * r, 1.04 * w) for a in (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi)]
    return _concat([rim, *marks, _pin(0.0, 0.0, 0.28 * r, 1.15 * w)])


def _valve_drive_parts(drive, lay, w, half, roller_arm_angle=0.0):
    """Rocker arm (in the lever's frame) or rod + valve lever parts."""
    out = {}
    if hasattr(drive, "valve_pivot"):  # rod and lever (Fig. 3)
        out["rod"] = _bar((drive.rod), 0.6 * half, 0.5 * w)
        d_local = (drive.arm_in, 0.0)
        f_local = (drive.arm_out * math.cos(drive.bend), drive.arm_out * math.sin(drive.bend))
        out["valve_lever"] = _concat([_bar_between((0.0, 0.0), d_local, half, 0.6 * w),
                                      _bar_between((0.0, 0.0), f_local, half, 0.6 * w), _pin(0.0, 0.0, 1.2 * half, 0.8 * w)])
        e = drive.valve_pivot
        out["valve_lever_pivot"] = _pin(e[0], e[1], 0.7 * half, 1.4 * w)
    return out


def _pivoted_parts(scene, lift, lay):
    gear = lift.gear
    w, half = _sizes(lay)
    theta = np.linspace(0.0, TWO_PI, 720, endpoint=False)
    contour = gear.geometry(theta).contour
    r = gear.roller_radius
    lever = [_bar(gear.arm, half, 0.6 * w), _pin(0.0, 0.0, 1.3 * half, 0.8 * w)]
    drive = gear.drive
    if not hasattr(drive, "valve_pivot"):  # rocker: the valve arm on the same lever
        lever.append(_bar_between((0.0, 0.0), (drive.arm * math.cos(drive.angle), drive.arm * math.sin(drive.angle)),
                                  half, 0.6 * w))
    parts = {
        "cam": extrude_contour(contour, w),
        "camshaft": _concat([_disc(0.32 * gear.base_radius, 3.2 * w), _pin(0.0, 0.32 * gear.base_radius, 0.1 * gear.base_radius, 3.2 * w)]),
        "roller": _roller(lay, r),
        "roller_lever": _concat(lever),
        "lever_pivot": _pin(gear.pivot[0], gear.pivot[1], 0.7 * half, 1.4 * w),
    }
    parts.update(_valve_drive_parts(drive, lay, w, half))
    return parts


def _roller_spin(theta, centre, contact, normal_ground, centre_rate, r):
    """Roller angle for rolling without slip on the cam: Omega = -((omega x C - v_R) . t) / r per
    unit omega, t = z x n, integrated by the trapezoid rule (a drawing, not a result)."""
    tx, ty = -normal_ground[:, 1], normal_ground[:, 0]
    cam_vx, cam_vy = -contact[:, 1], contact[:, 0]
    rate = -((cam_vx - centre_rate[:, 0]) * tx + (cam_vy - centre_rate[:, 1]) * ty) / r
    steps = np.diff(theta)
    return np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * steps)])


def _pivoted_poses(scene, lift, lay, theta):
    gear = lift.gear
    n = theta.size
    g = gear.geometry(theta)
    psi = g.lever_angle
    centre = g.roller_centre
    rate = np.column_stack([-gear.arm * np.sin(psi) * g.lever_rate, gear.arm * np.cos(psi) * g.lever_rate])
    spin = _roller_spin(theta, centre, g.contact, g.normal_ground, rate, gear.roller_radius)
    cam_q = quat_about_y(-theta)
    poses = {
        "cam": (_world(n, 0.0, 0.0), cam_q),
        "camshaft": (_world(n, 0.0, 0.0), cam_q),
        "roller": (np.column_stack([centre[:, 0], np.zeros(n), centre[:, 1]]), quat_about_y(-spin)),
        "roller_lever": (_world(n, *gear.pivot), quat_about_y(-psi)),
        "lever_pivot": (_world(n, 0.0, 0.0), _ident(n)),
    }
    poses.update(_drive_poses(gear.drive, psi, centre, n))
    return poses


def _drive_poses(drive, psi, roller_centre, n):
    if not hasattr(drive, "valve_pivot"):
        return {}
    beta = np.asarray(drive.valve_lever_angle(np.asarray(psi)), dtype=float)
    e = drive.valve_pivot
    dx = e[0] + drive.arm_in * np.cos(beta)
    dz = e[1] + drive.arm_in * np.sin(beta)
    rod_angle = np.arctan2(dz - roller_centre[:, 1], dx - roller_centre[:, 0])
    return {
        "rod": (np.column_stack([roller_centre[:, 0], np.zeros(n), roller_centre[:, 1]]), quat_about_y(-rod_angle)),
        "valve_lever": (_world(n, *e), quat_about_y(-beta)),
        "valve_lever_pivot": (_world(n, 0.0, 0.0), _ident(n)),
    }


def _eccentric_parts(drive, lay, w, half):
    e = drive.radius
    sheave = _disc(1.6 * e + 0.2 * e, 0.8 * w, centre=(e * math.cos(drive.phase), e * math.sin(drive.phase)))
    shaft = _concat([_disc(0.5 * e, 3.0 * w), _pin(0.0, 0.5 * e, 0.15 * e, 3.0 * w)])
    strap = _disc(1.6 * e + 0.35 * e, 0.5 * w)  # the rod's strap round the sheave, drawn as a ring disc
    rod = _concat([_bar(drive.rod, 0.6 * half, 0.5 * w), strap])
    return {"eccentric": sheave, "camshaft": shaft, "eccentric_rod": rod}


def _eccentric_poses(drive, theta):
    n = theta.size
    ex, ez = drive.centre(theta)
    bx, bz = drive.pin(theta)
    q = quat_about_y(-theta)
    return {
        "eccentric": (_world(n, 0.0, 0.0), q),
        "camshaft": (_world(n, 0.0, 0.0), q),
        "eccentric_rod": (np.column_stack([ex, np.zeros(n), ez]), quat_about_y(-np.arctan2(bz - ez, bx - ex))),
    }


def _rocking_parts(scene, lift, lay):
    gear = lift.gear
    w, half = _sizes(lay)
    contour, _ = gear.contour.contour_points(gear.roller_radius, n=241, margin=0.25)
    body = _sector(contour, w)
    arm = _bar(gear.drive.arm, half, 0.6 * w)
    parts = {
        "rocking_cam": _concat([body, arm, _pin(0.0, 0.0, 1.3 * half, 0.8 * w)]),
        "cam_pivot": _pin(gear.cam_pivot[0], gear.cam_pivot[1], 0.7 * half, 1.4 * w),
        "roller": _roller(lay, gear.roller_radius),
        "lever_pivot": _pin(gear.lever_pivot[0], gear.lever_pivot[1], 0.7 * half, 1.4 * w),
    }
    lever = [_bar(gear.lever_arm, half, 0.6 * w), _pin(0.0, 0.0, 1.3 * half, 0.8 * w)]
    valve = gear.valve
    if not hasattr(valve, "valve_pivot"):
        lever.append(_bar_between((0.0, 0.0), (valve.arm * math.cos(valve.angle), valve.arm * math.sin(valve.angle)), half, 0.6 * w))
    parts["roller_lever"] = _concat(lever)
    parts.update(_eccentric_parts(gear.drive, lay, w, half))
    parts.update(_valve_drive_parts(valve, lay, w, half))
    return parts


def _rocking_poses(scene, lift, lay, theta):
    gear = lift.gear
    n = theta.size
    d = gear.contact_details(theta)
    centre = d["roller_centre"]
    psi = d["lever_angle"]
    poses = {
        "rocking_cam": (_world(n, *gear.cam_pivot), quat_about_y(-d["rocking_angle"])),
        "cam_pivot": (_world(n, 0.0, 0.0), _ident(n)),
        "roller": (np.column_stack([centre[:, 0], np.zeros(n), centre[:, 1]]), _ident(n)),
        "roller_lever": (_world(n, *gear.lever_pivot), quat_about_y(-psi)),
        "lever_pivot": (_world(n, 0.0, 0.0), _ident(n)),
    }
    poses.update(_eccentric_poses(gear.drive, theta))
    poses.update(_drive_poses(gear.valve, psi, centre, n))
    return poses


def _rolling_parts(scene, lift, lay):
    gear = lift.gear
    w, half = _sizes(lay)
    face_a, face_b, _ = gear.faces(120)
    valve = gear.valve
    parts = {
        "rolling_lever": _concat([_sector(face_a, w), _bar(gear.drive.arm, half, 0.6 * w), _pin(0.0, 0.0, 1.3 * half, 0.8 * w)]),
        "valve_lever": _concat([_sector(face_b, w), _pin(0.0, 0.0, 1.3 * half, 0.8 * w),
                                _bar_between((0.0, 0.0), (valve.arm * math.cos(valve.angle), valve.arm * math.sin(valve.angle)),
                                             half, 0.6 * w)]),
        "cam_pivot": _pin(gear.pivot[0], gear.pivot[1], 0.7 * half, 1.4 * w),
        "valve_lever_pivot": _pin(gear.valve_pivot[0], gear.valve_pivot[1], 0.7 * half, 1.4 * w),
    }
    parts.update(_eccentric_parts(gear.drive, lay, w, half))
    return parts


def _rolling_poses(scene, lift, lay, theta):
    gear = lift.gear
    n = theta.size
    alpha = np.asarray(gear.drive.angle(theta), dtype=float)
    w = gear.rolling_swing(theta).c[0]
    beta = np.where(w > 0.0, np.asarray(gear.valve_lever_angle(np.maximum(w, 0.0)), dtype=float), gear.rest)
    poses = {
        "rolling_lever": (_world(n, *gear.pivot), quat_about_y(-alpha)),
        "valve_lever": (_world(n, *gear.valve_pivot), quat_about_y(-beta)),
        "cam_pivot": (_world(n, 0.0, 0.0), _ident(n)),
        "valve_lever_pivot": (_world(n, 0.0, 0.0), _ident(n)),
    }
    poses.update(_eccentric_poses(gear.drive, theta))
    return poses


def _trip_part_setting(scene, key):
    """[gear.trip] `key` when the scene's gear section has it (latch_width, latch_depth)."""
    try:
        return scene.gear.part("trip").get(key)
    except (AttributeError, KeyError, TypeError):
        return None


def _dashpot_bore(scene, default: float) -> float:
    """Bore radius of the scene's active dashpot ([gear.air_dashpot] or [gear.oil_dashpot]
    diameter), or `default` for a gear without a buffer."""
    try:
        buffer = scene.gear.part("trip")["buffer"]
        return 0.5 * float(scene.gear.part(f"{buffer}_dashpot")["diameter"]) if buffer != "none" else default
    except (AttributeError, KeyError, TypeError):
        return default


def _trip_geometry(scene, lift, lay) -> dict:
    """Where the trip gear's parts sit (world x-z, metres), shared by its parts and poses.

    The valve spindle (the stock valve, opening downwards) carries a catch collar under the
    dashpot. The latch is a plate that reaches the catch from the right: it rests `overtravel`
    above the collar, then pushes it down with the latch lift X - s_o; at the trip it slides out
    to the right by its engagement and passes the collar. It slides in a guide at the foot of
    the latch rod, which runs up beside the dashpot to a roller under the latch cam: a cam for
    the scene's latch law (valve-referred: the drawing has the ratio 1), turned upside down so
    that its lift pushes the roller, rod and latch down. The cam sits above the dashpot, the rod
    and roller clear of its side."""
    from ..lift.contours.translating import translating_profile

    w, half = _sizes(lay)
    rv, rs = lay.valve_radius, lay.stem_radius
    latch = lift.latch
    stroke = float(latch.height)
    depth = _trip_part_setting(scene, "latch_depth") or 0.3 * rv
    face = _trip_part_setting(scene, "latch_width") or 0.5 * w
    catch_r = rs + depth  # the collar: the latch bears on its rim, `depth` wide
    plate = max(0.12 * rv, half)  # thickness of latch plate and collar
    gap = 0.15 * rv
    # collar underside at rest: high enough on the spindle that the tripped latch, at the bottom
    # of its stroke beside the closed valve, stays `gap` above the spring retainer
    catch_z = max(lay.stem_top_rest + 2.0 * half,
                  lay.stem_top_rest - lay.retainer_drop + gap + stroke - plate - lift.overtravel)
    latch_rest = catch_z + plate + lift.overtravel  # latch face with X = 0
    bore = _dashpot_bore(scene, 1.1 * rv)  # the scene's dashpot
    outer = 1.25 * bore
    # piston at rest: the bore (top - 1.2 stroke .. top + 1.8 stroke) starts `gap` above the latch
    top = latch_rest + plate + gap + 1.2 * stroke
    dashpot_top = top + 1.8 * stroke
    roller = 0.3 * stroke
    base = 1.0 * stroke  # a cam about as large as the lift: moderate pressure angles for the usual laws
    rod_x = lay.valve_x + outer + gap + roller
    theta = np.linspace(0.0, TWO_PI, 720, endpoint=False)
    theta = np.unique(np.concatenate([theta, np.mod(np.asarray(latch.breakpoints(), dtype=float), TWO_PI)]))
    contour = translating_profile(latch, theta, base, roller, 0.0).contour
    reach = float(np.max(np.hypot(contour[:, 0], contour[:, 1])))
    prime = base + roller
    # the cam's swept disc clears the dashpot's top by `gap`
    cam_z = max(dashpot_top + gap + reach, latch_rest + 2.0 * prime)
    return dict(
        w=w, half=half, stroke=stroke, depth=depth, face=face, catch_r=catch_r, plate=plate, bore=bore,
        outer=outer, top=top, catch_z=catch_z, latch_rest=latch_rest, roller=roller, base=base, rod_x=rod_x,
        contour=contour, cam=(rod_x, cam_z), rod_length=cam_z - prime - latch_rest, slide=depth + gap,
    )


def _trip_parts(scene, lift, lay):
    g = _trip_geometry(scene, lift, lay)
    w, half, plate, stroke = g["w"], g["half"], g["plate"], g["stroke"]
    rs = lay.stem_radius
    reach_x = g["rod_x"] - lay.valve_x
    # latch: local origin on the valve axis at its face (underside); it starts over the stem's
    # surface, so it never meets the spindle, and ends beyond the rod's guide by the slide
    latch = extrude_contour(np.array([[rs, 0.0], [reach_x + g["slide"] + 0.5 * g["roller"], 0.0],
                                      [reach_x + g["slide"] + 0.5 * g["roller"], plate], [rs, plate]]), g["face"])
    collar = trimesh.creation.cylinder(radius=g["catch_r"], height=plate, sections=48)
    collar.apply_translation([0.0, 0.0, 0.5 * plate])
    # latch rod: local origin at the roller's centre; the guide at its foot embraces the latch
    rod_half = 0.3 * g["roller"]
    length = g["rod_length"]
    guide = extrude_contour(np.array([[-2.5 * rod_half, -length - 0.8 * plate], [2.5 * rod_half, -length - 0.8 * plate],
                                      [2.5 * rod_half, -length + 1.8 * plate], [-2.5 * rod_half, -length + 1.8 * plate]]),
                            1.3 * g["face"])
    fork = [_pin(0.0, 0.0, 0.3 * g["roller"], 1.6 * lay.roller_width)]
    bar = _bar_between((0.0, -length), (0.0, 0.0), rod_half, 0.5 * w)
    bar.apply_translation([0.0, 0.0, -length])  # _bar_between draws in the frame of its first point
    rod = _concat([bar, guide, *fork])
    cam = extrude_contour(g["contour"], 0.8 * w)
    shaft = 0.3 * g["base"]
    camshaft = _concat([_disc(shaft, 3.0 * w), _pin(0.0, shaft, 0.3 * shaft, 3.0 * w)])
    # dashpot: the piston (top of the rod, 0.4 stroke thick) runs from z = top down by the lift,
    # at most the latch stroke: the bore spans top - 1.2 stroke .. top + 1.8 stroke
    bore = g["bore"]
    top = g["top"]
    cylinder = trimesh.creation.annulus(r_min=bore, r_max=g["outer"], height=3.0 * stroke, sections=48)
    cylinder.apply_translation([lay.valve_x, 0.0, top + 0.3 * stroke])
    piston = trimesh.creation.cylinder(radius=0.98 * bore, height=0.4 * stroke, sections=48)
    piston_rod = trimesh.creation.cylinder(radius=rs, height=top - lay.stem_top_rest, sections=16)
    piston_rod.apply_translation([0.0, 0.0, 0.5 * (top - lay.stem_top_rest)])
    piston.apply_translation([0.0, 0.0, top - lay.stem_top_rest + 0.2 * stroke])
    return {"latch": latch, "catch": collar, "dashpot": cylinder, "dashpot_piston": _concat([piston_rod, piston]),
            "rod": rod, "roller": _roller(lay, g["roller"]), "cam": cam, "camshaft": camshaft}


def _trip_poses(scene, lift, lay, theta):
    g = _trip_geometry(scene, lift, lay)
    n = theta.size
    latch = np.asarray(lift.latch.derivatives(theta)[0])
    s = np.maximum(np.asarray(lift.derivatives(theta)[0]) - lift.overtravel, 0.0)
    phi = np.mod(theta - lift.start, TWO_PI)
    # tripped: from the release until the latch is back above its catching height
    tripped = (phi >= lift.phi_trip) & (latch > lift.overtravel - 1e-12)
    # the latch face meets the collar after the over-travel, then both move by X - s_o
    latch_z = g["latch_rest"] - latch
    cx, cz = g["cam"]
    # the cam is drawn upside down (turned by pi): its lift points down, onto the roller
    spin = _trip_roller_spin(scene, lift, g, theta)
    return {
        "latch": (np.column_stack([lay.valve_x + np.where(tripped, g["slide"], 0.0), np.zeros(n), latch_z]), _ident(n)),
        "catch": (np.column_stack([np.full(n, lay.valve_x), np.zeros(n), g["catch_z"] - s]), _ident(n)),
        "dashpot": (_world(n, 0.0, 0.0), _ident(n)),
        "dashpot_piston": (np.column_stack([np.full(n, lay.valve_x), np.zeros(n), lay.stem_top_rest - s]), _ident(n)),
        "rod": (np.column_stack([np.full(n, g["rod_x"]), np.zeros(n), latch_z + g["rod_length"]]), _ident(n)),
        "roller": (np.column_stack([np.full(n, g["rod_x"]), np.zeros(n), latch_z + g["rod_length"]]), quat_about_y(-spin)),
        "cam": (_world(n, cx, cz), quat_about_y(-(theta + math.pi))),
        "camshaft": (_world(n, cx, cz), quat_about_y(-(theta + math.pi))),
    }


def _trip_roller_spin(scene, lift, g, theta):
    """The latch roller rolling on its cam: explorer.view.parts.roller_spin for a translating roller
    of the drawing's base circle and radius (turning the whole cam and follower by pi changes
    neither the spin's sense nor its rate)."""
    follower = replace(scene.follower, type="translating-roller", base_radius=g["base"], roller_radius=g["roller"],
                       offset=0.0)
    return M.roller_spin(scene.with_changes(follower=follower), lift.latch, np.asarray(theta, dtype=float))
