"""Rigid kinematics: follower and valve motion from the lift curve; lash take-up and seating.

The valve moves only once the follower has taken up the lash: s = max(0, ratio L - lash).
At the take-up and seating instants the rigid theory gives the valve a finite velocity in zero
time (Schenker's v1, v2), i.e. an impact; the lash effect finds those instants by root-finding
on the analytic lift, not on the sampled grid.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.roots import root_in, roots_in
from ..lift.curves import TWO_PI, grid_with, lift_at, lift_rows




# the last lash_crossings asked for: the kinematics effect (the open angle) and the lash effect ask
# for the same lift object's crossings in one run; one entry, held with the lift itself (so that the
# object compared by identity is alive), its arrays read-only
_LAST: list = [None]


def lash_crossings(lift, ratio: float, lash: float, n_grid: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """Cam angles (rad) where ratio*L crosses `lash` upwards (take-up) and downwards (seating).

    Brackets come from a grid refined at the curve's breakpoints and at the lift's local maxima
    between closed grid points (a brief opening narrower than a grid cell would hide there); each
    root is polished with Brent's method on the analytic curve to machine precision. The arrays
    are read-only (the last call's are returned again for the same lift object and arguments).
    """
    last = _LAST[0]
    if last is not None and last[0] is lift and last[1] == (ratio, lash, n_grid):
        return last[2]
    found = _lash_crossings(lift, ratio, lash, n_grid)
    for array in found:
        array.setflags(write=False)
    _LAST[0] = (lift, (ratio, lash, n_grid), found)
    return found


def _lash_crossings(lift, ratio: float, lash: float, n_grid: int) -> tuple[np.ndarray, np.ndarray]:
    grid = np.linspace(0.0, 2.0 * math.pi, n_grid + 1)
    grid = grid_with(grid, lift.breakpoints())
    # only the rows each evaluation reads (lift_rows: the lift's derivatives' floats; one row of
    # one angle costs half of all four, and Brent takes some 14 of them a sweep)
    d = lift_rows(lift, grid, (0, 1))
    g = ratio * d[0] - lash

    def f(th: float) -> float:
        return float(ratio * lift_at(lift, th, 0) - lash)

    def slope(th: float) -> float:
        return lift_at(lift, th, 1)

    hidden = np.nonzero((d[1][:-1] > 0.0) & (d[1][1:] < 0.0) & (g[:-1] <= 0.0) & (g[1:] <= 0.0))[0]
    if hidden.size:
        peaks = [root_in(slope, grid[i], grid[i + 1], fa=d[1][i], fb=d[1][i + 1], xtol=1e-15, maxiter=200)
                 for i in hidden]
        grid = grid_with(grid, peaks)
        g = ratio * lift_rows(lift, grid, (0,))[0] - lash

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




ONE_SIDED = 1e-12  # rad either side of a breakpoint: its one-sided limits (a derivative may jump there)


def open_angle(ups: np.ndarray, downs: np.ndarray, always_open: bool) -> float:
    """The angle (rad) the valve is open in a revolution, from lash_crossings' take-ups and seatings
    (each take-up opens until the next seating, around the revolution); 2 pi or 0 without
    crossings (always_open: the valve never closes)."""
    if ups.size == 0 or downs.size == 0:
        return TWO_PI if always_open else 0.0
    marks = sorted([(float(a), 1) for a in ups] + [(float(a), -1) for a in downs])
    total, opened = 0.0, None
    for angle, kind in marks + [(a + TWO_PI, k) for a, k in marks]:  # twice round: intervals that wrap
        if kind > 0 and opened is None:
            opened = angle
        elif kind < 0 and opened is not None:
            if opened < TWO_PI:
                total += angle - opened
            opened = None
    return total


def closed_lines(lift, theta: np.ndarray, d: np.ndarray, needed) -> tuple[np.ndarray, dict, np.ndarray]:
    """(angles, line, across) for valve_extremes: the samples theta (sorted; d the lift's
    derivatives there) closed round the revolution with the one-sided angles at the lift's
    breakpoints merged in; line[row] the lift's derivative `row` of `needed` at those angles; and
    which brackets lie within a breakpoint's two one-sided angles (across a jump, not a zero of the
    next derivative)."""
    marks = np.sort(np.mod(np.asarray(lift.breakpoints(), dtype=float).reshape(-1), TWO_PI))
    sides = np.sort(np.concatenate([marks - ONE_SIDED, marks + ONE_SIDED]))
    angles = np.append(theta, theta[0] + TWO_PI)
    rows = np.concatenate([d[needed], d[needed][:, :1]], axis=1)
    if sides.size:  # (a lift without breakpoints: a contour followed by a face)
        at = np.searchsorted(angles, sides)
        angles = np.insert(angles, at, sides)
        rows = np.insert(rows, at, lift_rows(lift, sides, tuple(needed)), axis=1)
    across = ((angles[:-1, None] >= marks - ONE_SIDED) & (angles[1:, None] <= marks + ONE_SIDED)).any(axis=1)
    return angles, dict(zip(needed, rows)), across


def valve_extremes(lift, theta: np.ndarray, d: np.ndarray, ratio: float, lash: float, scales: dict[int, float],
                   ends=()) -> dict[int, tuple[float, float]]:
    """The largest and smallest scale * L^(row) of each row of `scales` (row 1, scale ratio w: the
    valve's velocity; row 2, scale ratio w^2: its acceleration, the floats of the kinematics'
    columns at a sample) over the revolution, exact rather than sampled: the samples theta (d: the
    lift's derivatives there), the one-sided limits at the lift's breakpoints (a derivative that
    jumps there has its supremum as the figure: Schenker's p at F, -117 -> +159 m/s^2), the extrema
    between samples, where L^(row+1) changes sign (Brent on the analytic curve), and the open
    stretches' ends (`ends`: lash_crossings' take-ups and seatings, where the valve's motion starts
    and stops: a peak there is its limit from inside). Where the valve is closed (ratio L - lash
    <= 0) its motion is 0, and 0 counts when it is closed anywhere. An extremum hidden between two
    samples with two sign changes of L^(row+1) is not seen (a sample grid of degrees or finer:
    none in the shipped laws)."""
    needed = sorted({0, *scales, *(row + 1 for row in scales)})
    angles, line, across = closed_lines(lift, theta, d, needed)
    is_open = ratio * line[0] - lash > 0.0
    closed_somewhere = not (ratio * d[0] - lash > 0.0).all()
    ends = np.asarray(ends, dtype=float).reshape(-1)
    # every row's brackets (where L^(row+1) changes sign)
    brackets = {row: np.nonzero((np.sign(line[row + 1][:-1]) * np.sign(line[row + 1][1:]) < 0.0) & ~across)[0]
                for row in scales}
    lower = np.concatenate([brackets[row] for row in scales]).astype(int)  # each bracket's first angle
    slope_of = np.concatenate([np.full(brackets[row].size, row + 1) for row in scales]).astype(int)
    slope_rows = tuple(sorted({row + 1 for row in scales}))

    def slopes(th, i):
        d = lift_rows(lift, th, slope_rows)
        return d[np.searchsorted(slope_rows, slope_of[i]), np.arange(th.size)]

    fa = np.concatenate([line[row + 1][brackets[row]] for row in scales])
    fb = np.concatenate([line[row + 1][brackets[row] + 1] for row in scales])
    if getattr(lift, "row_at", None) is not None:  # one angle in Python floats: cheaper than arrays
        roots = [root_in(lambda th, k=int(k): lift_at(lift, th, k), float(angles[i]), float(angles[i + 1]),
                         fa=float(ga), fb=float(gb), xtol=1e-15, maxiter=200)
                 for i, k, ga, gb in zip(lower, slope_of, fa, fb)]

        def at_root(n: int, row: int) -> float:
            return lift_at(lift, roots[n], row)

        def at_ends(row: int) -> list[float]:
            return [lift_at(lift, float(x), row) for x in ends]
    else:
        # all at once: roots_in gives each the float of its own root_in on lift_at (an angle's value
        # is the same float among other angles or alone: lift_at's contract), calling the lift once
        # a step for all (a spline or table lift at one angle costs as much as at a hundred)
        roots = roots_in(slopes, angles[lower], angles[lower + 1], fa=fa, fb=fb, xtol=1e-15, maxiter=200)
        on_roots, on_ends = (dict(zip(needed, lift_rows(lift, x, tuple(needed)).tolist())) if x.size
                             else {row: [] for row in needed} for x in (np.asarray(roots, dtype=float), ends))

        def at_root(n: int, row: int) -> float:
            return on_roots[row][n]

        def at_ends(row: int) -> list[float]:
            return on_ends[row]
    out, first = {}, 0
    for row, scale in scales.items():
        sampled = scale * line[row][is_open]
        values = [float(sampled.max()), float(sampled.min())] if sampled.size else []
        if closed_somewhere:
            values.append(0.0)
        for n in range(first, first + brackets[row].size):
            if ratio * at_root(n, 0) - lash > 0.0:
                values.append(scale * at_root(n, row))
        first += brackets[row].size
        values.extend(scale * v for v in at_ends(row))
        out[row] = (max(values), min(values)) if values else (math.nan, math.nan)
    return out


BISECT_LEVELS = 6  # halvings per evaluation of the lift in lash_take_ups (63 angles a bracket)


def lash_take_ups(lift, ratio: float, lashes, n_grid: int = 4096) -> np.ndarray:
    """The first take-up angle (rad, [0, 2 pi)) of each lash of `lashes` at once: what
    lash_crossings(lift, ratio, lash)[0][0] gives for one (NaN where the valve never opens), on the
    same grid (refined at the breakpoints and at every local maximum of the lift, where a brief
    opening could hide between grid points), each root bisected in its bracket to brentq's
    tolerance (xtol 1e-15 + 4 eps |x|): equal to Brent's root to that tolerance, for many lashes
    in a few vectorised evaluations of the lift (a tolerance study draws a new lash every run)."""
    lashes = np.atleast_1d(np.asarray(lashes, dtype=float))
    grid = np.linspace(0.0, 2.0 * math.pi, n_grid + 1)
    grid = grid_with(grid, lift.breakpoints())
    d = lift_rows(lift, grid, (0, 1))  # the rows read (lift_rows: the same floats)

    def slope(th: float) -> float:
        return lift_at(lift, th, 1)

    peaks = np.nonzero((d[1][:-1] > 0.0) & (d[1][1:] < 0.0))[0]
    if peaks.size:
        extra = [root_in(slope, grid[i], grid[i + 1], fa=d[1][i], fb=d[1][i + 1], xtol=1e-15) for i in peaks]
        grid = grid_with(grid, extra)
        d = lift_rows(lift, grid, (0, 1))
    level = ratio * d[0]
    # the first grid point above each lash (the running maximum is sorted); the take-up is the
    # interval before it -- unless the valve is open at 0 already, then the first rise after a
    # closed point (searched densely, for those lashes only)
    j = np.searchsorted(np.maximum.accumulate(level), lashes, side="right")
    i = j - 1
    has = j < level.size
    dense = has & (j == 0)
    if dense.any():
        g = level[None, :] - lashes[dense][:, None]
        up = (g[:, :-1] <= 0.0) & (g[:, 1:] > 0.0)
        i[dense] = np.where(up.any(axis=1), np.argmax(up, axis=1), -1)
        has[dense] = up.any(axis=1)
    i = np.where(has, i, 0)
    a, b = grid[i], grid[i + 1]
    at_a = (level[i] - lashes) == 0.0
    lo, hi = a.copy(), b.copy()
    todo = has & ~at_a
    tol = 4.0 * np.finfo(float).eps
    steps = 0
    while steps < 80:  # bounded: 2^-80 of a grid cell is far below the tolerance
        active = todo & (hi - lo > 1e-15 + tol * np.abs(hi))
        if not active.any():
            break
        # BISECT_LEVELS halvings of each active bracket from one evaluation of the lift: every
        # midpoint the next halvings could take (a tree of 2^levels - 1, each 0.5 (lo + hi) of its
        # bracket, as one halving at a time computes it), then the path the signs choose
        levels = min(BISECT_LEVELS, 80 - steps)
        idx = np.nonzero(active)[0]
        los, his = lo[idx][:, None], hi[idx][:, None]
        tree = []
        for _ in range(levels):
            mid = 0.5 * (los + his)
            tree.append(mid)
            los = np.stack([los, mid], axis=2).reshape(idx.size, -1)  # children (lo, mid), (mid, hi)
            his = np.stack([mid, his], axis=2).reshape(idx.size, -1)
        mids = np.concatenate(tree, axis=1)
        f = ratio * lift_rows(lift, mids.ravel(), (0,))[0].reshape(mids.shape) - lashes[idx][:, None]  # as lash_crossings' f
        rows = np.arange(idx.size)
        l, h = lo[idx], hi[idx]
        alive = np.ones(idx.size, bool)
        node = np.zeros(idx.size, np.intp)  # the bracket's place in its level
        for k in range(levels):
            if k:
                alive &= h - l > 1e-15 + tol * np.abs(h)
            col = (1 << k) - 1 + node
            m, right = mids[rows, col], f[rows, col] > 0.0
            h = np.where(alive & right, m, h)
            l = np.where(alive & ~right, m, l)
            node = 2 * node + ~right
        lo[idx], hi[idx] = l, h
        steps += levels
    root = np.where(at_a, a, 0.5 * (lo + hi))
    return np.where(has, np.fmod(root, 2.0 * math.pi), np.nan)


JUMP_TOLERANCE = 1e-6  # of the valve's largest |acceleration|: a smaller step is a smooth joint's round-off
OPEN_PROBE = 1e-6  # rad either side of a breakpoint where accel_jumps asks whether the valve is open


def accel_jumps(lift, ratio: float, lash: float, scale: float, peak: float) -> list[tuple[float, float, float]]:
    """(angle rad, before, after) at each breakpoint of the lift where the open valve's
    acceleration (scale L'', scale = ratio omega^2) jumps: its one-sided limits there (ONE_SIDED
    either side; 0 on a side where the valve is closed), where they differ by more than
    JUMP_TOLERANCE of `peak` (the largest |acceleration|). Schenker's lesson (1902): where two
    circular arcs of a cam meet, the acceleration jumps (his Fig. 2 at F: -117 -> +159 m/s^2), and
    there the jerk is unbounded, whatever the samples' jerk says. The valve's own jumps at the lash
    take-up and seating (from 0 to the follower's) are the impact's, not the cam's: not listed,
    unless one falls on a breakpoint (no lash: the valve leaves its seat where the rise begins, and
    a harmonic rise's acceleration jumps there from 0)."""
    marks = np.unique(np.mod(np.asarray(lift.breakpoints(), dtype=float).reshape(-1), TWO_PI))
    if not marks.size:
        return []
    sides = np.concatenate([marks - ONE_SIDED, marks + ONE_SIDED])
    # open on a side: a micro-radian in (with no lash the valve leaves its seat at a rise's first
    # breakpoint, where 1 - cos of 1e-12 rad is 0 in floats)
    probe = lift_rows(lift, np.concatenate([marks - OPEN_PROBE, marks + OPEN_PROBE]), (0,))[0]
    is_open = ratio * probe - lash > 0.0
    accel = np.where(is_open, scale * lift_rows(lift, sides, (2,))[0], 0.0)
    n = marks.size
    out = []
    for i in range(n):
        if not (is_open[i] or is_open[n + i]):
            continue
        before, after = float(accel[i]), float(accel[n + i])
        if abs(after - before) > JUMP_TOLERANCE * peak:
            out.append((float(marks[i]), before, after))
    return out
