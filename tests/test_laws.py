"""Motion laws: classic peak coefficients, boundary conditions, and derivative consistency.

Oracles: the coefficient tables of cam design (e.g. Norton, Cam Design and Manufacturing
Handbook), and integration of f''' back to f (independent of how f was written down).
"""

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

from explorer.lift.laws import LAWS

U = np.linspace(0.0, 1.0, 400_001)

# (Cv, Ca, Cj): peaks of f', |f''|, |f'''| for a unit rise over a unit angle.
COEFFICIENTS = {
    "cycloidal": (2.0, 2 * math.pi, 4 * math.pi**2),
    "harmonic": (math.pi / 2, math.pi**2 / 2, math.pi**3 / 2),
    "polynomial-345": (1.875, 5.7735, 60.0),
    "polynomial-4567": (2.1875, 7.5132, 52.5),
    # 5-6-7-8-9, by hand from f' = 630 u^4 (1-u)^4 with t = u - 1/2: f'' = -5040 t (1/4 - t^2)^3 peaks
    # at t^2 = 1/28; the jerk -5040 (1/4 - t^2)^2 (1/4 - 7 t^2) peaks at t = 0
    "polynomial-56789": (630 / 256, 5040 / math.sqrt(28) * (3 / 14) ** 3, 5040 / 64),
    "modified-trapezoid": (2.0, 4.8881, 61.426),
    "modified-sine": (1.7596, 5.5280, 69.466),
}


@pytest.mark.parametrize("name", COEFFICIENTS)
def test_peak_coefficients(name):
    f = LAWS[name](U)
    cv, ca, cj = COEFFICIENTS[name]
    # 4-5 significant figures in the tables; the grid resolves peaks to ~1e-10 relative.
    assert f[1].max() == pytest.approx(cv, rel=2e-5)
    assert np.abs(f[2]).max() == pytest.approx(ca, rel=2e-5)
    assert np.abs(f[3]).max() == pytest.approx(cj, rel=2e-5)


@pytest.mark.parametrize("name", COEFFICIENTS)
def test_boundary_values(name):
    f = LAWS[name](np.array([0.0, 1.0]))
    assert f[0] == pytest.approx([0.0, 1.0], abs=1e-14)
    assert f[1] == pytest.approx([0.0, 0.0], abs=1e-13)
    if name != "harmonic":  # the harmonic law has finite end accelerations by construction
        assert f[2] == pytest.approx([0.0, 0.0], abs=1e-12)


@pytest.mark.parametrize("name", COEFFICIENTS)
def test_derivatives_integrate_back(name):
    """Integrating f''' three times (Simpson) must return f: the derivatives are consistent."""
    f = LAWS[name](U)
    acc = f[2][0] + cumulative_simpson(f[3], x=U, initial=0.0)
    vel = cumulative_simpson(acc, x=U, initial=0.0)
    lift = cumulative_simpson(vel, x=U, initial=0.0)
    # piecewise laws have jerk jumps at segment joints: Simpson error ~ h^2 there
    assert np.abs(acc - f[2]).max() < 1e-6 * np.abs(f[2]).max()
    assert np.abs(vel - f[1]).max() < 1e-7
    assert np.abs(lift - f[0]).max() < 1e-7


@pytest.mark.parametrize("name", COEFFICIENTS)
def test_acceleration_areas_balance(name):
    """Seed 004: the acceleration areas above and below zero are equal (start and end at rest)."""
    f = LAWS[name](U)
    above = np.trapezoid(np.clip(f[2], 0, None), U)
    below = np.trapezoid(np.clip(f[2], None, 0), U)
    assert above == pytest.approx(-below, rel=1e-8)


def test_the_law_table_states_the_closed_forms_smoothness():
    """LawSpec.smoothness (explorer/lift/registry.py) is the highest derivative that stays
    continuous where the law meets a dwell: f^(k)(0) = f^(k)(1) = 0 for k = 1 .. smoothness, and the
    next derivative not zero at an end (the closed forms' own values, to rounding)."""
    from explorer.lift import registry

    closed = [registry.law_spec(name) for name in registry.closed_form_names()]
    assert [spec.name for spec in closed] == list(LAWS)
    for spec in closed:
        ends = spec.function()(np.array([0.0, 1.0]))
        scale = np.abs(spec.function()(np.linspace(0.0, 1.0, 2001))).max(axis=1)
        assert ends[0].tolist() == pytest.approx([0.0, 1.0], abs=1e-15), spec.name
        if spec.smoothness >= 3:  # beyond the jerk: the closed-form higher derivatives (polydyne's)
            from explorer.lift.laws import law_derivatives

            order = spec.smoothness + 1
            ends = law_derivatives(spec.name, np.array([0.0, 1.0]), order)
            scale = np.abs(law_derivatives(spec.name, np.linspace(0.0, 1.0, 2001), order)).max(axis=1)
        for k in range(1, spec.smoothness + 1):
            assert np.abs(ends[k]).max() <= 1e-9 * scale[k], (spec.name, k)
        assert np.abs(ends[spec.smoothness + 1]).max() > 1e-3 * scale[spec.smoothness + 1], spec.name


@pytest.mark.parametrize("name", COEFFICIENTS)
def test_a_laws_rows_asked_for_are_its_rows_among_all_four(name):
    """laws' evaluate(u, rows) (the sweep's zoom asks for f and f'' only): each subset and order
    of the rows the same floats as those rows of the full evaluation (oracle: LAWS[name](u)), at
    random u, the ends and the piecewise laws' segment joints."""
    from explorer.lift.laws import ALL_ROWS

    u = np.concatenate([np.random.default_rng(5).uniform(0.0, 1.0, 5000), [0.0, 0.125, 0.375, 0.625, 0.875, 1.0]])
    full = LAWS[name](u)
    for rows in [(0,), (2,), (0, 2), (2, 0), (1, 3), (3, 1, 0), ALL_ROWS]:
        assert np.array_equal(LAWS[name](u, rows), full[list(rows)]), rows


def test_a_law_lifts_derivative_rows_are_its_derivatives_rows():
    """LawLift.derivative_rows and lift_rows (only the rows asked for) against LawLift.derivatives
    (oracle: its rows), bit for bit, for every pair of rise and return laws with and without a
    dwell, at random angles (beyond 0 and 2 pi too), the breakpoints and their neighbouring floats;
    lift_rows of a lift without derivative_rows (a spline lift) is its derivatives' rows."""
    import itertools

    from explorer.lift.curves import LawLift, lift_rows

    rng = np.random.default_rng(6)
    for (rise, ret), dwell in itertools.product(itertools.product(LAWS, repeat=2), (0.0, 0.3)):
        lift = LawLift(height=0.009, start=0.5, rise=1.3, dwell=dwell, ret=1.1, rise_law=rise, return_law=ret)
        marks = lift.breakpoints()
        theta = np.concatenate([rng.uniform(-1.0, 8.0, 3000), marks, np.nextafter(marks, 0.0),
                                np.nextafter(marks, 7.0)])
        full = lift.derivatives(theta)
        for rows in [(0,), (2,), (0, 2), (2, 0), (1, 3), (3, 1, 0), (0, 1, 2, 3)]:
            assert np.array_equal(lift.derivative_rows(theta, rows), full[list(rows)]), (rise, ret, dwell, rows)
            assert np.array_equal(lift_rows(lift, theta, rows), full[list(rows)])
        grid = theta.reshape(3, -1)  # any shape, as derivatives takes it
        assert np.array_equal(lift.derivative_rows(grid, (0, 2)), lift.derivatives(grid)[[0, 2]])

    class Plain:  # a lift curve with derivatives only (the LiftCurve protocol)
        def derivatives(self, theta):
            return LawLift(0.009, 0.5, 1.3, 0.0, 1.1, "cycloidal", "harmonic").derivatives(theta)

    theta = rng.uniform(0.0, 7.0, 500)
    assert np.array_equal(lift_rows(Plain(), theta, (2, 0)), Plain().derivatives(theta)[[2, 0]])


def test_the_wraps_to_one_revolution_are_np_mod_floats():
    """lift.curves.wrap_two_pi and mechanics.forces._mod_two_pi (fmod and a correction, or the angles
    themselves when all are within [0, 2 pi) already) against the general form (fmod, plus 2 pi
    where negative; np.mod's floats for x >= 0), bit for bit and sign of zero included: arrays
    all inside (the fast path), with one angle outside (below 0, at 2 pi, beyond), -0.0 (fmod
    keeps its sign, and so does the fast path), NaN, empty."""
    from explorer.lift.curves import wrap_two_pi as _wrap
    from explorer.mechanics.forces import _mod_two_pi

    two_pi = 2.0 * math.pi
    inside = np.random.default_rng(9).uniform(0.0, two_pi, 1000)
    cases = [inside, inside.reshape(40, 25), np.append(inside, -1e-3), np.append(inside, two_pi),
             np.append(inside, 7.5), np.append(inside, np.nextafter(two_pi, 0.0)), np.append(inside, 0.0),
             np.append(inside, np.nan), np.zeros(0), np.linspace(-20.0, 20.0, 4001)]
    for x in cases:
        for wrap in (_wrap, _mod_two_pi):
            got = wrap(x.copy())
            expected = np.fmod(x, two_pi)  # the general form (np.mod's floats for x >= 0)
            expected = np.where(expected < 0.0, expected + two_pi, expected)
            assert got.shape == x.shape and np.array_equal(got, expected, equal_nan=True)
            assert np.array_equal(np.signbit(got), np.signbit(expected))
            if not np.isnan(x).any() and (x >= 0.0).all():
                assert np.array_equal(got, np.mod(x, two_pi))
    x = inside.copy()
    assert _mod_two_pi(x) is not x  # a new array, as fmod's (the zoom keeps its samples)
    minus_zero = np.append(inside, -0.0)
    assert np.signbit(_wrap(minus_zero)[-1]) == np.signbit(np.fmod(-0.0, two_pi))  # the general form's sign


def test_derivative_rows_of_a_plug_in_law_without_rows(monkeypatch):
    """A law registered as a plug-in is u -> (4, ...) only (LawSpec.normalised; it takes no rows):
    LawLift.derivative_rows selects its rows from all four (laws.law_rows), the same floats as
    derivatives' rows; the closed forms are marked as taking rows."""
    from explorer.lift import laws
    from explorer.lift.curves import LawLift

    def toy(u):  # 3u^2 - 2u^3, as tests/test_plugins.py's toy law
        u = np.asarray(u, dtype=float)
        return np.stack([3 * u**2 - 2 * u**3, 6 * u - 6 * u**2, 6 - 12 * u, np.full_like(u, -12.0)])

    monkeypatch.setitem(laws.LAWS, "toy-cubic", toy)
    lift = LawLift(height=0.008, start=0.0, rise=1.5, dwell=0.5, ret=1.5, rise_law="toy-cubic", return_law="cycloidal")
    theta = np.random.default_rng(10).uniform(0.0, 2.0 * math.pi, 2000)
    full = lift.derivatives(theta)
    for rows in [(0,), (0, 2), (3, 1), (0, 1, 2, 3)]:
        assert np.array_equal(lift.derivative_rows(theta, rows), full[list(rows)]), rows
    assert all(getattr(laws.LAWS[name], "takes_rows", False) for name in COEFFICIENTS)
    assert not getattr(toy, "takes_rows", False)


def test_one_angle_at_a_time_is_the_same_float_as_in_an_array():
    """laws.law_at (each closed form's scalar `at`) and LawLift.row_at, which the root searches
    call one angle at a time (curves.lift_at), against the array evaluation of that one angle
    (oracle: law_rows / derivative_rows on np.array([x]), the floats lift_at returned before),
    bit for bit: every law and row at random u, at the piecewise laws' segment joints and their
    neighbouring floats, beyond [0, 1]; every pair of rise and return laws with and without a
    dwell at random angles (beyond 0 and 2 pi too), at the breakpoints and their neighbours; and a
    non-finite angle. A plug-in law without `at` falls back to its array form; lift_at of a lift
    without row_at is its lift_rows."""
    import itertools

    from explorer.lift import laws
    from explorer.lift.curves import LawLift, lift_at, lift_rows

    rng = np.random.default_rng(11)
    joints = np.array([0.0, 0.125, 0.375, 0.625, 0.875, 1.0])
    u_all = np.concatenate([rng.uniform(0.0, 1.0, 400), joints, np.nextafter(joints, -1.0),
                            np.nextafter(joints, 2.0), rng.uniform(-0.5, 1.5, 40)])
    for name in COEFFICIENTS:
        assert getattr(LAWS[name], "at", None) is not None, name
        for u, row in itertools.product(u_all.tolist(), range(4)):
            expected = float(laws.law_rows(name, np.array([u]), (row,))[0, 0])
            assert laws.law_at(name, u, row) == expected, (name, u, row)
    for (rise, ret), dwell in itertools.product(itertools.product(COEFFICIENTS, repeat=2), (0.0, 0.3)):
        lift = LawLift(height=0.009, start=0.5, rise=1.3, dwell=dwell, ret=1.1, rise_law=rise, return_law=ret)
        marks = lift.breakpoints()
        theta = np.concatenate([rng.uniform(-1.0, 8.0, 40), marks, np.nextafter(marks, 0.0), np.nextafter(marks, 7.0)])
        for x, row in itertools.product(theta.tolist(), range(4)):
            expected = float(lift.derivative_rows(np.array([x]), (row,))[0, 0])
            assert lift.row_at(x, row) == expected == lift_at(lift, x, row), (rise, ret, dwell, x, row)
    lift = LawLift(0.009, 0.5, 1.3, 0.3, 1.1, "cycloidal", "polynomial-345")
    with np.errstate(invalid="ignore"):
        for x in (math.nan, math.inf):
            assert np.array_equal(lift.row_at(x, 0), lift.derivative_rows(np.array([x]), (0,))[0, 0], equal_nan=True)

    class Plain:  # a lift curve with derivatives only
        def derivatives(self, theta):
            return lift.derivatives(theta)

    assert lift_at(Plain(), 1.0, 2) == float(lift_rows(lift, np.array([1.0]), (2,))[0, 0])


def test_a_plug_in_law_without_at_is_evaluated_on_an_array_of_one(monkeypatch):
    from explorer.lift import laws

    def toy(u):
        u = np.asarray(u, dtype=float)
        return np.stack([3 * u**2 - 2 * u**3, 6 * u - 6 * u**2, 6 - 12 * u, np.full_like(u, -12.0)])

    monkeypatch.setitem(laws.LAWS, "toy-cubic", toy)
    for u in (0.0, 0.3, 0.7, 1.0):
        for row in range(4):
            assert laws.law_at("toy-cubic", u, row) == float(toy(np.array([u]))[row, 0])


def test_grid_with_is_np_unique_of_the_grid_and_the_points():
    """curves.grid_with (the points merged into a sorted grid) against np.unique(np.concatenate)
    (oracle), bit for bit and sign of zero included: breakpoints inside, on grid points, repeated,
    beyond 2 pi, none, -0.0, negative, NaN."""
    from explorer.lift.curves import grid_with

    grid = np.linspace(0.0, 2.0 * math.pi, 4097)
    rng = np.random.default_rng(12)
    cases = [rng.uniform(0.0, 6.2, 4), grid[[0, 7, 4096]], np.array([1.0, 1.0, 2.0]), np.array([7.0, 0.5]),
             np.zeros(0), np.array([-0.0, 1.0]), np.array([-0.5, 3.0]), np.array([np.nan, 1.0]),
             np.nextafter(grid[[5, 9]], 0.0), [3.0]]
    for points in cases:
        expected = np.unique(np.concatenate([grid, np.asarray(points, dtype=float)]))
        got = grid_with(grid, points)
        assert np.array_equal(got, expected, equal_nan=True), points
        assert np.array_equal(np.signbit(got), np.signbit(expected))


def test_polynomial_56789_coefficients_from_their_conditions_and_closed_form():
    """Oracle 1 (Norton, Cam Design and Manufacturing Handbook, polynomial cams: one coefficient per
    boundary condition): the degree-9 polynomial with f(0) = 0, f(1) = 1 and its first four
    derivatives 0 at both ends, solved here in exact rationals, is
    126 u^5 - 420 u^6 + 540 u^7 - 315 u^8 + 70 u^9. Oracle 2, a closed form independent of the
    coefficients: f is the regularised incomplete beta function
    I_u(5, 5) = sum_{j=5..9} C(9, j) u^j (1 - u)^(9 - j), whose derivative is 630 u^4 (1 - u)^4.
    The law's rows against both to 1e-12 of each row's peak (rounding of a degree-9 Horner sum with
    coefficients ~500 is ~1e-13), and its first four derivatives exactly 0 at the ends."""
    from fractions import Fraction

    from explorer.lift.laws import POLYNOMIAL_56789, law_derivatives

    def row(k: int, u: int) -> list[Fraction]:  # k-th derivative of u^m at u in {0, 1}, m = 0..9
        return [Fraction(math.perm(m, k)) * Fraction(u) ** (m - k) if m >= k else Fraction(0) for m in range(10)]

    a = [row(k, u) + [Fraction(1 if (k, u) == (0, 1) else 0)] for u in (0, 1) for k in range(5)]
    for col in range(10):  # Gauss-Jordan in exact rationals (the system is regular)
        pivot = next(i for i in range(col, 10) if a[i][col] != 0)
        a[col], a[pivot] = a[pivot], a[col]
        a[col] = [x / a[col][col] for x in a[col]]
        for i in range(10):
            if i != col and a[i][col] != 0:
                a[i] = [x - a[i][col] * y for x, y in zip(a[i], a[col])]
    assert tuple(r[-1] for r in a) == tuple(Fraction(c) for c in POLYNOMIAL_56789)

    u = np.linspace(0.0, 1.0, 2001)
    beta = sum(math.comb(9, j) * u**j * (1.0 - u) ** (9 - j) for j in range(5, 10))
    f = law_derivatives("polynomial-56789", u, 5)
    assert np.array_equal(f[:4], LAWS["polynomial-56789"](u))
    assert np.abs(f[0] - beta).max() < 1e-12
    assert np.abs(f[1] - 630.0 * u**4 * (1.0 - u) ** 4).max() < 1e-12 * 630 / 256
    ends = law_derivatives("polynomial-56789", np.array([0.0, 1.0]), 5)
    assert ends[0].tolist() == [0.0, 1.0] and np.all(ends[1:5] == 0.0)
    # the first derivative not 0 at the ends: f^(5) = 630 * 4! = 15120 at both (f' symmetric about 1/2)
    assert ends[5].tolist() == pytest.approx([15120.0, 15120.0], rel=1e-12)
