"""Truncated derivative jets: exact derivatives by the chain rule, no finite differences.

A jet is an array of shape (m + 1, ...) holding f, f', ..., f^(m) of one function of one
independent variable, at many points. Sums are row-wise; products, quotients and square roots
follow Leibniz' rule row by row, functions of a jet follow Faa di Bruno, so composing them gives
the exact derivatives of the composition (to rounding).

This is the one jet arithmetic of the package. The cam geometry (geometry/arcs.py,
geometry/parametric.py) calls these functions on bare arrays, for the roller-centre lift over a
contour, where writing the third derivative by hand would be long and easy to get wrong. The
valve gears (gears/jet.py) wrap the same functions in a `Jet` class with operators, for chains
of closed forms (circle intersections, atan2, acos) of the cam angle.
"""

from __future__ import annotations

from math import comb

import numpy as np


def constant(value, like: np.ndarray) -> np.ndarray:
    """The jet of a constant, shaped like `like`."""
    out = np.zeros_like(like, dtype=float)
    out[0] = value
    return out


def _term(n: int, k: int, a, b):
    """C(n, k) a b, without the multiplication by 1 at the ends (these run inside the gears'
    Newton loops on small arrays, where every numpy call counts)."""
    return a * b if k in (0, n) else comb(n, k) * a * b


def mul(f: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Leibniz: (fg)^(n) = sum_k C(n,k) f^(k) g^(n-k)."""
    m = min(len(f), len(g))
    first = f[0] * g[0]
    out = np.empty((m,) + np.shape(first))
    out[0] = first
    for n in range(1, m):
        acc = f[0] * g[n]  # the end terms (k = 0, n) have C(n, k) = 1: see _term
        for k in range(1, n):
            acc = acc + comb(n, k) * f[k] * g[n - k]
        out[n] = acc + f[n] * g[0]
    return out


def div(f: np.ndarray, g: np.ndarray) -> np.ndarray:
    """h = f / g from g h = f: h_n = (f_n - sum_{k>=1} C(n,k) g_k h_{n-k}) / g_0."""
    m = min(len(f), len(g))
    first = f[0] / g[0]
    out = np.empty((m,) + np.shape(first))
    out[0] = first
    for n in range(1, m):
        acc = _term(n, 1, g[1], out[n - 1])
        for k in range(2, n + 1):
            acc = acc + _term(n, k, g[k], out[n - k])
        out[n] = (f[n] - acc) / g[0]
    return out


def sqrt(f: np.ndarray) -> np.ndarray:
    """g = sqrt(f) from g g = f: g_n = (f_n - sum_{0<k<n} C(n,k) g_k g_{n-k}) / (2 g_0)."""
    out = np.empty_like(f, dtype=float)
    out[0] = np.sqrt(f[0])
    if len(f) > 1:
        twice = 2.0 * out[0]
        out[1] = f[1] / twice
    for n in range(2, len(f)):
        acc = _term(n, 1, out[1], out[n - 1])
        for k in range(2, n):
            acc = acc + _term(n, k, out[k], out[n - k])
        out[n] = (f[n] - acc) / twice
    return out


def compose(g: np.ndarray, f0, f1=None, f2=None, f3=None) -> np.ndarray:
    """h = F(g) given F, F', F'', F''' evaluated at g[0] (Faa di Bruno, up to the third derivative):
    h' = F' g',  h'' = F'' g'^2 + F' g'',  h''' = F''' g'^3 + 3 F'' g' g'' + F' g'''."""
    m = len(g)
    if m > 4:
        raise ValueError("compose supports up to the third derivative")
    out = np.empty(g.shape)
    out[0] = f0
    if m > 1:
        g1 = g[1]
        out[1] = f1 * g1
    if m > 2:
        out[2] = f2 * g1 * g1 + f1 * g[2]
    if m > 3:
        out[3] = (f3 * g1 * g1 + 3.0 * f2 * g[2]) * g1 + f1 * g[3]
    return out


def derivative(f: np.ndarray) -> np.ndarray:
    """The jet of f' (one order less)."""
    return f[1:]


def truncate(f: np.ndarray, rows: int) -> np.ndarray:
    return f[:rows]


def atan2(b: np.ndarray, a: np.ndarray) -> np.ndarray:
    """phi = atan2(b, a) with phi' = (a b' - b a') / (a^2 + b^2), applied as a jet one order lower."""
    m = min(len(a), len(b))
    first = np.arctan2(b[0], a[0])
    out = np.empty((m,) + np.shape(first))
    out[0] = first
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
