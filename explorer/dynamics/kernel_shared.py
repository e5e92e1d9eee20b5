"""What the compiled exact solver (explorer.dynamics.exact_kernel) shares with its callers without
numba: a run's status codes, the names of the figures and of the run parameters, and the grid of
one revolution in cam angle (built in Python, passed to the compiled code as arrays). exact_kernel
imports this module and not the numba modules at its top, so that a sweep that runs the kernel
ahead-of-time compiled (explorer/core/aot.py) never loads numba. The kernel's modules read these
constants, so this file is one of kernel_stamp.SOURCES."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .exact_grid import MAX_RHO_H, build_grid
from .model import Drive

OK, TOO_MANY_EVENTS, NO_PROGRESS = 0, 1, 2  # a run's status (exact.py's RuntimeErrors)

# the figures revolution() returns, in this order (the elastic effect's, as the sweep's rows read
# them: explorer/studies/sweep_engine.row_scalars)
FIGURES = ("first_separation_deg", "separations", "flight_time_s", "max_deviation_m", "peak_linkage_force_N",
           "peak_camshaft_back_pressure_N", "lift_off_delay_s", "seating_velocity_m_s", "seat_impacts",
           "largest_bounce_m", "residual_deviation_m", "residual_amplitude_m")

# the columns of a batch's run parameters (revolutions())
RUN_PARAMETERS = ("omega", "mass", "oscillating_mass", "stiffness", "damping", "lash", "seated_resistance",
                  "spring_rate", "friction", "restitution", "preload_closing", "take_up_s")


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
