"""Normalised motion laws: f(u) for u in [0, 1] with f(0) = 0, f(1) = 1 and analytic f', f'', f'''.

A rise of height h over cam angle beta is L = h f(u), u = (theta - theta0)/beta, so
dL/dtheta = h f'/beta, d2L/dtheta2 = h f''/beta^2, d3L/dtheta3 = h f'''/beta^3.
The peak coefficients Cv = max f', Ca = max |f''|, Cj = max |f'''| are the classic table values.

The trapezoid and sine families are built from segments whose acceleration is
c0 + c1 sin(w x) + c2 cos(w x); velocity and lift are their exact integrals, so nothing here
is differentiated or integrated numerically.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

TWO_PI = 2.0 * math.pi


# Every law below is evaluate(u, rows=ALL_ROWS): the rows of f and its first three derivatives
# asked for, in that order. Each row is its own arithmetic, so a row asked for alone is the same
# floats as among all four (the sweep's zoom, forces._zoom_minima, needs only f and f'').
ALL_ROWS = (0, 1, 2, 3)


def _polynomial(coefficients: tuple[float, ...]):
    """f(u) = sum c_k u^k, with exact derivatives."""
    p0 = np.polynomial.Polynomial(coefficients)
    rows_of = [tuple(float(c) for c in p0.deriv(k).coef) for k in range(4)]

    def evaluate(u: np.ndarray, rows: tuple[int, ...] = ALL_ROWS) -> np.ndarray:
        # Horner for each derivative into one array (numpy's polyval, without its per-call
        # domain mapping and stacking: the elastic solver evaluates the drive every revolution)
        u = np.asarray(u, dtype=float)
        x = u.reshape(-1)
        out = np.empty((len(rows), x.size))
        for row, k in zip(out, rows):
            c = rows_of[k]
            row[...] = c[-1]
            for ck in c[-2::-1]:
                row *= x
                row += ck
        return out.reshape((len(rows),) + u.shape)

    def at(u: float, row: int) -> float:  # evaluate's Horner in Python floats: the same products and sums
        c = rows_of[row]
        value = c[-1]
        for ck in c[-2::-1]:
            value = value * u + ck
        return value

    evaluate.at = at
    return evaluate


def _one(function, x: float) -> float:
    """function (np.sin, np.cos) of one angle as numpy computes it within an array of one element
    (the loop evaluate runs for a single angle; a Python scalar might take another)."""
    return float(function(np.array([x]))[0])


def _cycloidal(u: np.ndarray, rows: tuple[int, ...] = ALL_ROWS) -> np.ndarray:
    a = TWO_PI * u
    s = np.sin(a) if {0, 2} & set(rows) else None
    c = np.cos(a) if {1, 3} & set(rows) else None
    row = {0: lambda: u - s / TWO_PI, 1: lambda: 1.0 - c, 2: lambda: TWO_PI * s, 3: lambda: TWO_PI**2 * c}
    return np.stack([row[k]() for k in rows])


def _cycloidal_at(u: float, row: int) -> float:
    a = TWO_PI * u
    if row in (0, 2):
        s = _one(np.sin, a)
        return u - s / TWO_PI if row == 0 else TWO_PI * s
    c = _one(np.cos, a)
    return 1.0 - c if row == 1 else TWO_PI**2 * c


_cycloidal.at = _cycloidal_at


def _harmonic(u: np.ndarray, rows: tuple[int, ...] = ALL_ROWS) -> np.ndarray:
    a = math.pi * u
    s = np.sin(a) if {1, 3} & set(rows) else None
    c = np.cos(a) if {0, 2} & set(rows) else None
    row = {0: lambda: 0.5 * (1.0 - c), 1: lambda: 0.5 * math.pi * s, 2: lambda: 0.5 * math.pi**2 * c,
           3: lambda: -0.5 * math.pi**3 * s}
    return np.stack([row[k]() for k in rows])


def _harmonic_at(u: float, row: int) -> float:
    a = math.pi * u
    if row in (1, 3):
        s = _one(np.sin, a)
        return 0.5 * math.pi * s if row == 1 else -0.5 * math.pi**3 * s
    c = _one(np.cos, a)
    return 0.5 * (1.0 - c) if row == 0 else 0.5 * math.pi**2 * c


_harmonic.at = _harmonic_at


@dataclass(frozen=True)
class _Segment:
    start: float
    end: float
    c0: float  # constant acceleration part
    c1: float  # amplitude of sin(w (u - start))
    c2: float  # amplitude of cos(w (u - start))
    w: float


def _piecewise_harmonic(segments: list[_Segment]):
    """Exact integration of piecewise acceleration c0 + c1 sin + c2 cos, then scaled to f(1) = 1."""
    starts = np.array([s.start for s in segments])
    v0s, s0s = [], []
    v, s = 0.0, 0.0
    for seg in segments:
        v0s.append(v)
        s0s.append(s)
        x = seg.end - seg.start
        v, s = _segment_state(seg, x, v, s)[:2]
    scale = 1.0 / s  # makes f(1) = 1 exactly (up to rounding)

    def evaluate(u: np.ndarray, rows: tuple[int, ...] = ALL_ROWS) -> np.ndarray:
        u = np.asarray(u, dtype=float)
        out = np.empty((4,) + u.shape)
        index = np.clip(np.searchsorted(starts, u, side="right") - 1, 0, len(segments) - 1)
        for i, seg in enumerate(segments):
            mask = index == i
            if not np.any(mask):
                continue
            x = u[mask] - seg.start
            vv, ss, aa, jj = _segment_state(seg, x, v0s[i], s0s[i])
            out[0][mask] = ss * scale
            out[1][mask] = vv * scale
            out[2][mask] = aa * scale
            out[3][mask] = jj * scale
        return out if rows == ALL_ROWS else out[list(rows)]  # a segment's state comes whole

    def at(u: float, row: int) -> float:  # evaluate's segment (searchsorted, clip) and its arithmetic
        i = min(max(bisect.bisect_right(starts_list, u) - 1, 0), len(segments) - 1)
        seg = segments[i]
        x = u - seg.start
        w = seg.w
        sin, cos = _one(np.sin, w * x), _one(np.cos, w * x)
        if row == 0:
            # x * x: numpy squares an array's x**2 (np.square), Python's float ** calls pow
            value = s0s[i] + v0s[i] * x + 0.5 * seg.c0 * (x * x) + seg.c1 * (x / w - sin / w**2) \
                + seg.c2 * (1.0 - cos) / w**2
        elif row == 1:
            value = v0s[i] + seg.c0 * x + seg.c1 * (1.0 - cos) / w + seg.c2 * sin / w
        elif row == 2:
            value = seg.c0 + seg.c1 * sin + seg.c2 * cos
        else:
            value = w * (seg.c1 * cos - seg.c2 * sin)
        return value * scale

    starts_list = starts.tolist()
    evaluate.at = at
    return evaluate


def _segment_state(seg: _Segment, x, v0: float, s0: float):
    w = seg.w
    sin, cos = np.sin(w * x), np.cos(w * x)
    a = seg.c0 + seg.c1 * sin + seg.c2 * cos
    j = w * (seg.c1 * cos - seg.c2 * sin)
    v = v0 + seg.c0 * x + seg.c1 * (1.0 - cos) / w + seg.c2 * sin / w
    s = s0 + v0 * x + 0.5 * seg.c0 * x**2 + seg.c1 * (x / w - sin / w**2) + seg.c2 * (1.0 - cos) / w**2
    return v, s, a, j


_W4 = 4.0 * math.pi
# Modified trapezoid: sine ramps to +-1 over the first, middle and last eighths, constant between.
_MOD_TRAPEZOID = _piecewise_harmonic(
    [
        _Segment(0.0, 0.125, 0.0, 1.0, 0.0, _W4),
        _Segment(0.125, 0.375, 1.0, 0.0, 0.0, _W4),
        _Segment(0.375, 0.625, 0.0, 0.0, 1.0, _W4),
        _Segment(0.625, 0.875, -1.0, 0.0, 0.0, _W4),
        _Segment(0.875, 1.0, 0.0, 0.0, -1.0, _W4),
    ]
)
_MOD_SINE = _piecewise_harmonic(
    [
        _Segment(0.0, 0.125, 0.0, 1.0, 0.0, _W4),
        _Segment(0.125, 0.875, 0.0, 0.0, 1.0, _W4 / 3.0),
        _Segment(0.875, 1.0, 0.0, 0.0, -1.0, _W4),
    ]
)

# 5-6-7-8-9 polynomial (Norton, Cam Design and Manufacturing Handbook, polynomial cams): f(0) = 0,
# f(1) = 1 and its first four derivatives 0 at both ends, ten conditions for degree 9. Its velocity
# is f' = 630 u^4 (1 - u)^4 (f is the regularised incomplete beta function I_u(5, 5)). Its snap is
# continuous into a dwell: the wanted lift of a polydyne cam whose acceleration has no step.
POLYNOMIAL_56789 = (0, 0, 0, 0, 0, 126, -420, 540, -315, 70)

LAWS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "cycloidal": _cycloidal,
    "harmonic": _harmonic,
    "polynomial-345": _polynomial((0, 0, 0, 10, -15, 6)),
    "polynomial-4567": _polynomial((0, 0, 0, 0, 35, -84, 70, -20)),
    "polynomial-56789": _polynomial(POLYNOMIAL_56789),
    "modified-trapezoid": _MOD_TRAPEZOID,
    "modified-sine": _MOD_SINE,
}


for _evaluate in LAWS.values():  # the closed forms above take rows (a plug-in's law may not)
    _evaluate.takes_rows = True


def law_rows(name: str, u, rows: tuple[int, ...] = ALL_ROWS) -> np.ndarray:
    """The rows of the law `name` at u: all four as the law gives them; fewer from the law itself
    when it takes rows (the closed forms: the same floats), else its four rows' selection (a law
    registered as a plug-in, explorer.lift.registry.register_law: u -> (4, ...) only)."""
    function = LAWS[name]
    if rows == ALL_ROWS:
        return function(u)
    if getattr(function, "takes_rows", False):
        return function(u, rows)
    return function(u)[list(rows)]


def law_at(name: str, u: float, row: int) -> float:
    """law_rows(name, np.array([u]), (row,))[0, 0], the same float: from the law's own `at` where it
    has one (the closed forms: their arithmetic on one float, a tenth of the cost of arrays of one
    element), for the root searches that evaluate the lift at one angle at a time."""
    function = LAWS[name]
    at = getattr(function, "at", None)
    if at is not None:
        return at(u, row)
    return float(law_rows(name, np.array([u]), (row,))[0, 0])


def law(name: str) -> Callable[..., np.ndarray]:
    """The normalised law `name`: u -> array (4, ...) of f, f', f'', f''' (law_rows: some of them)."""
    return LAWS[name]


def _polynomial_high(coefficients: tuple[float, ...], u: np.ndarray, order: int) -> np.ndarray:
    p0 = np.polynomial.Polynomial(coefficients)
    return np.stack([p0.deriv(k)(u) if k else p0(u) for k in range(order + 1)])


def _cycloidal_high(u: np.ndarray, order: int) -> np.ndarray:
    # f = u - sin(a)/(2 pi), a = 2 pi u: f^(n) = -(2 pi)^(n-1) sin(a + n pi/2) for n >= 2
    a = TWO_PI * u
    rows = [u - np.sin(a) / TWO_PI, 1.0 - np.cos(a)]
    rows += [-(TWO_PI ** (n - 1)) * np.sin(a + n * 0.5 * math.pi) for n in range(2, order + 1)]
    return np.stack(rows[: order + 1])


def _harmonic_high(u: np.ndarray, order: int) -> np.ndarray:
    # f = (1 - cos(pi u))/2: f^(n) = -(pi^n / 2) cos(pi u + n pi/2) for n >= 1
    a = math.pi * u
    rows = [0.5 * (1.0 - np.cos(a))]
    rows += [-0.5 * math.pi**n * np.cos(a + n * 0.5 * math.pi) for n in range(1, order + 1)]
    return np.stack(rows)


# Laws with closed-form derivatives beyond the jerk (a polydyne cam needs the wanted lift's fourth
# and fifth); the trapezoid and sine families' jerk jumps, so no polydyne cam can take them anyway.
HIGH_ORDER_LAWS: dict[str, Callable[[np.ndarray, int], np.ndarray]] = {
    "cycloidal": _cycloidal_high,
    "harmonic": _harmonic_high,
    "polynomial-345": lambda u, order: _polynomial_high((0, 0, 0, 10, -15, 6), u, order),
    "polynomial-4567": lambda u, order: _polynomial_high((0, 0, 0, 0, 35, -84, 70, -20), u, order),
    "polynomial-56789": lambda u, order: _polynomial_high(POLYNOMIAL_56789, u, order),
}


def law_derivatives(name: str, u, order: int) -> np.ndarray:
    """(order + 1, ...) array: f and its first `order` derivatives of the normalised law `name`,
    in closed form (KeyError: a law without closed-form derivatives beyond the third). Complex u
    is kept complex (the tests' complex-step oracle)."""
    u = np.asarray(u)
    u = u if np.iscomplexobj(u) else u.astype(float)
    if order <= 3:
        return LAWS[name](u)[: order + 1]
    return HIGH_ORDER_LAWS[name](u, order)
