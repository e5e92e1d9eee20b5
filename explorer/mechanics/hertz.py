"""Hertz point contact: two bodies whose gap near the first touch is A x^2 + B y^2 (an ellipse).

A crowned tappet face (a sphere of radius Rf) on a cam (radius rho in the cam plane, straight
across it) touches in an elliptical patch, not along a line. With the principal curvature sums
    A = (1/Rf + 1/rho) / 2  (in the cam plane),   B = (1/Rf) / 2  (along the camshaft)
the patch has semi-axes a >= b and the pressure p = p0 sqrt(1 - x^2/a^2 - y^2/b^2), p0 = 3 P/(2 pi a b).
Johnson, Contact Mechanics (1985), section 3.4, eqs. (3.64): with e^2 = 1 - b^2/a^2 and the
complete elliptic integrals K(e), E(e),
    A = (p0 b / (E* a^2 e^2)) (K - E),      B = (p0 b / (E* a^2 e^2)) ((a/b)^2 E - K),
where A belongs to the long axis a (the smaller curvature sum). Their ratio fixes e alone,
    B/A = (E/(1 - e^2) - K) / (K - E),
which rises monotonically from 1 (a circle, e = 0) without bound (e -> 1): solved here by
bisection on log(1 - e^2), a bounded search (BISECTIONS halvings of a bracket of 60 e-folds
reach the float's resolution). Then P = (2/3) pi a b p0 gives a^3 = 3 P (K - E)/(2 pi A E* e^2).
Near e = 0, (K - E)/e^2 = (pi/4)(1 + 3 e^2/8 + ...) replaces the quotient of two small numbers.

Oracles in the tests: the sphere (A = B) in closed form, p0 = (6 P E*^2 / (pi^3 R^2))^(1/3);
Hamrock and Brewe's curve fits (J. Lubrication Technology 105, 1983, pp. 171-177) within their
stated few per cent; and the equations above substituted back.

E* is the plane-strain modulus of the pair, 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2
(explorer.mechanics.contact.effective_modulus).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ellipe, ellipkm1

# bracket of log(1 - e^2): from a circle (0) to an ellipse 1e13 times longer than wide (-60):
# B/A there is ~1e24, beyond any contact of finite bodies
_LOG_M1_MIN = -60.0
BISECTIONS = 64  # halvings of the 60-unit bracket: 60 / 2^64 ~ 3e-18, below the float's resolution
_SMALL_M = 1e-6  # below this e^2 the series of (K - E)/e^2 is exact to rounding


@dataclass(frozen=True)
class PointContact:
    """Elliptical Hertz contact, per sample."""

    peak_pressure: np.ndarray  # Pa, p0
    semi_major: np.ndarray  # m, a: along the direction of the smaller curvature sum
    semi_minor: np.ndarray  # m, b
    eccentricity_squared: np.ndarray  # e^2 = 1 - b^2/a^2


def _k_minus_e_over_m(m: np.ndarray, m1: np.ndarray) -> np.ndarray:
    """(K(m) - E(m)) / m with m = e^2 and m1 = 1 - m given separately (precision near m = 1)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        exact = (ellipkm1(m1) - ellipe(m)) / m
    series = 0.25 * math.pi * (1.0 + 0.375 * m)
    return np.where(m < _SMALL_M, series, exact)


def _curvature_ratio(log_m1: np.ndarray) -> np.ndarray:
    """B/A = (E/(1 - m) - K)/(K - E) as a function of log(1 - m)."""
    m1 = np.exp(log_m1)
    m = -np.expm1(log_m1)
    # E/(1 - m) - K = m E/(1 - m) - (K - E); over (K - E) = m q: E / ((1 - m) q) - 1
    return ellipe(m) / (m1 * _k_minus_e_over_m(m, m1)) - 1.0


def eccentricity_squared(ratio) -> np.ndarray:
    """e^2 of the contact ellipse for the curvature-sum ratio B/A >= 1 (bisection, bounded)."""
    ratio = np.asarray(ratio, dtype=float)
    lo = np.full(ratio.shape, _LOG_M1_MIN)  # very long ellipse: ratio above any target
    hi = np.zeros(ratio.shape)  # circle: ratio 1
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        above = _curvature_ratio(mid) > ratio
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    return -np.expm1(0.5 * (lo + hi))


def point_contact(force, curvature_a, curvature_b, e_star: float) -> PointContact:
    """Hertz contact of two bodies pressed by `force` (N) whose gap is A x^2 + B y^2 with
    A = curvature_a / 2, B = curvature_b / 2 (curvature_* = sum of the two bodies' principal
    curvatures in that direction, 1/m, > 0). The two may come in either order; force <= 0 gives
    zero pressure and size."""
    force = np.asarray(force, dtype=float)
    ka, kb = np.broadcast_arrays(np.asarray(curvature_a, dtype=float), np.asarray(curvature_b, dtype=float))
    small, large = np.minimum(ka, kb), np.maximum(ka, kb)
    if np.any(~(small > 0.0)):
        raise ValueError("point contact needs positive curvature sums in both directions")
    a_coef = 0.5 * small  # A: the long axis belongs to the smaller curvature sum
    m = eccentricity_squared(large / small)
    m1 = 1.0 - m
    q = _k_minus_e_over_m(m, m1)
    loaded = np.maximum(force, 0.0)
    semi_major = np.cbrt(3.0 * loaded * q / (2.0 * math.pi * a_coef * e_star))
    semi_minor = semi_major * np.sqrt(m1)
    with np.errstate(divide="ignore", invalid="ignore"):
        p0 = np.where(loaded > 0.0, 3.0 * loaded / (2.0 * math.pi * semi_major * semi_minor), 0.0)
    shape = np.broadcast_shapes(force.shape, ka.shape)
    return PointContact(np.broadcast_to(p0, shape), np.broadcast_to(semi_major, shape),
                        np.broadcast_to(semi_minor, shape), np.broadcast_to(m, shape))
