"""The compiled exact solver's grid (explorer.dynamics.exact_grid's, built in Python by
exact_grid.build_grid and passed in as arrays): a revolution's grid in cam angle, valid at every
speed (RevolutionGrid, revolution_grid, split_parts; the stepping reads it at the speed omega as
times theta / omega, S' and its bounds times omega, omega^2, omega^3, the step polynomials in
u = tau/h unchanged, scaling each value where it is read rather than copying the grid), the block
and window bounds read by the stepping (grid_bounds), and the time and drive at a point of a step.
Part of the compiled solver (explorer.dynamics.exact_kernel)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import kernel_stamp  # noqa: F401 (the cache is stale when a source it depends on changed)
from .exact_grid import MAX_RHO_H, build_grid
from .kernel_steps import deriv_into, horner
from .model import Drive

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


@dataclass(frozen=True)
class RevolutionGrid:
    """The grid of one revolution in cam angle (exact_grid.build_grid with omega = 1), valid at
    every speed (revolution() scales it): the n output samples of the elastic effect from the
    drive's lowest point (index i0) round to it again, the drive's breakpoints, steps split to
    rho h <= 0.5 for the rate `rho_theta` = rho / omega it was built for."""

    n: int
    i0: int
    nodes: np.ndarray
    h: np.ndarray
    PT: np.ndarray
    Dn: np.ndarray
    Sb: np.ndarray  # bounds of the drive's first three derivatives over each step (exact_grid.Grid.Sb)
    hidx: np.ndarray
    h_unique: np.ndarray
    out_nodes: np.ndarray  # the nodes of the n output samples, in run order
    h_max: float


def revolution_grid(lift, ratio: float, n: int, rho_theta: float = 0.0, base: "RevolutionGrid | None" = None):
    """The RevolutionGrid of a lift curve at `ratio` and n samples per revolution (as the elastic
    effect builds its run: effects/elastic.py), split for the rate rho_theta (0: not split).
    base: the unsplit grid, when known (its start angle and drive values are reused)."""
    drive = Drive(lift, ratio, 1.0)
    theta = np.arange(n) * (2.0 * math.pi / n)
    if base is None:
        i0 = int(np.argmin(drive(theta)[0]))
    else:
        i0 = base.i0
    run = np.concatenate([theta[i0:], theta[:i0] + 2.0 * math.pi])
    run = np.append(run, theta[i0] + 2.0 * math.pi)
    hmin = float(np.min(np.diff(run)))
    g = build_grid(drive, run, rho_theta, hmin)
    out = np.nonzero(g.is_out)[0][:n].astype(np.int64)
    return RevolutionGrid(n=n, i0=i0, nodes=g.nodes, h=g.h, PT=np.ascontiguousarray(g.PT), Dn=g.Dn,
                          Sb=np.ascontiguousarray(g.Sb), hidx=g.hidx.astype(np.int64), h_unique=g.h_unique, out_nodes=out, h_max=g.h_max)


def split_parts(grid: RevolutionGrid, rho_theta: float) -> np.ndarray | None:
    """How build_grid splits the steps of an unsplit grid for the rate rho_theta (None: it does
    not): grids with the same parts are the same grid."""
    if not rho_theta * grid.h_max / MAX_RHO_H > 1.0:
        return None
    return np.maximum(1, np.ceil(rho_theta * grid.h / MAX_RHO_H)).astype(np.int64)
