"""A polydyne cam whose wanted valve lift is a spline (lift.law = "polydyne", wanted_law = "spline").

Oracles: the conditions of the stations read off the solved polynomials directly (numpy's own
Polynomial, not the code's evaluation), to 1e-12 relative; the exact elastic solver at the design
speed, which must follow the wanted spline to 1e-9 m as it does for the closed-form laws
(tests/test_polydyne.py); the one degree-9 polynomial with s, v, a, j, snap given at both ends of a
rise (126 u^5 - 420 u^6 + 540 u^7 - 315 u^8 + 70 u^9, the 5-6-7-8-9 law: its ten end conditions
fix it), which the spline must reproduce and the cam must follow through the polydyne formula.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from conftest import SCENES
from test_polydyne import elastic_follows  # (the wanted lift against simulate, one definition)
from explorer import cli
from explorer.core.errors import InputError
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene, loads_scene

DEMO = SCENES / "polydyne_spline.toml"
ERROR_LINE = re.compile(r"^error: [^:\n]+: [^:\n]+: .+$")
H = 0.01


def station_conditions_hold(lift, options, h, tolerance=1e-12):
    """Every given value on both sides of its station, every derivative up to the continuity
    continuous at interior stations, and s to the snap 0 at both ends: read off the polynomials."""
    spline = lift.wanted.spline
    knots, coefficients = spline.knots, spline.coefficients
    last = len(knots) - 1

    def side(segment, u, k):
        p = np.polynomial.Polynomial(coefficients[segment]).deriv(k) if k else np.polynomial.Polynomial(coefficients[segment])
        return p(u) / (knots[segment + 1] - knots[segment]) ** k

    # "relative": to the largest size of that derivative at the stations, and at least h / beta^k
    n = len(coefficients)
    sizes = [max(abs(side(seg, u, k)) for seg in range(n) for u in (0.0, 1.0)) for k in range(options.continuity + 1)]
    checked = 0
    for i, st in enumerate(options.stations):
        sides = ([(i - 1, 1.0)] if i > 0 else []) + ([(i, 0.0)] if i < last else [])
        beta = min(knots[s + 1] - knots[s] for s, _ in sides)
        for k in range(options.continuity + 1):
            scale = max(h / beta**k, sizes[k])
            got = [side(seg, u, k) for seg, u in sides]
            value = st.values[k] if k < len(st.values) else None
            if value is not None:
                assert all(abs(g - value) <= tolerance * scale for g in got), (i, k, got, value)
            if len(got) == 2:
                assert abs(got[0] - got[1]) <= tolerance * scale, (i, k, got)
            elif k <= 4:  # an end: at rest to the snap, so the event joins the take-up ramp smoothly
                assert abs(got[0]) <= tolerance * scale, (i, k, got)
            checked += 1
    return checked


@pytest.mark.parametrize("continuity", [4, 5, 6])
def test_conditions_met_to_1e_12(continuity):
    scene = load_scene(DEMO, [f"lift.continuity={continuity}"])
    lift = build_lift(scene)
    assert station_conditions_hold(lift, scene.lift.options.spline, H) >= 5 * (continuity + 1)
    # the given values in time units at the design speed, as written in the scene
    w = scene.omega
    top = lift.wanted.derivatives(np.array([math.radians(80)]), 2)[:, 0]
    assert top[0] == pytest.approx(H, rel=1e-12) and abs(top[1]) < 1e-12
    assert top[2] * w**2 == pytest.approx(-1000.0, rel=1e-12)


def test_reproduces_the_56789_polynomial_and_the_cam_is_its_polydyne():
    """Rest to the snap at 0, 10 mm at rest to the snap at 80 deg and back: each segment is the
    5-6-7-8-9 polynomial; the cam is [lash + s + (M w^2 s'' + W(s))/k]/ratio of it."""
    text = DEMO.read_text()
    text = re.sub(r'\[\[lift.stations\]\]\nangle = "(40|120) deg"\ns = "5 mm"\n\n', "", text)
    text = text.replace('a = "-1000 m/s**2"\n', 'a = "0 m/s**2"\nj = "0 m/s**3"\nsnap = "0 m/s**4"\n')
    scene = loads_scene(text, "x.toml", ["follower.ratio=1.3", "follower.roller_radius=\"5 mm\""])
    lift = build_lift(scene)
    assert [len(c) for c in lift.wanted.spline.coefficients] == [10, 10]
    beta = math.radians(80)
    law = np.polynomial.Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])
    u = np.linspace(0.0, 1.0, 801)
    x = np.concatenate([u * beta, beta + u[1:-1] * beta])
    s = np.concatenate([H * law(u), H * law(1.0 - u[1:-1])])
    s2 = np.concatenate([H * law.deriv(2)(u), H * law.deriv(2)(1.0 - u[1:-1])]) / beta**2
    d = lift.wanted.derivatives(x, 2)
    # the solve is exact but for rounding in a 20 x 20 system of degree-9 monomials: ~1e-12 relative
    assert np.max(np.abs(d[0] - s)) <= 1e-11 * H and np.max(np.abs(d[2] - s2)) <= 1e-10 * H / beta**2
    v, sp, k, w = scene.valve, scene.spring, scene.linkage.stiffness, scene.omega
    cam = (v.lash + s + (v.mass * w**2 * s2 + sp.preload + sp.rate * s) / k) / 1.3
    got = lift.derivatives(scene.lift.start + x)[0]
    np.testing.assert_allclose(got, cam, rtol=1e-11, atol=1e-15)
    deviation, _, _ = elastic_follows(scene)
    assert deviation <= 1e-9


def test_cam_continuous_to_its_acceleration():
    """C4 wanted lift, at rest to the snap at the ends, cycloidal ramps: the cam's lift, slope and
    curvature (L, L', L'') are continuous at every breakpoint, the event's and the ramps'."""
    lift = build_lift(load_scene(DEMO))
    scale = (1e-3, 1e-3, 1e-3)
    for b in lift.breakpoints():
        left, right = lift.derivatives(np.array([b - 1e-10, b + 1e-10])).T
        for k in range(3):
            # the step is the next derivative times 2e-10 rad: below 1e-12 m per rad^k here
            assert abs(left[k] - right[k]) <= 1e-12 + 1e-6 * scale[k], (math.degrees(b), k, left, right)


CASES = {
    "demo": [],
    "ratio, M1, no lash": ["follower.ratio=1.6", "valve.oscillating_mass=\"0.09 kg\"", "valve.lash=0",
                           "spring.preload=\"400 N\""],
    "stiff, light, slow (stations at 2000 rpm)": ["linkage.stiffness=\"5e7 N/m\"", "valve.mass=\"0.05 kg\"", "drive.rpm=600",
                                                "lift.design_rpm=600", "lift.reference_rpm=2000"],
    "soft linkage, closing load, C6": ["linkage.stiffness=\"3e5 N/m\"", "loads.closing.gas=\"40 N\"", "drive.rpm=1200",
                                       "lift.design_rpm=1200", "lift.ramp=\"35 deg\"", "lift.continuity=6",
                                       "solver.steps_per_revolution=7200"],
}


@pytest.mark.parametrize("case", CASES)
def test_valve_follows_the_wanted_spline_at_design_speed(case):
    """The issue's oracle for a spline wanted lift: |s - s_wanted| <= 1e-9 m over the revolution
    (measured ~5e-16 m for the demo)."""
    scene = load_scene(DEMO, CASES[case])
    deviation, velocity_error, result = elastic_follows(scene)
    assert deviation <= 1e-9
    assert velocity_error <= 1e-6
    lift = build_lift(scene)
    theta = np.radians(result.columns["cam_angle_deg"])
    cam = scene.follower.ratio * lift.derivatives(theta)[0] - scene.valve.lash
    assert np.max(np.abs(cam - lift.wanted_valve_lift(theta, 0)[0])) > 1e-4  # an elastic problem, not the rigid one
    kinds = [e["kind"] for e in result.events if e.get("effect") == "elastic"]
    assert "separation" not in kinds


def test_off_design_the_valve_deviates():
    """The cam is exact only at its design speed: 10 % slower, the valve is microns off."""
    deviation, _, _ = elastic_follows(load_scene(DEMO, ["drive.rpm=1800"]))
    assert deviation > 1e-7


ROUGH = [
    (["lift.continuity=2"], "lift.continuity", "jerk continuous"),
    (["lift.continuity=1"], "lift.continuity", "acceleration continuous"),
]


@pytest.mark.parametrize("overrides,key,text", ROUGH)
def test_too_low_continuity_names_the_derivative(overrides, key, text):
    with pytest.raises(InputError) as info:
        load_scene(DEMO, overrides)
    assert info.value.key == key and text in info.value.reason and "too rough" in info.value.reason, info.value.reason


def _replaced(text, station_angle, line, new):
    block_start = text.index(f'angle = "{station_angle} deg"')
    block_end = text.find("[[lift.stations]]", block_start)
    block_end = len(text) if block_end < 0 else block_end
    block = text[block_start:block_end]
    assert line in block
    return text[:block_start] + block.replace(line, new, 1) + text[block_end:]


@pytest.mark.parametrize("angle,line,new,derivative", [
    ("0", 'j = "0 m/s**3"', 'j = "100 m/s**3"', "jerk"),
])
def test_end_not_at_rest_names_the_derivative(tmp_path, capsys, angle, line, new, derivative):
    """An end not at rest to the snap makes that derivative jump onto the ramp: one line, naming
    the station and the derivative, exit 2, nothing written."""
    scene = tmp_path / "rough.toml"
    scene.write_text(_replaced(DEMO.read_text(), angle, line, new))
    out = tmp_path / "x.csv"
    assert cli.main(["simulate", str(scene), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert ERROR_LINE.match(err), err
    assert f": lift.stations[{0 if angle == '0' else 4}]: " in err and f"{derivative} continuous" in err, err
    assert "too rough" in err and not out.exists()


BAD = [
    (["lift.height=\"10 mm\""], "lift.height", "not used with wanted_law"),
    (["lift.rise=\"80 deg\""], "lift.rise", "not used with wanted_law"),
    (["lift.continuity=7"], "lift.continuity", ""),
    (["lift.ramp=\"110 deg\""], "lift.ramp", "exceed 360 deg"),
    (["lift.design_rpm=6000"], "lift.design_rpm", "would have to pull"),
    (["lift.wanted_law=\"polynomial-4567\"", "lift.height=\"10 mm\"", "lift.rise=\"70 deg\""], "lift.stations",
     "only with wanted_law"),
]


@pytest.mark.parametrize("overrides,key,text", BAD)
def test_bad_spline_polydyne_scenes(tmp_path, capsys, overrides, key, text):
    out = tmp_path / "x.csv"
    assert cli.main(["simulate", str(DEMO), "-o", str(out), *sum((["--set", o] for o in overrides), [])]) == 2
    err = capsys.readouterr().err.strip()
    assert ERROR_LINE.match(err) and f": {key}" in err and text in err, err
    assert not out.exists()


def test_free_values_are_refused():
    text = DEMO.read_text().replace('angle = "40 deg"\ns = "5 mm"', 'angle = "40 deg"\ns = "free"')
    with pytest.raises(InputError) as info:
        loads_scene(text, "x.toml")
    assert info.value.key == "lift.stations[1].s" and "explorer design" in info.value.reason


def test_an_end_not_at_rest_in_its_snap_warns_of_the_cam_acceleration_step(tmp_path):
    """A toy spline: the demo's last station with snap = 1e6 m/s**4 (at the design speed, the
    reference). Its snap drops from 1e6 to 0 onto the ramp, so the cam's acceleration
    [s'' (1 + rate/k) + (M w^2/k) s^(4)] steps by -(M/k) 1e6 m/s**4 = -0.06 m/s**2 there (the w^4 of
    the snap's time units and of the formula cancel at the design speed). The same rule as the
    closed forms': the run goes on and warns once, naming the station, its cam angle and the step."""
    from explorer.effects.pipeline import simulate
    from explorer.lift.polydyne import acceleration_steps

    scene = loads_scene(_replaced(DEMO.read_text(), "160", 'snap = "0 m/s**4"', 'snap = "1e6 m/s**4"'), "toy.toml")
    steps = acceleration_steps(build_lift(scene))
    assert len(steps) == 1 and math.degrees(steps[0].cam_angle) == pytest.approx(60 + 160, abs=1e-9)
    assert steps[0].jump == pytest.approx(-0.12 / 2e6 * 1e6, rel=1e-9)
    lines = [w for w in simulate(scene).warnings if w.startswith("polydyne:")]
    assert len(lines) == 1 and "-0.06 m/s**2 at cam angle 220 deg (station 4" in lines[0], lines
    assert "spline" in lines[0] and "polynomial-56789" in lines[0]


def test_continuity_3_warns_at_the_interior_stations():
    """continuity = 3 leaves the snap free to jump at the interior stations (40, 80, 120 deg): the
    cam's acceleration steps there (warned, as for a closed form), each step (M w^4/k) times the
    snap's jump read off the polynomials on both sides (numpy's own derivatives of the coefficients)."""
    from explorer.lift.polydyne import acceleration_steps

    scene = load_scene(DEMO, ["lift.continuity=3"])
    lift = build_lift(scene)
    spline, w = lift.wanted.spline, scene.omega
    steps = acceleration_steps(lift)
    assert [round(math.degrees(s.cam_angle), 9) for s in steps] == [100, 140, 180]
    for s, i in zip(steps, (1, 2, 3)):
        widths = np.diff(spline.knots)
        snap = [np.polynomial.Polynomial(spline.coefficients[j]).deriv(4)(u) / widths[j] ** 4
                for j, u in ((i - 1, 1.0), (i, 0.0))]
        assert s.jump == pytest.approx(0.12 * w**4 / 2e6 * (snap[1] - snap[0]), rel=1e-9)
    assert len(lift.warnings) == 1 and "station 2" in lift.warnings[0]
