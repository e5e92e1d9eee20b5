"""The compiled exact solver's grid (explorer.dynamics.exact_grid's, built in Python by
exact_grid.build_grid and passed in as arrays): a revolution's grid in cam angle, valid at every
speed (RevolutionGrid, revolution_grid, split_parts: in kernel_shared, numba-free; the stepping reads it at the speed omega as
times theta / omega, S' and its bounds times omega, omega^2, omega^3, the step polynomials in
u = tau/h unchanged, scaling each value where it is read rather than copying the grid), the block
and window bounds read by the stepping (grid_bounds), and the time and drive at a point of a step.
Part of the compiled solver (explorer.dynamics.exact_kernel)."""

from __future__ import annotations

import numpy as np
from numba import njit

from . import kernel_stamp  # noqa: F401 (the cache is stale when a source it depends on changed)
from .kernel_shared import RevolutionGrid, revolution_grid, split_parts  # noqa: F401 (moved: numba-free)
from .kernel_steps import deriv_into, horner

BLOCK = 8  # steps a seated valve's bound clears at once (small: a seated stretch starts anywhere, and
# its bound fails near the lift-off; 8 measured faster than 16 and 64)
WINDOW = 16  # steps a moving valve's window bound clears at once (~1/10 of the steps between events)


@njit(cache=True)
def node_time(nodes, h, inv, ns, j, u):
    """The time at u within step j (the last node from j = ns on) of a grid whose node positions
    and step lengths times inv are times (a grid in cam angle at the speed 1 / inv, or inv = 1)."""
    if j >= ns:
        return nodes[ns] * inv
    return nodes[j] * inv + u * (h[j] * inv)


@njit(cache=True)
def drive_at(PT, Dn, h, inv, sw1, ns, j, u, tmp):
    """S and S' at u within step j (node_time's grid: Dn's S' times sw1 is per time)."""
    if j >= ns:
        return Dn[0, ns], Dn[1, ns] * sw1
    P = PT[j]
    deriv_into(P, 6, h[j] * inv, tmp)
    return horner(P, 6, u), horner(tmp, 6, u)


@njit(cache=True)
def grid_bounds(h, Dn, Sb):
    """What the block and window bounds read of a grid, computed once per grid (a sweep's runs
    share it; solve_nodes scales it to its speed sw1, each entry by a positive factor, under which
    the largest value stays the largest; h and Sb of the grid at the speed 1):
    blk (per BLOCK steps, the seated valve's block clearance): the largest S and S1 at its nodes
    and the largest h^2/8 |S2| and h^2/8 |S3| over its steps (at the speed sw1: times 1, sw1, 1,
    sw1, for h in time is h in angle / sw1);
    win (per WINDOW steps, the moving valve's window bound): the largest bounds of |S1|, |S2|, |S3|
    over its steps (times sw1, sw1^2, sw1^3)."""
    ns = h.size
    nb = ns // BLOCK
    blk = np.full((4, max(nb, 1)), -np.inf)
    for bk in range(nb):
        for i in range(bk * BLOCK, bk * BLOCK + BLOCK + 1):
            blk[0, bk] = max(blk[0, bk], Dn[0, i])
            blk[1, bk] = max(blk[1, bk], Dn[1, i])
        for i in range(bk * BLOCK, bk * BLOCK + BLOCK):
            hh = h[i] * h[i] / 8.0
            blk[2, bk] = max(blk[2, bk], hh * Sb[1, i])
            blk[3, bk] = max(blk[3, bk], hh * Sb[2, i])
    nw = ns // WINDOW
    win = np.zeros((3, max(nw, 1)))
    for wb in range(nw):
        for q in range(wb * WINDOW, wb * WINDOW + WINDOW):
            win[0, wb] = max(win[0, wb], Sb[0, q])
            win[1, wb] = max(win[1, wb], Sb[1, q])
            win[2, wb] = max(win[2, wb], Sb[2, q])
    return blk, win
