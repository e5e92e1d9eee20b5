"""Compiled loops of a speed sweep's rigid figures (explorer/studies/sweep_rigid.py), with numba.

Why compiled: the rigid contact force at many speeds is F = w^2 A + G on a grid of some 2 000 to
4 000 samples (explorer.mechanics.forces); the sweep needs, per speed, the smallest F on each
smooth piece (min_contact_forces) and the largest camshaft torque c(F) F (peak_torques). In numpy
each is six to eight passes over a (speeds x samples) temporary; here each is one pass with no
temporary (issue #27.5: they were 40 % of a 1000-speed sweep of valve_float_demo.toml). The same
floats as numpy's: F is one product and one sum (numba does not fuse them without fastmath), a
minimum keeps the first of equal values (np.argmin), a NaN wins (np.minimum, np.argmin), and the
torque keeps the finite values only (contact.peak_torques). tests/test_sweep_kernel.py compares
them with the numpy forms bit for bit.

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
    np.minimum.reduceat and np.argmin of each piece's slice (a NaN: the first NaN)."""
    speeds, pieces = w2.size, lows.size
    minima = np.empty((speeds, pieces))
    where = np.empty((speeds, pieces), dtype=np.intp)
    for s in range(speeds):
        w = w2[s]
        for k in range(pieces):
            lo, hi = lows[k], highs[k]
            best = w * a_coef[lo] + g_part[lo]
            j = 0
            if best == best:
                for i in range(lo + 1, hi):
                    v = w * a_coef[i] + g_part[i]
                    if v < best:
                        best, j = v, i - lo
                    elif v != v:
                        best, j = v, i - lo
                        break
            minima[s, k] = best
            where[s, k] = j
    return minima, where


@njit(cache=True)
def peak_torques(w2, a_coef, g_part, push, pull, floor):
    """Largest finite T = F c of each speed, F = w2[s] A + G, c = push where F > 0 else pull, and
    at least `floor` (0: some samples are closed and carry no force; -inf: none is)."""
    out = np.empty(w2.size)
    for s in range(w2.size):
        w = w2[s]
        best = floor
        for i in range(a_coef.size):
            f = w * a_coef[i] + g_part[i]
            t = f * (push[i] if f > 0.0 else pull[i])
            if t > best and math.isfinite(t):
                best = t
        out[s] = best
    return out


def warm() -> None:
    """Compile (or load) both kernels for the argument types the sweep passes."""
    x = np.linspace(-1.0, 1.0, 8)
    lows, highs = np.array([0, 4], dtype=np.intp), np.array([4, 8], dtype=np.intp)
    piece_minima(x[:2].copy(), x, x, lows, highs)
    peak_torques(x[:2].copy(), x, x, x, x, 0.0)


def aot_exports() -> dict:
    """What the ahead-of-time module exports (sweep_loops.build_aot): both loops, for the argument
    types and layouts sweep_loops passes."""
    from numba import types as T

    A1, P1 = T.float64[::1], T.intp[::1]
    return {"piece_minima": (T.Tuple((T.float64[:, ::1], T.intp[:, ::1]))(A1, A1, A1, P1, P1), piece_minima),
            "peak_torques": (A1(A1, A1, A1, A1, A1, T.float64), peak_torques)}


if __name__ == "__main__":
    warm()
