"""3D parts of the gears (their views, explorer/view/gear_views.py, through explorer.view.parts): shapes, colours,
and contacts that the drawing must keep - roller on cam, valve pin over the valve stem."""

import math
from pathlib import Path

import numpy as np
import pytest
import trimesh

from explorer.view import parts as meshes
from explorer.effects.pipeline import simulate
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

SCENES = Path(__file__).resolve().parent.parent / "assets" / "scenes"
NAMES = ["pivoted_roller_lever", "rocking_cam", "rolling_lever", "trip_gear_dashpot"]


@pytest.fixture(scope="module")
def built():
    out = {}
    for name in NAMES:
        scene = load_scene(SCENES / f"{name}.toml", ["solver.steps_per_revolution=360", 'effects=["kinematics", "lash"]'])
        result = simulate(scene)
        lift = build_lift(scene)
        lay = meshes.layout(scene, result)
        parts = meshes.build_parts(scene, result, lay=lay, lift=lift)
        poses = meshes.part_poses(scene, result, magnification=0.0, lay=lay, lift=lift)
        out[name] = (scene, result, lift, lay, parts, poses)
    return out


def world(mesh, pose, i):
    p, q = pose
    transform = trimesh.transformations.quaternion_matrix(q[i])
    transform[:3, 3] = p[i]
    return trimesh.transform_points(mesh.vertices, transform)


@pytest.mark.parametrize("name", NAMES)
def test_parts_poses_and_colours(built, name):
    scene, result, lift, lay, parts, poses = built[name]
    n = len(result.columns["cam_angle_deg"])
    assert set(parts) == set(poses)
    for part, (p, q) in poses.items():
        assert len(meshes.PART_COLORS[part]) == 3  # stock or gear colour, looked up as the viewer does
        assert p.shape == (n, 3) and q.shape == (n, 4)
        assert np.all(np.isfinite(p)) and np.allclose(np.linalg.norm(q, axis=1), 1.0)
        assert len(parts[part].faces) > 0
    for part in meshes.STATIC_PARTS:
        if part in poses:
            assert np.ptp(poses[part][0], axis=0).max() == 0.0


@pytest.mark.parametrize("name, cam", [("pivoted_roller_lever", "cam"), ("rocking_cam", "rocking_cam")])
def test_roller_touches_its_cam_in_the_drawing(built, name, cam):
    """In world coordinates the roller centre stays one roller radius from the nearest vertex of
    the cam's side (polygon sampling error ~ spacing^2 / 8r, a few micrometres)."""
    scene, result, lift, lay, parts, poses = built[name]
    r = scene.follower.roller_radius
    for i in range(0, 360, 17):
        v = world(parts[cam], poses[cam], i)
        centre = poses["roller"][0][i]
        d = np.hypot(v[:, 0] - centre[0], v[:, 2] - centre[2])
        assert d.min() == pytest.approx(r, abs=2e-5), i


def test_valve_lever_pin_stays_on_the_valve_stem_over_the_lash(built):
    """Fig. 3's valve lever end f (drawn part, posed) sits the lash above the stem top when the
    valve is open, and comes down to it as the lash is taken up (rigid motion)."""
    scene, result, lift, lay, parts, poses = built["pivoted_roller_lever"]
    drive = lift.gear.drive
    f_local = np.array([drive.arm_out * math.cos(drive.bend), 0.0, drive.arm_out * math.sin(drive.bend)])
    p, q = poses["valve_lever"]
    lash = scene.valve.lash
    L = np.asarray(result.columns["follower_lift_m"])
    for i in range(0, 360, 7):
        transform = trimesh.transformations.quaternion_matrix(q[i])
        pin = transform[:3, :3] @ f_local + p[i]
        stem = poses["valve"][0][i]
        assert pin[2] - stem[2] == pytest.approx(-min(L[i], lash), abs=1e-12)
        # the pin swings on an arc: its sideways drift is the arc's sagitta, about L^2 / (2 arm)
        assert abs(pin[0] - stem[0]) <= L.max() ** 2 / drive.arm_out


def test_lever_ends_at_the_roller(built):
    for name in ("pivoted_roller_lever", "rocking_cam"):
        scene, result, lift, lay, parts, poses = built[name]
        gear = lift.gear
        arm = gear.arm if hasattr(gear, "arm") and not hasattr(gear, "lever_arm") else gear.lever_arm
        p, q = poses["roller_lever"]
        for i in range(0, 360, 29):
            end = trimesh.transformations.quaternion_matrix(q[i])[:3, :3] @ np.array([arm, 0.0, 0.0]) + p[i]
            assert np.allclose(end, poses["roller"][0][i], atol=1e-12)


def test_rolling_faces_touch_while_in_contact(built):
    """The two rolling faces, each posed by its lever angle, meet on the line of centres."""
    scene, result, lift, lay, parts, poses = built["rolling_lever"]
    gear = lift.gear
    w = gear.rolling_swing(np.radians(result.columns["cam_angle_deg"])).c[0]
    for i in np.nonzero(w > 0.05)[0][::9]:
        a = world(parts["rolling_lever"], poses["rolling_lever"], i)
        b = world(parts["valve_lever"], poses["valve_lever"], i)
        ax, az = gear.pivot
        point = np.array([ax, az]) + gear.law.rho(w[i]) * (np.array(gear.valve_pivot) - np.array([ax, az])) / gear.law.distance
        da = np.hypot(a[:, 0] - point[0], a[:, 2] - point[1]).min()
        db = np.hypot(b[:, 0] - point[0], b[:, 2] - point[1]).min()
        spacing = 2.0 * gear.law.rho(gear.max_rolling_swing()) * gear.max_rolling_swing() / 119
        assert da < spacing and db < spacing


def test_dashpot_piston_stays_inside_its_cylinder(built):
    """Seen in the browser: at full lift the trip gear's piston hung below the dashpot. Over the
    whole revolution the posed piston's vertical extent lies within the cylinder's (exact bounds
    of the meshes, 1e-9 m for rounding)."""
    scene, result, lift, lay, parts, poses = built["trip_gear_dashpot"]
    cyl = world(parts["dashpot"], poses["dashpot"], 0)
    lo, hi = cyl[:, 2].min(), cyl[:, 2].max()
    s = np.asarray(result.columns["valve_lift_m"])
    for i in (int(np.argmax(s)), *range(0, 360, 23)):
        rod = world(parts["dashpot_piston"], poses["dashpot_piston"], i)
        assert rod[:, 2].max() <= hi + 1e-9, i
        assert rod[:, 2].max() >= lo + 0.4 * float(lift.latch.height) - 1e-9, i  # piston head in the bore


def _box(points):
    return points.min(axis=0), points.max(axis=0)


def _apart(a, b, tol=1e-9):
    """True when two axis-aligned boxes share no volume (they may touch)."""
    (alo, ahi), (blo, bhi) = a, b
    return bool(np.any(alo >= bhi - tol) or np.any(blo >= ahi - tol))


def test_trip_latch_rod_rides_on_its_cam(built):
    """The latch no longer floats: its rod's roller stays on the latch cam all revolution, one
    roller radius from the turning cam's surface (nearest contour vertex: the polygon's
    sampling error, ~ spacing^2 / 8 r, stays below 2e-5 m), and rod and latch move together."""
    scene, result, lift, lay, parts, poses = built["trip_gear_dashpot"]
    roller = np.asarray(parts["roller"].vertices)
    r = np.hypot(roller[:, 0], roller[:, 2]).max()  # the rim polygon's vertices lie on the radius
    for i in range(0, 360, 11):
        cam = world(parts["cam"], poses["cam"], i)
        centre = poses["roller"][0][i]
        assert np.hypot(cam[:, 0] - centre[0], cam[:, 2] - centre[2]).min() == pytest.approx(r, abs=2e-5), i
        np.testing.assert_allclose(poses["rod"][0][i], centre, atol=1e-15)
    # the latch follows the latch law: its height changes by exactly the latch lift
    latch = np.asarray(lift.latch.derivatives(np.radians(result.columns["cam_angle_deg"]))[0])
    z = poses["latch"][0][:, 2]
    np.testing.assert_allclose(z[0] - z, latch - latch[0], atol=1e-12)


def test_trip_latch_carries_the_catch_then_slides_clear_of_every_part(built):
    """Over the revolution: while the valve is off its seat before the trip, the latch face lies
    on the catch collar (same height to 1e-12 m) over the collar's rim; at no step does the
    latch share volume with the collar, the valve (retainer, stem) or the dashpot, nor do its
    rod, roller and cam enter the dashpot (bounding boxes of the posed meshes: the parts are
    box-like or apart by more than their rounding)."""
    scene, result, lift, lay, parts, poses = built["trip_gear_dashpot"]
    s = np.asarray(result.columns["valve_lift_m"])
    theta = np.radians(result.columns["cam_angle_deg"])
    before_trip = np.mod(theta - lift.start, 2 * math.pi) < lift.phi_trip
    dashpot = _box(world(parts["dashpot"], poses["dashpot"], 0))
    carried = 0
    for i in range(360):
        latch = _box(world(parts["latch"], poses["latch"], i))
        collar = _box(world(parts["catch"], poses["catch"], i))
        valve = world(parts["valve"], poses["valve"], i)
        assert _apart(latch, collar), i
        radial = np.hypot(valve[:, 0] - lay.valve_x, valve[:, 1])
        assert _apart(latch, _box(valve[radial <= 1.01 * lay.stem_radius])), i  # the stem
        assert _apart(latch, _box(valve[(radial > 1.5 * lay.stem_radius) & (valve[:, 2] > lay.spring_seat_z)])), i  # retainer
        assert _apart(latch, dashpot), i
        for name in ("rod", "roller", "cam"):
            assert _apart(_box(world(parts[name], poses[name], i)), dashpot), (name, i)
        if s[i] > 1e-9 and before_trip[i]:
            carried += 1
            assert latch[0][2] == pytest.approx(collar[1][2], abs=1e-12), i
            assert latch[0][0] < collar[1][0] - 1e-4, i  # over the rim, not beside it
    assert carried > 10


def _trip_with_buffer(buffer):
    """(scene, result, lift, lay, parts, poses) of the trip gear scene with the given buffer."""
    scene = load_scene(SCENES / "trip_gear_dashpot.toml",
                       ["solver.steps_per_revolution=360", 'effects=["kinematics", "lash"]', f'gear.trip.buffer="{buffer}"'])
    result = simulate(scene)
    lift = build_lift(scene)
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay, lift=lift)
    poses = meshes.part_poses(scene, result, magnification=0.0, lay=lay, lift=lift)
    return scene, result, lift, lay, parts, poses


@pytest.mark.parametrize("buffer, radius", [("air", 0.0375), ("oil", 0.015)])
def test_trip_dashpot_is_drawn_with_the_scenes_bore(buffer, radius):
    """The drawn dashpot's bore is the active buffer's [gear.*_dashpot] diameter (75 mm air, 30 mm
    oil in the scene), its piston just inside it."""
    scene, result, lift, lay, parts, poses = _trip_with_buffer(buffer)
    cylinder = np.asarray(parts["dashpot"].vertices)
    r = np.hypot(cylinder[:, 0] - lay.valve_x, cylinder[:, 1])
    assert r.min() == pytest.approx(radius, rel=1e-9)
    piston = np.asarray(parts["dashpot_piston"].vertices)
    assert np.hypot(piston[:, 0], piston[:, 1]).max() < radius


@pytest.mark.parametrize("buffer", ["oil", "none"])
def test_trip_parts_clear_each_other_with_every_buffer(buffer):
    """The dashpot is drawn at the active buffer's bore, which moves the latch rod: the latch
    checks above hold with the oil dashpot (30 mm) and with no buffer as well."""
    built = {"trip_gear_dashpot": _trip_with_buffer(buffer)}
    test_trip_latch_rod_rides_on_its_cam(built)
    test_trip_latch_carries_the_catch_then_slides_clear_of_every_part(built)
