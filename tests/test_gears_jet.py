"""Jets (value + three derivatives) against an independent oracle.

Oracle: Cauchy's integral formula. For an analytic f, sampling f(x0 + r e^{i phi}) at K points
and taking the FFT gives the Taylor coefficients a_k = f^(k)(x0)/k! / r^k... times r^k, exact to
rounding for K large (the aliasing error falls like r^K). It shares no code with the jets: numpy's
complex functions versus Leibniz and Faa di Bruno on real arrays.
"""

import math

import numpy as np
import pytest

from explorer.gears import jet as J
from explorer.gears.jet import Jet


def cauchy_derivatives(f, x0: float, radius: float = 0.05, k: int = 64) -> np.ndarray:
    z = x0 + radius * np.exp(2j * np.pi * np.arange(k) / k)
    coeff = np.fft.fft(f(z)) / k
    return np.array([math.factorial(n) * coeff[n].real / radius**n for n in range(4)])


CASES = [
    ("sin(x^2)", lambda j: J.sin(j * j), lambda z: np.sin(z * z)),
    ("sqrt(x^3)/(1+e^x)", lambda j: J.sqrt(j * j * j) / (1.0 + J.exp(j)), lambda z: np.sqrt(z**3) / (1 + np.exp(z))),
    ("acos(x/2) cos(3x)", lambda j: J.acos(j / 2.0) * J.cos(3.0 * j), lambda z: np.arccos(z / 2) * np.cos(3 * z)),
    ("log(2+x) - 1/x", lambda j: J.log(2.0 + j) - 1.0 / j, lambda z: np.log(2 + z) - 1 / z),
    ("hypot(x, 1-x^2)", lambda j: J.hypot(j, 1.0 - j * j), lambda z: np.sqrt(z**2 + (1 - z**2) ** 2)),
    ("x^2.5", lambda j: j**2.5, lambda z: z**2.5),
]


@pytest.mark.parametrize("name, jet_f, complex_f", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("x0", [0.4, 0.9, 1.3])
def test_jet_matches_cauchy_taylor_coefficients(name, jet_f, complex_f, x0):
    got = jet_f(Jet.variable(np.array([x0]))).c[:, 0]
    want = cauchy_derivatives(complex_f, x0)
    # the FFT oracle is good to ~1e-13 relative for these smooth functions at r = 0.05
    assert got == pytest.approx(want, rel=1e-9, abs=1e-10)


def test_atan2_of_a_curve():
    """atan2(y, x) along the circle (cos t^2, sin t^2) is t^2 exactly: derivatives 2t, 2, 0."""
    t = Jet.variable(np.linspace(0.1, 1.7, 9))
    angle = J.atan2(3.0 * J.sin(t * t), 3.0 * J.cos(t * t))
    tv = t.c[0]
    assert np.allclose(angle.c[0], tv**2, atol=1e-15)
    assert np.allclose(angle.c[1], 2 * tv, atol=1e-13)
    assert np.allclose(angle.c[2], 2.0, atol=1e-12)
    assert np.allclose(angle.c[3], 0.0, atol=1e-11)


def test_solve_implicit_gives_the_inverse_function_derivatives():
    """y(x) with y^3 + y - x = 0: implicit differentiation by hand gives
    y' = 1/(3y^2+1), y'' = -6y y'^3, y''' = -6 y'^4 + 108 y^2 y'^5 (derived from y' = g(y))."""
    x = np.array([0.3, 2.0, 10.0])
    y0 = np.array([np.roots([1, 0, 1, -xi])[np.isreal(np.roots([1, 0, 1, -xi]))].real[0] for xi in x])
    xj = Jet.variable(x)
    y = J.solve_implicit(lambda yy, xx: yy * yy * yy + yy - xx, y0, args=(xj,))
    d1 = 1.0 / (3 * y0**2 + 1)
    d2 = -6 * y0 * d1**3
    d3 = -6 * d1**4 + 108 * y0**2 * d1**5
    assert np.allclose(y.c[1], d1, rtol=1e-13)
    assert np.allclose(y.c[2], d2, rtol=1e-12)
    assert np.allclose(y.c[3], d3, rtol=1e-11)


def test_newton_converges_and_flags_failure():
    x, ok = J.newton(lambda j: j * j - 2.0, np.array([1.0, 3.0]))
    assert np.allclose(x, math.sqrt(2.0), rtol=1e-15) and ok.all()
    x, ok = J.newton(lambda j: j * j + 1.0, np.array([0.5]), max_iter=20)  # no real root
    assert not ok.any()
