"""3D parts and poses (explorer.meshes) against geometry that does not come from the mesh code:
Steiner's formula for the cam area, rolling contact distances, the lever's exact ratio, the
coin-rotation rule for the roller spin, and the spring's length bookkeeping."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explorer import load_scene, meshes
from explorer.effects import simulate
from explorer.geometry.translating import translating_profile
from explorer.lift import build_lift
from explorer.result import Result

from conftest import SCENES

DEMO = SCENES / "cycloidal_demo.toml"


def _scene(*overrides):
    return load_scene(DEMO, list(overrides))


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
    xy = meshes.cam_contour(scene, lift, 360)
    assert meshes._signed_area(xy) > 0.0
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
    spin = meshes.roller_spin(scene, lift, theta)
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
