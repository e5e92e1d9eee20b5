"""Truncated derivative jets: exact derivatives by the chain rule, no finite differences.

A jet is an array of shape (m + 1, ...) holding f, f', ..., f^(m) of one function at many
points. Sums are row-wise; products, quotients, square roots and atan2 follow Leibniz' rule
row by row, so composing them gives the exact derivatives of the composition (to rounding).
The cam geometry uses them for the roller-centre lift over a contour, where writing the third
derivative by hand would be long and easy to get wrong.
"""

from __future__ import annotations

from math import comb

import numpy as np


def constant(value, like: np.ndarray) -> np.ndarray:
    """The jet of a constant, shaped like `like`."""
    out = np.zeros_like(like, dtype=float)
    out[0] = value
    return out


def mul(f: np.ndarray, g: np.ndarray) -> np.ndarray:
    m = min(len(f), len(g))
    out = np.empty((m,) + np.broadcast_shapes(f.shape[1:], g.shape[1:]))
    for n in range(m):
        out[n] = sum(comb(n, k) * f[k] * g[n - k] for k in range(n + 1))
    return out


def div(f: np.ndarray, g: np.ndarray) -> np.ndarray:
    """h = f / g from g h = f: h_n = (f_n - sum_{k>=1} C(n,k) g_k h_{n-k}) / g_0."""
    m = min(len(f), len(g))
    out = np.empty((m,) + np.broadcast_shapes(f.shape[1:], g.shape[1:]))
    for n in range(m):
        acc = f[n] - sum(comb(n, k) * g[k] * out[n - k] for k in range(1, n + 1))
        out[n] = acc / g[0]
    return out


def sqrt(f: np.ndarray) -> np.ndarray:
    """g = sqrt(f) from g g = f: g_n = (f_n - sum_{0<k<n} C(n,k) g_k g_{n-k}) / (2 g_0)."""
    out = np.empty_like(f, dtype=float)
    out[0] = np.sqrt(f[0])
    for n in range(1, len(f)):
        acc = f[n] - sum(comb(n, k) * out[k] * out[n - k] for k in range(1, n))
        out[n] = acc / (2.0 * out[0])
    return out


def derivative(f: np.ndarray) -> np.ndarray:
    """The jet of f' (one order less)."""
    return f[1:]


def truncate(f: np.ndarray, rows: int) -> np.ndarray:
    return f[:rows]


def atan2(b: np.ndarray, a: np.ndarray) -> np.ndarray:
    """phi = atan2(b, a) with phi' = (a b' - b a') / (a^2 + b^2), applied as a jet one order lower."""
    m = min(len(a), len(b))
    out = np.empty((m,) + np.broadcast_shapes(a.shape[1:], b.shape[1:]))
    out[0] = np.arctan2(b[0], a[0])
    if m > 1:
        a0, b0 = a[: m - 1], b[: m - 1]
        rate = div(mul(a0, derivative(b)[: m - 1]) - mul(b0, derivative(a)[: m - 1]), mul(a0, a0) + mul(b0, b0))
        out[1:] = rate
    return out


def rotation(theta: np.ndarray, rows: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Jets of cos(theta) and sin(theta) with respect to theta itself."""
    c, s = np.cos(theta), np.sin(theta)
    cos_rows = [c, -s, -c, s]
    sin_rows = [s, c, -s, -c]
    return (np.stack([cos_rows[k % 4] for k in range(rows)]), np.stack([sin_rows[k % 4] for k in range(rows)]))


def reparametrize(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Derivatives of y with respect to x, both given as jets in a common parameter t.

    With D = (1/x') d/dt:
      y_x   = y'/x'
      y_xx  = (y'' x' - y' x'') / x'^3
      y_xxx = (y''' x' - y' x''') / x'^4 - 3 x'' (y'' x' - y' x'') / x'^5
    """
    m = min(len(y), len(x))
    out = np.full((m,) + np.broadcast_shapes(y.shape[1:], x.shape[1:]), np.nan)
    out[0] = y[0]
    if m > 1:
        out[1] = y[1] / x[1]
    if m > 2:
        inner = y[2] * x[1] - y[1] * x[2]
        out[2] = inner / x[1] ** 3
    if m > 3:
        out[3] = (y[3] * x[1] - y[1] * x[3]) / x[1] ** 4 - 3.0 * x[2] * inner / x[1] ** 5
    if m > 4:
        raise ValueError("reparametrize supports up to the third derivative")
    return out
