"""Compiled loops of a speed sweep's rigid figures (explorer/studies/sweep_rigid.py), with numba.

Why compiled: the rigid contact force at many speeds is F = w^2 A + G on a grid of some 2 000 to
4 000 samples (explorer.mechanics.forces); the sweep needs, per speed, the smallest F on each
smooth piece (min_contact_forces) and the largest camshaft torque c(F) F (peak_torques). In numpy
each is six to eight passes over a (speeds x samples) temporary; here each is one pass with no
temporary (issue #27.5: they were 40 % of a 1000-speed sweep of valve_float_demo.toml). The same
floats as numpy's: F is one product and one sum (numba does not fuse them without fastmath), a
minimum keeps the first of equal values (np.argmin), a NaN wins (np.minimum, np.argmin), and the
torque keeps the finite values only (contact.peak_torques). A third loop takes each round of the
refining zoom's F and its minimum per row from the lift there (zoom_minima: load_parts' arithmetic
and np.argmin in one pass instead of some fifteen numpy passes). tests/test_sweep_kernel.py
compares them with the numpy forms bit for bit.

Imported only on the compiled sweep's path, through mechanics/sweep_loops.py, when no current
ahead-of-time module of these loops exists (forces.min_contact_forces and contact.peak_torques with
compiled=True, both called from studies/sweep_rigid.py; the browser's speed sweep uses
peak_torques' numpy form: its first page must not load numba). Cached on disk (cache=True) beside
this file, compiled by `make` (`python -m explorer.mechanics.sweep_kernels`), and compiled ahead
of time by `make` too (`python -m explorer.mechanics.sweep_loops --aot`: explorer/core/aot.py).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def piece_minima(w2, a_coef, g_part, lows, highs):
    """(minimum, index of its first occurrence from the piece's start) of F = w2[s] A + G over the
    samples lows[k] <= i < highs[k] of each piece k, for every speed s: (speeds x pieces) each;
    np.minimum.reduceat and np.argmin of each piece's slice (a NaN: the first NaN).

    The speeds are the inner loop: each speed visits the samples in the same order and compares as
    a loop of its own would (a smaller value replaces, the first NaN replaces and ends its scan),
    the same floats, but the speeds' lanes are independent, which the compiler vectorises (five
    times faster than the samples inside: a running minimum carried from sample to sample)."""
    speeds, pieces = w2.size, lows.size
    minima = np.empty((speeds, pieces))
    where = np.empty((speeds, pieces), dtype=np.intp)
    best = np.empty(speeds)
    at = np.empty(speeds, dtype=np.intp)
    for k in range(pieces):
        lo, hi = lows[k], highs[k]
        a, g = a_coef[lo], g_part[lo]
        for s in range(speeds):
            best[s] = w2[s] * a + g
            at[s] = 0
        for i in range(lo + 1, hi):
            a, g = a_coef[i], g_part[i]
            for s in range(speeds):
                b = best[s]
                v = w2[s] * a + g
                if b == b and (v < b or v != v):  # a NaN best has ended this speed's scan
                    best[s] = v
                    at[s] = i - lo
        for s in range(speeds):
            minima[s, k] = best[s]
            where[s, k] = at[s]
    return minima, where


@njit(cache=True)
def peak_torques(w2, a_coef, g_part, push, pull, floor):
    """Largest finite T = F c of each speed, F = w2[s] A + G, c = push where F > 0 else pull, and
    at least `floor` (0: some samples are closed and carry no force; -inf: none is). The speeds are
    the inner loop (as in piece_minima: each speed's samples in the same order, independent lanes)."""
    out = np.full(w2.size, floor)
    for i in range(a_coef.size):
        a, g, p, q = a_coef[i], g_part[i], push[i], pull[i]
        for s in range(w2.size):
            f = w2[s] * a + g
            t = f * (p if f > 0.0 else q)
            if t > out[s] and math.isfinite(t):
                out[s] = t
    return out


@njit(cache=True)
def zoom_minima(lift_at, accel_at, w2, direction, ratio, lash, mass_ratio, preload, rate, friction, closing):
    """(smallest F, index of its first occurrence) over each row's samples, for a round of the
    sweep's zoom (forces._zoom_minima): row r has the lift L and L'' at its samples in row r of
    lift_at, accel_at, its speed w2[r] and friction sign direction[r]. F is forces.load_parts'
    arithmetic, operation for operation,
    x = ratio L - lash, s = x where x > 0 else 0, A = (mass ratio) L'', G = preload + rate s +
    friction direction + closing (left to right), then F = w2 A + G, a value not finite taken as
    +inf, and the first of equal minima (np.argmin): the same floats as the numpy form."""
    rows, points = lift_at.shape
    best = np.empty(rows)
    where = np.empty(rows, dtype=np.intp)
    for r in range(rows):
        w = w2[r]
        fd = friction * direction[r]
        for i in range(points):
            x = ratio * lift_at[r, i] - lash
            s = x if x > 0.0 else 0.0
            f = w * (mass_ratio * accel_at[r, i]) + (((preload + rate * s) + fd) + closing)
            if not math.isfinite(f):
                f = math.inf
            if i == 0 or f < best[r]:
                best[r] = f
                where[r] = i
    return best, where


def warm() -> None:
    """Compile (or load) both kernels for the argument types the sweep passes."""
    x = np.linspace(-1.0, 1.0, 8)
    lows, highs = np.array([0, 4], dtype=np.intp), np.array([4, 8], dtype=np.intp)
    piece_minima(x[:2].copy(), x, x, lows, highs)
    peak_torques(x[:2].copy(), x, x, x, x, 0.0)
    grid = x.reshape(2, 4)
    zoom_minima(grid, grid, x[:2].copy(), x[:2].copy(), 1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0)


def aot_exports() -> dict:
    """What the ahead-of-time module exports (sweep_loops.build_aot): the three loops, for the argument
    types and layouts sweep_loops passes."""
    from numba import types as T

    A1, P1, A2, F = T.float64[::1], T.intp[::1], T.float64[:, ::1], T.float64
    return {"piece_minima": (T.Tuple((T.float64[:, ::1], T.intp[:, ::1]))(A1, A1, A1, P1, P1), piece_minima),
            "peak_torques": (A1(A1, A1, A1, A1, A1, T.float64), peak_torques),
            "zoom_minima": (T.Tuple((A1, P1))(A2, A2, A1, A1, F, F, F, F, F, F, F), zoom_minima)}


if __name__ == "__main__":
    warm()
