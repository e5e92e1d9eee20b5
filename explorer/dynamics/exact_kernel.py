"""The `exact` solver compiled (numba): the same model, closed forms and events as exact.py, for the
batch engine of sweeps (explorer/effects/elastic_batch.py, which the sweep engine and the browser's
speed sweep use) and as the solver table's `exact-compiled` (solve: one revolution, a scene's
[solver] method). Only elastic_batch and the solver table's entry import this module, and only
this module imports the compiled parts (numba costs ~0.4 s to import; `import explorer` must not
pay it).

The compiled code follows the Python solver's seams, one module each:
  kernel_grid     the grid (exact_grid.build_grid, called in Python and passed in as arrays; a
                  revolution's grid in cam angle scaled to each speed), the block and window bounds
  kernel_steps    a step: the drive over it (the quintic Hermite through S, S', S'' at both ends), its
                  response as the Taylor series of the phase ODE (exact_steps' recursion; steps split
                  to rho h <= MAX_RHO_H by the grid), the one-step propagator
  kernel_events   the event functions (phases.py's rules as exact_events' rows aP S + bP S' + const +
                  l0 s + l1 v, combined by min/max) and the search in a step that is not cleared (start
                  clearance, Newton in a proven rising bracket, subdivision search with the
                  coefficient bounds, Illinois): exact_events.py
  kernel_phase    a run phase by phase (exact_phase.py, exact._Solver): the rigorous clearing of a
                  step (max of the end values + h^2/8 sup|e''|, sup|e''| from the ODE's bounds of |a|
                  and |jerk|, then the step's own Taylor coefficients), in blocks and windows first;
                  what happens at an event (lift-off, separation, re-contact, seat with restitution
                  and the chatter's closed-form Zeno tail, velocity zero with Coulomb friction, stick
                  and release)
  kernel_figures  the elastic effect's figures of a revolution (the sweep's row), of many runs
They take the constants they share with the Python solver from its modules; kernel_stamp keeps
numba's cache true to all of them.

What differs from exact.py: the node states are carried step by step by the one-step propagator
x[i+1] = Phi(h) x[i] + W_P P[i] - Fc g1 (the unit responses' end values; the tables of exact_steps
for each step length), not by modal.py's closed form over a window. Both are the exact solution of
the same step ODE; they differ by rounding (~1e-16 relative per step, a few 1e-15 over a revolution:
tests/test_sweep_kernel.py holds every row to simulate's within 1e-12 m and 1e-12 s).

The LinkageModel without stiffness_profile only (constant coefficients): `supports(model)`.

`python -m explorer.dynamics.exact_kernel --warm` compiles (and caches beside the modules) every
compiled function once: `make` runs it at install and when a source changes, so the first sweep
does not compile. `--aot` compiles the batch entry point (revolutions) and solve's compiled call
(kernel_phase.solve_nodes) ahead of time into _exact_kernel_aot (explorer/core/aot.py), which
run_batch and solve use while it is current: this module imports the numba modules (kernel_phase,
kernel_figures, kernel_grid, kernel_events) only inside the functions that run them, so a sweep or
a `simulate` with exact-compiled loads no numba then.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from ..core import aot
from . import exact_output, kernel_stamp
from .exact_grid import MAX_RHO_H, build_grid  # noqa: F401 (MAX_RHO_H: elastic_batch's)
from .exact_steps import LinearPhase, taylor_terms
from .kernel_shared import (FIGURES, NO_PROGRESS, OK, RUN_PARAMETERS, TOO_MANY_EVENTS,  # noqa: F401
                            RevolutionGrid, revolution_grid, split_parts)
from .model import Drive, DynamicsSolution, LinkageModel
from .phases import CONTACT, FLIGHT, SEATED, phase_of_state

# the batch entry point (revolutions) compiled ahead of time by `make` (build_aot below): used when
# it was built from the kernel's current sources (explorer/core/aot.py), so that a sweep's process
# loads no numba; else numba's revolutions
AOT_MODULE = "explorer.dynamics._exact_kernel_aot"

EVENT_NAMES = ("lift-off", "separation", "re-contact", "seat")  # model.EVENT_KINDS: the kernel's codes 0-3


def supports(model) -> bool:
    """The kernel solves this model: constant coefficients (no stiffness profile)."""
    return getattr(model, "stiffness_profile", None) is None


def _check(status: int) -> None:
    if status == TOO_MANY_EVENTS:
        raise RuntimeError("exact solver (compiled): too many events; the motion does not settle")
    if status == NO_PROGRESS:
        raise RuntimeError("exact solver (compiled): events repeat at one instant without progress")


def model_arguments(model: LinkageModel) -> tuple:
    return (float(model.mass), float(model.oscillating_mass), float(model.stiffness), float(model.damping),
            float(model.lash), float(model.seated_resistance), float(model.spring_rate), float(model.friction),
            float(model.restitution))


def phase_rates(model: LinkageModel) -> float:
    """rho: the fastest rate of the contact and flight phases (exact_phase.PhaseStepper's)."""
    M, M1, k, c, _, _, rate, _, _ = model_arguments(model)
    return max(lin.rho for lin in _phases(M, M1, k, c, rate).values())


def events_list(ev: np.ndarray) -> list[dict]:
    """The kernel's event rows as exact.py's event dicts."""
    out = []
    for code, t, vel, zeno in ev.tolist():
        item = {"kind": EVENT_NAMES[int(code)], "time_s": t, "velocity_m_s": vel}
        if not math.isnan(zeno):
            item["zeno_accumulation_s"] = zeno
        out.append(item)
    return out


def solve(model: LinkageModel, drive, t: np.ndarray, initial_state: tuple[float, float] | None = None,
          zeno_height: float = 1e-12, max_events: int = 100_000) -> DynamicsSolution:
    """exact.solve compiled (the solver table's `exact-compiled`): the same grid, start and output
    (exact_grid.build_grid, phases.phase_of_state, exact_output), the stepping and the events in
    one compiled call (nodes_function: the ahead-of-time module's solve_nodes while it is current,
    so a process that runs it need not import numba). initial_state: (s, v) at t[0], default at
    rest on the seat; zeno_height, max_events: exact.solve's. RuntimeError where exact.py raises."""
    return _solve(model, drive, t, initial_state, zeno_height, max_events, nodes_function())


def _solve(model: LinkageModel, drive, t, initial_state, zeno_height: float, max_events: int,
           kernel) -> DynamicsSolution:
    """solve() with the compiled solve_nodes `kernel` (the AOT module's or numba's)."""
    if not supports(model):
        raise ValueError("the compiled exact solver needs a constant linkage stiffness")
    t_req, t_nodes, inverse, hmin = exact_output.output_nodes(t)
    M, M1, k, c, lash, W0, rate, R, e = args = model_arguments(model)
    lins = _phases(M, M1, k, c, rate)
    rho = max(lin.rho for lin in lins.values())
    g = build_grid(drive, t_nodes, rho, hmin)
    N = taylor_terms(rho * g.h_max)
    if initial_state is None:
        start = (SEATED, 0.0, 0.0, 1.0, False)
    else:  # (exact._Solver.run's start: the drive at the first node is the first step's polynomial's)
        s0, v0 = (float(x) for x in initial_state)
        phase0, sigma0 = phase_of_state(float(g.Dn[0, 0]), float(g.Dn[1, 0]), k, c, lash, s0, v0, W0, rate, R)
        start = (phase0, s0, v0, sigma0, v0 == 0.0)
    cont = np.ascontiguousarray  # (the exported signature's layout: a copy of P.T only; the rest already are)
    out_s, out_v, out_sigma, out_phase, ev, status, n_detail = kernel(
        cont(g.nodes), cont(g.h), cont(g.PT), cont(g.Dn), cont(g.Sb), cont(g.hidx, dtype=np.int64), cont(g.h_unique),
        *args, float(zeno_height), int(max_events), int(N), *start)
    _check(status)
    stats = {"method": "exact-compiled", "nodes": int(g.nodes.size), "steps": int(g.h.size), "taylor_terms": N,
             "detail_searches": int(n_detail), "events": int(ev.shape[0]), "warnings": []}
    return exact_output.solution(t_req, inverse, out_s, out_v, out_sigma, out_phase, g.Dn, g.is_out, lins, k, c,
                                 lash, W0, R, events_list(ev), stats)


@functools.lru_cache(maxsize=64)
def _phases(M: float, M1: float, k: float, c: float, rate: float) -> Mapping[int, LinearPhase]:
    """The LinearPhase of contact and flight (exact_phase.PhaseStepper's), by phase code: a
    model's are built once (a scene's revolutions reuse them)."""
    return MappingProxyType({CONTACT: LinearPhase(M1, c, k + rate, k, c), FLIGHT: LinearPhase(M, 0.0, rate, 0.0, 0.0)})


def run_revolution(grid: RevolutionGrid, omega: float, model: LinkageModel, ratio: float, take_up_s: float,
                   ref: np.ndarray, dwell: int, S_dwell: float, zeno_height: float = 1e-12, max_events: int = 100_000):
    """revolution() on a RevolutionGrid: (FIGURES, valve lift at the output samples, revolution
    events as the elastic effect lists them). RuntimeError where exact.py raises. ref, dwell,
    S_dwell: the residual figures' (revolution())."""
    from .kernel_figures import openings, revolution
    from .kernel_grid import grid_bounds
    from .kernel_phase import run_buffers

    rho = phase_rates(model)
    N = taylor_terms(rho * grid.h_max / omega)
    buffers = run_buffers(grid.nodes.size, int(N), grid.h_unique.size)
    opens = np.empty(grid.n, dtype=np.int64)
    n_opens = openings(grid.n, grid.i0, grid.out_nodes, grid.Dn, float(model.lash), opens)
    fig, rev, status = revolution(
        grid.nodes, grid.h, grid.PT, grid.Dn, grid.Sb, grid.hidx, grid.h_unique, grid.out_nodes, grid.i0, float(omega),
        *model_arguments(model), float(zeno_height), int(max_events), int(N), float(ratio),
        float(model.preload + model.closing_load), float(take_up_s), np.ascontiguousarray(ref, dtype=float),
        int(dwell), float(S_dwell), *grid_bounds(grid.h, grid.Dn, grid.Sb), buffers, np.empty(6), opens, n_opens)
    _check(status)
    return fig, np.roll(buffers[0][grid.out_nodes], grid.i0), rev  # output column (r + i0) mod n: run sample r


def run_batch(grid: RevolutionGrid, ratio: float, runs: np.ndarray, ref: np.ndarray, dwell: int, S_dwell: float,
              zeno_height: float = 1e-12, max_events: int = 100_000, kernel=None):
    """revolutions() on a RevolutionGrid: (FIGURES per run, status per run: OK, or the exact
    solver's RuntimeErrors as TOO_MANY_EVENTS, NO_PROGRESS); ref, dwell, S_dwell: revolution()'s,
    shared by the runs (one lever ratio and lash). kernel: revolutions to call (default
    batch_function(): the ahead-of-time module's when it is current, else numba's)."""
    c = np.ascontiguousarray  # (the exported signature's layout; the grid's arrays already are)
    return (kernel or batch_function())(
        c(grid.nodes), c(grid.h), c(grid.PT), c(grid.Dn), c(grid.Sb), c(grid.hidx, dtype=np.int64), c(grid.h_unique),
        c(grid.out_nodes, dtype=np.int64), int(grid.i0), float(grid.h_max), float(ratio), c(runs, dtype=float),
        float(zeno_height), int(max_events), c(ref, dtype=float), int(dwell), float(S_dwell))


def aot_sources() -> list:
    """The sources the ahead-of-time module compiles: the kernel's (kernel_stamp.SOURCES: every file
    whose code or constants the compiled code reads, the exported functions and their signatures
    among them: kernel_figures' revolutions, kernel_phase's solve_nodes)."""
    return [kernel_stamp.HERE / name for name in kernel_stamp.SOURCES]


@functools.cache
def batch_function():
    """revolutions: the ahead-of-time module's when it was built from the current sources (it
    imports no numba), else numba's kernel_figures.revolutions."""
    module = aot.load(AOT_MODULE, aot_sources())
    if module is not None:
        return module.revolutions
    from .kernel_figures import revolutions

    return revolutions


@functools.cache
def nodes_function():
    """solve_nodes (the `exact-compiled` solver's compiled call): the ahead-of-time module's when it
    was built from the current sources (it imports no numba), else numba's kernel_phase.solve_nodes."""
    module = aot.load(AOT_MODULE, aot_sources())
    if module is not None and hasattr(module, "solve_nodes"):
        return module.solve_nodes
    from .kernel_phase import solve_nodes

    return solve_nodes


def build_aot() -> float:
    """Compile revolutions and solve_nodes (each with its callees in its object code) ahead of
    time into one module, for the argument types run_batch and solve pass
    (kernel_figures.aot_exports, kernel_phase.aot_exports); the seconds it took."""
    from ..core.aot_build import build
    from . import kernel_figures, kernel_phase

    return build(AOT_MODULE, kernel_stamp.HERE, {**kernel_figures.aot_exports(), **kernel_phase.aot_exports()},
                 aot_sources())


def revolution_events(rev: np.ndarray) -> list[dict]:
    """revolution()'s event rows as the elastic effect's event dicts."""
    return [{"kind": EVENT_NAMES[int(code)], "time_s": t, "cam_angle_deg": angle, "velocity_m_s": vel}
            for code, t, vel, angle in rev.tolist()]


def warm() -> None:
    """Compile (or load from the cache) every entry point on a small case."""
    class _Lift:
        def derivatives(self, x):
            x = np.asarray(x, dtype=float)
            return np.stack([1e-3 * (1.0 - np.cos(x)), 1e-3 * np.sin(x), 1e-3 * np.cos(x), -1e-3 * np.sin(x)])

        def breakpoints(self):
            return [1.0]

    model = LinkageModel(mass=0.1, oscillating_mass=0.09, stiffness=3e6, damping=8.0, lash=1e-4, preload=50.0,
                         spring_rate=3e4, friction=5.0, restitution=0.5)
    omega = 2 * math.pi * 100.0
    t = np.linspace(0.0, 2 * math.pi / omega, 181)
    from .kernel_phase import solve_nodes  # (numba's, even where the AOT module is current: the fallback)

    _solve(model, Drive(_Lift(), 1.0, omega), t, None, 1e-12, 100_000, solve_nodes)
    grid = revolution_grid(_Lift(), 1.0, 180)
    ref = np.zeros(180)
    run_revolution(grid, omega, model, 1.0, 0.0, ref, -1, math.nan)
    from .kernel_figures import revolutions  # (numba's, even where the AOT module is current: the fallback)

    run_batch(grid, 1.0, np.array([[omega, *model_arguments(model), 50.0, 0.0]]), ref, 3, 1e-3, kernel=revolutions)


if __name__ == "__main__":
    import sys

    if "--warm" in sys.argv[1:]:
        warm()
    if "--aot" in sys.argv[1:]:
        build_aot()
