"""Spline lifts (lift.law = "spline") and `explorer design`.

Oracles: the conditions themselves (met to 1e-12 relative), the 3-4-5 and 4-5-6-7 laws (the unique
polynomials of their end conditions, explorer.lift.laws), the known minimum-jerk optimum (Flash & Hogan
1985: the 3-4-5 polynomial minimises the integral of the squared jerk between rest positions), an
independent linear programme for the peak acceleration, and the standard laws on the same event.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from conftest import SCENES
from explorer import cli
from explorer.studies.design import DesignLimits, design, evaluate
from explorer.core.errors import InputError
from explorer.lift.curves import LawLift
from explorer.lift.spline import solve_spline
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene, loads_scene

DEMO = SCENES / "spline_demo.toml"
ERROR_LINE = re.compile(r"^error: [^:\n]+: [^:\n]+: .+$")
H = 0.01


def scene_text(stations, continuity=3, rpm=2000, extra=""):
    body = "\n".join(
        "[[lift.stations]]\n" + "\n".join(f"{k} = {v!r}".replace("'", '"') for k, v in st.items()) for st in stations)
    return f"""
name = "spline test"
effects = ["kinematics", "lash", "forces", "elastic"]
[drive]
rpm = {rpm}
[lift]
law = "spline"
start = "30 deg"
continuity = {continuity}
{body}
[follower]
base_radius = "30 mm"
roller_radius = "12 mm"
[valve]
mass = "0.12 kg"
lash = "0.3 mm"
[spring]
preload = "250 N"
rate = "25 N/mm"
[linkage]
stiffness = "2e6 N/m"
{extra}"""


REST = {"s": "0 mm", "v": "0 m/s", "a": "0 m/s**2"}
REST4 = {**REST, "j": "0 m/s**3"}


def rise_return(law_conditions, top_conditions, beta=70):
    return [{"angle": "0 deg", **law_conditions}, {"angle": f"{beta} deg", **top_conditions},
            {"angle": f"{2 * beta} deg", **law_conditions}]


@pytest.mark.parametrize("law,rest,continuity", [("polynomial-345", REST, 2), ("polynomial-4567", REST4, 3)])
def test_reproduces_the_polynomial_laws(law, rest, continuity):
    """With the 3-4-5 (s, v, a) or 4-5-6-7 (s, v, a, j) conditions at rest, top and rest again
    the spline is that law's rise and return."""
    top = {k: ("10 mm" if k == "s" else v) for k, v in rest.items()}
    scene = loads_scene(scene_text(rise_return(rest, top), continuity))
    lift = build_lift(scene)
    beta = math.radians(70)
    reference = LawLift(H, math.radians(30), beta, 0.0, beta, law, law)
    theta = np.linspace(0, 2 * math.pi, 7201)
    d, r = lift.derivatives(theta), reference.derivatives(theta)
    for k in range(4):
        scale = H / beta**k
        assert np.max(np.abs(d[k] - r[k])) <= 1e-12 * scale * 10, k


def test_conditions_met_to_1e_12():
    """Five stations with mixed conditions: every given value holds on both sides of its station,
    every other derivative up to the continuity order is continuous."""
    stations = [
        {"angle": "0 deg", **REST4},
        {"angle": "40 deg", "s": "5 mm", "v": "1.5 m/s"},
        {"angle": "80 deg", "s": "10 mm", "v": "0 m/s", "a": "-600 m/s**2"},
        {"angle": "120 deg", "s": "5 mm", "j": "1e4 m/s**3"},
        {"angle": "160 deg", **REST4},
    ]
    scene = loads_scene(scene_text(stations))
    lift = build_lift(scene)
    w = scene.omega
    options = scene.lift.options
    knots, coefficients = lift.knots, lift.coefficients

    def side(segment, u, k):  # k-th derivative per radian of one segment's polynomial, exactly at its end
        p = np.polynomial.Polynomial(coefficients[segment])
        return p.deriv(k)(u) / (knots[segment + 1] - knots[segment]) ** k if k else p(u)

    last = len(options.stations) - 1
    for i, st in enumerate(options.stations):
        sides = ([(i - 1, 1.0)] if i > 0 else []) + ([(i, 0.0)] if i < last else [])
        for k, value in enumerate(st.values):
            scale = H / math.radians(40) ** k
            got = [side(seg, u, k) for seg, u in sides]
            if value is not None:
                assert all(abs(g - value) <= 1e-12 * scale for g in got), (i, k, got, value)
            elif len(got) == 2 and k <= options.continuity:
                assert abs(got[0] - got[1]) <= 1e-12 * scale, (i, k, got)
    # the given values in time units, as written
    np.testing.assert_allclose(lift.local_derivatives(np.array([math.radians(80)]), 2)[2, 0] * w**2, -600.0, rtol=1e-12)


def test_spline_on_a_pivoted_lever_is_one_line(tmp_path):
    """The gears build their lift from a closed-form law or a table: a spline there is refused
    naming lift.law (main's pivoted-lever rule), never a traceback."""
    lever = (SCENES / "pivoted_roller_lever.toml").read_text()
    stations = DEMO.read_text()
    block = stations[stations.index("[[lift.stations]]"):stations.index("[follower]")]
    text = re.sub(r"\[lift\][^\[]*", '[lift]\nlaw = "spline"\nstart = "60 deg"\n' + block, lever, count=1)
    with pytest.raises(InputError) as info:
        from explorer.effects.pipeline import simulate

        simulate(loads_scene(text, str(tmp_path / "x.toml")))
    assert info.value.key == "lift.law"


def test_spline_runs_every_effect():
    from explorer.effects.pipeline import simulate

    result = simulate(load_scene(DEMO))
    theta = math.radians(60 + 80)  # the top station: s = 10 mm there, the lash taken off
    assert np.interp(theta, np.radians(result.columns["cam_angle_deg"]), result.columns["rigid_valve_lift_m"]) == pytest.approx(H - 0.3e-3, rel=1e-9)
    assert np.isfinite(result.columns["valve_jerk_m_s3"]).all()


BAD = [
    ('[[lift.stations]]\nangle = "0 deg"\ns = "1 mm"\n', "lift.stations[0].s", "base circle"),
    ('[[lift.stations]]\nangle = "10 deg"\ns = "0 mm"\n', "lift.stations[0].angle", "angle 0"),
    ('[[lift.stations]]\nangle = "0 deg"\ns = "0 mm"\nq = 1\n', "lift.stations[0].q", "unknown key"),
    ('[[lift.stations]]\nangle = "0 deg"\ns = "0 kg"\n', "lift.stations[0].s", ""),
    ('[[lift.stations]]\nangle = "0 deg"\ns = "0 mm"\nj = "1 m/s"\n', "lift.stations[0].j", ""),
]


@pytest.mark.parametrize("first,key,text", BAD)
def test_bad_stations(first, key, text):
    rest = '[[lift.stations]]\nangle = "80 deg"\ns = "10 mm"\nv = 0\n[[lift.stations]]\nangle = "160 deg"\ns = "0 mm"\nv = 0\n'
    src = scene_text([]).replace("[follower]", first + rest + "[follower]")
    with pytest.raises(InputError) as info:
        loads_scene(src, "x.toml")
    assert info.value.key == key and text in info.value.reason, info.value


def test_bad_systems():
    # decreasing angles
    with pytest.raises(InputError, match="increase"):
        loads_scene(scene_text([{"angle": "0 deg", "s": "0 mm"}, {"angle": "90 deg", "s": "1 mm"},
                                {"angle": "80 deg", "s": "0 mm"}]), "x.toml")
    # a lift below the base circle
    with pytest.raises(InputError, match="dips below the base circle"):
        loads_scene(scene_text([{"angle": "0 deg", **REST}, {"angle": "30 deg", "s": "-1 mm"},
                                {"angle": "60 deg", "s": "10 mm", "v": "0 m/s"}, {"angle": "120 deg", **REST}]), "x.toml")
    # more conditions than a unique lift allows: the same value twice on one segment's ends
    with pytest.raises(InputError, match="never leaves the base circle"):
        loads_scene(scene_text([{"angle": "0 deg", "s": "0 mm"}, {"angle": "120 deg", "s": "0 mm"}]), "x.toml")
    # five conditions on a segment of four coefficients (C = 7 on two segments): singular
    with pytest.raises(InputError, match="not independent"):
        loads_scene(scene_text([{"angle": "0 deg", **REST4}, {"angle": "60 deg", "s": "5 mm"},
                                {"angle": "120 deg", "s": "0 mm"}], continuity=0), "x.toml")
    with pytest.raises(InputError, match="not used by law 'spline'"):
        loads_scene(scene_text(rise_return(REST, {"s": "10 mm", "v": "0 m/s"}), extra="").replace(
            'start = "30 deg"', 'start = "30 deg"\nheight = "1 mm"'), "x.toml")


def test_known_optimum_minimum_jerk_is_345():
    """Flash & Hogan (1985): between rest positions (s, v, a given) the integral of the squared
    jerk is least for the 3-4-5 polynomial. Stations in the middle of each flank with all four
    values free; the optimiser must find the 3-4-5 rise and return."""
    free = {"s": "free", "v": "free", "a": "free", "j": "free"}
    stations = [{"angle": "0 deg", **REST}, {"angle": "30 deg", **free}, {"angle": "70 deg", "s": "10 mm", "v": "0 m/s", "a": "0 m/s**2"},
                {"angle": "100 deg", **free}, {"angle": "140 deg", **REST}]
    scene = loads_scene(scene_text(stations, continuity=2))
    report = design(scene, "jerk-energy", DesignLimits())
    assert report.success
    from explorer.lift.spline import solve_spline

    lift = solve_spline(report.options.stations, 2, scene.lift.start)
    beta = math.radians(70)
    reference = LawLift(H, scene.lift.start, beta, 0.0, beta, "polynomial-345", "polynomial-345")
    theta = np.linspace(0, 2 * math.pi, 3601)
    assert np.max(np.abs(lift.derivatives(theta)[0] - reference.derivatives(theta)[0])) < 1e-9 * H * 1e3  # 1e-8 m
    value_345 = evaluate(scene, reference, "jerk-energy", DesignLimits())[0]
    assert report.value == pytest.approx(value_345, rel=1e-8)
    assert report.value <= min(v for v, _ in report.comparison.values()) * (1 + 1e-9)  # (3-4-5 is among them)


def _minimum_jerk_with_area(area_factor):
    """The scene of test_known_optimum_minimum_jerk_is_345 without lash, the open area held at
    area_factor times the 3-4-5's, and the analytic optimum (see the test)."""
    free = {"s": "free", "v": "free", "a": "free", "j": "free"}
    stations = [{"angle": "0 deg", **REST}, {"angle": "30 deg", **free}, {"angle": "70 deg", "s": "10 mm", "v": "0 m/s", "a": "0 m/s**2"},
                {"angle": "100 deg", **free}, {"angle": "140 deg", **REST}]
    scene = loads_scene(scene_text(stations, continuity=2).replace('lash = "0.3 mm"', 'lash = "0 mm"'))
    beta = math.radians(70)
    area = area_factor * H * beta  # the 3-4-5 rise and return enclose h beta / 2 each
    # Euler-Lagrange of  integral (s''')^2 + lambda integral s:  s^(6) = const on each flank, with
    # s, v, a given at both ends: s = h P345(u) + c u^3 (1 - u)^3, u = theta / beta, the same c on
    # both flanks (one lambda); integral of u^3 (1 - u)^3 over [0, 1] = B(4, 4) = 1/140
    c = 140.0 * (area / (2.0 * beta) - H / 2.0)

    def exact(theta):
        x = np.mod(theta - scene.lift.start, 2 * math.pi)
        u = np.where(x < beta, x / beta, np.where(x < 2 * beta, (2 * beta - x) / beta, 0.0))
        bump = np.where(x < 2 * beta, u**3 * (1 - u) ** 3, 0.0)
        return H * (10 * u**3 - 15 * u**4 + 6 * u**5) + c * bump

    return scene, area, exact


@pytest.mark.parametrize("area_factor", [0.9, 1.0, 1.15])
def test_known_optimum_minimum_jerk_with_the_open_area_held(area_factor):
    """With the valve's open area held (an equality), the minimum of the squared jerk is the 3-4-5
    plus the multiple of u^3 (1 - u)^3 that gives that area (Euler-Lagrange with a multiplier for
    the area; at factor 1 the 3-4-5 itself). The optimiser must find it, and hold the area."""
    from scipy.integrate import quad

    from explorer.lift.spline import solve_spline

    scene, area, exact = _minimum_jerk_with_area(area_factor)
    report = design(scene, "jerk-energy", DesignLimits(open_area=area))
    assert report.success and report.slacks["open area [mm*deg]"] == 0.0 and report.open_area == area
    lift = solve_spline(report.options.stations, 2, scene.lift.start)
    theta = np.linspace(0, 2 * math.pi, 7201)
    assert np.max(np.abs(lift.derivatives(theta)[0] - exact(theta))) < 1e-9  # m (optimiser's ftol 1e-14)
    start = scene.lift.start
    inside = quad(lambda t: float(lift.derivatives(np.array([t]))[0][0]), start, start + math.radians(140),
                  limit=200, points=[start + math.radians(a) for a in (30, 70, 100)], epsabs=1e-15, epsrel=1e-13)[0]
    assert inside == pytest.approx(area, rel=1e-9)  # the held area by independent quadrature


def _quad_open_area(scene, lift):
    """The valve's open area by scipy quad between the lift's breakpoints and its lash crossings."""
    from scipy.integrate import quad

    from explorer.mechanics.kinematics import lash_crossings

    ratio, lash = scene.follower.ratio, scene.valve.lash
    ups, downs = lash_crossings(lift, ratio, lash)
    marks = np.sort(np.mod(np.concatenate([lift.breakpoints(), ups, downs]) - scene.lift.start, 2 * math.pi))
    edges = np.unique(np.concatenate([[0.0], marks, [2 * math.pi]]))
    return sum(quad(lambda x: max(ratio * float(lift.derivatives(np.array([scene.lift.start + x]))[0][0]) - lash, 0.0),
                    a, b, epsabs=0.0, epsrel=1e-13, limit=200)[0] for a, b in zip(edges[:-1], edges[1:]))


def test_design_holds_the_exact_open_area():
    """`explorer design --open-area "700 mm*deg"` on spline_demo: the optimum's open area by quad
    (split at its lash crossings) is 700 mm*deg to 1e-9 relative (the optimiser's Gauss-Legendre
    stand-in, with the lash's kink inside its panels, alone was 4.9e-7 off)."""
    scene = load_scene(DEMO)
    area = math.radians(0.7)  # 700 mm*deg in m*rad
    report = design(scene, "jerk-energy", DesignLimits(open_area=area))
    assert report.success and report.slacks["open area [mm*deg]"] == 0.0 and "projected" in report.message
    lift = solve_spline(report.options.stations, report.options.continuity, scene.lift.start)
    assert _quad_open_area(scene, lift) == pytest.approx(area, rel=1e-9)


def test_the_projection_onto_the_exact_area_keeps_an_active_limit():
    """With the pressure angle active at the optimum (17 deg on spline_demo's peak acceleration),
    a projection along the area's gradient alone broke it by 9.5e-6 deg; moving only in the null
    space of the active limits' Jacobian keeps it (main reported -3.5e-12 deg there) and meets the
    exact area (quad, 1e-9)."""
    scene = load_scene(DEMO)
    report = design(scene, "peak-acceleration", DesignLimits(max_pressure_angle=math.radians(17), open_area="keep"))
    assert report.success and report.slacks["pressure angle [deg]"] >= -1e-9
    assert -1e-6 < report.slacks["pressure angle [deg]"] < 1e-3  # active indeed
    lift = solve_spline(report.options.stations, report.options.continuity, scene.lift.start)
    assert _quad_open_area(scene, lift) == pytest.approx(report.open_area, rel=1e-9)


def test_open_area_kept_costs_peak_acceleration_and_standard_laws_are_judged_by_it(capsys):
    """--open-area keep: the optimum holds the starting lift's area; the freedom it takes away can
    only raise the optimum; the standard laws on the same event (another area) are marked."""
    scene = load_scene(DEMO)
    free = design(scene, "peak-acceleration", DesignLimits())
    kept = design(scene, "peak-acceleration", DesignLimits(open_area="keep"))
    assert kept.success and kept.slacks["open area [mm*deg]"] == 0.0
    # the area held is the starting lift's and the optimum's, both by quad split at the lash crossings
    # (Brent on the lift: independent of the closed form per piece), to 1e-9
    start_lift = build_lift(scene)
    assert _quad_open_area(scene, start_lift) == pytest.approx(kept.open_area, rel=1e-12)
    assert _quad_open_area(scene, solve_spline(kept.options.stations, kept.options.continuity, scene.lift.start)) \
        == pytest.approx(kept.open_area, rel=1e-9)
    assert free.value <= kept.value * (1 + 1e-9) and kept.value < kept.start_value
    assert any(slacks["open area [mm*deg]"] < 0 for _, slacks in kept.comparison.values())
    assert cli.main(["design", str(DEMO), "--objective", "jerk-energy", "--open-area", "700 mm*deg"]) == 0
    out = capsys.readouterr().out
    assert "open area held at 700 mm*deg" in out and "open area [mm*deg] 0" in out


def test_peak_acceleration_beats_every_standard_law_and_the_linear_programme_agrees():
    scene = load_scene(DEMO)
    limits = DesignLimits(max_pressure_angle=math.radians(30), radius_margin=0.002, contact_margin=20.0, contact_rpm=2000)
    report = design(scene, "peak-acceleration", limits)
    assert report.success and all(v >= 0 for v in report.slacks.values())
    best_standard = min(v for v, slacks in report.comparison.values() if min(slacks.values()) >= 0)
    assert report.value < best_standard
    # an independent check of optimality: HiGHS on the same LP (no nonlinear limit is active)
    from explorer.studies.design import Problem, _peak_by_linear_programme

    problem = Problem(scene, "peak-acceleration", DesignLimits())
    z = _peak_by_linear_programme(scene, problem, 2, 1.0, DesignLimits())
    lp = float(np.max(np.abs(scene.omega**2 * problem.derivatives(z)[2])))
    assert report.value <= lp * (1 + 1e-6)


def test_design_command_and_toml_round_trip(tmp_path, capsys):
    assert cli.main(["design", str(DEMO), "--objective", "peak-acceleration", "--max-pressure-angle", "30 deg"]) == 0
    text = capsys.readouterr().out
    assert "limits met" in text and "modified-trapezoid" in text and "pressure angle [deg]" in text
    assert cli.main(["design", str(DEMO), "--objective", "peak-acceleration", "--toml"]) == 0
    stations = capsys.readouterr().out
    scene_file = tmp_path / "optimised.toml"
    original = DEMO.read_text()
    head = original[: original.index("[[lift.stations]]")]
    tail = original[original.index("[follower]"):]
    scene_file.write_text(head + stations + "\n" + tail)
    optimised = load_scene(scene_file)
    value = evaluate(optimised, build_lift(optimised), "peak-acceleration", DesignLimits())[0]
    assert value < 1100.0  # below the modified trapezoid's 1099.8 m/s**2 on this event


@pytest.mark.parametrize("args,key", [
    (["--objective", "peak-jerk", "--max-pressure-angle", "95 deg"], "--max-pressure-angle"),
    (["--objective", "residual-vibration", "--band", "3:2"], "--band"),
    (["--objective", "peak-jerk", "--radius-margin", "-2 mm"], "--radius-margin"),
    (["--objective", "peak-jerk", "--contact-margin", "2 mm"], "--contact-margin"),
    (["--objective", "peak-jerk", "--open-area", "7 N"], "--open-area"),
    (["--objective", "peak-jerk", "--open-area", "5 mm"], "--open-area"),
    (["--objective", "peak-jerk", "--open-area", "0 mm*deg"], "--open-area"),
    (["--objective", "peak-jerk", "--open-area", "-5 mm*deg"], "--open-area"),
])
def test_design_bad_options(capsys, args, key):
    assert cli.main(["design", str(DEMO), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert ERROR_LINE.match(err) and f": {key}: " in err, err


def test_design_needs_a_spline_with_free_values(capsys):
    assert cli.main(["design", str(SCENES / "cycloidal_demo.toml"), "--objective", "peak-jerk"]) == 2
    assert "spline lift" in capsys.readouterr().err
