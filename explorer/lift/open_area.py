"""The valve's open area of a piecewise polynomial lift, exact: the integral of max(q, 0) with
q(u) = ratio P(u) - lash on each piece (P in the piece's local u in [0, 1]).

max(q, 0) has a kink where the valve lift crosses the lash; a quadrature panel across it errs
(Gauss-Legendre between the stations: 4.9e-7 of spline_demo's area). Here each piece is cut where
q may change sign, and q is integrated in closed form between the cuts; a part is kept when its
integral is positive. That rule needs only that q keeps one sign between consecutive cuts, not
that the cuts are q's roots to the last bit: a lift tangent to the lash (a double root, no sign
change) is harmless, and a root off by e changes the area by |q'| e^2 / 2.

The cuts come from the monotone stretches (`sign_cuts`): between consecutive sign changes of q',
q is monotone, so it changes sign there at most once, and only if its ends' values have strictly
opposite signs (then Brent's method, bracketed, finds the root); the sign changes of q' come the
same way from q'', down to a linear polynomial. Nothing divides by the leading coefficient (a
companion matrix would: a leading coefficient near zero scatters its roots), and every search is
bounded (Brent's 200 iterations, the recursion by the degree).
"""

from __future__ import annotations

import numpy as np

from ..core.roots import brent


def _value(c, u: float) -> float:
    total = 0.0
    for ck in reversed(c):  # Horner
        total = total * u + ck
    return total


def _trim(c) -> list[float]:
    c = [float(x) for x in c]
    while len(c) > 1 and c[-1] == 0.0:
        c.pop()
    return c


def sign_cuts(coef) -> list[float]:
    """Points of (0, 1), ascending, such that the polynomial sum coef_k u^k is monotone and keeps
    one sign (zero allowed) between consecutive ones of [0] + cuts + [1]: its critical points where
    q' changes sign and its roots where q does."""
    c = _trim(coef)
    if len(c) <= 1:
        return []
    if len(c) == 2:
        root = -c[0] / c[1]
        return [root] if 0.0 < root < 1.0 else []
    critical = sign_cuts([k * c[k] for k in range(1, len(c))])
    edges = [0.0] + critical + [1.0]
    cuts = list(critical)
    for a, b in zip(edges[:-1], edges[1:]):
        fa, fb = _value(c, a), _value(c, b)
        if (fa < 0.0 < fb) or (fb < 0.0 < fa):  # monotone here: one root at most, bracketed
            cuts.append(brent(lambda u: _value(c, u), a, b, fa, fb, 1e-16, 4.0 * np.finfo(float).eps, 200))
    return sorted(cuts)


def open_parts(coef) -> list[tuple[float, float]]:
    """The stretches (a, b) of [0, 1] where q(u) = sum coef_k u^k > 0 (adjacent ones merged)."""
    c = np.asarray(coef, dtype=float)
    # on [0, 1], |q - c0| <= sum |c_k|: a piece open or closed all along needs no roots
    spread = float(np.sum(np.abs(c[1:])))
    if c[0] - spread > 0.0:
        return [(0.0, 1.0)]
    if c[0] + spread <= 0.0:
        return []
    edges = [0.0] + sign_cuts(c) + [1.0]
    parts: list[tuple[float, float]] = []
    for a, b in zip(edges[:-1], edges[1:]):
        if b > a and float(c @ _power_integrals([(a, b)], c.size)) > 0.0:  # one sign on (a, b): its integral's
            if parts and parts[-1][1] == a:
                parts[-1] = (parts[-1][0], b)
            else:
                parts.append((a, b))
    return parts


def _power_integrals(parts, n: int) -> np.ndarray:
    """Sum over the parts (a, b) of the integrals of u^k, k = 0 .. n-1."""
    k = np.arange(1, n + 1)
    total = np.zeros(n)
    for a, b in parts:
        total += (float(b) ** k - float(a) ** k) / k
    return total


def piece_open_area(c, width: float, ratio: float, lash: float) -> float:
    """Integral over a piece of `width` (rad) of max(ratio P(u) - lash, 0), P(u) = sum c_k u^k."""
    q = ratio * np.asarray(c, dtype=float)
    q[0] -= lash
    return width * float(q @ _power_integrals(open_parts(q), q.size))


def spline_open_area(knots, coefficients, ratio: float, lash: float) -> float:
    """The open area (m*rad) of piecewise polynomials (ascending powers of the local u) on `knots`
    (rad); outside them the lift is 0, below any lash >= 0."""
    widths = np.diff(np.asarray(knots, dtype=float))
    return float(sum(piece_open_area(c, w, ratio, lash) for c, w in zip(coefficients, widths)))


def affine_open_area(c_base: np.ndarray, c_cols: np.ndarray, widths, ratio: float, lash: float):
    """For pieces whose coefficients are c_base + z . c_cols (c_base (pieces, m), c_cols (free,
    pieces, m)): area(z) -> (the open area, its gradient in z). The gradient is the integral of
    the columns over the open parts: the parts' ends move with z, but the integrand is 0 there."""
    widths = np.asarray(widths, dtype=float)
    cols = ratio * np.asarray(c_cols, dtype=float)

    def area(z):
        coef = ratio * (c_base + np.tensordot(np.asarray(z, dtype=float), c_cols, axes=1))
        coef[:, 0] -= lash
        value, grad = 0.0, np.zeros(cols.shape[0])
        for i, (q, w) in enumerate(zip(coef, widths)):
            powers = _power_integrals(open_parts(q), q.size)
            value += w * float(q @ powers)
            grad += w * (cols[:, i, :] @ powers)
        return value, grad

    return area
