"""The valve's open area, exact: the integral over cam angle of max(ratio L - lash, 0)
(explorer.lift.open_area for polynomial pieces; explorer.studies.design.exact_open_area for any lift).

Oracles:
- closed forms with lash, derived here. Harmonic rise L = h (1 - cos pi u) / 2 over beta, rocker
  ratio r, c = lash / (r h): the valve opens where cos(pi u) < 1 - 2c, past u_c, and
  A_rise = beta [(r h / 2 - lash)(1 - u_c) + r h sin(pi u_c) / (2 pi)].
  Cycloidal rise L = h (u - sin(2 pi u) / (2 pi)): u_c solves L(u_c) = lash / r and
  A_rise = beta [r h ((1 - u_c^2) / 2 + (1 - cos 2 pi u_c) / (4 pi^2)) - lash (1 - u_c)].
  3-4-5 rise P = h (10u^3 - 15u^4 + 6u^5): A_rise = beta [r h (F(1) - F(u_c)) - lash (1 - u_c)],
  F = 2.5u^4 - 3u^5 + u^6. Each is checked against scipy quad here before it is used.
- scipy.integrate.quad with points= at the crossings (numpy's companion-matrix roots, another
  root finder than the module's), 1e-12 relative;
- a lift tangent to the lash (a double root: the lift touches the level), lash 0 (the
  polynomial's integral), lash above the peak (0), a leading coefficient of 1e-30;
- hypothesis: random polynomial pieces against quad.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.optimize import brentq

from explorer.lift.curves import LawLift
from explorer.lift.open_area import open_parts, piece_open_area, sign_cuts, spline_open_area
from explorer.studies.design import exact_open_area

H, BETA, RATIO = 0.01, math.radians(60), 1.5


def _harmonic_rise_area(h, beta, r, lash):
    c = lash / (r * h)
    uc = math.acos(1.0 - 2.0 * c) / math.pi
    return beta * ((r * h / 2 - lash) * (1 - uc) + r * h * math.sin(math.pi * uc) / (2 * math.pi))


def _cycloidal_rise_area(h, beta, r, lash):
    uc = brentq(lambda u: h * (u - math.sin(2 * math.pi * u) / (2 * math.pi)) - lash / r, 0.0, 1.0, xtol=1e-16)
    return beta * (r * h * ((1 - uc**2) / 2 + (1 - math.cos(2 * math.pi * uc)) / (4 * math.pi**2)) - lash * (1 - uc))


def _quad_rise(law, h, beta, r, lash):
    """The same area by quad, split at the crossing (found by brentq on the law)."""
    uc = brentq(lambda u: r * law(u) - lash, 0.0, 1.0, xtol=1e-16)
    return beta * quad(lambda u: r * law(u) - lash, uc, 1.0, epsabs=0, epsrel=1e-13)[0]


HARMONIC = lambda u: H * (1 - math.cos(math.pi * u)) / 2  # noqa: E731
CYCLOIDAL = lambda u: H * (u - math.sin(2 * math.pi * u) / (2 * math.pi))  # noqa: E731


@pytest.mark.parametrize("lash", [0.1e-3, 0.3e-3, 5e-3, 14e-3])
def test_the_closed_forms_against_quad(lash):
    """The closed forms of the module docstring, checked before they serve as oracles."""
    assert _harmonic_rise_area(H, BETA, RATIO, lash) == pytest.approx(_quad_rise(HARMONIC, H, BETA, RATIO, lash), rel=1e-13)
    assert _cycloidal_rise_area(H, BETA, RATIO, lash) == pytest.approx(_quad_rise(CYCLOIDAL, H, BETA, RATIO, lash), rel=1e-13)


def _scene(ratio, lash, start=0.3):
    # what exact_open_area reads of a scene: the rocker ratio, the valve's lash, the lift's start
    return SimpleNamespace(follower=SimpleNamespace(ratio=ratio), valve=SimpleNamespace(lash=lash),
                           lift=SimpleNamespace(start=start))


@pytest.mark.parametrize("law,closed", [("harmonic", _harmonic_rise_area), ("cycloidal", _cycloidal_rise_area)])
@pytest.mark.parametrize("lash", [0.1e-3, 0.3e-3, 5e-3])
def test_standard_laws_against_their_closed_form(law, closed, lash):
    """Rise, dwell, return of one law: the area (Gauss-Legendre between the breakpoints and the
    lash crossings, exact_open_area's way for a law) is twice the rise's closed form plus the dwell's
    rectangle, to 1e-12 (the crossings are Brent's to 1e-15 rad; a panel across the kink would err
    by ~1e-6)."""
    dwell = math.radians(20)
    lift = LawLift(height=H, start=0.3, rise=BETA, dwell=dwell, ret=BETA, rise_law=law, return_law=law)
    expected = 2 * closed(H, BETA, RATIO, lash) + dwell * (RATIO * H - lash)
    assert exact_open_area(_scene(RATIO, lash), lift) == pytest.approx(expected, rel=1e-12)


def _p345(h):
    return np.array([0, 0, 0, 10 * h, -15 * h, 6 * h])


@pytest.mark.parametrize("lash", [0.05e-3, 0.3e-3, 7e-3, 14.9e-3])
def test_345_piece_against_its_closed_form_and_quad(lash):
    c = _p345(H)
    P = np.polynomial.Polynomial(c)
    uc = brentq(lambda u: RATIO * P(u) - lash, 0.0, 1.0, xtol=1e-16)
    F = lambda u: 2.5 * u**4 - 3 * u**5 + u**6  # noqa: E731
    closed = BETA * (RATIO * H * (F(1.0) - F(uc)) - lash * (1 - uc))
    by_quad = BETA * quad(lambda u: max(RATIO * P(u) - lash, 0.0), 0.0, 1.0, points=[uc], epsabs=0, epsrel=1e-13)[0]
    assert closed == pytest.approx(by_quad, rel=1e-12)
    assert piece_open_area(c, BETA, RATIO, lash) == pytest.approx(closed, rel=1e-12)
    # rise and return (its mirror image P(1 - u)) as two pieces of a spline
    mirror = np.polynomial.Polynomial(c)(np.polynomial.Polynomial([1.0, -1.0])).coef
    assert spline_open_area([0.0, BETA, 2 * BETA], [c, mirror], RATIO, lash) == pytest.approx(2 * closed, rel=1e-12)


def test_lash_zero_is_the_integral_and_lash_above_the_peak_is_zero():
    c = _p345(H)
    assert piece_open_area(c, BETA, RATIO, 0.0) == pytest.approx(BETA * RATIO * H / 2, rel=1e-15)
    assert piece_open_area(c, BETA, RATIO, RATIO * H * 1.0001) == 0.0
    assert open_parts(RATIO * c - np.array([RATIO * H * 1.0001, 0, 0, 0, 0, 0])) == []


def test_a_lift_tangent_to_the_lash():
    """A double root: a bump 16 h u^2 (1 - u)^2 whose peak ratio h touches the lash (area 0, the
    valve never opens), and a lift whose minimum touches the lash from above, lash/r + k (u - 1/2)^2
    (area k/12 over the piece: the touch point is no end of an open part)."""
    bump = 16 * H * np.array([0, 0, 1, -2, 1])
    assert piece_open_area(bump, BETA, RATIO, RATIO * H) <= 1e-15 * BETA * RATIO * H
    lash, k = 0.3e-3, 0.02
    valley = np.array([lash / RATIO + k / 4, -k, k])  # lash / r + k (u - 1/2)^2
    assert piece_open_area(valley, BETA, RATIO, lash) == pytest.approx(BETA * RATIO * k / 12, rel=1e-12)
    assert len(open_parts(RATIO * valley - np.array([lash, 0, 0]))) == 1  # one part: [0, 1]
    # slightly below the touch: two simple roots 2e-4 apart, the dip's area (2/3)(1e-4)^3 r k off
    dipped = valley - np.array([k * 1e-8, 0, 0])
    assert piece_open_area(dipped, BETA, RATIO, lash) == pytest.approx(
        BETA * RATIO * (k / 12 - k * 1e-8 + (4 / 3) * k * 1e-12), rel=1e-12)


def test_a_near_zero_leading_coefficient():
    """1e-30 u^6 on a line: no companion matrix (that would divide by it); the root at 1/2."""
    c = np.array([-0.5, 1.0, 0, 0, 0, 0, 1e-30])
    parts = open_parts(c)
    assert len(parts) == 1 and parts[0][0] == pytest.approx(0.5, abs=1e-15) and parts[0][1] == 1.0
    assert piece_open_area(c, 1.0, 1.0, 0.0) == pytest.approx(0.125, rel=1e-14)


def _quad_positive_part(c):
    # numpy's roots of the polynomial without high terms below rounding on [0, 1] (a 1e-159 leading
    # coefficient sends the companion matrix's roots to 0 and 1e158); quad needs the kinks only roughly
    trimmed = np.polynomial.Polynomial(c).trim(tol=1e-14 * float(np.max(np.abs(c))))
    roots = [r.real for r in trimmed.roots() if abs(r.imag) < 1e-9 and 0.0 < r.real < 1.0]
    value = quad(lambda u: max(np.polynomial.polynomial.polyval(u, c), 0.0), 0.0, 1.0, points=sorted(roots) or None,
                 epsabs=1e-15 * float(np.sum(np.abs(c))), epsrel=1e-13, limit=400)[0]
    return value


@settings(max_examples=300, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0, allow_nan=False, allow_subnormal=False), min_size=1, max_size=10))
def test_random_polynomial_pieces_against_quad(coef):
    """Any piece (degree 0 to 9): the exact positive-part integral against quad split at numpy's
    roots, 1e-12 relative to the piece's scale sum |c_k|; the cuts keep one sign between them."""
    c = np.array(coef)
    scale = float(np.sum(np.abs(c))) or 1.0
    assert piece_open_area(c, 1.0, 1.0, 0.0) == pytest.approx(_quad_positive_part(c), abs=1e-12 * scale)
    edges = [0.0] + sign_cuts(c) + [1.0]
    for a, b in zip(edges[:-1], edges[1:]):
        probes = np.polynomial.polynomial.polyval(np.linspace(a, b, 9)[1:-1], c)
        assert np.all(probes >= -1e-12 * scale) or np.all(probes <= 1e-12 * scale)


def test_the_projection_is_bounded_and_says_when_it_fails():
    """design's Newton projection onto the area: it reaches a reachable level (|z|^2 = 4 from
    (1, 0.5): quadratic convergence, a few steps, to 1e-13) and, on an area it cannot move (zero
    gradient) or within PROJECTION_STEPS, stops and says how far off it is."""
    from explorer.studies.design import PROJECTION_STEPS, _project_on_area

    z, note = _project_on_area(lambda z: (float(z @ z), 2.0 * z), np.array([1.0, 0.5]), 4.0)
    assert float(z @ z) == pytest.approx(4.0, rel=1e-13) and "projected" in note
    z, note = _project_on_area(lambda z: (1.0, np.zeros(2)), np.array([1.0, 0.5]), 4.0)
    assert "stopped 0.75 (relative) off it" in note and np.all(z == [1.0, 0.5])
    calls = []

    def slow(z):  # a step only halves the deviation: not done within the bound
        calls.append(1)
        return 4.0 - 0.5 ** len(calls), np.array([1e30, 0.0])

    z, note = _project_on_area(slow, np.array([0.0, 0.0]), 4.0)
    assert "stopped" in note and len(calls) == PROJECTION_STEPS + 1
