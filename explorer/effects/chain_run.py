"""The set-up of a run of the scene's chain solver (explorer/dynamics/solvers.py: chain_entry), the
same for the spring chain (chain_elastic.py) and the train of parts (train_elastic.py): the drive
referred to the valve, the solid-height check, the solver and its options, and the run's times
over whole revolutions from the lowest drive position (where the valve rests on its seat, in
static equilibrium)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from ..core.errors import InputError, echo
from ..dynamics import solvers as registry
from ..dynamics.chain import solid_travel
from ..dynamics.model import Drive


def chain_solver(method: str, file: str):
    """The chain function of the registry's solver `method`, or InputError naming solver.method."""
    function = registry.solver(method).chain_function()
    if function is None:
        able = [name for name, info in registry.SOLVERS.items() if info.chain_entry]
        raise InputError(file, "solver.method", f"{echo(method)} takes only the massless spring; with spring.elements > 0 "
                         f"use {' or '.join(map(repr, able))}")
    return function


def check_solid(scene, drive_lift_max: float) -> None:
    """InputError when the static lift alone compresses the spring to its solid height."""
    sp = scene.spring
    if sp.free_length is None or sp.solid_height is None:
        return
    travel = solid_travel(sp)
    lift = drive_lift_max - scene.valve.lash
    if lift >= travel:
        raise InputError(scene.source, "spring.solid_height", f"the valve lift {lift * 1e3:.4g} mm alone compresses "
                         f"the spring to its solid height (travel to solid {travel * 1e3:.4g} mm from closed)")


@dataclass(frozen=True)
class ChainRun:
    """What chain_run sets up; the effect runs `solve(model, drive, t_run, **options)`."""

    drive: Drive  # S(t) = ratio * L(omega t)
    D: np.ndarray  # drive(ctx.time): S and its derivatives on the output grid
    period: float  # s, one revolution
    i0: int  # the output sample the run starts at: the lowest drive position
    t_run: np.ndarray  # s, the run's times: `revolutions` revolutions from ctx.time[i0]
    solve: Callable  # the scene's solver's chain function
    options: Mapping[str, Any]  # its [solver] options


def chain_run(ctx, revolutions: int = 1) -> ChainRun:
    """The run set-up of a chain effect (ctx: effects.context.Context); InputError for a spring
    driven solid or a solver without a chain function."""
    scene = ctx.scene
    omega = ctx.omega
    drive = Drive(ctx.lift, scene.follower.ratio, omega)
    period = 2.0 * math.pi / omega
    D = drive(ctx.time)
    check_solid(scene, float(D[0].max()))
    solve = chain_solver(scene.solver.method, scene.source)
    options = dict(scene.solver.options)
    i0 = int(np.argmin(D[0]))
    one = np.concatenate([ctx.time[i0:], ctx.time[:i0] + period])
    t_run = one if revolutions == 1 else np.concatenate([one + k * period for k in range(revolutions)])
    return ChainRun(drive, D, period, i0, t_run, solve, options)
