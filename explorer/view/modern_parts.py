"""3D parts of today's valve trains (bucket tappet, finger follower, OHC rocker, pushrod train),
for the browser explorer and the rerun recordings: pure functions of a gear object (explorer.gears.
flat_face, arm, pushrod) and the cam angles, returning trimesh meshes and one pose per cam angle.

Conventions of explorer.view.parts and explorer.view.gear_parts: metres, z up, the gear drawn in
the x-z plane, shafts along y; a counter-clockwise turn by a in the gear's plane is the world
rotation quat_about_y(-a). Each gear's plane is first turned by its drawing's `frame` angle
(the bucket tappet's layout, tappet above the cam, is drawn upside down, cam on top as in a
DOHC head; the others as laid out). Every mesh is in its own frame; a pose is (positions (N, 3),
wxyz (N, 4)), the position being where the mesh's origin goes:

cam, camshaft     origin at the camshaft's centre, turning with theta
tappet, lifter    origin at the face's (or roller's) centre on the axis at zero lift; translate
roller            origin at its centre; turns with the arm (or not, on a lifter) plus its spin
finger, rocker    origin at the pivot, built with the arm's reference direction along +x
pushrod           origin at the lower ball's centre, built along the gear plane's +y
valve             built where it sits when closed; translates along its axis
lash_adjuster     the finger's pivot: body and ball, fixed
cam_contact, tip_contact   small spheres at the contacts, so the pad contacts are visible

The valve is drawn at `valve_lift` (for example the elastic solution's, magnified), by default the
rigid max(0, s - lash); the other parts follow the rigid kinematics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

from .gear_parts import extrude_contour
from .drawing import quat_about_y

TWO_PI = 2.0 * math.pi

MODERN_PART_COLORS: dict[str, tuple[int, int, int]] = {
    "cam": (214, 126, 44),
    "camshaft": (120, 124, 132),
    "tappet": (150, 160, 175),
    "lifter": (150, 160, 175),
    "roller": (60, 130, 200),
    "finger": (90, 170, 110),
    "rocker": (90, 170, 110),
    "pushrod": (170, 175, 185),
    "lash_adjuster": (95, 100, 110),
    "valve": (200, 70, 70),
    "cam_contact": (240, 220, 40),
    "tip_contact": (240, 220, 40),
    "hla_body": (95, 100, 110),  # a train's lash adjuster (explorer.view.train_motion): its body
    "hla_plunger": (205, 175, 70),  # and its plunger, moving
}
STATIC_PARTS = ("lash_adjuster",)  # parts that never move (their pose is the same at every step)


@dataclass(frozen=True)
class Drawing:
    """The meshes of one gear and the frame its plane is drawn in."""

    parts: dict[str, trimesh.Trimesh]
    frame: float  # rad: the gear's plane turned by this before (x, y) -> world (x, z)


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def _turn(xy: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    xy = np.atleast_2d(np.asarray(xy, dtype=float))
    return np.column_stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]])


def to_world(xy, frame: float) -> np.ndarray:
    """Gear-plane points (N, 2) -> world (N, 3) in the drawing's frame."""
    p = _turn(xy, frame)
    return np.column_stack([p[:, 0], np.zeros(len(p)), p[:, 1]])


def _framed(mesh: trimesh.Trimesh, frame: float) -> trimesh.Trimesh:
    mesh.apply_transform(trimesh.transformations.rotation_matrix(-frame, [0.0, 1.0, 0.0]))
    return mesh


def _prism(xy: np.ndarray, width: float, frame: float, y: float = 0.0) -> trimesh.Trimesh:
    mesh = extrude_contour(_turn(xy, frame), width)
    if y:
        mesh.apply_translation([0.0, y, 0.0])
    return mesh


def _stadium(p, q, half: float, sections: int = 12) -> np.ndarray:
    """Outline of a bar from p to q with round ends of radius `half` (gear plane)."""
    p, q = np.asarray(p, dtype=float), np.asarray(q, dtype=float)
    d = q - p
    angle = math.atan2(d[1], d[0])
    a = np.linspace(-0.5 * math.pi, 0.5 * math.pi, sections)
    right = q + half * np.column_stack([np.cos(angle + a), np.sin(angle + a)])
    left = p + half * np.column_stack([np.cos(angle + math.pi + a), np.sin(angle + math.pi + a)])
    return np.vstack([right, left])


def _circle(centre, radius: float, sections: int = 48) -> np.ndarray:
    a = np.linspace(0.0, TWO_PI, sections, endpoint=False)
    return np.asarray(centre, dtype=float) + radius * np.column_stack([np.cos(a), np.sin(a)])


def _sector(centre, radius: float, middle: float, half_angle: float, sections: int = 24) -> np.ndarray:
    """A pad: the arc of radius `radius` about `centre` over middle +- half_angle, closed by a chord
    drawn a quarter of the radius deep (so a large pad radius stays a slim pad)."""
    a = middle + np.linspace(-half_angle, half_angle, sections)
    arc = np.asarray(centre) + radius * np.column_stack([np.cos(a), np.sin(a)])
    depth = min(0.25 * radius, 0.3 * np.hypot(*(arc[0] - arc[-1])))
    inward = -np.array([math.cos(middle), math.sin(middle)]) * depth
    return np.vstack([arc, arc[-1] + inward, arc[0] + inward])


def _roller_mesh(radius: float, width: float, marks: int = 4) -> trimesh.Trimesh:
    rim = extrude_contour(_circle((0.0, 0.0), radius, 64), width)
    bores = [extrude_contour(_circle(0.62 * radius * np.array([math.cos(a), math.sin(a)]), 0.12 * radius, 12), 1.04 * width)
             for a in TWO_PI / marks * np.arange(marks)]
    return trimesh.util.concatenate([rim, *bores])


def _sphere(radius: float) -> trimesh.Trimesh:
    return trimesh.creation.icosphere(subdivisions=2, radius=radius)


def _cylinder_along(start, direction, length: float, radius: float, frame: float, sections: int = 32) -> trimesh.Trimesh:
    """Cylinder from the gear-plane point `start` along the gear-plane unit `direction`."""
    mesh = trimesh.creation.cylinder(radius=radius, height=length, sections=sections)
    mesh.apply_translation([0.0, 0.0, 0.5 * length])  # along +z from the origin
    angle = math.atan2(direction[1], direction[0]) + frame  # world angle in the x-z plane
    mesh.apply_transform(trimesh.transformations.rotation_matrix(0.5 * math.pi - angle, [0.0, 1.0, 0.0]))
    mesh.apply_translation(to_world(np.asarray(start)[None, :], frame)[0])
    return mesh


def _cam_parts(contour: np.ndarray, width: float, frame: float, shaft: float) -> dict[str, trimesh.Trimesh]:
    return {"cam": _prism(contour, width, frame),
            "camshaft": extrude_contour(_circle((0.0, 0.0), shaft, 48), 3.0 * width)}


def _colour(parts: dict[str, trimesh.Trimesh]) -> dict[str, trimesh.Trimesh]:
    for name, mesh in parts.items():
        if name in MODERN_PART_COLORS:
            mesh.visual.face_colors = (*MODERN_PART_COLORS[name], 255)
    return parts


def _fixed(n: int, point) -> np.ndarray:
    return np.tile(np.broadcast_to(np.asarray(point, dtype=float), (3,)), (n, 1))


def _ident(n: int) -> np.ndarray:
    return np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))


def _spin(theta: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """Integral of rate d theta from the first sample (trapezoids)."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * np.diff(theta))])


def _valve_mesh(tip, axis, stem: float, length: float, frame: float) -> trimesh.Trimesh:
    head = _cylinder_along(np.asarray(tip) + (length - 0.08 * length) * np.asarray(axis), axis, 0.08 * length, 4.0 * stem, frame)
    return trimesh.util.concatenate([_cylinder_along(tip, axis, length, stem, frame), head])


def _valve_pose(n: int, axis, frame: float, travel) -> tuple[np.ndarray, np.ndarray]:
    u = to_world(np.asarray(axis)[None, :], frame)[0]
    return np.asarray(travel, dtype=float)[:, None] * u[None, :], _ident(n)


def _displayed(lift_rows: np.ndarray, lash: float, valve_lift) -> np.ndarray:
    return np.maximum(lift_rows[0] - lash, 0.0) if valve_lift is None else np.asarray(valve_lift, dtype=float)


# --------------------------------------------------------------------------------------------
# bucket tappet
# --------------------------------------------------------------------------------------------


BUCKET_FRAME = math.pi  # cam on top, as in a DOHC head


def bucket_drawing(gear, *, cam_width: float | None = None, n: int = 720, frame: float = BUCKET_FRAME) -> Drawing:
    t = gear.tappet
    width = cam_width or t.cam_width or 0.5 * t.base_radius
    theta = np.linspace(0.0, TWO_PI, n, endpoint=False)
    parts = _cam_parts(gear.surface(theta).contour, width, frame, 0.45 * t.base_radius)
    diameter = t.face_diameter or 1.6 * t.base_radius
    height = 0.8 * diameter
    wall = 0.06 * diameter
    # the bucket: a cup, face at its origin, opening away from the cam
    cup = trimesh.creation.annulus(r_min=0.5 * diameter - wall, r_max=0.5 * diameter, height=height, sections=64)
    cup.apply_translation([0.0, 0.0, 0.5 * height])
    face = trimesh.creation.cylinder(radius=0.5 * diameter, height=wall, sections=64)
    face.apply_translation([0.0, 0.0, 0.5 * wall])
    parts["tappet"] = _framed(trimesh.util.concatenate([cup, face]), frame)
    stem = 0.08 * diameter
    parts["valve"] = _valve_mesh((0.0, t.base_radius + wall), (0.0, 1.0), stem, 6.0 * diameter, frame)
    parts["cam_contact"] = _sphere(0.03 * diameter)
    return Drawing(_colour(parts), frame)


def bucket_poses(gear, theta, *, valve_lift=None, lash: float = 0.0, frame: float = BUCKET_FRAME) -> dict:
    theta = np.asarray(theta, dtype=float)
    k = gear.kinematics(theta)
    n = theta.size
    face = np.column_stack([np.zeros(n), gear.tappet.base_radius + k.lift[0]])
    return {
        "cam": (_fixed(n, 0.0), quat_about_y(-theta)),
        "camshaft": (_fixed(n, 0.0), quat_about_y(-theta)),
        "tappet": (to_world(face, frame), _ident(n)),
        "valve": _valve_pose(n, (0.0, 1.0), frame, _displayed(k.lift, lash, valve_lift) + lash),
        "cam_contact": (to_world(k.surface.contact, frame), _ident(n)),
    }


# --------------------------------------------------------------------------------------------
# finger follower and OHC rocker (explorer.gears.arm)
# --------------------------------------------------------------------------------------------


def _arm_frame(points: np.ndarray, pivot, psi: np.ndarray) -> np.ndarray:
    """Ground points (N, 2) at arm angles psi (N,) -> the arm's frame (pivot at the origin,
    reference direction along +x)."""
    rel = np.asarray(points) - np.asarray(pivot)
    c, s = np.cos(psi), np.sin(psi)
    return np.column_stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]])


def arm_half_width(gear) -> float:
    """Half the width of the arm's bars (from the roller's radius, or the pad's arm)."""
    side = gear.arm.cam_side
    return 0.35 * (side.radius if side.kind == "roller" else 0.25 * side.arm)


def adjuster_ball(gear) -> float:
    """Radius of the lash adjuster's ball (the finger's pivot); its body is 1.6 times as wide."""
    return 0.3 * arm_half_width(gear) + 0.004


def hla_parts(gear, frame: float = 0.0) -> dict[str, trimesh.Trimesh]:
    """A finger's lash adjuster as a train with [hla] draws it: the body (world frame, fixed) and
    the plunger with the ball (the pivot) it carries, origin at the pivot, sliding along the
    valve's axis (into the body)."""
    ball, down = adjuster_ball(gear), gear.valve.axis
    pivot = to_world(np.asarray(gear.arm.pivot)[None, :], frame)[0]
    body = _cylinder_along((0.0, 0.0) + 2.5 * ball * down, down, 6.5 * ball, 1.6 * ball, frame)
    body.apply_translation(pivot)
    plunger = trimesh.util.concatenate([_sphere(ball), _cylinder_along((0.0, 0.0), down, 4.0 * ball, 1.2 * ball, frame)])
    return _colour({"lash_adjuster": body, "hla_plunger": plunger})


def arm_drawing(gear, *, width: float | None = None, n: int = 720, frame: float = 0.0) -> Drawing:
    arm, side, valve = gear.arm, gear.arm.cam_side, gear.valve
    theta = np.linspace(0.0, TWO_PI, n, endpoint=False)
    k = gear.kinematics(theta)
    w = width or side.width or 0.6 * arm.base_radius
    parts = _cam_parts(k.surface.contour, w, frame, 0.45 * arm.base_radius)
    rest = arm.rest
    pad_c = valve.drive.arm * np.array([math.cos(valve.drive.angle), math.sin(valve.drive.angle)])
    tip_dir = _turn(valve.axis[None, :], -rest)[0]
    half = arm_half_width(gear)
    plate = 0.25 * w
    body = []
    element = np.array([side.arm, 0.0])  # the roller's centre or the pad's crown
    if side.kind == "roller":
        # two side plates carry the roller's axle (pivot to roller, pivot to valve pad)
        for y in (-(0.5 * w + 0.5 * plate), 0.5 * w + 0.5 * plate):
            for end in (element, pad_c):
                body.append(_prism(_stadium((0.0, 0.0), end, half), plate, frame, y))
        parts["roller"] = _roller_mesh(side.radius, w)
    else:
        for end in (element, pad_c):
            body.append(_prism(_stadium((0.0, 0.0), end, half), w, frame))
        contacts = _arm_frame(k.surface.contact, arm.pivot, k.arm_angle[0])
        normal = np.array([math.cos(side.face_angle + math.pi), math.sin(side.face_angle + math.pi)])  # towards the cam
        along = contacts @ np.array([-normal[1], normal[0]])
        span = float(along.max() - along.min()) + 0.2 * side.arm
        if side.circular:
            a, delta = side.centre_polar()
            centre = a * np.array([math.cos(delta), math.sin(delta)])
            half_angle = min(0.5 * span / side.radius + 0.05, 0.5 * math.pi)
            body.append(_prism(_sector(centre, side.radius, math.atan2(normal[1], normal[0]), half_angle), w, frame))
        else:
            crown = np.array([side.arm, 0.0])
            mid = 0.5 * (along.max() + along.min())
            t = np.array([-normal[1], normal[0]])
            foot = crown + (mid - crown @ t) * t
            depth = 0.15 * side.arm
            block = np.array([foot - 0.5 * span * t, foot + 0.5 * span * t,
                              foot + 0.5 * span * t - depth * normal, foot - 0.5 * span * t - depth * normal])
            body.append(_prism(block, w, frame))
    body.append(_prism(_sector(pad_c, valve.pad_radius, math.atan2(tip_dir[1], tip_dir[0]), 0.6), w, frame))
    name = gear.kind  # the arm's part: "finger" or "rocker"
    parts[name] = trimesh.util.concatenate(body)
    ball = adjuster_ball(gear)
    if gear.kind == "finger":
        # the hydraulic lash adjuster: its ball is the pivot, its body stands along the valve's axis
        down = valve.axis
        adjuster = [_sphere(ball), _cylinder_along((0.0, 0.0) + ball * down, down, 8.0 * ball, 1.6 * ball, frame)]
        for mesh in adjuster:
            mesh.apply_translation(to_world(np.asarray(arm.pivot)[None, :], frame)[0])
        parts["lash_adjuster"] = trimesh.util.concatenate(adjuster)
    stem = valve.tip_radius or 0.003
    parts["valve"] = _valve_mesh(valve.rest_contact(), valve.axis, stem, 0.12, frame)
    parts["cam_contact"] = _sphere(0.08 * half + 0.0006)
    parts["tip_contact"] = _sphere(0.08 * half + 0.0006)
    return Drawing(_colour(parts), frame)


def arm_poses(gear, theta, *, valve_lift=None, lash: float = 0.0, frame: float = 0.0) -> dict:
    theta = np.asarray(theta, dtype=float)
    k = gear.kinematics(theta)
    n = theta.size
    psi = k.arm_angle[0]
    pivot = to_world(np.asarray(gear.arm.pivot)[None, :], frame)[0]
    name = gear.kind  # the arm's part: "finger" or "rocker"
    poses = {
        "cam": (_fixed(n, 0.0), quat_about_y(-theta)),
        "camshaft": (_fixed(n, 0.0), quat_about_y(-theta)),
        name: (_fixed(n, pivot), quat_about_y(-psi)),
        "valve": _valve_pose(n, gear.valve.axis, frame, _displayed(k.lift, lash, valve_lift) + lash),
        "cam_contact": (to_world(k.surface.contact, frame), _ident(n)),
        "tip_contact": (to_world(k.tip.point, frame), _ident(n)),
    }
    if k.roller_rate is not None:
        poses["roller"] = (to_world(k.centre, frame), quat_about_y(-(psi + _spin(theta, k.roller_rate))))
    if gear.kind == "finger":
        poses["lash_adjuster"] = (_fixed(n, 0.0), _ident(n))
    return poses


# --------------------------------------------------------------------------------------------
# pushrod train (explorer.gears.pushrod)
# --------------------------------------------------------------------------------------------


def pushrod_drawing(gear, *, n: int = 720, frame: float = 0.0) -> Drawing:
    f = gear.lifter
    theta = np.linspace(0.0, TWO_PI, n, endpoint=False)
    k = gear.kinematics(theta)
    w = f.width or 0.7 * gear.base_radius
    parts = _cam_parts(k.surface.contour, w, frame, 0.45 * gear.base_radius)
    radius = 0.6 * gear.base_radius
    ball = 0.25 * radius
    if f.kind == "roller":
        parts["roller"] = _roller_mesh(f.radius, w)
        body_start = (0.0, 0.6 * f.radius)
    else:
        body_start = (0.0, 0.0)
    lifter = _cylinder_along(body_start, (0.0, 1.0), f.socket_height + ball - body_start[1], radius, frame)
    parts["lifter"] = lifter
    top = _sphere(ball)
    top.apply_translation(to_world([[0.0, gear.pushrod_length]], frame)[0])
    parts["pushrod"] = trimesh.util.concatenate([
        _sphere(ball), _cylinder_along((0.0, 0.0), (0.0, 1.0), gear.pushrod_length, 0.45 * ball, frame, 16), top,
    ])
    valve = gear.valve
    cup = np.array([gear.rocker_arm, 0.0])
    pad_c = valve.drive.arm * np.array([math.cos(valve.drive.angle), math.sin(valve.drive.angle)])
    half = 0.3 * gear.rocker_arm
    tip_dir = _turn(valve.axis[None, :], -gear.rest)[0]
    parts["rocker"] = trimesh.util.concatenate([
        _prism(_stadium(cup, (0.0, 0.0), half), w, frame), _prism(_stadium((0.0, 0.0), pad_c, half), w, frame),
        _prism(_sector(pad_c, valve.pad_radius, math.atan2(tip_dir[1], tip_dir[0]), 0.6), w, frame),
    ])
    stem = valve.tip_radius or 0.004
    parts["valve"] = _valve_mesh(valve.rest_contact(), valve.axis, stem, 0.14, frame)
    parts["cam_contact"] = _sphere(0.1 * ball)
    parts["tip_contact"] = _sphere(0.1 * ball)
    return Drawing(_colour(parts), frame)


def pushrod_poses(gear, theta, *, valve_lift=None, lash: float = 0.0, frame: float = 0.0) -> dict:
    theta = np.asarray(theta, dtype=float)
    k = gear.kinematics(theta)
    n = theta.size
    f = gear.lifter
    L = k.lifter_lift[0]
    y0 = gear.lifter.rest_height(gear.base_radius) - f.socket_height
    axis_point = np.column_stack([np.full(n, f.offset), y0 + L])
    rod = k.upper_ball - k.lower_ball
    rod_angle = np.arctan2(rod[:, 1], rod[:, 0])
    poses = {
        "cam": (_fixed(n, 0.0), quat_about_y(-theta)),
        "camshaft": (_fixed(n, 0.0), quat_about_y(-theta)),
        "lifter": (to_world(axis_point, frame), _ident(n)),
        "pushrod": (to_world(k.lower_ball, frame), quat_about_y(-(rod_angle - 0.5 * math.pi))),
        "rocker": (_fixed(n, to_world(np.asarray(gear.rocker_pivot)[None, :], frame)[0]), quat_about_y(-k.rocker_angle[0])),
        "valve": _valve_pose(n, gear.valve.axis, frame, _displayed(k.lift, lash, valve_lift) + lash),
        "cam_contact": (to_world(k.surface.contact, frame), _ident(n)),
        "tip_contact": (to_world(k.tip.point, frame), _ident(n)),
    }
    if f.kind == "roller":
        poses["roller"] = (to_world(axis_point, frame), quat_about_y(-_spin(theta, k.roller_rate)))
    return poses
