"""The elastic effect's figures for many runs of one scene (a sweep's compiled path, the browser's
elastic speed sweep): the elastic figures of a run from the compiled
exact solver (explorer/dynamics/exact_kernel.py), sharing across runs what does not depend on the
varied values.

Shared per chunk (`shared`: an object with lift, grids and take_ups, e.g. studies.sweep_engine._Shared or
BatchCache below): the lift curve; the grid of one revolution in cam angle
(exact_kernel.RevolutionGrid: the drive's step polynomials in u = tau/h are the same at every
speed, S' and S'' scale with omega and omega^2, the times with 1/omega), one per lever ratio and
steps per revolution, and the split grids of stiff linkages (per the split they need; bounded
cache); the lash take-up angles per lash. A run then costs its scene's values, one compiled call
(the stepping, the events and the figures) and, when the scene has them, the rigid effects
(forces, contact) as sweep_engine computes them.

The compiled path takes a run when the elastic effect would solve the LinkageModel with a solver
that has a compiled batch module (explorer/dynamics/solvers.py: batch_entry, the exact solver's
exact_kernel) and a constant stiffness (no spring chain, no stiffness carried by the lift, a lift
shared by all runs): `accepts`. Otherwise sweep_engine's other paths do.

numba is imported (with the batch module) only when a run takes this path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..dynamics import solvers

ELASTIC = ("first_separation_deg", "separations", "flight_time_s", "max_deviation_m", "peak_linkage_force_N",
           "peak_camshaft_back_pressure_N", "lift_off_delay_s", "seating_velocity_m_s", "seat_impacts",
           "largest_bounce_m", "residual_deviation_m", "residual_amplitude_m")  # exact_kernel.FIGURES


@dataclass
class BatchCache:
    """What the runs of a batch share (the sweep engine's _Shared holds the same and more): the
    lift curve, the revolution grids, the lash take-up angles and residual references."""

    lift: Any = None
    grids: dict = field(default_factory=dict)
    take_ups: dict = field(default_factory=dict)


def _residual_reference(shared, lift, ratio: float, lash: float, n: int):
    """The residual figures' reference lift at the n output angles (value and slope per radian)
    and the dwell's first sample (-1: none): effects/residual.py's, per lever ratio and lash."""
    from .residual import dwell_sample, reference_lift
    from ..core.memo import remember

    def base():  # what does not depend on the lash (a tolerance study draws a new lash every run)
        theta = np.arange(n) * (2.0 * math.pi / n)
        i = dwell_sample(lift, theta)
        if getattr(lift, "wanted_valve_lift", None) is not None:  # a polydyne's wanted lift: no lash in it
            return np.ascontiguousarray(reference_lift(lift, ratio, lash, theta, 1)), (-1 if i is None else i), True
        return lift.derivatives(theta)[:2] * ratio, (-1 if i is None else i), False

    def make():
        d, i, fixed = remember(shared.grids, ("residual", ratio, n), base)
        if fixed:
            return d, i
        d = d.copy()  # reference_lift's arithmetic on its lift derivatives: the same floats
        is_open = d[0] - lash > 0.0
        d[0] -= lash
        return np.ascontiguousarray(np.where(is_open, d, 0.0)), i

    return remember(shared.take_ups, ("residual", ratio, lash, n), make)


def accepts(scene, shared) -> bool:
    """The elastic effect of this scene is the compiled kernel's model and method."""
    from .registry import order

    if not scene.gear_plugin.batch_sweeps:  # a gear whose runs do not share one lift, or its own effects
        return False
    if "elastic" not in order(scene.effects):
        return False
    if scene.spring.elements > 0 or solvers.solver(scene.solver.method).batch_entry is None:
        return False
    if shared.lift is None:
        shared.lift = scene.gear_plugin.build_lift(scene)
    return getattr(shared.lift, "linkage_stiffness", None) is None


def elastic_run(scene, shared):
    """(figures as a dict of ELASTIC, valve lift at the output samples, the revolution's elastic
    events) of one run. InputError: a speed beyond the solver's step budget (as the elastic
    effect); RuntimeError: a motion that does not settle (as the exact solver)."""
    from ..dynamics.model import LinkageModel
    from .elastic import check_resolution
    from ..mechanics.kinematics import lash_crossings
    from ..core.memo import remember as _remember

    lift = shared.lift
    ratio, lash = scene.follower.ratio, scene.valve.lash
    n = scene.solver.steps_per_revolution
    omega = scene.drive.omega
    model = LinkageModel.from_scene(scene)
    period = 2.0 * math.pi / omega
    kernel = solvers.solver(scene.solver.method).batch_module()
    check_resolution(model, np.array([0.0, period]), scene.solver.method, scene.source)
    base = _remember(shared.grids, (ratio, n), lambda: kernel.revolution_grid(lift, ratio, n))
    rho_theta = kernel.phase_rates(model) / omega
    parts = kernel.split_parts(base, rho_theta)
    grid = base if parts is None else _remember(
        shared.grids, (ratio, n, parts.tobytes()), lambda: kernel.revolution_grid(lift, ratio, n, rho_theta, base))
    ups = _remember(shared.take_ups, (ratio, lash), lambda: lash_crossings(lift, ratio, lash)[0])
    take_up = ups[0] / omega if len(ups) else math.nan
    ref, dwell = _residual_reference(shared, lift, ratio, lash, n)
    fig, lift_column, rev = kernel.run_revolution(grid, omega, model, ratio, take_up, ref, dwell)
    return dict(zip(ELASTIC, fig.tolist())), lift_column, rev


def elastic_chunk(scenes, shared) -> tuple[np.ndarray, np.ndarray]:
    """The ELASTIC figures (runs x figures) of many runs and which failed (as elastic_run would
    raise: a speed beyond the step budget, a motion that does not settle), the runs on one grid
    in one compiled call (exact_kernel.revolutions: no Python per run but its scene's values)."""
    from .elastic import MAX_SOLVER_NODES
    from ..core.memo import remember

    lift = shared.lift
    kernel = solvers.solver(scenes[0].solver.method).batch_module()
    R = len(scenes)
    figures = np.full((R, len(ELASTIC)), math.nan)
    failed = np.zeros(R, bool)
    params = np.empty((R, len(kernel.RUN_PARAMETERS)))
    groups: dict = {}
    ups_of = _take_ups(scenes, shared)
    for r, scene in enumerate(scenes):
        v, sp, link = scene.valve, scene.spring, scene.linkage
        ratio, lash = scene.follower.ratio, v.lash
        omega = scene.drive.omega
        M1 = v.oscillating_mass if v.oscillating_mass is not None else v.mass
        closing = scene.loads.closing_total
        ups = ups_of[(ratio, lash)]
        params[r] = (omega, v.mass, M1, link.stiffness, link.damping, lash, sp.preload + closing, sp.rate,
                     scene.loads.friction, scene.seat.restitution, sp.preload + closing,
                     ups[0] / omega if len(ups) else math.nan)
        groups.setdefault((ratio, scene.solver.steps_per_revolution, lash), []).append(r)
    # the fastest rate of each run: the step budget (effects.elastic.check_resolution) and the split
    M, M1, k, c, rate = (params[:, i] for i in (1, 2, 3, 4, 7))
    alpha = 0.5 * c / M1
    w2 = (k + rate) / M1
    over = alpha * alpha > w2
    rho = np.where(over, alpha + np.sqrt(np.where(over, alpha * alpha - w2, 0.0)), np.sqrt(np.abs(w2)))
    rho = np.maximum(rho, np.sqrt(rate / M))
    omega = params[:, 0]
    failed |= ~(rho * (2.0 * math.pi / omega) / 0.5 <= MAX_SOLVER_NODES)
    for (ratio, n, lash), members in groups.items():
        base = remember(shared.grids, (ratio, n), lambda: kernel.revolution_grid(lift, ratio, n))
        ref, dwell = _residual_reference(shared, lift, ratio, lash, n)
        members = np.array([m for m in members if not failed[m]], dtype=np.int64)
        if not members.size:
            continue
        rho_theta = rho[members] / omega[members]
        split = rho_theta * base.h_max / kernel.MAX_RHO_H > 1.0
        plain = members[~split]
        if plain.size:
            figs, status = kernel.run_batch(base, ratio, params[plain], ref, dwell)
            figures[plain] = figs
            failed[plain] = status != kernel.OK
        for m, rt in zip(members[split].tolist(), rho_theta[split].tolist()):
            parts = kernel.split_parts(base, rt)
            grid = remember(shared.grids, (ratio, n, parts.tobytes()),
                            lambda: kernel.revolution_grid(lift, ratio, n, rt, base))
            figs, status = kernel.run_batch(grid, ratio, params[m:m + 1], ref, dwell)
            figures[m] = figs[0]
            failed[m] = status[0] != kernel.OK
    figures[failed] = math.nan
    return figures, failed


def _take_ups(scenes, shared) -> dict:
    """{(ratio, lash): [first take-up angle]} of a chunk's runs, the lashes found together
    (mechanics.kinematics.lash_take_ups: lash_crossings' root to brentq's tolerance): a tolerance
    study's runs each draw their own lash, and one Brent search per lash cost ten times the
    compiled revolution. Every lash takes this one search whatever else its chunk holds, so a table
    does not depend on how it was cut into chunks (each lane of the search is elementwise)."""
    from ..core.memo import remember
    from ..mechanics.kinematics import lash_take_ups

    out: dict = {}
    wanted: dict[float, set] = {}
    for scene in scenes:
        ratio, lash = scene.follower.ratio, scene.valve.lash
        cached = shared.take_ups.get(("batched", ratio, lash))
        if cached is not None:
            out[(ratio, lash)] = cached
        else:
            wanted.setdefault(ratio, set()).add(lash)
    for ratio, lashes in wanted.items():
        values = np.array(sorted(lashes))
        for lash, up in zip(values.tolist(), lash_take_ups(shared.lift, ratio, values).tolist()):
            ups = np.array([up]) if math.isfinite(up) else np.zeros(0)
            out[(ratio, lash)] = ups
            remember(shared.take_ups, ("batched", ratio, lash), lambda ups=ups: ups)
    return out


def kernel_outputs(scene, shared) -> tuple[list[dict], np.ndarray]:
    """For tests: (the revolution's elastic events as the elastic effect lists them, the valve lift
    at the output samples as its valve_lift_m column)."""
    _, lift_column, rev = elastic_run(scene, shared)
    return solvers.solver(scene.solver.method).batch_module().revolution_events(rev), lift_column
