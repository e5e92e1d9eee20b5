"""The finger follower and the rocker arm as gears (explorer.gears.finger_follower, rocker_arm,
arm_train; issue #24 phase B): the built-in scenes run every effect they list, and the columns
the gear adds are checked against independent oracles.

- Lift and ratio: the vector loop of tests/test_modern_arm.py (Newton on the closure of the finger's
  roller on the cam the scene synthesised, written in that test) at many angles, to 1e-10; the
  pushrod train's ratio ds/dL from the loop of pushrod and rocker solved by Newton here, to 1e-10.
- The ratio's derivatives: central differences of the ratio column's own function (h = 1e-4 rad:
  truncation ~h^2 |r'''| ~ 1e-8 relative, rounding ~1e-12 / h), to 1e-6 relative.
- Virtual work on the scene's columns: camshaft torque x omega = contact force x valve velocity
  + the heat of the sliding contacts (mu N |v_slide| at a pad or flat lifter on the cam,
  mu_t F |v_slide| at the valve tip), to 1e-9 of the peak power; without friction, T omega = F v
  and the cam's normal force is ratio F / cos(pressure angle).
- Bad geometry (the pad off the valve tip, the roller through the base circle, the arm through
  the cam): one line naming the key, exit status 2, no traceback; random keys (hypothesis) load
  or fail with an InputError, nothing else.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import run_cli
from explorer.core.errors import InputError
from explorer.effects.lift import build_lift
from explorer.effects.pipeline import simulate
from explorer.scene.scene import load_scene, loads_scene

SCENES = Path(__file__).resolve().parent.parent / "assets" / "scenes"
FINGER = SCENES / "finger_follower.toml"
PUSHROD = SCENES / "pushrod_rocker.toml"
ALL_EFFECTS = ["kinematics", "lash", "forces", "contact", "elastic", "gear"]


@pytest.fixture(scope="module")
def finger():
    scene = load_scene(FINGER)
    return scene, simulate(scene)


@pytest.fixture(scope="module")
def pushrod():
    scene = load_scene(PUSHROD)
    return scene, simulate(scene)


def test_the_scenes_run_every_effect_they_list(finger, pushrod):
    for scene, result in (finger, pushrod):
        assert list(scene.effects) == ALL_EFFECTS
        for name, column in result.columns.items():
            assert np.isfinite(np.asarray(column, dtype=float)).all(), name
        report = result.report()
        assert report["valve_floats"] is False
        assert report["jump_speed_rpm"] > scene.drive.rpm
    f, p = finger[1].report(), pushrod[1].report()
    assert 1.6 <= f["min_valve_ratio"] and f["max_valve_ratio"] <= 1.8
    assert 1.5 <= p["min_valve_ratio"] and p["max_valve_ratio"] <= 1.7
    assert f["max_valve_lift_m"] == pytest.approx(0.0093, rel=1e-12)
    assert p["max_valve_lift_m"] == pytest.approx(0.0102, rel=1e-12)


def test_the_finger_scene_lift_and_ratio_through_the_vector_loop(finger):
    from test_modern_arm import LoopArm, loop_on_contour

    scene, result = finger
    gear = build_lift(scene).gear
    arm = LoopArm(gear)
    i = np.arange(0, 3600, 40)
    theta = np.radians(result.columns["cam_angle_deg"][i])
    psi = loop_on_contour(arm, gear.synthesised_contour(), theta, theta[0], gear.arm.rest)
    travel = np.array([arm.travel(p) for p in psi])
    assert np.max(np.abs(travel - result.columns["follower_lift_m"][i])) < 1e-10 * 0.0093
    ratio = np.array([abs(arm.valve_per_arm(p)) for p in psi]) / gear.arm.cam_side.arm
    assert np.max(np.abs(result.columns["valve_ratio"][i] - ratio)) < 1e-10 * ratio.max()


def test_the_pushrod_scene_ratio_through_the_loop_of_pushrod_and_rocker(pushrod):
    """ds/dL: Newton for the rocker angle psi on |O + a e(psi) - B_L(L)| = l at the lifter's lift L
    (from the gear), the valve travel of the test's own rocker: u . (C(psi) - C(psi0)); its slope
    by implicit differentiation, d psi/dL = -g_L / g_psi."""
    scene, result = pushrod
    train = build_lift(scene).gear
    o, a, l = np.asarray(train.rocker_pivot), train.rocker_arm, train.pushrod_length
    y0 = train.lifter.rest_height(scene.follower.base_radius)
    v = train.valve.drive
    u = np.array([math.cos(v.axis), math.sin(v.axis)])

    def centre(psi):
        return o + v.arm * np.array([math.cos(psi + v.angle), math.sin(psi + v.angle)])

    i = np.arange(0, 3600, 30)
    lifter = result.columns["lifter_lift_m"][i]
    psi, ratio, travel = train.rest, [], []
    for L in lifter:
        b = np.array([train.lifter.offset, y0 + L])
        for _ in range(60):
            cup = o + a * np.array([math.cos(psi), math.sin(psi)])
            g = (cup - b) @ (cup - b) - l * l
            g_psi = 2.0 * (cup - b) @ (a * np.array([-math.sin(psi), math.cos(psi)]))
            step = g / g_psi
            psi -= step
            if abs(step) < 1e-16:
                break
        cup = o + a * np.array([math.cos(psi), math.sin(psi)])
        dpsi_dl = -(-2.0 * (cup - b)[1]) / (2.0 * (cup - b) @ (a * np.array([-math.sin(psi), math.cos(psi)])))
        c = centre(psi)
        ratio.append(abs(u @ (v.arm * np.array([-math.sin(psi + v.angle), math.cos(psi + v.angle)]))) * abs(dpsi_dl))
        travel.append(u @ (c - centre(train.rest)))
    ratio, travel = np.array(ratio), np.array(travel)
    assert np.max(np.abs(result.columns["valve_ratio"][i] - ratio)) < 1e-10 * ratio.max()
    assert np.max(np.abs(result.columns["follower_lift_m"][i] - travel)) < 1e-10 * 0.0102


@pytest.mark.parametrize("path", [FINGER, PUSHROD])
def test_the_ratio_derivatives_are_the_ratio_s(path):
    scene = load_scene(path)
    lift = build_lift(scene)
    gear = scene.gear_plugin
    theta = np.radians(np.arange(35.1, 175.0, 2.5))  # off the law's breakpoints (30, 115, 200 deg): its jerk jumps there
    h = 1e-4
    ratio = lambda th: lift.gear.kinematics(th).ratio  # noqa: E731
    k = lift.gear.kinematics(theta)
    d1 = (ratio(theta + h) - ratio(theta - h)) / (2 * h)
    d2 = (ratio(theta + h) - 2 * ratio(theta) + ratio(theta - h)) / h**2
    result = simulate(scene.with_changes(effects=("kinematics",)))
    rows = np.searchsorted(np.radians(result.columns["cam_angle_deg"]), theta)
    assert np.allclose(np.radians(result.columns["cam_angle_deg"][rows]), theta, atol=1e-12)
    assert np.max(np.abs(result.columns["valve_ratio_d1"][rows] - d1)) < 1e-6 * np.abs(d1).max()
    assert np.max(np.abs(result.columns["valve_ratio_d2"][rows] - d2)) < 1e-4 * np.abs(d2).max()
    assert np.array_equal(result.columns["valve_ratio"][rows], k.ratio)
    assert gear.type in ("finger-follower", "rocker-arm")


@pytest.mark.parametrize("path", [FINGER, PUSHROD])
@pytest.mark.parametrize("frictionless", [False, True])
def test_camshaft_power_is_valve_power_plus_the_heat_of_sliding(path, frictionless):
    overrides = ["contact.tip_friction=0"] if frictionless else []
    if frictionless and path == PUSHROD:
        overrides.append("contact.sliding_friction=0")
    scene = load_scene(path, overrides)
    result = simulate(scene)
    c, w = result.columns, scene.drive.omega
    force, v = np.asarray(c["contact_force_N"]), np.asarray(c["follower_velocity_m_s"])
    heat = (np.abs(c["cam_friction_force_N"]) * np.abs(c["cam_sliding_velocity_m_s"])
            + np.abs(c["tip_friction_force_N"]) * np.abs(c["tip_sliding_velocity_m_s"]))
    pushing = force > 0.0
    power = c["camshaft_torque_Nm"] * w
    scale = np.max(np.abs(force * v))
    assert np.max(np.abs((power - force * v - heat)[pushing])) < 1e-9 * scale
    if frictionless:
        assert np.max(heat) == 0.0
        normal = c["valve_ratio"] * force / np.cos(np.radians(c["pressure_angle_deg"]))
        assert np.max(np.abs(c["cam_normal_force_N"] - normal)) < 1e-9 * np.max(normal)
    else:
        assert np.max(heat) > 1e-3 * scale  # the friction really is in the balance


def test_the_sliding_and_entrainment_columns(finger, pushrod):
    """The finger's roller rolls (no sliding at the cam); its pad slides on the tip at
    -psi' t . J (X - O) per rad (valve_end's closed form); the flat lifter slides at the cam."""
    scene, result = finger
    c = result.columns
    assert np.max(np.abs(c["cam_sliding_velocity_m_s"])) == 0.0
    assert np.max(np.abs(c["cam_entrainment_velocity_m_s"])) > 1.0
    assert np.max(np.abs(c["tip_sliding_velocity_m_s"])) > 0.1
    gear = build_lift(scene).gear
    k = gear.kinematics(np.radians(c["cam_angle_deg"]))
    t = k.tip.tangent
    jac = k.tip.arm_jacobian
    want = -scene.drive.omega * k.arm_angle[1] * np.einsum("ij,ij->i", t, jac)
    assert np.max(np.abs(c["tip_sliding_velocity_m_s"] - want)) < 1e-12 * np.abs(want).max()
    # the scrub's rate is the derivative of the scrub (per rad, times omega)
    scrub = c["tip_scrub_m"]
    rate = np.gradient(scrub, np.radians(c["cam_angle_deg"])) * scene.drive.omega
    assert np.max(np.abs(rate - c["tip_scrub_velocity_m_s"])[5:-5]) < 1e-4 * np.abs(rate).max()
    p = pushrod[1].columns
    assert np.max(np.abs(p["cam_sliding_velocity_m_s"])) > 1.0
    assert np.all(p["pushrod_force_N"][p["contact_force_N"] > 0] > 0)


@pytest.mark.parametrize("path", [FINGER, PUSHROD])
def test_exports_of_the_synthesised_cam(path, tmp_path):
    from explorer.view.exports import cam_source, dxf_text, grinding_table, point_table

    scene = load_scene(path)
    src = cam_source(scene)
    theta = np.linspace(0.0, 2 * math.pi, 720, endpoint=False)
    g = src.at(theta)
    k = build_lift(scene).gear.kinematics(theta)
    assert np.array_equal(g.contour, k.surface.contour)
    assert np.allclose(np.hypot(*g.normal.T), 1.0, atol=1e-12)
    assert "LWPOLYLINE" in dxf_text(src, 1e-6) or "POLYLINE" in dxf_text(src, 1e-6)
    assert len(point_table(src, 360).splitlines()) > 360
    table = grinding_table(src, 0.2, 720)
    assert table is not None


@pytest.mark.parametrize("path", [FINGER, PUSHROD])
def test_the_parts_and_their_poses(path):
    from explorer.view.parts import build_parts, part_poses

    scene = load_scene(path)
    result = simulate(scene.with_changes(effects=("kinematics",)))
    parts, poses = build_parts(scene, result), part_poses(scene, result)
    assert set(parts) == set(poses)
    want = {"cam", "camshaft", "valve", "spring", "seat", "cam_contact", "tip_contact"}
    want |= {"finger", "roller", "lash_adjuster"} if path == FINGER else {"rocker", "pushrod", "lifter"}
    assert want <= set(parts)
    for name, (position, quaternion) in poses.items():
        assert position.shape == (3600, 3) and quaternion.shape == (3600, 4), name
        assert np.isfinite(position).all() and np.isfinite(quaternion).all(), name


@pytest.mark.parametrize("path", [FINGER, PUSHROD])
def test_the_design_rules_read_the_gear_s_cam_contact(path):
    scene = load_scene(path)
    lift = build_lift(scene)
    theta = np.linspace(0.0, 2 * math.pi, 360, endpoint=False)
    contact = scene.gear_plugin.cam_contact(scene, lift, theta)
    k = lift.gear.kinematics(theta)
    assert np.array_equal(contact.geometry.contour_radius, k.surface.radius)
    assert contact.oscillating == (path == FINGER)
    if path == FINGER:  # the roller rolls: both surfaces at the same speed; the pitch radius rho + r
        assert np.array_equal(contact.motion.cam_rate, contact.motion.follower_rate)
        assert contact.roller_radius == scene.follower.roller_radius
    proc = run_cli("check", path)
    assert "Traceback" not in proc.stderr
    assert "(0 fail," in proc.stdout, proc.stdout  # the built-in scenes pass every rule that applies


# --- bad geometry: one line naming the key, exit 2 ---------------------------------------------


def _edited(path, old, new):
    text = path.read_text()
    for a, b in zip(old.split("|"), new.split("|")):  # several edits: "|"-separated pairs
        assert a in text
        text = text.replace(a, b)
    return text


BAD = [
    (FINGER, 'tip_radius = "3.5 mm"', 'tip_radius = "0.3 mm"', "gear.valve.tip_radius", "does not reach the valve tip"),
    (FINGER, 'arm = "33.24 mm"             # pivot -> roller axle', 'arm = "3 mm"', "gear.finger.arm", "base circle"),
    # the pivot beside the nose's path (tests/test_modern_arm.py's case): the lobe sweeps the arm
    (FINGER, 'pivot = ["-32 mm", "-36 mm"]|arm = "33.24 mm"|arm = "56.89 mm"|angle = "-5.58 deg"|axis = "-90 deg"|tip_radius = "3.5 mm"',
     'pivot = ["-20 mm", "12 mm"]|arm = "34 mm"|arm = "60 mm"|angle = "0 deg"||', "gear.finger.pivot", "through the cam"),
    (PUSHROD, 'tip_radius = "4 mm"', 'tip_radius = "0.1 mm"', "gear.valve.tip_radius", "does not reach the valve tip"),
    (PUSHROD, 'type = "rocker-arm"', 'type = "rocker-arm"\nratio = 1.6', "follower.ratio", "ratio"),
]


@pytest.mark.parametrize("path, old, new, key, words", BAD)
def test_bad_geometry_is_one_line_naming_the_key(path, old, new, key, words, tmp_path):
    text = _edited(path, old, new)
    with pytest.raises(InputError) as info:
        loads_scene(text, "bad.toml")
    assert info.value.key == key and words in info.value.reason
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    out = tmp_path / "out.csv"
    proc = run_cli("simulate", bad, "-o", out)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().count("\n") == 0 and key in proc.stderr and "Traceback" not in proc.stderr
    assert not out.exists()


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pivot_x=st.floats(-80.0, 80.0), pivot_y=st.floats(-80.0, 80.0), arm=st.floats(0.5, 80.0),
       pad=st.floats(0.5, 40.0), tip=st.floats(0.1, 10.0))
def test_random_finger_geometry_loads_or_names_a_key(pivot_x, pivot_y, arm, pad, tip):
    text = FINGER.read_text()
    text = text.replace('pivot = ["-32 mm", "-36 mm"]', f'pivot = ["{pivot_x} mm", "{pivot_y} mm"]')
    text = text.replace('arm = "33.24 mm"', f'arm = "{arm} mm"').replace('radius = "12 mm"', f'radius = "{pad} mm"')
    text = text.replace('tip_radius = "3.5 mm"', f'tip_radius = "{tip} mm"')
    try:
        scene = loads_scene(text, "random.toml")
    except InputError as exc:
        assert exc.key.startswith(("gear.", "follower.")) and "\n" not in str(exc)
        return
    lift = build_lift(scene)
    k = lift.gear.kinematics(np.linspace(0.0, 2 * math.pi, 360, endpoint=False))
    assert np.isfinite(k.ratio).all() and np.isfinite(k.surface.radius).all()


@pytest.mark.parametrize("path", [FINGER, PUSHROD])
def test_a_speed_sweep_takes_the_compiled_path_and_its_rows_are_simulate_s(path):
    """The lift is the valve's (ratio 1, no elasticity of its own): the compiled batch engine takes
    the scene's runs (Gear.batch_sweeps), and each row equals simulate's figures (the kernel is
    the exact solver's arithmetic: to 1e-9 of each figure's scale, as tests/test_sweep_kernel.py)."""
    from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns, row_figures
    from explorer.studies.sweep_spec import scene_for

    base = load_scene(path)
    shared = _Shared()
    assert engine_for(base, shared).name == "compiled"
    names = result_columns(base)
    values = np.array([[0.6], [1.0], [1.4]]) * base.drive.rpm
    table = compute_chunk(base, ("drive.rpm",), values, names, shared)
    for i, row in enumerate(values):
        expected = row_figures(names, simulate(scene_for(base, ("drive.rpm",), row)))
        for name, value in expected.items():
            got = table[i, names.index(name)]
            if math.isnan(value):
                assert math.isnan(got), (i, name)
            else:
                assert got == pytest.approx(value, rel=1e-9, abs=1e-12), (i, name, got, value)


def test_a_cam_side_stiffness_is_referred_to_the_valve_through_the_ratio(tmp_path):
    """[gear.finger] stiffness k at the roller: k / i^2 at the valve (energy), its derivative
    -2 k i' / i^3 against central differences; in series with [linkage] in the elastic effect,
    which then needs a solver that takes k(t) (the exact one is refused naming solver.method)."""
    text = FINGER.read_text().replace('width = "10 mm"              # roller width (Hertz)',
                                      'width = "10 mm"\nstiffness = "60 kN/mm"')
    with pytest.raises(InputError) as info:
        loads_scene(text, "k.toml")
    assert info.value.key == "solver.method" and "taylor" in info.value.reason
    scene = loads_scene(text.replace('method = "exact"', 'method = "taylor"'), "k.toml")
    lift = build_lift(scene)
    theta = np.radians(np.arange(0.1, 360.0, 1.0))
    k, dk = lift.linkage_stiffness(theta)
    ratio = lift.gear.kinematics(theta).ratio
    assert np.max(np.abs(k - 60e6 / ratio**2)) < 1e-12 * k.max()
    h = 1e-5
    fd = (lift.linkage_stiffness(theta + h)[0] - lift.linkage_stiffness(theta - h)[0]) / (2 * h)
    assert np.max(np.abs(dk - fd)) < 1e-6 * np.abs(fd).max()
    result = simulate(scene)
    stats = result.report()["elastic_solver"]
    series = 1.0 / (1.0 / k + 1.0 / scene.linkage.stiffness)
    assert stats["stiffness_max_N_m"] == pytest.approx(series.max(), rel=1e-3)
    assert result.report()["gear"]["valve_referred_side_stiffness_N_m"][0] == pytest.approx(60e6 / 1.71136**2, rel=1e-4)


@pytest.mark.parametrize("path, arm", [(FINGER, "finger"), (PUSHROD, "rocker")])
def test_the_browser_and_a_recording_draw_the_train(path, arm, tmp_path):
    """The browser's bundle (layout, meshes, poses) and a rerun recording hold the arm, posed at
    the kinematics' arm angle (a turn by a in the gear's plane is quat_about_y(-a))."""
    from explorer.view.browser.model import Request, prepare
    from explorer.view.rerun.read import read_rrd
    from explorer.view.rerun.recording import with_parts, write_recordings

    bundle = prepare(Request(str(path)))
    assert {arm, "cam", "valve", "spring", "seat", "tip_contact"} <= set(bundle.meshes) == set(bundle.poses)
    angle = np.radians(bundle.result.columns["arm_angle_deg"])
    wxyz = bundle.poses[arm][1]
    turned = 2.0 * np.arctan2(-wxyz[:, 2], wxyz[:, 0])
    assert np.max(np.abs(np.angle(np.exp(1j * (turned - angle))))) < 1e-12

    out = tmp_path / "train.rrd"
    write_recordings(out, [with_parts("train", simulate(load_scene(path)))])
    (run,) = read_rrd(out)
    quaternion = run.temporal[f"/parts/{arm}"]["Transform3D:quaternion"]  # x y z w
    turned = 2.0 * np.arctan2(-quaternion[:, 1], quaternion[:, 3])
    assert np.max(np.abs(np.angle(np.exp(1j * (turned - angle))))) < 1e-6


def test_the_hertz_rule_judges_a_crowned_lifter_as_its_ellipse():
    """The pushrod scene's crowned flat lifter touches the lobe in a Hertz ellipse: the design rule
    judges the gear's own pressure (the contact effect's hertz_stress_Pa at the scene's speed, the
    same rigid force), not a line contact over the lifter's width (about 650 MPa against 1.05 GPa)."""
    from explorer.checks.run import check

    scene = load_scene(PUSHROD)
    column = simulate(scene).columns["hertz_stress_Pa"]
    rule = check(scene, rpm=scene.drive.rpm, only=("hertz_stress",)).result("hertz_stress")
    assert rule.value == pytest.approx(float(np.max(column)), rel=1e-6)
    line = loads_scene(PUSHROD.read_text().replace('face_radius = "1.5 m"', ""), "flat.toml")
    flat = check(line, rpm=line.drive.rpm, only=("hertz_stress",)).result("hertz_stress")
    assert rule.value > 1.3 * flat.value
