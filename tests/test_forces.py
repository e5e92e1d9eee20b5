"""Rigid-train forces: per-step loads, the exact float (jump) speed, the forces effect, bad input."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import SCENES, run_cli
from explorer.effects.pipeline import simulate
from explorer.core.errors import InputError
from explorer.mechanics.forces import (
    TrainLoads,
    float_speed,
    friction_direction,
    min_contact_force,
    rigid_train_forces,
)
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene, loads_scene

SCENE = """
name = "forces test"
effects = ["forces"]
[drive]
rpm = {rpm}
[lift]
law = "{law}"
height = "{height} mm"
start = "20 deg"
rise = "{rise} deg"
dwell = "{dwell} deg"
return = "{ret} deg"
{return_law}
[follower]
ratio = {ratio}
[valve]
mass = "{mass} kg"
lash = "{lash} mm"
[spring]
preload = "{preload} N"
rate = "{rate} N/mm"
[loads]
friction = "{friction} N"
[loads.closing]
gas = "{closing} N"
[solver]
steps_per_revolution = {steps}
"""
DEFAULTS = dict(rpm=1000, law="harmonic", height=10, rise=60, dwell=0, ret=60, return_law="", ratio=1.0, mass=0.1,
                lash=0, preload=200, rate=0, friction=0, closing=0, steps=720)


def scene(**changes):
    return loads_scene(SCENE.format(**(DEFAULTS | changes)))


# --- per-step loads ---------------------------------------------------------------------------------


def test_rigid_train_forces_by_hand():
    loads = TrainLoads(mass=2.0, preload=100.0, rate=1000.0, friction=10.0, closing=5.0)
    s = np.array([0.0, 0.01, 0.01, 0.02, 0.02])
    v = np.array([0.0, 1.0, -1.0, 0.0, 0.0])
    a = np.array([0.0, -30.0, -30.0, -50.0, 20.0])
    cols = rigid_train_forces(s, v, a, loads, ratio=1.5)
    # seated: the linkage carries nothing, the seat carries spring + closing loads
    assert cols["contact_force_N"][0] == 0.0
    assert cols["required_spring_force_N"][0] == -5.0
    assert cols["spring_margin_N"][0] == 105.0
    # opening: F = M p + P0 + k s + R + D = -60 + 110 + 10 + 5
    assert cols["contact_force_N"][1] == pytest.approx(65.0)
    # closing: friction flips sign: -60 + 110 - 10 + 5
    assert cols["contact_force_N"][2] == pytest.approx(45.0)
    # at rest friction takes the direction of the coming motion (sign of p)
    assert cols["friction_force_N"][3] == -10.0 and cols["friction_force_N"][4] == 10.0
    assert np.array_equal(cols["linkage_force_N"], cols["contact_force_N"])
    assert np.allclose(cols["follower_force_N"], 1.5 * cols["contact_force_N"])
    opened = s > 0
    assert np.allclose(cols["spring_margin_N"][opened], cols["contact_force_N"][opened])
    assert np.allclose(cols["spring_force_N"], 100.0 + 1000.0 * s)


def test_friction_direction():
    assert friction_direction([1.0, -1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 3.0, -3.0, 0.0]).tolist() == [1, -1, 1, -1, 0]


# --- float speed against closed forms -------------------------------------------------------------
# Harmonic rise/return of angle beta: L'' = h f''/beta^2 with f''min = -pi^2/2 at the end of the rise
# (and the start of the return), so for a constant load W the float speed is
#   w_jump = sqrt(W / (M h |f''|min)) * beta.
# Tolerance 1e-9: the minimum sits at a breakpoint, evaluated 1e-11 rad inside (one-sided limit).


@pytest.mark.parametrize("dwell", [0, 30])
def test_jump_speed_harmonic_constant_load(dwell):
    sc = scene(dwell=dwell, preload=150, closing=30)
    jump = float_speed(build_lift(sc), TrainLoads.from_scene(sc))
    beta, h, m, w_load = math.radians(60), 0.010, 0.1, 180.0
    expected = math.sqrt(w_load / (m * h * math.pi**2 / 2)) * beta
    assert jump.omega == pytest.approx(expected, rel=1e-9)
    assert not jump.static_loss


def test_jump_speed_harmonic_friction_rate_ratio_lash():
    """Friction makes the closing side worse (W - R); the rate adds k s at full lift; the valve sees
    ratio * L'' and a lift ratio * h - lash at the top."""
    ratio, lash, h, k, p0, d, fr, m = 1.4, 0.4e-3, 0.010, 20e3, 150.0, 30.0, 12.0, 0.1
    sc = scene(dwell=25, preload=p0, closing=d, friction=fr, rate=k / 1e3, ratio=ratio, lash=lash * 1e3)
    jump = float_speed(build_lift(sc), TrainLoads.from_scene(sc), ratio, lash)
    beta = math.radians(60)
    w_load = p0 + k * (ratio * h - lash) + d - fr
    expected = math.sqrt(w_load / (m * ratio * h * math.pi**2 / 2)) * beta
    assert jump.omega == pytest.approx(expected, rel=1e-9)
    # on the closing side: just after the dwell, where the return begins
    assert math.degrees(jump.theta) == pytest.approx(20 + 60 + 25, abs=1e-6)


def test_jump_speed_cycloidal_interior_minimum():
    """Cycloidal: f'' = 2 pi sin(2 pi u), deepest (-2 pi) in the interior of the return (u = 1/4)."""
    # opening side: (W + R) beta_r^2 = 155 * 90^2 > closing side (W - R) beta_d^2 = 125 * 80^2
    sc = scene(law="cycloidal", rise=90, dwell=10, ret=80, preload=120, closing=20, friction=15)
    jump = float_speed(build_lift(sc), TrainLoads.from_scene(sc))
    beta_d, h, m = math.radians(80), 0.010, 0.1
    expected = math.sqrt((120 + 20 - 15) / (m * h * 2 * math.pi)) * beta_d
    assert jump.omega == pytest.approx(expected, rel=1e-9)
    assert math.degrees(jump.theta) == pytest.approx(20 + 90 + 10 + 80 / 4, abs=1e-4)


@settings(max_examples=12, deadline=None)
@given(
    law=st.sampled_from(["cycloidal", "polynomial-345", "polynomial-4567", "modified-sine", "modified-trapezoid"]),
    rise=st.floats(40, 120),
    ret=st.floats(40, 120),
    dwell=st.floats(0, 40),
    rate=st.floats(0, 40),
    friction=st.floats(0, 30),
    lash=st.floats(0, 0.5),
)
def test_jump_speed_brackets_contact_loss_on_a_dense_grid(law, rise, ret, dwell, rate, friction, lash):
    """Converged reference: on 400 000 samples the contact force stays >= 0 just below the float
    speed (1e-6) and goes negative just above it (1e-3)."""
    sc = scene(law=law, rise=rise, ret=ret, dwell=dwell, rate=rate, friction=friction, lash=lash, preload=200)
    lift = build_lift(sc)
    loads = TrainLoads.from_scene(sc)
    jump = float_speed(lift, loads, 1.0, lash * 1e-3)
    theta = np.linspace(0, 2 * math.pi, 400_001)
    d = lift.derivatives(theta)
    x = d[0] - lash * 1e-3
    opened = x > 0
    direction = friction_direction(d[1], d[2])

    def contact(w):
        f = loads.mass * w**2 * d[2] + loads.preload + loads.rate * np.maximum(x, 0) + loads.friction * direction + loads.closing
        return f[opened].min()

    scale = loads.preload + loads.rate * 0.01
    assert contact(jump.omega * (1 - 1e-6)) > -1e-9 * scale
    # above: the deficit 2e-3 W beats what the grid spacing (1.6e-5 rad) can hide next to a
    # breakpoint minimum (slope / W <= C_j / (C_a beta) ~ 20 per rad -> 3e-4 W)
    assert contact(jump.omega * (1 + 1e-3)) < 0


def test_static_loss_gives_zero_jump_speed():
    sc = scene(preload=10, closing=-50)  # an intake valve whose steam load beats the spring
    jump = float_speed(build_lift(sc), TrainLoads.from_scene(sc))
    assert jump.omega == 0.0 and jump.static_loss
    out = simulate(sc)
    assert out.summary["jump_speed_rpm"] == 0.0
    assert any("float" in w and "standstill" in w for w in out.warnings)
    assert any("lifts off its seat" in w for w in out.warnings)


# --- the effect ------------------------------------------------------------------------------------


def test_effect_columns_and_identities():
    sc = scene(law="polynomial-345", rate=25, friction=10, closing=15, lash=0.3, ratio=1.2, dwell=20, steps=3600)
    out = simulate(sc)
    c, s = out.columns, out.summary
    for name in ("spring_force_N", "contact_force_N", "linkage_force_N", "required_spring_force_N", "spring_margin_N",
                 "follower_force_N", "friction_force_N", "inertia_force_N", "closing_load_N"):
        assert name in c and np.all(np.isfinite(c[name]))
    opened = c["rigid_valve_lift_m"] > 0
    assert np.array_equal(c["linkage_force_N"], c["contact_force_N"])
    assert np.allclose(c["spring_margin_N"][opened], c["contact_force_N"][opened])
    assert np.all(c["contact_force_N"][~opened] == 0.0)
    # the refined minimum lies at or below every sample, and close to the sampled one
    assert s["min_contact_force_N"] <= c["contact_force_N"][opened].min() + 1e-9
    assert s["min_contact_force_N"] == pytest.approx(c["contact_force_N"][opened].min(), rel=1e-3)
    # d'Alembert: the inertia part is M * p of the rigid valve motion
    assert np.allclose(c["inertia_force_N"][opened], 0.1 * c["rigid_valve_accel_m_s2"][opened])


def test_inertia_scales_with_speed_squared_and_loads_do_not():
    a = simulate(scene(rpm=1000, rate=20, friction=5, closing=10, law="cycloidal"))
    b = simulate(scene(rpm=1500, rate=20, friction=5, closing=10, law="cycloidal"))
    assert np.allclose(b.columns["inertia_force_N"], 2.25 * a.columns["inertia_force_N"], rtol=1e-12, atol=1e-12)
    static_a = a.columns["contact_force_N"] - a.columns["inertia_force_N"]
    static_b = b.columns["contact_force_N"] - b.columns["inertia_force_N"]
    assert np.allclose(static_a, static_b)
    assert a.summary["jump_speed_rpm"] == pytest.approx(b.summary["jump_speed_rpm"], rel=1e-12)


def test_float_warning_at_and_above_jump_speed():
    base = dict(law="cycloidal", rate=20, friction=8, closing=12, lash=0.2)
    jump_rpm = simulate(scene(**base)).summary["jump_speed_rpm"]
    below = simulate(scene(rpm=jump_rpm * (1 - 1e-7), **base)).report()
    assert not below["valve_floats"] and not any("float" in w for w in below["warnings"])
    assert below["min_contact_force_N"] > 0
    at = simulate(scene(rpm=jump_rpm, **base)).summary
    assert at["min_contact_force_N"] == pytest.approx(0.0, abs=1e-7 * 200)
    above = simulate(scene(rpm=jump_rpm * 1.05, **base))
    s = above.report()
    assert s["valve_floats"] and any("float" in w for w in s["warnings"])
    assert s["min_contact_force_N"] < 0
    losses = [e for e in s["events"] if e["kind"] == "rigid-contact-loss"]
    assert losses
    # each event is a zero of the rigid contact force (Brent-polished), time = angle / w
    lift = build_lift(above.scene)
    loads = TrainLoads.from_scene(above.scene)
    for e in losses:
        th = math.radians(e["cam_angle_deg"])
        d = lift.derivatives(np.array([th]))
        x = d[0, 0] - 0.2e-3
        f = loads.mass * above.scene.omega**2 * d[2, 0] + loads.preload + loads.rate * x + loads.friction * np.sign(d[1, 0]) + loads.closing
        assert abs(f) < 1e-6
        assert e["time_s"] == pytest.approx(th / above.scene.omega)


def test_schenker_sides_in_the_summary():
    """A law event with known peaks: the summary's p1, p2, F1, F2 follow Schenker's bookkeeping."""
    sc = scene(law="polynomial-345", rise=50, ret=90, friction=20, closing=30, rpm=1200)
    s = simulate(sc).summary
    w = sc.omega
    ca = 10 / math.sqrt(3)
    p1 = -ca * 0.01 * w**2 / math.radians(50) ** 2
    p2 = -ca * 0.01 * w**2 / math.radians(90) ** 2
    assert s["opening_side"]["peak_deceleration_m_s2"] == pytest.approx(p1, rel=1e-9)
    assert s["closing_side"]["peak_deceleration_m_s2"] == pytest.approx(p2, rel=1e-9)
    assert s["opening_side"]["required_spring_force_N"] == pytest.approx(-0.1 * p1 - 20 - 30, rel=1e-9)
    assert s["closing_side"]["required_spring_force_N"] == pytest.approx(-0.1 * p2 + 20 - 30, rel=1e-9)
    assert s["optimum_deceleration_difference_m_s2"] == pytest.approx(2 * 20 / 0.1)


def test_min_contact_force_matches_dense_reference():
    sc = scene(law="modified-sine", rate=30, friction=10, closing=5, lash=0.3, rpm=2500)
    lift = build_lift(sc)
    loads = TrainLoads.from_scene(sc)
    f_min, th = min_contact_force(lift, loads, sc.omega, 1.0, 0.3e-3)
    theta = np.linspace(0, 2 * math.pi, 1_000_001)
    d = lift.derivatives(theta)
    x = d[0] - 0.3e-3
    f = loads.mass * sc.omega**2 * d[2] + loads.preload + loads.rate * np.maximum(x, 0) + loads.friction * friction_direction(d[1], d[2]) + loads.closing
    ref = f[x > 0].min()
    assert f_min <= ref + 1e-9
    assert f_min == pytest.approx(ref, abs=1e-6 * loads.preload)


# --- bad input ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "field, value, key",
    [
        ("friction", -5, "loads.friction"),
        ("mass", -0.1, "valve.mass"),
        ("mass", 0, "valve.mass"),
        ("preload", -1, "spring.preload"),
    ],
)
def test_scene_rejects_negative_values(field, value, key):
    with pytest.raises(InputError) as err:
        scene(**{field: value})
    assert err.value.key == key


def test_missing_spring_for_forces():
    text = SCENE.format(**DEFAULTS).split("[spring]")[0] + "[solver]\nsteps_per_revolution = 720\n"
    with pytest.raises(InputError) as err:
        loads_scene(text)
    assert err.value.key == "spring" and "forces" in err.value.reason


@pytest.mark.parametrize("bad", [dict(mass=-1.0), dict(friction=-2.0), dict(rate=-5.0), dict(preload=float("nan"))])
def test_train_loads_reject_bad_numbers(bad):
    args = dict(mass=1.0, preload=10.0, rate=0.0) | bad
    with pytest.raises(InputError):
        TrainLoads(**args)


def test_cli_bad_friction_is_one_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE.format(**(DEFAULTS | dict(friction=-3))))
    out = tmp_path / "out.csv"
    proc = run_cli("simulate", path, "-o", out)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "loads.friction" in lines[0]
    assert "Traceback" not in proc.stderr and not out.exists()


def test_cli_missing_spring_is_one_line(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(SCENE.format(**DEFAULTS).split("[spring]")[0])
    proc = run_cli("simulate", path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and ": spring: " in lines[0]


# --- built-in scenes -----------------------------------------------------------------------------------


def test_float_demo_scene_floats(scenes_dir):
    out = simulate(load_scene(scenes_dir / "valve_float_demo.toml"))
    s = out.report()
    assert s["valve_floats"] and s["jump_speed_rpm"] < s["rpm"]
    assert any("float" in w for w in s["warnings"])
    # the advisor's spring keeps the requested 50 N at the scene's speed
    assert s["spring_design"]["advice"]["min_contact_force_N"] >= 50.0 - 1e-9


def test_intake_scene_has_a_negative_closing_load(scenes_dir):
    sc = load_scene(scenes_dir / "schenker1902_intake_valve.toml")
    assert sc.loads.closing["steam_on_stem"] < 0
    s = simulate(sc).summary
    assert s["closing_loads_N"] == pytest.approx((-36 + 10 + 12 + 8) * 9.80665)
    assert not s["valve_floats"] and s["jump_speed_rpm"] > 240


SCHENKER_LOADS = [
    'effects=["forces"]',
    'valve.mass="2.9 kgf*s**2/m"',
    'valve.lash="0.6 mm"',
    'spring.preload="260 kgf"',
    "spring.rate=0",
    'loads.friction="15 kgf"',
    'loads.closing={Ds = "36 kgf", Dv = "10 kgf", Gu = "12 kgf", Gf = "8 kgf"}',
]


def test_schenker_fig2_forces_against_the_paper(scenes_dir):
    """Schenker's Fig. 2 cam (rebuilt from its arcs by the geometry) with his section 4 loads: the
    largest decelerations read off his figure are p1 = -35 (lift) and p2 = -117 m/s^2 (closing) and
    they need F1 = 21 kg and F2 = 288 kg of spring. The arcs are fitted to his figures, so the
    decelerations must come out within the reading accuracy of a 1902 diagram (1 m/s^2 here, the
    fit is better), and F1, F2 within the paper's whole-kilogram rounding plus that."""
    from explorer.core.units import KGF

    path = scenes_dir / "schenker1902_fig2.toml"
    if path.exists():
        sc = load_scene(path, SCHENKER_LOADS)
        lift, ratio, lash, w = build_lift(sc), sc.follower.ratio, sc.valve.lash, sc.omega
        loads = TrainLoads.from_scene(sc)
    else:
        fig2 = pytest.importorskip("explorer.lift.contours.schenker_fig2")
        lift, ratio, lash, w = fig2.lift_of(fig2.PAPER_DESIGN), 1.0, 0.6e-3, fig2.OMEGA
        loads = TrainLoads(mass=2.9 * 9.80665, preload=260 * KGF, rate=0.0, friction=15 * KGF, closing=66 * KGF)
    from explorer.mechanics.forces import side_extremes, smooth_pieces

    sides = side_extremes(lift, loads, w, ratio, lash, smooth_pieces(lift, ratio, lash))
    p1 = sides["opening"]["peak_deceleration_m_s2"]
    p2 = sides["closing"]["peak_deceleration_m_s2"]
    assert abs(p1 + 35) < 1.0 and abs(p2 + 117) < 1.0
    f1 = sides["opening"]["required_spring_force_N"] / KGF
    f2 = sides["closing"]["required_spring_force_N"] / KGF
    # F = |p| M -+ R - D with M = 2.9: 1 m/s^2 of p is 2.9 kg of F
    assert abs(f1 - 21) < 0.5 + 2.9 and abs(f2 - 288) < 0.5 + 2.9
    # his 260 kg spring (section 3) is below F2: the rigid gear would float just under 240 rpm
    jump = float_speed(lift, loads, ratio, lash)
    assert jump.rpm < 240
    # rate 0: the float speed is where M |p2| (w/w0)^2 reaches P0 - R + D at the p2 point
    assert jump.rpm == pytest.approx(240 * math.sqrt((260 - 15 + 66) / (2.9 * abs(p2))), rel=1e-9)


# --- contact loss: one definition, loss and regain paired ----------------------------------------


def test_loss_intervals_pair_losses_with_regains_on_synthetic_pieces():
    """Closed forms: cos(t) - 1/2 on an open half revolution is <= 0 from pi/3 to its end, where
    the valve seats (the regain); sin(t - 0.3) on a revolution that is open throughout is <= 0
    from pi + 0.3 through 0 to 0.3 (the stretch wraps). A jump at a piece start is a loss there."""
    from explorer.mechanics.forces import Pieces, loss_intervals

    def pieces(starts, ends, is_open):
        return Pieces(np.array(starts), np.array(ends), np.array(is_open), np.ones(len(starts)))

    half = pieces([0.0, math.pi], [math.pi, 2 * math.pi], [True, False])
    (loss, regain), = loss_intervals(half, lambda t, d: np.cos(t) - 0.5)
    assert loss == pytest.approx(math.pi / 3, abs=1e-13) and regain == math.pi

    whole = pieces([0.0], [2 * math.pi], [True])
    (loss, regain), = loss_intervals(whole, lambda t, d: np.sin(t - 0.3))
    assert loss == pytest.approx(math.pi + 0.3, abs=1e-13) and regain == pytest.approx(0.3, abs=1e-13)

    # positive on the first piece, negative from the second's start (a breakpoint) until 3 pi/2
    two = pieces([0.0, 1.0], [1.0, 2 * math.pi], [True, True])
    (loss, regain), = loss_intervals(two, lambda t, d: np.where(t < 1.0, 1.0, t - 1.5 * math.pi))
    assert loss == 1.0 and regain == pytest.approx(1.5 * math.pi, abs=1e-13)

    assert loss_intervals(whole, lambda t, d: 1.0 + 0.0 * t) == []
    assert loss_intervals(whole, lambda t, d: -1.0 + 0.0 * t) == []  # never in contact: no stretch to pair


def test_float_scene_reports_one_set_of_angles_everywhere():
    """valve_float_demo at its 4000 rpm: the summary's stretches, the paired events and the warning
    hold the same angles, those of this speed; every sampled contact force inside a stretch is
    <= 0 and every one outside it (valve open) > 0 (the columns are an independent computation)."""
    result = simulate(load_scene(SCENES / "valve_float_demo.toml"))
    s, c = result.report(), result.columns
    stretches = s["contact_loss_cam_angles_deg"]
    assert len(stretches) == 2
    kinds = [(e["kind"], e["cam_angle_deg"]) for e in s["events"] if e["kind"].startswith("rigid-contact")]
    assert kinds == [(k, a) for pair in stretches for k, a in zip(("rigid-contact-loss", "rigid-contact-regain"), pair)]
    (warning,) = [w for w in s["warnings"] if w.startswith("valve float")]
    for loss, regain in stretches:
        assert f"from cam angle {loss:.2f} to {regain:.2f} deg" in warning or f"from {loss:.2f} to {regain:.2f} deg" in warning
    assert f"contact is first lost, at cam angle {s['jump_cam_angle_deg']:.2f} deg" in warning  # named as the float speed's
    theta, force = c["cam_angle_deg"], c["contact_force_N"]
    is_open = c["rigid_valve_lift_m"] > 0.0
    inside = np.zeros_like(is_open)
    for loss, regain in stretches:
        inside |= (theta > loss) & (theta < regain)
    near = np.zeros_like(is_open)  # samples within a step of a root can round either way
    for angle in np.ravel(stretches):
        near |= np.abs(theta - angle) < 0.2
    assert np.all(force[inside & ~near] <= 0.0)
    assert np.all(force[is_open & ~inside & ~near] > 0.0)


def test_max_contact_force_is_refined_against_a_dense_maximum():
    """The summary's largest contact force is the refined maximum of the closed-form force (as the
    minimum is), not the largest of the output samples (720 a revolution here: 0.5 deg apart).
    Oracle: F = M r w^2 L'' + P + c s + R sgn(v) + D (s = r L - lash) on 2e6 + 1 angles (step
    3.1e-6 rad: an interior maximum's sampling error F'' dtheta^2 / 2 is ~1e-10 relative), so the
    refined value agrees with it to 1e-9 relative and lies at or above it and every output sample."""
    sc = scene(law="polynomial-345", rate=25, friction=10, closing=15, lash=0.3, ratio=1.2, rpm=2500)
    out = simulate(sc)
    s, c = out.summary, out.columns
    lift = build_lift(sc)
    loads = TrainLoads.from_scene(sc)
    theta = np.linspace(0.0, 2.0 * math.pi, 2_000_001)
    d = lift.derivatives(theta)
    x = 1.2 * d[0] - 0.3e-3
    v = 1.2 * d[1]
    a = 1.2 * d[2]
    sgn = np.where(v > 0, 1.0, np.where(v < 0, -1.0, np.sign(a)))
    f = loads.mass * sc.omega**2 * a + loads.preload + loads.rate * x + loads.friction * sgn + loads.closing
    opened = x > 0.0
    k = int(np.argmax(np.where(opened, f, -np.inf)))
    assert s["max_contact_force_N"] == pytest.approx(f[k], rel=1e-9)
    assert s["max_contact_force_N"] >= f[k] - 1e-12 * abs(f[k])
    assert s["max_contact_force_cam_angle_deg"] == pytest.approx(math.degrees(theta[k]), abs=1e-3)
    sampled = c["contact_force_N"][c["rigid_valve_lift_m"] > 0].max()
    assert sampled <= s["max_contact_force_N"]
    assert s["max_contact_force_N"] - sampled > 1e-6 * sampled  # the samples miss the peak here
    # the follower-side force: virtual work through the rigid lever (valve travel = ratio x the
    # follower's), F_f dL = F_v r dL
    assert s["max_follower_force_N"] == 1.2 * s["max_contact_force_N"]
