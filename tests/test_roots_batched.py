"""explorer.core.roots.roots_in (many bracketed searches at once, the function called on all their
points together) against its oracle, root_in called on each bracket in turn: the same steps in the
same floating-point operations, so every root must be the same float (bit for bit), and the error
raised the one the loop would raise first. On random polynomials with random brackets
(hypothesis), and on the project's own kind of call: the zeros of the rates of a translating
roller's pressure angle and pitch radius (explorer.effects.contour.geometry_extremes) on every
shipped lift law and on the spline and table lifts of the built-in scenes, where the lift is
evaluated on arrays of many angles instead of one (the lift's values must not depend on the other
angles of the call)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from explorer.core.roots import NoBracket, root_in, roots_in
from explorer.effects.contour import _rates
from explorer.effects.lift import build_lift
from explorer.lift.curves import TWO_PI, LawLift, lift_rows
from explorer.lift.laws import LAWS
from explorer.scene.scene import load_scene

from conftest import SCENES


def _horner(coefs, x):
    """sum c_k x^k by Horner, on Python floats or numpy arrays alike (the same IEEE products and sums)."""
    value = coefs[-1] + 0.0 * x
    for c in coefs[-2::-1]:
        value = value * x + c
    return value


def _one_by_one(g, a, b, fa=None, fb=None, **kw):
    """The oracle: root_in on each bracket in turn, g(x, i) called on one point."""
    return [root_in(lambda t, i=i: float(g(np.array([t]), np.array([i]))[0]), a[i], b[i],
                    fa=None if fa is None else fa[i], fb=None if fb is None else fb[i], **kw) for i in range(len(a))]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.lists(st.floats(-5.0, 5.0), min_size=2, max_size=6), st.floats(-3.0, 0.0),
                          st.floats(0.01, 3.0)), min_size=1, max_size=8),
       st.sampled_from([1e-15, 1e-9]), st.sampled_from([3, 200]))
def test_roots_in_equals_root_in_on_random_polynomials(cases, xtol, maxiter):
    cases = [(c, a, b) for c, a, b in cases if _horner(c, a) * _horner(c, b) < 0.0]
    if not cases:
        return
    coefs = [np.array(c) for c, _, _ in cases]
    a, b = [a for _, a, _ in cases], [b for _, _, b in cases]

    def g(x, i):
        return np.array([_horner(coefs[k], t) for t, k in zip(x, i)])

    def g_vector(x, i):  # the same Horner on arrays: numpy's elementwise products and sums
        width = max(len(c) for c in coefs)
        table = np.array([np.pad(c, (0, width - len(c))) for c in coefs])[i]
        return _horner(list(table.T), x)

    want = _one_by_one(g, a, b, xtol=xtol, maxiter=maxiter)
    assert roots_in(g, a, b, xtol=xtol, maxiter=maxiter) == want
    assert roots_in(g_vector, a, b, xtol=xtol, maxiter=maxiter) == want


def test_ends_and_errors_as_root_in():
    """An end with value zero is the root; rounding's sign change (given ends) takes the smaller
    end; the first failing bracket's error is raised, as the loop of root_in would."""
    def g(x, i):
        shift = np.array([0.25, 0.0, 0.5])[i]
        return x - shift

    assert roots_in(g, [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]) == _one_by_one(g, [0.0] * 3, [1.0] * 3)
    assert roots_in(g, [0.0], [1.0]) == [0.25]
    # the caller's grid saw a sign change that the scalar values do not: the smaller end
    assert roots_in(lambda x, i: x + 1.0, [0.0], [1.0], fa=[-1e-300], fb=[1.0]) == [0.0]
    with pytest.raises(NoBracket) as first:
        roots_in(lambda x, i: np.where(i == 0, x - 0.5, x + 1.0 + i), [0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    assert first.value.fa == 2.0  # bracket 1's, not bracket 2's
    with pytest.raises(ValueError, match="NaN"):
        # bracket 0 meets a NaN in its search, bracket 1 has no sign change: bracket 0's error
        roots_in(lambda x, i: np.where(i == 0, np.where(x < 0.25, -1.0, np.where(x < 0.9, np.nan, 1.0)), x + 1.0),
                 [0.0, 0.0], [1.0, 1.0])
    assert roots_in(lambda x, i: x, [], []) == []


def _rate_brackets(lift, follower_y0: float, offset: float, n: int = 720):
    """Sign changes of geometry_extremes' two rates on a grid of n angles: (a, b, fa, fb, which)."""
    grid = np.linspace(0.0, TWO_PI, n + 1)
    with np.errstate(all="ignore"):
        rates = _rates(lift_rows(lift, grid, (0, 1, 2, 3)), follower_y0, offset)[:2]
    out = []
    for k, rate in enumerate(rates):
        for i in np.nonzero(np.sign(rate[:-1]) * np.sign(rate[1:]) < 0.0)[0]:
            out.append((grid[i], grid[i + 1], rate[i], rate[i + 1], k))
    return out


LIFTS = {f"law {name}": (lambda name=name: LawLift(0.009, 0.3, 1.7, 0.2, 1.9, name, name)) for name in sorted(LAWS)}
LIFTS.update({scene: (lambda scene=scene: build_lift(load_scene(SCENES / f"{scene}.toml")))
              for scene in ("spline_demo", "table_demo", "polydyne_spline", "acceleration_demo")})


@pytest.mark.parametrize("name", sorted(LIFTS))
def test_roots_in_on_a_lifts_rates_equals_root_in(name):
    lift = LIFTS[name]()
    y0, e = 0.04, 0.004
    a, b, fa, fb, which = map(np.array, zip(*_rate_brackets(lift, y0, e)))

    def g(x, i):
        with np.errstate(all="ignore"):
            phi_rate, rho_rate = _rates(lift_rows(lift, x, (0, 1, 2, 3)), y0, e)[:2]
        return np.where(which[i] == 0, phi_rate, rho_rate)

    got = roots_in(g, a, b, fa=fa, fb=fb, xtol=1e-15, maxiter=200)
    assert len(got) >= 4 and all(math.isfinite(x) for x in got)
    assert got == _one_by_one(g, a, b, fa, fb, xtol=1e-15, maxiter=200)


def _valve_extremes_one_by_one(lift, theta, d, ratio, lash, scales, ends):
    """valve_extremes' searches as first written (the oracle): each bracket's root_in on lift_at in
    turn, the lift at each root and end by lift_at (the samples and brackets: closed_lines, which
    the batching did not change)."""
    from explorer.lift.curves import lift_at
    from explorer.mechanics.kinematics import closed_lines

    needed = sorted({0, *scales, *(row + 1 for row in scales)})
    angles, line, across = closed_lines(lift, theta, d, needed)
    is_open = ratio * line[0] - lash > 0.0
    closed_somewhere = not (ratio * d[0] - lash > 0.0).all()
    out = {}
    for row, scale in scales.items():
        sampled = scale * line[row][is_open]
        values = [float(sampled.max()), float(sampled.min())] if sampled.size else []
        if closed_somewhere:
            values.append(0.0)
        slope = line[row + 1]
        for i in np.nonzero((np.sign(slope[:-1]) * np.sign(slope[1:]) < 0.0) & ~across)[0]:
            x = root_in(lambda th, k=row + 1: lift_at(lift, th, k), float(angles[i]), float(angles[i + 1]),
                        fa=float(slope[i]), fb=float(slope[i + 1]), xtol=1e-15, maxiter=200)
            if ratio * lift_at(lift, x, 0) - lash > 0.0:
                values.append(scale * lift_at(lift, x, row))
        values.extend(scale * lift_at(lift, float(x), row) for x in ends)
        out[row] = (max(values), min(values)) if values else (math.nan, math.nan)
    return out


@pytest.mark.parametrize("scene", ["spline_demo", "table_demo", "schenker1902_fig2", "polydyne_spline",
                                   "cycloidal_demo"])
@pytest.mark.parametrize("lash", [0.0, 2e-4, 0.02])
def test_valve_extremes_as_one_search_at_a_time(scene, lash):
    """The kinematics' exact peaks (valve_extremes: all brackets through roots_in where the lift has
    no one-angle form) are the floats of the searches one at a time, open or closed valve."""
    from explorer.mechanics.kinematics import lash_crossings, valve_extremes

    lift = build_lift(load_scene(SCENES / f"{scene}.toml"))
    theta = np.arange(3600) * (TWO_PI / 3600)
    d = lift.derivatives(theta)
    ups, downs = lash_crossings(lift, 1.3, lash)
    ends = np.concatenate([ups, downs])
    scales = {0: 1.0, 1: 1.3 * 500.0, 2: 1.3 * 500.0**2}
    got = valve_extremes(lift, theta, d, 1.3, lash, scales, ends)
    assert repr(got) == repr(_valve_extremes_one_by_one(lift, theta, d, 1.3, lash, scales, ends))
