"""Polynomial helpers shared by the piecewise solvers (exact, taylor) and the tabulated drive.

Over a step of length h a drive (or a stiffness) is carried as a polynomial in u = tau/h with
scaled coefficients c[n] = p^(n) h^n / n!. Numpy only (fast to import).
"""

from __future__ import annotations

import numpy as np


def taylor_shift(D: np.ndarray, d) -> np.ndarray:
    """Drive derivatives (4, n) at x moved to x + d by their Taylor polynomial (d ~ 1e-7 h)."""
    S, S1, S2, S3 = D
    return np.stack([
        S + d * (S1 + d * (S2 / 2 + d * S3 / 6)),
        S1 + d * (S2 + d * S3 / 2),
        S2 + d * S3,
        S3,
    ])


def taylor_shift1(D, d: float) -> list:
    """taylor_shift for one point (lists)."""
    S, S1, S2, S3 = D
    return [S + d * (S1 + d * (S2 / 2 + d * S3 / 6)), S1 + d * (S2 + d * S3 / 2), S2 + d * S3, S3]


def hermite5(h: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Scaled coefficients (6, n) in u = tau/h of the quintic with S, S', S'' given at both ends."""
    out = np.empty((6, h.size))
    c0, c1, c2 = out[0], out[1], out[2]
    c0[...] = start[0]
    np.multiply(h, start[1], out=c1)
    hh = h * h
    np.multiply(hh, start[2], out=c2)
    c2 *= 0.5
    d = np.empty((3, h.size))
    np.subtract(end[0], c0 + c1 + c2, out=d[0])
    np.subtract(h * end[1], c1 + 2.0 * c2, out=d[1])
    np.subtract(hh * end[2], 2.0 * c2, out=d[2])
    np.matmul(HERMITE_HIGH, d, out=out[3:])
    return out


# the quintic's coefficients 3..5 from the end mismatches of value, slope and curvature
HERMITE_HIGH = np.array([[10.0, -4.0, 0.5], [-15.0, 7.0, -1.0], [6.0, -3.0, 0.5]])


def horner(c, x: float) -> float:
    """The polynomial with coefficients c (lowest first) at x, in plain floats."""
    acc = 0.0
    for ck in reversed(c):
        acc = acc * x + ck
    return acc
