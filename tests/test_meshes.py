"""3D parts and poses (explorer.view.parts) against geometry that does not come from the mesh code:
Steiner's formula for the cam area, rolling contact distances, the lever's exact ratio, the
coin-rotation rule for the roller spin, and the spring's length bookkeeping."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explorer import load_scene
from explorer.view import parts as meshes
from explorer.view import drawing
from explorer.view import translating_roller as stock
from explorer.effects.pipeline import simulate
from explorer.lift.contours.translating import translating_profile
from explorer.effects.lift import build_lift
from explorer.result import Result

from conftest import SCENES

DEMO = SCENES / "cycloidal_demo.toml"


def _scene(*overrides):
    # the demo's rigid motion (it opens with forces and the elastic linkage too, #28.10)
    return load_scene(DEMO, ['effects=["kinematics", "lash"]', *overrides])


@pytest.fixture(scope="module")
def demo():
    scene = _scene()
    return scene, simulate(scene)


@pytest.fixture(scope="module")
def offset_lever():
    # offset follower, lever ratio 1.5, different return law: nothing symmetric to hide errors
    scene = _scene("follower.offset=\"6 mm\"", "follower.ratio=1.5", "lift.return_law=\"polynomial-345\"",
                   "solver.steps_per_revolution=720")
    return scene, simulate(scene)


def _rotate(q, v):
    """Rotate vectors v (M, 3) by unit quaternion q = (w, x, y, z)."""
    w, x, y, z = q
    r = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])
    return np.asarray(v) @ r.T


def _polygon_area_perimeter(xy):
    x, y = xy[:, 0], xy[:, 1]
    area = 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    return area, float(np.sum(np.linalg.norm(np.roll(xy, -1, axis=0) - xy, axis=1)))


def test_cam_disc_volume_follows_steiners_formula(demo):
    # The contour is the inner parallel curve of the pitch curve at distance rr, so for a convex
    # cam area(contour) = area(pitch) - rr * perimeter(pitch) + pi rr^2 (Steiner). Polygons of
    # 20000 points make the pitch-side figures exact to ~1e-8; the mesh uses 720 points, whose
    # chord error on the area is ~ (2 pi / 720)^2 / 12 ~ 6e-6 relative: tolerance 1e-4.
    scene, result = demo
    lay = meshes.layout(scene, result)
    lift = build_lift(scene)
    f = scene.follower
    prof = translating_profile(lift, np.linspace(0, 2 * np.pi, 20000, endpoint=False), f.base_radius, f.roller_radius)
    assert np.all(prof.pitch_radius > f.roller_radius)  # convex, no undercut: Steiner applies
    area_p, perim_p = _polygon_area_perimeter(prof.pitch)
    expected = lay.cam_width * (area_p - f.roller_radius * perim_p + math.pi * f.roller_radius**2)
    cam = meshes.build_parts(scene, result)["cam"].copy()
    cam.merge_vertices()
    assert cam.is_watertight and cam.is_winding_consistent
    assert cam.volume == pytest.approx(expected, rel=1e-4)


def test_contour_is_counter_clockwise_and_contains_breakpoints(offset_lever):
    scene, _ = offset_lever
    lift = build_lift(scene)
    xy = stock.cam_contour(scene, lift, 360)
    assert drawing.signed_area(xy) > 0.0
    f = scene.follower
    corners = translating_profile(lift, lift.breakpoints(), f.base_radius, f.roller_radius, f.offset).contour
    for point in corners:
        assert np.min(np.linalg.norm(xy - point, axis=1)) < 1e-12


@pytest.mark.parametrize("case", ["demo", "offset_lever"])
def test_roller_rolls_on_the_turning_cam_without_gap_or_penetration(case, request):
    # Independent of the pose code: the cam mesh rotated by the cam's pose and the roller centre
    # placed by the roller's pose must be exactly one roller radius apart at every step. The
    # polygon's chord sagitta (< R (2 pi/720)^2 / 8 ~ 4e-7 m) bounds the error: tolerance 2e-6 m.
    scene, result = request.getfixturevalue(case)
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    poses = meshes.part_poses(scene, result, lay=lay)
    cam_vertices = parts["cam"].vertices
    rim = cam_vertices[np.abs(cam_vertices[:, 1] + 0.5 * lay.cam_width) < 1e-12]  # one cap's ring
    rr = scene.follower.roller_radius
    n = len(result.columns["cam_angle_deg"])
    for i in np.linspace(0, n - 1, 37).astype(int):
        world = _rotate(poses["cam"][1][i], rim) + poses["cam"][0][i]
        centre = poses["roller"][0][i]
        dist = np.hypot(world[:, 0] - centre[0], world[:, 2] - centre[2])
        # distance to the polygon (segments), not only to its vertices
        a, b = world[:, [0, 2]], np.roll(world[:, [0, 2]], -1, axis=0)
        ab = b - a
        t = np.clip(np.sum((centre[[0, 2]] - a) * ab, axis=1) / np.sum(ab * ab, axis=1), 0.0, 1.0)
        seg = np.linalg.norm(a + t[:, None] * ab - centre[[0, 2]], axis=1)
        assert seg.min() == pytest.approx(rr, abs=2e-6), (case, i)
        assert dist.min() >= rr - 2e-6


def test_lever_reproduces_the_ratio_and_touches_the_follower(offset_lever):
    scene, result = offset_lever
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    poses = meshes.part_poses(scene, result, lay=lay)
    L = result.columns["follower_lift_m"]
    rod_top_local = parts["follower"].vertices[:, 2].max()
    for i in range(0, len(L), 7):
        q, p = poses["lever"][1][i], poses["lever"][0][i]
        pad = _rotate(q, [[-lay.arm_follower, 0.0, 0.0]])[0] + p
        tip = _rotate(q, [[lay.arm_valve, 0.0, 0.0]])[0] + p
        # follower rod top touches the round pad (radius = lever half thickness) from below
        assert pad[2] - lay.lever_half_thickness == pytest.approx(poses["follower"][0][i][2] + rod_top_local, abs=1e-12)
        # the valve end drops by exactly ratio * L
        assert lay.pivot[2] - tip[2] == pytest.approx(scene.follower.ratio * L[i], abs=1e-12)
        # the screw ball sits on the lever tip, set back by the lash (magnification 1)
        np.testing.assert_allclose(poses["adjuster"][0][i], tip + [0.0, 0.0, scene.valve.lash], atol=1e-12)


def test_ball_meets_stem_when_open_and_leaves_the_lash_when_closed(demo):
    scene, result = demo
    lay = meshes.layout(scene, result)
    poses = meshes.part_poses(scene, result, lay=lay)
    s = result.columns["valve_lift_m"]
    L = result.columns["follower_lift_m"]
    ball_bottom = poses["adjuster"][0][:, 2] - lay.ball_radius
    stem_top = poses["valve"][0][:, 2]
    gap = ball_bottom - stem_top
    open_ = s > 0
    np.testing.assert_allclose(gap[open_], 0.0, atol=1e-12)
    np.testing.assert_allclose(gap[~open_], scene.valve.lash - L[~open_], atol=1e-12)
    np.testing.assert_allclose(lay.stem_top_rest - stem_top, s, atol=1e-15)


def test_closed_valve_head_touches_the_seat_ring(demo):
    scene, result = demo
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    valve = parts["valve"].vertices + [lay.valve_x, 0.0, lay.stem_top_rest]
    seat = parts["seat"].vertices
    # the seat ring's lowest inner edge lies on the valve's 45-degree face (line contact)
    ring = seat[np.hypot(seat[:, 0] - lay.valve_x, seat[:, 1]) < lay.valve_radius * 0.9]
    ring = ring[ring[:, 2] < lay.seat_z]
    r_edge = np.hypot(ring[:, 0] - lay.valve_x, ring[:, 1])
    face = 0.25 * lay.valve_radius
    z_face = lay.seat_z - (r_edge - (lay.valve_radius - face))
    np.testing.assert_allclose(ring[:, 2], z_face, atol=1e-12)
    assert valve[:, 2].max() == pytest.approx(lay.stem_top_rest)


def test_roller_spin_rolls_without_slip():
    scene = _scene("solver.steps_per_revolution=20000")
    lift = build_lift(scene)
    theta = np.linspace(0.0, 2 * np.pi, 20001)
    spin = stock.roller_spin(scene, lift, theta)
    f = scene.follower
    # on the base circle (before the rise at 20 deg) the roller turns back at Rb / rr per radian
    base = theta < math.radians(19.0)
    np.testing.assert_allclose(np.gradient(spin[base], theta[base]), -f.base_radius / f.roller_radius, rtol=1e-9)
    # coin rotation: over one revolution the roller turns by -perimeter(contour) / rr in the
    # ground frame (the follower does not turn). Trapezoid rule error ~ 1e-8 at 20000 steps.
    contour = translating_profile(lift, theta[:-1], f.base_radius, f.roller_radius).contour
    _, perimeter = _polygon_area_perimeter(contour)
    assert spin[-1] == pytest.approx(-perimeter / f.roller_radius, rel=1e-6)


def test_spring_follows_the_retainer_and_never_goes_solid(offset_lever):
    scene, result = offset_lever
    lay = meshes.layout(scene, result)
    poses = meshes.part_poses(scene, result, lay=lay)
    s = meshes.displayed_valve_lift(result)
    lengths = meshes.spring_length(lay, s)
    retainer_bottom = poses["valve"][0][:, 2] - lay.retainer_drop - lay.retainer_thickness
    np.testing.assert_allclose(poses["spring"][0][:, 2] + lengths, retainer_bottom, atol=1e-12)
    assert lengths.min() > 1.2 * lay.spring_solid_length
    faces = meshes.spring_faces(lay)
    batch = meshes.spring_vertices(lay, lengths[[0, len(lengths) // 3]])
    for k, length in enumerate(lengths[[0, len(lengths) // 3]]):
        single = meshes.spring_vertices(lay, length)
        np.testing.assert_array_equal(batch[k], single)
        # the wire's outside spans exactly the spring length (bottom and top coils ground flat
        # at z = 0 and z = L to within the tube's polygon, 1 % of the wire radius)
        assert single[:, 2].min() == pytest.approx(0.0, abs=0.02 * lay.spring_wire_radius)
        assert single[:, 2].max() == pytest.approx(length, abs=0.02 * lay.spring_wire_radius)
    import trimesh

    mesh = trimesh.Trimesh(meshes.spring_vertices(lay, lengths.min()), faces, process=False)
    assert mesh.is_watertight and mesh.volume > 0.0
    # wire volume: centre-line length times the wire section (Pappus); the section is a regular
    # k-gon inscribed in the wire circle, area (k/2) sin(2 pi/k) rw^2; the centre line's chords
    # and the frame's twist leave < 1 %
    centre_length = sum(
        math.hypot(2 * math.pi * lay.spring_mean_radius, pitch) * turns
        for pitch, turns in ((2 * lay.spring_wire_radius, 2 * meshes.SPRING_DEAD_COILS),
                             ((lengths.min() - 2 * lay.spring_wire_radius - 4 * lay.spring_wire_radius * meshes.SPRING_DEAD_COILS)
                              / meshes.SPRING_ACTIVE_COILS, meshes.SPRING_ACTIVE_COILS))
    )
    k = meshes.SPRING_WIRE_SEGMENTS
    section = 0.5 * k * math.sin(2 * math.pi / k) * lay.spring_wire_radius**2
    assert mesh.volume == pytest.approx(centre_length * section, rel=0.01)
    scale = meshes.spring_axial_scale(scene, result, lay=lay)
    np.testing.assert_allclose(scale * lay.spring_rest_length, lengths)


def test_magnification_scales_deviation_and_gap_only():
    # A synthetic "elastic" result: the valve flies 0.1 mm ahead of the rigid motion in mid-lift
    # and bounces 0.05 mm off its seat after closing.
    scene = _scene("solver.steps_per_revolution=360")
    base = simulate(scene)
    cols = dict(base.columns)
    rigid = cols["rigid_valve_lift_m"]
    dev = np.zeros_like(rigid)
    dev[(rigid > 0.004)] = 1e-4
    closed_after = np.arange(rigid.size) > np.nonzero(rigid > 0)[0].max() + 3
    dev[closed_after & (np.arange(rigid.size) < np.nonzero(rigid > 0)[0].max() + 8)] = 5e-5
    cols["valve_lift_m"] = rigid + dev
    result = Result.build(scene, cols, dict(base.summary))
    lay = meshes.layout(scene, result)
    m = 10.0
    poses = meshes.part_poses(scene, result, magnification=m, lay=lay)
    shown = lay.stem_top_rest - poses["valve"][0][:, 2]
    np.testing.assert_allclose(shown, rigid + m * dev, atol=1e-15)
    ball_gap = poses["adjuster"][0][:, 2] - lay.ball_radius - poses["valve"][0][:, 2]
    true_gap = scene.valve.lash + cols["valve_lift_m"] - cols["follower_lift_m"]
    np.testing.assert_allclose(ball_gap, m * true_gap, atol=1e-12)
    # cam, roller, follower and lever are untouched by the magnification
    plain = meshes.part_poses(scene, result, magnification=1.0, lay=lay)
    for name in ("cam", "roller", "follower", "lever", "spring", "seat"):
        np.testing.assert_array_equal(plain[name][0], poses[name][0])
        np.testing.assert_array_equal(plain[name][1], poses[name][1])
    # never below the seat, whatever the magnification
    assert meshes.displayed_valve_lift(Result.build(scene, {**cols, "valve_lift_m": rigid - 1e-4}, {}), 50.0).min() == 0.0


def test_layout_depends_on_the_cam_only_not_on_speed_or_lash():
    scene = _scene()
    other = _scene("drive.rpm=700", "valve.lash=\"0.9 mm\"", "spring.rate=\"40 N/mm\"")
    assert meshes.layout(scene, simulate(scene)) == meshes.layout(other, simulate(other)) == meshes.layout(scene)
    assert meshes.layout(_scene("lift.height=\"12 mm\"")) != meshes.layout(scene)


def test_every_part_exists_with_a_pose_per_step_and_unit_quaternions(offset_lever):
    scene, result = offset_lever
    parts = meshes.build_parts(scene, result)
    poses = meshes.part_poses(scene, result)
    n = len(result.columns["cam_angle_deg"])
    assert set(parts) == set(poses) == set(meshes.PART_COLORS)
    for name, (pos, quat) in poses.items():
        assert pos.shape == (n, 3) and quat.shape == (n, 4)
        np.testing.assert_allclose(np.linalg.norm(quat, axis=1), 1.0, rtol=1e-12)
        assert np.all(np.isfinite(parts[name].vertices)) and len(parts[name].faces) > 0
    for name in meshes.STATIC_PARTS:
        assert np.ptp(poses[name][0], axis=0).max() == 0.0


# ---------------------------------------------------------------------------------------------
# Framing: the box over a revolution and the camera that sees it

FRAMED = ["cycloidal_demo", "schenker1902_fig2", "pivoted_roller_lever", "rocking_cam", "rolling_lever",
          "trip_gear_dashpot"]


def _posed(name):
    """Parts, poses and the spring's drawn lengths of a scene at 360 steps (kinematics and lash:
    the framing depends on the drawn motion, not on which effects made it)."""
    scene = load_scene(SCENES / f"{name}.toml", ["solver.steps_per_revolution=360", 'effects=["kinematics", "lash"]'])
    result = simulate(scene)
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    poses = meshes.part_poses(scene, result, magnification=1.0, lay=lay)
    lengths = meshes.spring_length(lay, meshes.displayed_valve_lift(result, 1.0))
    return lay, parts, poses, lengths


def _world_vertices(parts, poses, lay, lengths, i):
    """Every vertex as drawn at step i, posed with trimesh's own quaternion matrix (not the
    code under test); the spring at that step's length, as the viewer redraws it."""
    import trimesh

    out = []
    for name, mesh in parts.items():
        position, wxyz = poses[name][0][i], poses[name][1][i]
        v = meshes.spring_vertices(lay, lengths[i]) if name == "spring" else np.asarray(mesh.vertices)
        transform = trimesh.transformations.quaternion_matrix(wxyz)
        transform[:3, 3] = position
        out.append(trimesh.transform_points(v, transform))
    return np.vstack(out)


@pytest.mark.parametrize("name", FRAMED)
def test_motion_bounds_is_the_union_of_every_part_at_every_step(name):
    """The box holds every vertex of every part at every step of the revolution (the spring at
    its drawn length), and is no larger: brute force over all 360 steps reaches each of its six
    faces (1e-9 m: rounding of the two ways of rotating). At step 0 alone the box is smaller
    for the gears whose parts swing out (the latch slides aside, levers swing)."""
    lay, parts, poses, lengths = _posed(name)
    lo, hi = meshes.motion_bounds(parts, poses)
    seen_lo, seen_hi = np.full(3, np.inf), np.full(3, -np.inf)
    for i in range(len(lengths)):
        v = _world_vertices(parts, poses, lay, lengths, i)
        assert np.all(v >= lo - 1e-12) and np.all(v <= hi + 1e-12), i
        seen_lo, seen_hi = np.minimum(seen_lo, v.min(axis=0)), np.maximum(seen_hi, v.max(axis=0))
    np.testing.assert_allclose(seen_lo, lo, atol=1e-9)
    np.testing.assert_allclose(seen_hi, hi, atol=1e-9)
    first = _world_vertices(parts, poses, lay, lengths, 0)
    assert np.all(first.min(axis=0) >= lo - 1e-12) and np.all(first.max(axis=0) <= hi + 1e-12)
    if name in ("trip_gear_dashpot", "rocking_cam"):
        assert np.any(first.min(axis=0) > lo + 1e-4) or np.any(first.max(axis=0) < hi - 1e-4)


def test_motion_bounds_takes_meshes_vertex_pairs_and_unposed_parts():
    """The viewer hands (vertices, faces) pairs; a part without a pose is in the world frame."""
    lay, parts, poses, lengths = _posed("cycloidal_demo")
    pairs = {name: (np.asarray(m.vertices, dtype=np.float32), np.asarray(m.faces)) for name, m in parts.items()}
    lo, hi = meshes.motion_bounds(parts, poses)
    lo32, hi32 = meshes.motion_bounds(pairs, poses)
    np.testing.assert_allclose(lo32, lo, atol=1e-6)  # float32 vertices: 1e-7 relative of ~0.2 m
    np.testing.assert_allclose(hi32, hi, atol=1e-6)
    marker = np.array([[5.0, -1.0, 2.0]])
    lo2, hi2 = meshes.motion_bounds({**parts, "marker": marker}, poses)
    np.testing.assert_array_equal(hi2, np.maximum(hi, marker[0]))
    np.testing.assert_array_equal(lo2, np.minimum(lo, marker[0]))


def _project(points, frame):
    """Picture coordinates (x / depth, y / depth) and depths of world points, from a look-at
    basis built here (right = forward x up, as three.js and rerun do)."""
    position, target, up = (np.asarray(a, dtype=float) for a in (frame.position, frame.look_at, frame.up))
    forward = (target - position) / np.linalg.norm(target - position)
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    upward = np.cross(right, forward)
    rel = np.asarray(points, dtype=float) - position
    depth = rel @ forward
    return (rel @ right) / depth, (rel @ upward) / depth, depth


def _corners(lo, hi):
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


@pytest.mark.parametrize("seed", range(12))
def test_frame_bounds_sees_every_corner_and_comes_as_near_as_it_can(seed):
    """Random boxes (flat, long, tiny, far from the origin), lenses and picture shapes: every
    corner is in front of the camera and inside the picture with the margin to spare, the
    tightest corner exactly at the margin (the nearest such camera along that direction), and
    the picture balanced: the projected box's middle at the centre (to 1e-9 of its extent: the
    sideways placement is a root found by bisection to rounding)."""
    rng = np.random.default_rng(seed)
    size = 10.0 ** rng.uniform(-3, 0, 3) * rng.uniform(0.05, 1.0, 3)
    lo = rng.uniform(-2.0, 2.0, 3)
    hi = lo + size
    fov = math.radians(rng.uniform(25.0, 80.0))
    aspect = rng.uniform(0.3, 2.2)
    direction = np.array([rng.uniform(-0.6, 0.6), -1.0, rng.uniform(-0.5, 0.8)])
    margin = rng.uniform(0.0, 0.15)
    frame = meshes.frame_bounds(lo, hi, fov=fov, aspect=aspect, direction=direction, margin=margin)
    x, y, depth = _project(_corners(lo, hi), frame)
    tan_v, tan_h = math.tan(0.5 * fov), math.tan(0.5 * fov) * aspect
    assert np.all(depth > 0.0)
    assert np.all(np.abs(x) <= tan_h * (1.0 - margin) * (1 + 1e-9))
    assert np.all(np.abs(y) <= tan_v * (1.0 - margin) * (1 + 1e-9))
    assert max(np.abs(x).max() / tan_h, np.abs(y).max() / tan_v) == pytest.approx(1.0 - margin, rel=1e-9)
    # it looks along -direction, with the world's up kept up
    view = np.subtract(frame.position, frame.look_at)
    assert np.cross(view, direction) == pytest.approx(np.zeros(3), abs=1e-9 * np.linalg.norm(view) * np.linalg.norm(direction))
    assert np.dot(view, direction) > 0.0
    assert (frame.fov, frame.aspect) == (fov, aspect)
    assert abs(x.max() + x.min()) <= 1e-9 * (x.max() - x.min())
    assert abs(y.max() + y.min()) <= 1e-9 * (y.max() - y.min())


@pytest.mark.parametrize("name", ["rocking_cam", "trip_gear_dashpot"])
def test_the_framed_camera_sees_every_vertex_of_the_revolution(name):
    """The viewer's camera for the gears that came out badly framed (the dashpot cut off, the
    valve group small): at the viewer's lens and a canvas taller than wide, every posed vertex
    of a sample of steps is in the picture (a convex frustum holding the box's corners holds
    the box), and the gear fills it: its silhouette spans at least 60 % of the picture's width
    or height."""
    from explorer.view.browser.camera import ASSUMED_ASPECT, CAMERA_FOV

    lay, parts, poses, lengths = _posed(name)
    lo, hi = meshes.motion_bounds(parts, poses)
    frame = meshes.frame_bounds(lo, hi, fov=CAMERA_FOV, aspect=ASSUMED_ASPECT)
    tan_v = math.tan(0.5 * CAMERA_FOV)
    tan_h = tan_v * ASSUMED_ASPECT
    xs, ys = [], []
    for i in range(0, len(lengths), 9):
        x, y, depth = _project(_world_vertices(parts, poses, lay, lengths, i), frame)
        assert np.all(depth > 0.0) and np.all(np.abs(x) <= tan_h) and np.all(np.abs(y) <= tan_v), i
        xs += [x.min(), x.max()]
        ys += [y.min(), y.max()]
    assert max((max(xs) - min(xs)) / (2 * tan_h), (max(ys) - min(ys)) / (2 * tan_v)) >= 0.6


def test_rerun_eye_frames_the_whole_revolution_at_reruns_lens():
    """The rerun recording's 3D eye (a blueprint cannot set rerun's 55-degree field of view)
    comes from the same box over the revolution and the same framing: every corner of the box
    is in a square view at that lens."""
    from explorer.view.rerun import recording

    scene = load_scene(SCENES / "trip_gear_dashpot.toml", ["solver.steps_per_revolution=360"])
    run = recording.with_parts("trip", simulate(scene))
    lo, hi = recording.parts_bounds(run.parts, run.poses)
    expected = meshes.motion_bounds(run.parts, run.poses)
    np.testing.assert_array_equal(lo, expected[0])
    np.testing.assert_array_equal(hi, expected[1])
    eye = recording.eye_for((lo, hi))
    frame = meshes.frame_bounds(lo, hi, fov=math.radians(55.0), aspect=1.0)
    assert eye == {"position": list(frame.position), "look_target": list(frame.look_at), "eye_up": [0.0, 0.0, 1.0]}
    x, y, depth = _project(_corners(lo, hi), frame)
    assert np.all(depth > 0.0) and np.all(np.abs(x) <= math.tan(math.radians(27.5)))
    assert np.all(np.abs(y) <= math.tan(math.radians(27.5)))
