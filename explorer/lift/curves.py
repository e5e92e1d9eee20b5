"""Follower lift over cam angle: the one curve every effect is computed from.

A lift curve is anything with `derivatives(theta) -> array (4, N)` holding L, dL/dtheta,
d2L/dtheta2, d3L/dtheta3 (theta in rad, periodic in 2 pi; L in m) and `breakpoints()`, the
angles in [0, 2 pi) where a derivative may jump. Time derivatives at constant speed follow as
v = w L', a = w^2 L'', j = w^3 L'''.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .laws import ALL_ROWS, law_at, law_rows

TWO_PI = 2.0 * math.pi


class LiftCurve(Protocol):
    def derivatives(self, theta: np.ndarray) -> np.ndarray: ...

    def breakpoints(self) -> np.ndarray: ...


@dataclass(frozen=True)
class LawLift:
    """Rise with one law, optional dwell, return with the same or another law, base circle elsewhere."""

    height: float
    start: float
    rise: float
    dwell: float
    ret: float
    rise_law: str
    return_law: str

    def derivatives(self, theta) -> np.ndarray:
        return self.derivative_rows(theta, ALL_ROWS)

    def derivative_rows(self, theta, rows: tuple[int, ...]) -> np.ndarray:
        """derivatives(theta)[list(rows)] (rows: of 0..3, in the order wanted), the same floats,
        computing only those rows (each row is its own arithmetic; lift_rows below)."""
        theta = np.asarray(theta, dtype=float)
        x = wrap_two_pi(theta.reshape(-1) - self.start)  # angle since the rise began
        out = np.zeros((len(rows), x.size))
        h = self.height
        # Classify by the signs of successive differences, not by comparing x with sums such as
        # rise + dwell: (x - rise) - dwell and x < rise + dwell round differently, which left a
        # point on the dwell's end in no stretch at all (lift 0 there instead of h).
        x_top = x - self.rise
        x_ret = x_top - self.dwell
        rising = _selection(x_top < 0.0)
        if rising is not None:
            f = law_rows(self.rise_law, x[rising] / self.rise, rows)
            f *= h
            f /= np.array([self.rise**k for k in rows])[:, None]  # h f[k] / rise**k
            out[:, rising] = f
        if 0 in rows:
            top = (x_top >= 0.0) & (x_ret < 0.0)
            out[rows.index(0)][top] = h
        falling = _selection((x_ret >= 0.0) & (x_ret < self.ret))
        if falling is not None:
            g = law_rows(self.return_law, x_ret[falling] / self.ret, rows)
            slopes = [i for i, k in enumerate(rows) if k]  # the derivatives' rows
            if len(slopes) < len(rows):
                out[rows.index(0), falling] = h * (1.0 - g[rows.index(0)])
            if slopes:
                block = slopes == list(range(slopes[0], slopes[-1] + 1))  # all four: rows 1..3
                g = g[slopes[0]:slopes[-1] + 1] if block else g[slopes]
                g *= -h
                g /= np.array([self.ret**rows[i] for i in slopes])[:, None]  # -h g[k] / ret**k
                if block:
                    out[slopes[0]:slopes[-1] + 1, falling] = g
                else:
                    for i, row in zip(slopes, g):
                        out[i, falling] = row
        return out.reshape((len(rows),) + theta.shape)

    def row_at(self, theta: float, row: int) -> float:
        """derivative_rows(np.array([theta]), (row,))[0, 0], the same float at a tenth of the cost:
        the wrap, the stretch and the scaling in Python floats (+, -, *, /, fmod and ** of floats are
        the same IEEE operations numpy does), the law on a one-element array as there. The root
        searches (lift_at) evaluate one angle at a time, some 30 times a revolution."""
        x = float(theta) - self.start
        if not math.isfinite(x):
            return float(self.derivative_rows(np.array([theta], dtype=float), (row,))[0, 0])
        if not 0.0 <= x < TWO_PI:  # wrap_two_pi's fmod and correction
            x = math.fmod(x, TWO_PI)
            if x < 0.0:
                x += TWO_PI
        h = self.height
        x_top = x - self.rise
        x_ret = x_top - self.dwell
        value = 0.0  # the stretches in derivative_rows' order of writing (they do not overlap)
        if x_top < 0.0:
            value = law_at(self.rise_law, x / self.rise, row) * h / self.rise**row
        if row == 0 and x_top >= 0.0 and x_ret < 0.0:
            value = h
        if x_ret >= 0.0 and x_ret < self.ret:
            g = law_at(self.return_law, x_ret / self.ret, row)
            value = h * (1.0 - g) if row == 0 else g * -h / self.ret**row
        return value

    def breakpoints(self) -> np.ndarray:
        top = self.rise + self.dwell  # the running sums of np.cumsum, in plain Python (4 values)
        marks = [x + self.start for x in (0.0, self.rise, top, top + self.ret)]
        return np.array(sorted({x % TWO_PI for x in marks}))  # (float % is np.mod)


def law_lift(spec) -> LawLift:
    """The closed-form lift of a [lift] spec (scene.lift: height, start, rise, dwell, return and
    the laws of the rise and the return)."""
    return LawLift(height=spec.height, start=spec.start, rise=spec.rise, dwell=spec.dwell, ret=spec.ret,
                   rise_law=spec.law, return_law=spec.return_law or spec.law)


def lift_rows(lift, theta, rows: tuple[int, ...]) -> np.ndarray:
    """lift.derivatives(theta)[list(rows)]: from the lift's derivative_rows when it has one (the
    same floats, only those rows computed: LawLift), else its derivatives."""
    own = getattr(lift, "derivative_rows", None)
    return own(theta, rows) if own is not None else lift.derivatives(theta)[list(rows)]


def lift_at(lift, theta: float, row: int) -> float:
    """Row `row` of the lift's derivatives at one angle (lift_rows: only that row computed; the
    lift's own row_at where it has one, the same float), for the root searches of one angle at a
    time."""
    own = getattr(lift, "row_at", None)
    if own is not None:
        return own(theta, row)
    return float(lift_rows(lift, np.array([theta]), (row,))[0, 0])


def grid_with(grid: np.ndarray, points) -> np.ndarray:
    """np.unique(np.concatenate([grid, points])), the same floats, for a strictly increasing grid
    (a revolution's 4097 angles and a lift's few breakpoints): the points merged in, not the grid
    sorted again (np.unique's sort was a third of a lash search). Negative, -0.0 or non-finite
    points take np.unique itself (where its order of equal values would matter)."""
    points = np.asarray(points, dtype=float).reshape(-1)
    if points.size == 0:
        return grid.copy()
    if not np.isfinite(points).all() or np.signbit(points).any():
        return np.unique(np.concatenate([grid, points]))
    points = np.unique(points)
    at = np.searchsorted(grid, points)
    new = (at >= grid.size) | (grid[np.minimum(at, grid.size - 1)] != points)
    return np.insert(grid, at[new], points[new])


def wrap_two_pi(x: np.ndarray) -> np.ndarray:
    """np.mod(x, 2 pi) from fmod and one correction (np.mod also computes the quotient and costs
    three times as much; the drive is evaluated at every node of every revolution). x itself when
    it is within [0, 2 pi) already (fmod returns such an x exactly, and the correction adds
    nothing): two reductions instead of fmod, the sweep's zoom of an open stretch's angles."""
    if x.size and x.min() >= 0.0 and x.max() < TWO_PI:  # (a NaN fails both: the general form)
        return x
    x = np.fmod(x, TWO_PI)
    np.add(x, TWO_PI, out=x, where=x < 0.0)
    return x


def _selection(mask: np.ndarray):
    """The points where mask holds: a slice when they are one run (sorted angles), else their
    indices; None when there are none."""
    idx = mask.nonzero()[0]
    if idx.size == 0:
        return None
    first, last = int(idx[0]), int(idx[-1])
    return slice(first, last + 1) if last - first + 1 == idx.size else idx


