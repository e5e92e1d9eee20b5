"""Rigid kinematics: follower and valve motion from the lift curve; lash take-up and seating.

The valve moves only once the follower has taken up the lash: s = max(0, ratio L - lash).
At the take-up and seating instants the rigid theory gives the valve a finite velocity in zero
time (Schenker's v1, v2), i.e. an impact; the lash effect finds those instants by root-finding
on the analytic lift, not on the sampled grid.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.roots import root_in




def lash_crossings(lift, ratio: float, lash: float, n_grid: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """Cam angles (rad) where ratio*L crosses `lash` upwards (take-up) and downwards (seating).

    Brackets come from a grid refined at the curve's breakpoints and at the lift's local maxima
    between closed grid points (a brief opening narrower than a grid cell would hide there); each
    root is polished with Brent's method on the analytic curve to machine precision.
    """
    grid = np.linspace(0.0, 2.0 * math.pi, n_grid + 1)
    grid = np.unique(np.concatenate([grid, np.asarray(lift.breakpoints(), dtype=float)]))
    d = lift.derivatives(grid)
    g = ratio * d[0] - lash

    def f(th: float) -> float:
        return float(ratio * lift.derivatives(np.array([th]))[0, 0] - lash)

    def slope(th: float) -> float:
        return float(lift.derivatives(np.array([th]))[1, 0])

    hidden = np.nonzero((d[1][:-1] > 0.0) & (d[1][1:] < 0.0) & (g[:-1] <= 0.0) & (g[1:] <= 0.0))[0]
    if hidden.size:
        peaks = [root_in(slope, grid[i], grid[i + 1], fa=d[1][i], fb=d[1][i + 1], xtol=1e-15, maxiter=200)
                 for i in hidden]
        grid = np.unique(np.concatenate([grid, peaks]))
        g = ratio * lift.derivatives(grid)[0] - lash

    # The valve is open where ratio*L - lash > 0 (the kinematics' own test), so only changes of
    # that state count: a lift that just touches the lash (g = 0 at a point, or on a whole dwell)
    # never opens the valve and gives no take-up or seating.
    is_open = g > 0.0
    ups, downs = [], []
    for i in np.nonzero(is_open[:-1] != is_open[1:])[0]:
        a, b = grid[i], grid[i + 1]
        if g[i] == 0.0 or g[i + 1] == 0.0:
            root = a if g[i] == 0.0 else b
        else:
            root = root_in(f, a, b, fa=g[i], fb=g[i + 1], xtol=1e-15, maxiter=200)
        (ups if is_open[i + 1] else downs).append(math.fmod(root, 2.0 * math.pi))
    return np.unique(ups), np.unique(downs)


