"""The translating roller's geometry figures (largest pressure angle, smallest convex pitch and
contour radius, smallest concave contour radius) are exact, not the run's samples'
(explorer.effects.contour.geometry_extremes), checked against an independent oracle: the closed
forms for a translating roller on a cycloidal law (Norton, Cam Design and Manufacturing Handbook,
ch. 7): tan(phi) = (s' - e) / (sqrt(rp^2 - e^2) + s), s' per radian, and for e = 0 the pitch-curve
radius rho = ((rp + s)^2 + s'^2)^1.5 / ((rp + s)^2 + 2 s'^2 - (rp + s) s''), the cycloidal law's
derivatives written out here, the extremes found by a dense scan refined by scipy's bounded
minimiser. Tolerance 1e-9 relative: the figures are values at a stationary point (first-order
insensitive to the angle), so both sides agree to rounding; 1e-9 leaves room for the flatness."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from explorer.effects.contour import geometry_columns
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

from conftest import SCENES

CYCLOIDAL = SCENES / "cycloidal_demo.toml"
REL = 1e-9


def cycloidal(x, h, beta, rising: bool):
    """s, s', s'' (per radian) of a cycloidal rise (or return) of height h over beta at x in [0, beta]."""
    u = 2.0 * math.pi * x / beta
    s = h * (x / beta - np.sin(u) / (2.0 * math.pi))
    s1 = h / beta * (1.0 - np.cos(u))
    s2 = 2.0 * math.pi * h / beta**2 * np.sin(u)
    return (s, s1, s2) if rising else (h - s, -s1, -s2)


def norton(scene):
    """(max |phi| deg, min convex pitch radius m, min concave contour radius m or None) of the scene's
    cycloidal cam, from the closed forms (module doc), refined to the extremum."""
    f, lw = scene.follower, scene.lift
    rp, e = f.base_radius + f.roller_radius, f.offset
    h = lw.height

    def curves(x, beta, rising):
        s, s1, s2 = cycloidal(x, h, beta, rising)
        phi = np.arctan((s1 - e) / (math.sqrt(rp * rp - e * e) + s))
        y = rp + s  # e = 0 for rho (Norton's form)
        rho = (y * y + s1 * s1) ** 1.5 / (y * y + 2.0 * s1 * s1 - y * s2)
        return phi, rho

    phis, convex, concave = [], [rp], []
    for beta, rising in ((lw.rise, True), (lw.ret, False)):
        x = np.linspace(0.0, beta, 200001)
        phi, rho = curves(x, beta, rising)

        def refine(g, i):
            lo, hi = x[max(i - 1, 0)], x[min(i + 1, x.size - 1)]
            r = minimize_scalar(g, bounds=(lo, hi), method="bounded", options={"xatol": 1e-15, "maxiter": 500})
            return min(float(r.fun), float(g(x[i])))

        i = int(np.argmax(np.abs(phi)))
        phis.append(-refine(lambda t: -abs(curves(t, beta, rising)[0]), i))
        if e == 0.0:
            pos = np.where(rho > 0.0, rho, np.inf)
            convex.append(refine(lambda t: curves(t, beta, rising)[1] if curves(t, beta, rising)[1] > 0 else np.inf,
                                 int(np.argmin(pos))))
            if np.any(rho < 0.0):
                neg = np.where(rho < 0.0, -rho, np.inf)
                concave.append(refine(lambda t: -curves(t, beta, rising)[1] if curves(t, beta, rising)[1] < 0 else np.inf,
                                      int(np.argmin(neg))))
    return (math.degrees(max(phis)), min(convex),
            (min(concave) + f.roller_radius) if concave else None)


def summary(scene, steps: int) -> dict:
    lift = build_lift(scene)
    theta = np.arange(steps) * (2.0 * math.pi / steps)
    return geometry_columns(scene, theta, lift.derivatives(theta), 0.0, lift)[1]


CASES = [
    [],  # the demo as shipped: 70 deg rise and return
    ['lift.rise="25 deg"', 'lift.return="35 deg"', 'follower.roller_radius="5 mm"'],
    ['lift.rise="40 deg"', 'lift.dwell="10 deg"', 'lift.return="30 deg"', 'follower.base_radius="20 mm"',
     'follower.roller_radius="4 mm"'],
]


@pytest.mark.parametrize("overrides", CASES)
@pytest.mark.parametrize("steps", [360, 3600])
def test_extremes_match_closed_forms(overrides, steps):
    scene = load_scene(CYCLOIDAL, overrides)
    phi, rho, concave = norton(scene)
    got = summary(scene, steps)
    assert got["max_abs_pressure_angle_deg"] == pytest.approx(phi, rel=REL)
    assert got["min_convex_pitch_radius_m"] == pytest.approx(rho, rel=REL)
    assert got["min_convex_contour_radius_m"] == pytest.approx(rho - scene.follower.roller_radius, rel=REL)
    if concave is None:
        assert got["min_concave_contour_radius_m"] is None
    else:
        assert got["min_concave_contour_radius_m"] == pytest.approx(concave, rel=REL)


def test_offset_pressure_angle_matches_closed_form():
    """With an offset (e = 5 mm) the rise and return differ; the larger |phi| is the figure."""
    scene = load_scene(CYCLOIDAL, ['follower.offset="5 mm"', 'lift.rise="30 deg"', 'lift.return="50 deg"',
                                   'follower.roller_radius="5 mm"'])
    assert summary(scene, 720)["max_abs_pressure_angle_deg"] == pytest.approx(norton(scene)[0], rel=REL)


def test_extremes_do_not_move_with_steps():
    """The figures of a short event (a 3 deg rise, where 360 steps hold 3 samples) at 360 and 36000
    steps: the same to rounding, and at least the sampled columns' extremes."""
    scene = load_scene(CYCLOIDAL, ['lift.rise="3 deg"', 'lift.return="3 deg"', 'follower.roller_radius="0.3 mm"',
                                   'lift.height="1 mm"'])
    coarse, fine = summary(scene, 360), summary(scene, 36000)
    for key in ("max_abs_pressure_angle_deg", "min_convex_pitch_radius_m", "min_convex_contour_radius_m"):
        assert coarse[key] == pytest.approx(fine[key], rel=1e-12), key
    phi, rho, _ = norton(scene)
    assert fine["max_abs_pressure_angle_deg"] == pytest.approx(phi, rel=REL)
    assert fine["min_convex_pitch_radius_m"] == pytest.approx(rho, rel=REL)


def test_schenker_fig2_pressure_angle_is_its_limit_at_f():
    """Schenker's Fig. 2 (schenker1902_fig2.toml: arcs EF and FG meet at F, where the acceleration
    jumps -117 -> +159 m/s^2): the largest pressure angle is the one-sided limit at the junction F,
    49.962 deg (an audit's hand figure; the scene's comment says 49.9 deg), not the 3600 samples'
    49.938 deg, and it is placed at F."""
    from explorer.lift.contours.translating import pitch_geometry

    scene = load_scene(SCENES / "schenker1902_fig2.toml")
    lift = build_lift(scene)
    got = summary(scene, 3600)
    f = scene.follower
    # F: the breakpoint where the sampled maximum lies (the nose EF meets the flank FG)
    marks = np.mod(lift.breakpoints(), 2.0 * math.pi)
    at_f = float(marks[np.argmin(np.abs(np.degrees(marks) - 147.5))])
    sides = np.array([at_f - 1e-12, at_f + 1e-12])
    phi, _ = pitch_geometry(lift.derivatives(sides), f.base_radius, f.roller_radius, f.offset)
    assert got["max_abs_pressure_angle_deg"] == pytest.approx(math.degrees(np.abs(phi).max()), rel=REL)
    assert round(got["max_abs_pressure_angle_deg"], 3) == 49.962
    assert got["max_abs_pressure_angle_at_deg"] == pytest.approx(math.degrees(at_f), abs=1e-6)


def test_schenker_fig2_arcs_radii_without_a_search_per_sample(monkeypatch):
    """On a circular arc the pitch radius is constant (arc radius + roller radius convex, arc radius
    - roller radius concave), so its rate is rounding and changes sign at random samples (1599 of
    them on Schenker's Fig. 2: 2 s of Brent searches a run before). Those brackets are not searched
    (contour.RATE_ROUNDING), and the figures are still the arcs' own: the nose EF (9.46 mm) + the
    10 mm roller as the smallest convex pitch radius, and FG's 86.1 mm as the smallest concave
    contour radius, to rounding. The searches left are bounded by the genuine extrema (a few)."""
    import explorer.effects.contour as contour

    calls = []
    real = contour.roots_in

    def counting(*args, **kwargs):  # one search per bracket (roots_in runs them all at once)
        calls.extend(np.asarray(args[1]).reshape(-1))
        return real(*args, **kwargs)

    monkeypatch.setattr(contour, "roots_in", counting)
    got = summary(load_scene(SCENES / "schenker1902_fig2.toml"), 3600)
    assert got["min_convex_pitch_radius_m"] == pytest.approx(9.46e-3 + 10e-3, rel=1e-12)
    assert got["min_convex_contour_radius_m"] == pytest.approx(9.46e-3, rel=1e-12)
    assert got["min_concave_contour_radius_m"] == pytest.approx(86.1e-3, rel=1e-12)
    assert len(calls) <= 10, len(calls)


def test_rounding_filter_keeps_every_true_extremum():
    """The filter drops a bracket only where the rate is below RATE_ROUNDING of its terms at both
    ends; at the true extrema of every built-in translating-roller cam the rate is 5e-3 of its terms
    or more at one end, so the figures are those found with no filter (the filter set to -1)."""
    import explorer.effects.contour as contour

    for path in sorted(SCENES.glob("*.toml")):
        scene = load_scene(path)
        if not getattr(scene.follower, "roller_envelope", False) or path.stem == "schenker1902_fig2":
            continue
        lift = build_lift(scene)
        filtered = contour.geometry_extremes(lift, scene.follower)
        old = contour.RATE_ROUNDING
        try:
            contour.RATE_ROUNDING = -1.0
            unfiltered = contour.geometry_extremes(lift, scene.follower)
        finally:
            contour.RATE_ROUNDING = old
        for a, b in zip(filtered, unfiltered):
            np.testing.assert_array_equal(a, b, err_msg=path.stem)


@pytest.mark.parametrize("name", ["schenker1902_fig2", "valve_float_demo", "cycloidal_demo"])
def test_contact_reports_the_same_exact_pressure_angle(name):
    """The contact effect's max_pressure_angle_deg is the kinematics' refined extremum (one figure
    under both names; before, the contact's was the samples': 49.938 deg against 49.962 on Fig. 2)."""
    import explorer

    scene = load_scene(SCENES / f"{name}.toml", ['effects=["kinematics", "lash", "forces", "contact"]'])
    s = explorer.simulate(scene).summary
    assert s["max_pressure_angle_deg"] == s["max_abs_pressure_angle_deg"]
    assert s["max_pressure_angle_cam_angle_deg"] == s["max_abs_pressure_angle_at_deg"]
    sampled = float(np.abs(explorer.simulate(scene).columns["pressure_angle_deg"]).max())
    assert s["max_pressure_angle_deg"] >= sampled
