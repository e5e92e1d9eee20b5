"""Effect `elastic` (explorer/effects/elastic.py) in the pipeline.

Oracles: the solver called directly on the same model, the phase ODEs (linkage force and back
pressure are W + M1 a in contact; jerk from the ODE against the closed form's), invariance under
a rotation of the cam, the scipy reference through the scene's solver section, and the
1902 scheme's stability limit.
"""

import math
import subprocess
import sys

import numpy as np
import pytest

from explorer.effects.elastic import elastic_jerk
from explorer.dynamics.model import PHASE_CODES, Drive, LinkageModel
from explorer.dynamics.solvers import solve
from explorer.effects.pipeline import simulate
from explorer.effects.lift import build_lift
from explorer.scene.scene import loads_scene
from conftest import process_timeout
from dynamics_cases import float_valve_scene

SCENE = float_valve_scene("elastic test", ["elastic"], """[loads.closing]
gas = "15 N"
[follower]
base_radius = "30 mm"
roller_radius = "12 mm"
[linkage]
stiffness = "3e6 N/m"
[seat]
restitution = 0.3
""")


@pytest.fixture(scope="module")
def result():
    return simulate(loads_scene(SCENE))


def test_columns_replace_the_rigid_valve_motion(result):
    c, n = result.columns, result.scene.solver.steps_per_revolution
    for name in ("valve_lift_m", "valve_velocity_m_s", "valve_accel_m_s2", "valve_jerk_m_s3", "linkage_force_N",
                 "camshaft_back_pressure_N", "deviation_from_drive_m", "rigid_valve_lift_m"):
        assert c[name].shape == (n,) and np.all(np.isfinite(c[name]))
    assert np.abs(c["valve_lift_m"] - c["rigid_valve_lift_m"]).max() > 1e-4  # the valve floats
    s = result.summary
    assert s["elastic_method"] == "exact" and s["elastic_solver"]["method"] == "exact"
    assert result.timings["elastic"].requested and set(result.timings) == {"kinematics", "lash", "elastic"}
    assert "effects" not in s and "events" not in s and "warnings" not in s  # fields of the Result, not figures
    assert s["separated_angle_deg"] > 5.0 and s["peak_linkage_force_N"] == pytest.approx(c["linkage_force_N"].max())
    result.json_text()  # JSON-able, no NaN


def test_columns_equal_the_solver_run_from_the_lowest_drive_angle(result):
    scene = result.scene
    model = LinkageModel.from_scene(scene)
    drive = Drive(build_lift(scene), scene.follower.ratio, scene.drive.omega)
    t = result.columns["time_s"]
    i0 = int(np.argmin(drive(t)[0]))
    period = 2 * math.pi / scene.drive.omega
    run = solve(model, drive, np.concatenate([t[i0:], t[:i0] + period]))
    np.testing.assert_array_equal(np.roll(run.s, i0), result.columns["valve_lift_m"])
    np.testing.assert_array_equal(np.roll(run.linkage_force, i0), result.columns["linkage_force_N"])
    events = [e for e in result.events if e["effect"] == "elastic"]
    assert [e["kind"] for e in events] == [e["kind"] for e in run.events]
    for e in events:
        assert e["cam_angle_deg"] == pytest.approx(math.degrees(scene.drive.omega * e["time_s"]) % 360.0, abs=1e-9)
        assert 0.0 <= e["time_s"] < period


def test_a_rotated_cam_gives_the_rotated_motion(result):
    turned = simulate(loads_scene(SCENE, overrides=['lift.start="120 deg"']))
    shift = 900  # 90 deg at 3600 steps
    for name in ("valve_lift_m", "valve_velocity_m_s", "linkage_force_N"):
        a, b = result.columns[name], np.roll(turned.columns[name], -shift)
        assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()


def test_force_identities_in_contact_and_the_lever_ratio():
    # ratio 2: the drive is twice the follower lift; the back pressure is twice the linkage
    # force (virtual work) and in contact the linkage force is W + M1 a (W with friction sign)
    r = simulate(loads_scene(SCENE, overrides=["follower.ratio=2.0", 'lift.height="4.75 mm"']))
    c, scene = r.columns, r.scene
    np.testing.assert_allclose(c["camshaft_back_pressure_N"], 2.0 * c["linkage_force_N"], rtol=1e-15)
    moving = c["valve_phase"] == PHASE_CODES["contact"]
    s, v, a = c["valve_lift_m"][moving], c["valve_velocity_m_s"][moving], c["valve_accel_m_s2"][moving]
    W = scene.spring.preload + scene.loads.closing_total + scene.spring.rate * s + scene.loads.friction * np.sign(v)
    np.testing.assert_allclose(c["linkage_force_N"][moving], W + scene.valve.mass * a, rtol=1e-9)
    # deviation from Schenker's (S - W/k) curve: -M1 a / k while the valve moves in contact
    np.testing.assert_allclose(c["deviation_from_drive_m"][moving], -scene.valve.mass * a / scene.linkage.stiffness,
                               rtol=1e-6, atol=1e-12)
    assert np.all(c["deviation_from_drive_m"][c["valve_lift_m"] == 0.0] == 0.0)


def test_jerk_from_the_ode_equals_the_closed_form_jerk(result):
    scene = result.scene
    model = LinkageModel.from_scene(scene)
    drive = Drive(build_lift(scene), 1.0, scene.drive.omega)
    t = result.columns["time_s"]
    sol = solve(model, drive, t)
    closed = sol.jerk
    from_ode = elastic_jerk(model, drive(t), sol.__class__(**{**sol.__dict__, "jerk": None}))
    scale = np.abs(closed).max()
    assert scale > 1e5
    np.testing.assert_allclose(from_ode, closed, rtol=0, atol=1e-9 * scale)
    # and the closed form is the derivative of the acceleration (central differences, 100x finer)
    fine_t = np.linspace(t[1000], t[1001], 101)
    fine = solve(model, drive, fine_t, initial_state=(sol.s[1000], sol.v[1000]))
    if np.all(fine.phase == fine.phase[0]):
        diff = np.gradient(fine.a, fine_t)
        np.testing.assert_allclose(diff[1:-1], fine.jerk[1:-1], rtol=1e-5, atol=1e-6 * scale)


def test_the_scipy_method_from_the_scene_agrees(result):
    ref = simulate(loads_scene(SCENE, overrides=['solver.method="scipy"', "solver.rtol=1e-12", "solver.atol=1e-15"]))
    assert ref.summary["elastic_method"] == "scipy" and ref.summary["elastic_solver"]["method"] == "DOP853"
    assert np.abs(ref.columns["valve_lift_m"] - result.columns["valve_lift_m"]).max() < 1e-9
    kinds = [e["kind"] for e in result.events if e["effect"] == "elastic"]
    assert [e["kind"] for e in ref.events if e["effect"] == "elastic"] == kinds


def test_the_1902_scheme_beyond_its_stability_limit_is_run_with_a_warning():
    # k = 3e7 N/m on 0.1 kg: Tn = 0.36 ms; 36 steps at 4000 rpm are 0.42 ms = 1.15 Tn, far
    # beyond the printed scheme's limit of 0.39 Tn
    unstable = simulate(loads_scene(SCENE, overrides=['solver.method="schenker1902"', "solver.steps_per_revolution=36",
                                                      'linkage.stiffness="3e7 N/m"']))
    assert any("unstable" in w for w in unstable.warnings)
    assert unstable.summary["elastic_solver"]["step_over_period"] > unstable.summary["elastic_solver"]["stability_limit"]
    stable = simulate(loads_scene(SCENE, overrides=['solver.method="schenker1902"', "solver.steps_per_revolution=3600"]))
    assert not any("unstable" in w for w in stable.warnings)
    assert stable.summary["elastic_method"] == "schenker1902"
    assert np.all(np.isfinite(stable.columns["valve_lift_m"]))


def test_a_valve_that_does_not_come_back_to_rest_is_reported():
    # friction larger than the spring can overcome: the valve stays stuck open after the event
    stuck = simulate(loads_scene(SCENE, overrides=['loads.friction="400 N"', 'spring.preload="100 N"']))
    assert any("not come back to rest" in w for w in stuck.warnings)
    assert stuck.columns["valve_lift_m"][-1] > 0.0


def test_a_kinematics_only_scene_never_loads_a_dynamics_solver(tmp_path):
    scene = tmp_path / "kin.toml"
    scene.write_text(SCENE.replace('effects = ["elastic"]', 'effects = ["kinematics", "lash"]'))
    code = (
        "import sys\n"
        "from explorer.scene.scene import load_scene\n"
        "from explorer.effects.pipeline import simulate\n"
        f"r = simulate(load_scene({str(scene)!r}))\n"
        "assert 'elastic' not in r.timings\n"
        # the registry of solver names (standard library only) is read by the scene loader
        "registry = ('explorer.dynamics', 'explorer.dynamics.solvers', 'explorer.dynamics.solver_base')\n"
        "loaded = [m for m in sys.modules if m.startswith('explorer.dynamics') and m not in registry]\n"
        "assert not loaded, loaded\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=process_timeout())
    assert out.returncode == 0, out.stderr
