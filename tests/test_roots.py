"""explorer.core.roots.brent against its oracle, scipy.optimize.brentq: the same iteration in the
same floating-point operations, so every root must be the same float (bit for bit), on smooth,
flat, steep and kinked functions and on the project's own kind of call (a lift's velocity zero)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from explorer.core.roots import EPS_RTOL, NoBracket, root_in


def _scipy(f, a, b, xtol, rtol, maxiter):
    root, _ = brentq(f, a, b, xtol=xtol, rtol=rtol, maxiter=maxiter, full_output=True, disp=False)
    return float(root)


FUNCTIONS = {
    "cubic": lambda x: x**3 - 2.0 * x - 5.0,
    "cosine": lambda x: math.cos(x) - x,
    "flat": lambda x: (x - 0.3) ** 9,
    "steep": lambda x: math.tanh(1e4 * (x - 0.123456789)),
    "kink": lambda x: abs(x - 0.7) - 0.2 if x > 0.7 else x - 0.5,
    "exp": lambda x: math.exp(x) - 1e3,
}


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
@pytest.mark.parametrize("xtol", [1e-15, 1e-12, 1e-6])
@pytest.mark.parametrize("maxiter", [3, 200])
def test_brent_is_brentq_bit_for_bit(name, xtol, maxiter):
    f = FUNCTIONS[name]
    a, b = {"cubic": (2.0, 3.0), "cosine": (0.0, 1.0), "flat": (-1.0, 2.0), "steep": (0.0, 1.0),
            "kink": (0.0, 2.0), "exp": (0.0, 10.0)}[name]
    assert root_in(f, a, b, xtol=xtol, maxiter=maxiter) == _scipy(f, a, b, xtol, EPS_RTOL, maxiter)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-5.0, 5.0), min_size=2, max_size=6), st.floats(-3.0, 0.0), st.floats(0.01, 3.0))
def test_brent_equals_brentq_on_random_polynomials(coefs, a, b):
    poly = np.polynomial.Polynomial(coefs)
    f = lambda x: float(poly(x))  # noqa: E731
    fa, fb = f(a), f(b)
    if not (fa < 0.0 < fb or fb < 0.0 < fa):
        return
    assert root_in(f, a, b) == _scipy(f, a, b, 1e-15, EPS_RTOL, 200)


def test_lift_velocity_zero_as_the_forces_find_it():
    """A sign change found on a grid (velocity_zeros' call: fa, fb given) gives brentq's float."""
    f = lambda th: math.sin(3.0 * th) * (1.0 + 0.1 * th)  # noqa: E731
    assert root_in(f, 1.0, 1.1, fa=f(1.0), fb=f(1.1)) == _scipy(f, 1.0, 1.1, 1e-15, EPS_RTOL, 200)


def test_nan_raises_and_no_bracket():
    with pytest.raises(ValueError, match="NaN"):
        root_in(lambda x: -1.0 if x < 0.25 else (math.nan if x < 0.9 else 1.0), 0.0, 1.0)
    with pytest.raises(NoBracket):
        root_in(lambda x: 1.0 + x, 0.0, 1.0)


def test_an_overflowing_interpolation_step_is_silent_with_numpy_tolerances():
    """A caller's tolerance as a numpy scalar makes the iterates numpy scalars; an interpolation
    whose divided differences overflow then divides inf by inf. As in C (and scipy's brentq) that
    NaN step must fall back to bisection without a RuntimeWarning (the rocking cam's bad-target
    search warned here)."""
    import warnings

    from explorer.core.roots import _div

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert math.isnan(_div(np.float64(np.inf), np.float64(np.inf)))
        assert _div(np.float64(1.0), np.float64(0.0)) == np.inf
