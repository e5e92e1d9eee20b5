"""The drawing of the translating roller follower (the stock gear): cam, camshaft, roller and its
follower, the follower's guide, a lever (rocker) about a fixed pivot with its adjusting screw, and
the valve group (explorer.view.drawing).

The gear is laid out like a push-rod gear of Schenker's time, in the x-z plane:

    camshaft along y at the origin; the cam turns counter-clockwise in the x-z plane
    (cam frame (x, y) of explorer.lift.contours.translating -> world (x, z));
    roller follower on the vertical axis x = offset, pushed up by the cam;
    a lever (rocker) about a fixed pivot: the follower lifts its left end at arm a, the right
    end (arm b = ratio * a) pushes the valve down through an adjusting screw with a ball end;
    the lash is the gap between that ball and the valve stem (the screw is set `lash` above the
    lever's line, so the valve and its seat stay where they are whatever the lash);
    the valve opens downwards, away from its seat, against a helical spring between a fixed
    spring seat and the retainer on the stem.

The lever angle is phi = asin(L / a), so the follower end rises by exactly L and the valve end
drops by exactly b sin(phi) = ratio * L: the lever reproduces the scene's constant ratio. The
adjusting screw slides in the lever to show the magnified gap (magnification m: m times the true
gap between screw ball and stem); cam, roller, follower and lever keep their true positions.
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np
import trimesh

from ..effects.contour import cam_contour as contour_envelope
from ..effects.lift import build_lift
from ..lift.contours.translating import profile_from_derivatives, translating_profile
from .base import GearView
from .drawing import (ROLLER_MARKS, SPRING_ACTIVE_COILS, SPRING_DEAD_COILS, Layout, _drop_duplicates, box, concat,
                      cylinder_y, cylinder_z, displayed_valve_lift, extrude_contour, loop_spin, quat_about_y,
                      signed_area, stadium_bar, tube_z, valve_group)
from .train_motion import TRAIN_MAGNIFICATION, train_shape

# Display colours (RGB 0-255) of its parts, shared by the viewers so parts look the same everywhere.
COLORS = MappingProxyType({
    "cam": (214, 126, 44),
    "camshaft": (120, 124, 132),
    "roller": (60, 130, 200),
    "follower": (150, 160, 175),
    "follower_guide": (95, 100, 110),
    "lever": (90, 170, 110),
    "lever_pivot": (95, 100, 110),
    "adjuster": (230, 200, 60),
    "valve": (200, 70, 70),
    "spring": (170, 120, 210),
    "seat": (110, 112, 120),
})


def _max_follower_lift(scene, result=None) -> float:
    if result is not None and "follower_lift_m" in result.columns:
        return max(float(np.max(result.columns["follower_lift_m"])), 0.0)
    return max(float(np.max(build_lift(scene).derivatives(np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False))[0])), 0.0)


def layout(scene, result=None) -> Layout:
    """Dimensions derived from the cam geometry (base circle, roller, offset, ratio, lift).

    Parts the scene does not dimension (lever, valve, spring) are proportioned from the cam and
    the lift so that the gear looks plausible at any scale: lever arms long enough for small
    angles, valve diameter about three times its lift, a spring that never goes solid. Speed,
    lash, masses and springs do not enter, so editing them never moves the seat or the frame;
    the lash is taken up by the adjusting screw, which stands `lash` above the lever's line."""
    f = scene.follower
    rb, rr, e, ratio = f.base_radius, f.roller_radius, f.offset, f.ratio
    h = _max_follower_lift(scene, result)
    s = ratio * h
    prime_y = math.sqrt((rb + rr) ** 2 - e * e)
    size = rb + rr  # the scale of the drawing
    cam_width = 0.45 * size
    roller_draw = rr if rr > 0.0 else 0.06 * rb
    arm_a = max(1.4 * (rb + rr + h), 3.2 * h, 1e-3)
    arm_b = ratio * arm_a
    lever_half = 0.12 * size
    ball = 1.6 * lever_half
    # lever high enough for the follower guide between roller and lever
    pivot_z = prime_y + roller_draw + h + 0.9 * size
    valve_x = e + arm_a + arm_b
    valve_radius = min(max(1.6 * s, 0.45 * size), 0.9 * size)
    stem_radius = max(0.16 * valve_radius, 0.03 * size)
    stem_top_rest = pivot_z - ball
    spring_mean = 0.72 * valve_radius
    wire = 0.1 * spring_mean
    solid = 2.0 * wire * (SPRING_ACTIVE_COILS + 2.0 * SPRING_DEAD_COILS + 1.0)
    # a spring that stays at least 25 % above solid at full lift (more if the motion overshoots)
    spring_rest = 1.25 * solid + 1.5 * s + 0.5 * stem_radius
    retainer_drop = 2.5 * stem_radius
    retainer_thickness = 0.6 * stem_radius + wire
    spring_seat_z = stem_top_rest - retainer_drop - retainer_thickness - spring_rest
    seat_z = spring_seat_z - 0.9 * valve_radius
    return Layout(
        base_radius=rb, roller_radius=rr, offset=e, prime_y=prime_y, ratio=ratio,
        max_follower_lift=h, valve_travel=s, cam_width=cam_width, roller_width=0.8 * cam_width,
        roller_draw_radius=roller_draw, shaft_radius=0.32 * rb, rod_radius=max(0.35 * roller_draw, 0.08 * size),
        arm_follower=arm_a, arm_valve=arm_b, lever_half_thickness=lever_half, pivot=(e + arm_a, 0.0, pivot_z),
        ball_radius=ball, valve_x=valve_x, stem_top_rest=stem_top_rest, stem_radius=stem_radius,
        valve_radius=valve_radius, seat_z=seat_z, retainer_drop=retainer_drop,
        retainer_thickness=retainer_thickness, spring_seat_z=spring_seat_z, spring_rest_length=spring_rest,
        spring_mean_radius=spring_mean, spring_wire_radius=wire,
    )


def cam_contour(scene, lift=None, n: int = 720) -> np.ndarray:
    """Cam surface (N, 2) in the cam frame, counter-clockwise, metres.

    For law cams the exact envelope of the roller (explorer.lift.contours.translating); for contour
    and arc cams the geometry package's own contour when it provides `cam_contour`, else the
    envelope of the roller over the lift derived from that contour (the same surface wherever
    the roller touches it). Samples include the lift curve's breakpoints, so corners between
    arcs and the ends of dwells are exact vertices."""
    lift = lift if lift is not None else build_lift(scene)
    xy = None
    if scene.cam is not None:  # a [cam] contour: the envelope over the lift derived from it
        xy = np.asarray(contour_envelope(scene, lift, n), dtype=float)
    else:
        theta = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
        theta = np.unique(np.concatenate([theta, np.mod(np.asarray(lift.breakpoints(), dtype=float), 2.0 * math.pi)]))
        f = scene.follower
        xy = translating_profile(lift, theta, f.base_radius, f.roller_radius, f.offset).contour
    xy = _drop_duplicates(xy)
    if signed_area(xy) < 0.0:
        xy = xy[::-1]
    return xy


def _roller_mesh(lay: Layout) -> trimesh.Trimesh:
    """Roller about the y axis with four bores, so that its spin is visible; local origin at its centre."""
    r, w = lay.roller_draw_radius, lay.roller_width
    if lay.roller_radius <= 0.0:
        return trimesh.creation.icosphere(subdivisions=2, radius=r)
    rim = cylinder_y(r, w, 64)
    hub = cylinder_y(0.28 * r, 1.15 * w, 24)
    marks = [
        cylinder_y(0.12 * r, 1.04 * w, 12, (0.62 * r * math.cos(a), 0.0, 0.62 * r * math.sin(a)))
        for a in (2.0 * math.pi / ROLLER_MARKS) * np.arange(ROLLER_MARKS)
    ]
    return concat([rim, hub, *marks])


def _follower_mesh(lay: Layout, rod: bool = True) -> trimesh.Trimesh:
    """Fork around the roller and the rod up to the lever (without it: the lifter of a train
    whose pushrod is a mass of its own, `_pushrod_mesh`); local origin at the roller centre."""
    r, w = lay.roller_draw_radius, lay.roller_width
    rod_top = lay.pivot[2] - lay.lever_half_thickness - lay.prime_y  # rod top at zero lift
    plate_t = 0.12 * w
    plate_h = 1.6 * r
    plates = [
        box([1.3 * r, plate_t, plate_h], [0.0, sgn * (0.5 * w + 0.6 * plate_t + 0.02 * w), 0.35 * plate_h])
        for sgn in (-1.0, 1.0)
    ]
    bridge = box([1.3 * r, w + 2.6 * plate_t, plate_t * 1.5], [0.0, 0.0, 0.35 * plate_h + 0.5 * plate_h])
    pin = cylinder_y(0.22 * r, w + 3.0 * plate_t, 16)
    if not rod:
        return concat([*plates, bridge, pin])
    return concat([*plates, bridge, _pushrod_mesh(lay), pin])


def _pushrod_mesh(lay: Layout) -> trimesh.Trimesh:
    """The follower's rod from its fork's bridge up to the lever; local origin at the roller
    centre (at zero lift), as the follower's."""
    r, w = lay.roller_draw_radius, lay.roller_width
    rod_top = lay.pivot[2] - lay.lever_half_thickness - lay.prime_y  # rod top at zero lift
    plate_t, plate_h = 0.12 * w, 1.6 * r
    return cylinder_z(lay.rod_radius, 0.35 * plate_h + 0.5 * plate_h, rod_top, 32)


# The lash adjuster of a train with [hla], drawn over the lever's pivot: a body, and a plunger
# coming out of it towards the pivot (extending: down). The drawing is the scene's ratio, not the
# finger's geometry, and the finger's own travel (its column) already holds what the adjuster adds
# to the valve's lift (train.py: the cam joint's -g p): so the lever turns about its fixed pivot
# by its own travel, and the plunger shows the adjuster's travel in its body. At rest it hangs
# above the pivot by what the revolution's largest extension comes to at the default
# magnification, so that at x20 the pumped-up plunger just reaches the pivot (hla_clearance).
# Sizes in the lever's half-thickness; both meshes in their own frame, origin at the plunger's
# end at rest (so a new result moves them without new meshes).
HLA_PLUNGER_RADIUS, HLA_PLUNGER_LENGTH = 1.1, 3.5
HLA_BODY_RADII, HLA_BODY_SPAN = (1.2, 1.7), (1.0, 5.5)  # the bore and the outside; bottom and top above the plunger's end


def hla_clearance(lay: Layout, result) -> float:
    """Height of the plunger's end at rest above the pivot's shaft (see above)."""
    half = lay.lever_half_thickness
    p = None if result is None else result.columns.get("hla_plunger_travel_m")
    extension = 0.0 if p is None else max(0.0, -float(np.min(p)))
    return 0.7 * half + 0.3 * half + TRAIN_MAGNIFICATION * extension


def _hla_plunger_mesh(lay: Layout) -> trimesh.Trimesh:
    half = lay.lever_half_thickness
    return concat([cylinder_z(HLA_PLUNGER_RADIUS * half, 0.0, HLA_PLUNGER_LENGTH * half, 32),
                   trimesh.creation.icosphere(subdivisions=2, radius=0.6 * half)])


def _hla_body_mesh(lay: Layout) -> trimesh.Trimesh:
    """A bore the plunger slides in, closed on top."""
    half = lay.lever_half_thickness
    (r_in, r_out), (z0, z1) = HLA_BODY_RADII, HLA_BODY_SPAN
    return concat([tube_z(r_in * half, r_out * half, z0 * half, z1 * half, 32),
                   cylinder_z(r_out * half, z1 * half, (z1 + 0.5) * half, 32)])


def _follower_guide_mesh(lay: Layout) -> trimesh.Trimesh:
    r = lay.roller_draw_radius
    z_low = lay.prime_y + lay.max_follower_lift + 1.9 * r + 0.05 * lay.base_radius
    z_high = lay.pivot[2] - lay.lever_half_thickness - 0.25 * (lay.base_radius + lay.roller_radius)
    z_high = max(z_high, z_low + 0.1 * lay.base_radius)
    return tube_z(1.15 * lay.rod_radius, 1.9 * lay.rod_radius, z_low, z_high, 32, lay.offset)


def _lever_mesh(lay: Layout) -> trimesh.Trimesh:
    """Lever in its own frame: pivot at the origin, follower pad at x = -a, valve end at x = +b."""
    half, w = lay.lever_half_thickness, 0.7 * lay.cam_width
    bar = stadium_bar(-lay.arm_follower, lay.arm_valve, half, w)
    boss = cylinder_y(1.5 * half, 1.2 * w, 32)
    end_boss = cylinder_z(1.25 * lay.ball_radius * 0.6, -half, 1.4 * half, 24, lay.arm_valve)
    return concat([bar, boss, end_boss])


def _adjuster_mesh(lay: Layout) -> trimesh.Trimesh:
    """Adjusting screw with a ball end; local origin at the ball centre."""
    rb = lay.ball_radius
    ball = trimesh.creation.icosphere(subdivisions=3, radius=rb)
    stud = cylinder_z(0.45 * rb, 0.0, 2.6 * rb, 20)
    nut = cylinder_z(0.8 * rb, 1.7 * rb, 2.3 * rb, 6)
    return concat([ball, stud, nut])


def _pivot_mesh(lay: Layout) -> trimesh.Trimesh:
    half = lay.lever_half_thickness
    w = 0.7 * lay.cam_width
    px, _, pz = lay.pivot
    shaft = cylinder_y(0.7 * half, 2.2 * w, 24, (px, 0.0, pz))
    posts = [box([1.6 * half, 0.25 * w, 1.2 * half], [px, sgn * 0.95 * w, pz]) for sgn in (-1.0, 1.0)]
    return concat([shaft, *posts])


def _camshaft_mesh(lay: Layout) -> trimesh.Trimesh:
    shaft = cylinder_y(lay.shaft_radius, 3.2 * lay.cam_width, 40)
    key = box([0.5 * lay.shaft_radius, 3.2 * lay.cam_width, 0.4 * lay.shaft_radius],
               [0.0, 0.0, lay.shaft_radius])  # key: makes the shaft's turning visible
    return concat([shaft, key])


def parts(scene, result=None, lay: Layout | None = None, lift=None, contour_samples: int = 720,
                only: tuple[str, ...] | None = None) -> dict[str, trimesh.Trimesh]:
    """Every part's mesh in its local frame (see `poses` for where each frame sits);
    `only` limits it to some parts (a viewer whose layout did not change rebuilds just the cam).

    cam and camshaft: origin on the shaft axis; roller and follower: origin at the roller centre;
    lever: origin at the pivot; adjuster: ball centre; valve: stem top; spring: its bottom
    (at rest length); static parts (follower_guide, lever_pivot, seat): world frame."""
    lay = lay or layout(scene, result)
    elements, hla = train_shape(scene)
    builders = {
        "cam": lambda: extrude_contour(cam_contour(scene, lift, contour_samples), lay.cam_width),
        "camshaft": lambda: _camshaft_mesh(lay),
        "roller": lambda: _roller_mesh(lay),
        "follower": lambda: _follower_mesh(lay, rod=not elements),
        "follower_guide": lambda: _follower_guide_mesh(lay),
        "lever": lambda: _lever_mesh(lay),
        "lever_pivot": lambda: _pivot_mesh(lay),
        "adjuster": lambda: _adjuster_mesh(lay),
    }
    if elements:  # a train of masses: the rod is the pushrod, moving with its own mass
        builders["pushrod"] = lambda: _pushrod_mesh(lay)
    if hla:  # the adjuster over the pivot
        builders.update(hla_body=lambda: _hla_body_mesh(lay), hla_plunger=lambda: _hla_plunger_mesh(lay))
    parts = {name: build() for name, build in builders.items() if only is None or name in only}
    parts.update(valve_group(lay, only))
    return parts


def roller_spin(scene, lift, theta: np.ndarray) -> np.ndarray:
    """Roller angle (rad, counter-clockwise in the cam plane) for rolling without slip on the cam,
    zero at theta[0]. Pure rolling: the roller's surface speed at the contact equals the cam's,
    omega_r rr = (omega x p - v_f) . t, integrated over the (uniform or not) samples.

    Over a revolution the roller turns by perimeter / rr, in general not a whole number of turns:
    `poses` draws it with `loop_spin` so that a looped animation does not jump at 360 -> 0."""
    rr = scene.follower.roller_radius
    if rr <= 0.0:
        return np.zeros_like(theta)
    f = scene.follower
    d = lift.derivatives(theta)
    prof = profile_from_derivatives(theta, d, f.base_radius, rr, f.offset)
    p = prof.contact_local
    centre = np.column_stack([np.full(len(theta), f.offset), math.sqrt((f.base_radius + rr) ** 2 - f.offset**2) + d[0]])
    nrm = (p - centre) / rr
    tangent = np.column_stack([-nrm[:, 1], nrm[:, 0]])
    cam_velocity = np.column_stack([-p[:, 1], p[:, 0]])  # omega x p per unit omega
    follower_velocity = np.column_stack([np.zeros(len(theta)), d[1]])
    rate = np.sum((cam_velocity - follower_velocity) * tangent, axis=1) / rr  # d(beta)/d(theta)
    steps = np.diff(theta)
    return np.concatenate([[0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1]) * steps)])


def poses(scene, result, magnification: float = 1.0, lay: Layout | None = None, lift=None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """One world pose per step of `result.columns` for every part: name -> (positions (N, 3),
    wxyz (N, 4)). The spring's pose is fixed; its shape follows `spring_length(lay,
    displayed_valve_lift(result, magnification))`."""
    lay = lay or layout(scene, result)
    cols = result.columns
    theta = np.radians(np.asarray(cols["cam_angle_deg"], dtype=float))
    n = theta.size
    L = np.asarray(cols["follower_lift_m"], dtype=float)
    s_true = np.asarray(cols["valve_lift_m"], dtype=float)
    s_disp = displayed_valve_lift(result, magnification)
    ident = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))

    def fixed(x, y, z):
        return np.tile([x, y, z], (n, 1)).astype(float)

    # cam frame (x, y) -> world (x, z); a counter-clockwise turn by theta there is a rotation by
    # -theta about +y in the world
    cam_q = quat_about_y(-theta)
    roller_pos = np.column_stack([np.full(n, lay.offset), np.zeros(n), lay.prime_y + L])
    lift = lift if lift is not None else build_lift(scene)
    # the revolution's last step back to 2 pi too: the spin over the whole revolution
    spin = roller_spin(scene, lift, np.append(theta, theta[0] + 2.0 * math.pi))
    spin = loop_spin(spin[:-1], spin[-1])
    phi = np.arcsin(np.clip(L / lay.arm_follower, -1.0, 1.0))
    px, py, pz = lay.pivot
    stem_top = lay.stem_top_rest - s_disp
    # true gap between screw ball and stem top (negative: linkage compressed)
    gap = (scene.valve.lash if scene.valve is not None else 0.0) + s_true - lay.ratio * L
    ball_bottom = stem_top + magnification * gap
    ball_x = px + lay.arm_valve * np.cos(phi)
    poses = {
        "cam": (fixed(0.0, 0.0, 0.0), cam_q),
        "camshaft": (fixed(0.0, 0.0, 0.0), cam_q),
        "roller": (roller_pos, quat_about_y(-spin)),
        "follower": (roller_pos.copy(), ident.copy()),
        "follower_guide": (fixed(0.0, 0.0, 0.0), ident.copy()),
        "lever": (fixed(px, py, pz), quat_about_y(phi)),
        "lever_pivot": (fixed(0.0, 0.0, 0.0), ident.copy()),
        "adjuster": (np.column_stack([ball_x, np.zeros(n), ball_bottom + lay.ball_radius]), quat_about_y(phi)),
        "valve": (np.column_stack([np.full(n, lay.valve_x), np.zeros(n), stem_top]), ident.copy()),
        "spring": (fixed(lay.valve_x, 0.0, lay.spring_seat_z), ident.copy()),
        "seat": (fixed(0.0, 0.0, 0.0), ident.copy()),
    }
    elements, hla = train_shape(scene)
    if elements:  # the rod drawn as a part of its own (train_poses moves it with its mass)
        poses["pushrod"] = (roller_pos.copy(), ident.copy())
    if hla:  # rigid: the plunger at rest in its body
        rest = fixed(px, py, pz + hla_clearance(lay, result))
        poses.update(hla_body=(rest, ident.copy()), hla_plunger=(rest.copy(), ident.copy()))
    return poses


# The train's masses on the drawing, cam first (explorer.view.train_motion): the follower with its
# roller (a lifter, or a finger's roller), the rod (a pushrod), the lever with its screw.
STATIONS = (("roller", "follower"), ("pushrod",), ("lever", "adjuster"))


def train_poses(scene, result, motion, rigid, lay: Layout | None = None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The poses of the train's masses (explorer.view.train_motion.TrainMotion over STATIONS):
    roller and follower, and the rod, rise by their displayed travel / ratio (the drawing's
    follower lift); the lever turns so that its follower end is at its own displayed travel; the
    screw shows the pad's true gap to the stem, magnified, as for the rigid drawing; the
    adjuster's plunger moves by its displayed travel (into its body: up)."""
    lay = lay or layout(scene, result)
    cols = result.columns
    m = motion.magnification
    n = len(motion.drive)
    lift_f, lift_rod, lift_lever = (np.asarray(d, dtype=float) / lay.ratio for d in motion.displayed)
    ident = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    out = {}
    for name, lift_at in (("roller", lift_f), ("follower", lift_f), ("pushrod", lift_rod)):
        pos = np.column_stack([np.full(n, lay.offset), np.zeros(n), lay.prime_y + lift_at])
        out[name] = (pos, rigid[name][1] if name in rigid else ident.copy())
    px, py, pz = lay.pivot
    phi = np.arcsin(np.clip(lift_lever / lay.arm_follower, -1.0, 1.0))
    pivot = np.column_stack([np.full(n, px), np.full(n, py), np.full(n, pz)])
    out["lever"] = (pivot, quat_about_y(phi))
    if motion.plunger is not None and "hla_plunger" in rigid:
        pos, q = rigid["hla_plunger"]
        out["hla_plunger"] = (pos + np.column_stack([np.zeros(n), np.zeros(n), motion.plunger]), q)
    s_true = np.asarray(cols["valve_lift_m"], dtype=float)
    stem_top = lay.stem_top_rest - displayed_valve_lift(result, m)
    gap = (scene.valve.lash if scene.valve is not None else 0.0) + s_true - motion.travel[-1]
    ball_x = pivot[:, 0] + lay.arm_valve * np.cos(phi)
    out["adjuster"] = (np.column_stack([ball_x, np.zeros(n), stem_top + m * gap + lay.ball_radius]), quat_about_y(phi))
    return out


class TranslatingRollerView(GearView):
    colors = COLORS

    def train_stations(self, scene):
        return STATIONS

    def train_poses(self, scene, result, motion, rigid, lay=None, lift=None):
        return train_poses(scene, result, motion, rigid, lay)

    def layout(self, scene, result=None, lift=None) -> Layout:
        return layout(scene, result)

    def parts(self, scene, result=None, lay=None, lift=None, contour_samples: int = 720, only=None):
        return parts(scene, result, lay=lay, lift=lift, contour_samples=contour_samples, only=only)

    def poses(self, scene, result, magnification: float = 1.0, lay=None, lift=None):
        return poses(scene, result, magnification=magnification, lay=lay, lift=lift)


VIEW = TranslatingRollerView()
