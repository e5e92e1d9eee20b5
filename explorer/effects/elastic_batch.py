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

from ..core.memo import remember, remember as _remember
from ..dynamics import solvers
from ..dynamics.model import LinkageModel
from ..mechanics.kinematics import lash_crossings, lash_take_ups
from .elastic import MAX_SOLVER_NODES, check_resolution
from .registry import order
from .residual import lash_reference, reference_parts

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
    """The residual figures' reference lift at the n output angles, the dwell's first sample (-1:
    none) and the drive there: effects/residual.residual_reference, per lever ratio and lash."""
    def base():  # what does not depend on the lash (a tolerance study draws a new lash every run)
        return reference_parts(lift, ratio, np.arange(n) * (2.0 * math.pi / n))

    def make():
        d, i, S, less_lash = remember(shared.grids, ("residual", ratio, n), base)
        return (lash_reference(d, lash) if less_lash else d), i, S

    return remember(shared.take_ups, ("residual", ratio, lash, n), make)


def accepts(scene, shared) -> bool:
    """The elastic effect of this scene is the compiled kernel's model and method."""
    if not scene.gear_plugin.batch_sweeps:  # a gear whose runs do not share one lift, or its own effects
        return False
    if "elastic" not in order(scene.effects):
        return False
    if scene.spring.elements > 0 or solvers.solver(scene.solver.method).batch_entry is None:
        return False
    if scene.linkage.elements or getattr(scene, "hla", None) is not None:  # a train of parts: the shared path
        return False
    if shared.lift is None:
        shared.lift = scene.gear_plugin.build_lift(scene)
    return getattr(shared.lift, "linkage_stiffness", None) is None


def elastic_run(scene, shared):
    """(figures as a dict of ELASTIC, valve lift at the output samples, the revolution's elastic
    events) of one run. InputError: a speed beyond the solver's step budget (as the elastic
    effect); RuntimeError: a motion that does not settle (as the exact solver)."""
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
    ref, dwell, S_dwell = _residual_reference(shared, lift, ratio, lash, n)
    fig, lift_column, rev = kernel.run_revolution(grid, omega, model, ratio, take_up, ref, dwell, S_dwell)
    return dict(zip(ELASTIC, fig.tolist())), lift_column, rev


def elastic_chunk(scenes, shared) -> tuple[np.ndarray, np.ndarray]:
    """The ELASTIC figures (runs x figures) of many runs and which failed (as elastic_run would
    raise: a speed beyond the step budget, a motion that does not settle), the runs on one grid
    in one compiled call (exact_kernel.revolutions: no Python per run but its scene's values)."""
    kernel = solvers.solver(scenes[0].solver.method).batch_module()
    params = np.empty((len(scenes), len(kernel.RUN_PARAMETERS)))
    group = np.empty((len(scenes), 2))  # per run: lever ratio, steps per revolution
    for r, scene in enumerate(scenes):
        v, sp, link = scene.valve, scene.spring, scene.linkage
        M1 = v.oscillating_mass if v.oscillating_mass is not None else v.mass
        closing = scene.loads.closing_total
        params[r, :11] = (scene.drive.omega, v.mass, M1, link.stiffness, link.damping, v.lash, sp.preload + closing,
                          sp.rate, scene.loads.friction, scene.seat.restitution, sp.preload + closing)
        group[r] = scene.follower.ratio, scene.solver.steps_per_revolution
    return _chunk(kernel, params, group, shared)


# the run parameters a sweep key sets (studies.sweep_spec.SWEEP_KEYS; drive.rpm sets omega, and
# spring.preload both columns that add the closing loads to it)
KEY_PARAMETERS = {"drive.rpm": "omega", "valve.mass": "mass", "valve.oscillating_mass": "oscillating_mass",
                  "linkage.stiffness": "stiffness", "linkage.damping": "damping", "valve.lash": "lash",
                  "spring.preload": "seated_resistance", "spring.rate": "spring_rate", "loads.friction": "friction",
                  "seat.restitution": "restitution"}


def elastic_chunk_values(base, keys, values, shared) -> tuple[np.ndarray, np.ndarray]:
    """elastic_chunk of the runs of the scene `base` with `values` (runs x keys, SI) in place of
    its own (studies.sweep_spec.scene_for's runs), the run parameters built column by column
    with the same arithmetic as elastic_chunk's per scene, no scene built per run. keys: sweep keys
    (KEY_PARAMETERS)."""
    unknown = [key for key in keys if key not in KEY_PARAMETERS]
    if unknown:  # a key this table does not map would be silently left at the base scene's value
        raise ValueError(f"elastic_chunk_values: no run parameter for the sweep keys {unknown}")
    values = np.asarray(values, dtype=float)
    R = values.shape[0]
    col = {key: values[:, j] for j, key in enumerate(keys)}
    v, sp, link = base.valve, base.spring, base.linkage

    def column(key, default):
        return col[key] if key in col else np.full(R, float(default))

    closing = base.loads.closing_total
    kernel = solvers.solver(base.solver.method).batch_module()
    params = np.empty((R, len(kernel.RUN_PARAMETERS)))
    params[:, 0] = column("drive.rpm", base.drive.rpm) * 2.0 * math.pi / 60.0  # (Drive.omega's operations)
    params[:, 1] = column("valve.mass", v.mass)
    if "valve.oscillating_mass" in col or v.oscillating_mass is not None:
        params[:, 2] = column("valve.oscillating_mass", v.oscillating_mass)
    else:
        params[:, 2] = params[:, 1]
    params[:, 3] = column("linkage.stiffness", link.stiffness)
    params[:, 4] = column("linkage.damping", link.damping)
    params[:, 5] = column("valve.lash", v.lash)
    params[:, 6] = column("spring.preload", sp.preload) + closing
    params[:, 7] = column("spring.rate", sp.rate)
    params[:, 8] = column("loads.friction", base.loads.friction)
    params[:, 9] = column("seat.restitution", base.seat.restitution)
    params[:, 10] = params[:, 6]
    group = np.empty((R, 2))
    group[:, 0] = base.follower.ratio
    group[:, 1] = base.solver.steps_per_revolution
    return _chunk(kernel, params, group, shared)


def _chunk(kernel, params, group, shared) -> tuple[np.ndarray, np.ndarray]:
    """elastic_chunk from the run parameters (the batch module `kernel`'s RUN_PARAMETERS but
    take_up_s, filled here) and per run its lever ratio and steps per revolution: the runs of one
    grid and lash in one call."""
    lift = shared.lift
    R = params.shape[0]
    figures = np.full((R, len(ELASTIC)), math.nan)
    failed = np.zeros(R, bool)
    groups = _run_groups(group[:, 0], group[:, 1], params[:, 5])  # runs of one grid and lash
    ups_of = _take_ups([(ratio, lash) for ratio, _, lash in groups], shared)
    omega = params[:, 0]
    for (ratio, n, lash), members in groups.items():
        ups = ups_of[(ratio, lash)]
        params[members, 11] = ups[0] / omega[members] if len(ups) else math.nan
    # the fastest rate of each run: the step budget (effects.elastic.check_resolution) and the split
    M, M1, k, c, rate = (params[:, i] for i in (1, 2, 3, 4, 7))
    alpha = 0.5 * c / M1
    w2 = (k + rate) / M1
    over = alpha * alpha > w2
    rho = np.where(over, alpha + np.sqrt(np.where(over, alpha * alpha - w2, 0.0)), np.sqrt(np.abs(w2)))
    rho = np.maximum(rho, np.sqrt(rate / M))
    failed |= ~(rho * (2.0 * math.pi / omega) / 0.5 <= MAX_SOLVER_NODES)
    for (ratio, n, lash), members in groups.items():
        base = remember(shared.grids, (ratio, n), lambda: kernel.revolution_grid(lift, ratio, n))
        ref, dwell, S_dwell = _residual_reference(shared, lift, ratio, lash, n)
        members = members[~failed[members]]
        if not members.size:
            continue
        rho_theta = rho[members] / omega[members]
        split = rho_theta * base.h_max / kernel.MAX_RHO_H > 1.0
        plain = members[~split]
        if plain.size:
            figs, status = kernel.run_batch(base, ratio, params[plain], ref, dwell, S_dwell)
            figures[plain] = figs
            failed[plain] = status != kernel.OK
        for m, rt in zip(members[split].tolist(), rho_theta[split].tolist()):
            parts = kernel.split_parts(base, rt)
            grid = remember(shared.grids, (ratio, n, parts.tobytes()),
                            lambda: kernel.revolution_grid(lift, ratio, n, rt, base))
            figs, status = kernel.run_batch(grid, ratio, params[m:m + 1], ref, dwell, S_dwell)
            figures[m] = figs[0]
            failed[m] = status[0] != kernel.OK
    figures[failed] = math.nan
    return figures, failed


def _run_groups(ratio, n, lash) -> dict:
    """{(ratio, n, lash): its runs (int64 indices, in run order)} of a chunk's runs, the groups in
    the order of their first run (as a dict filled run by run would hold them): one lexsort for
    the chunk, no Python per run."""
    order = np.lexsort((lash, n, ratio))  # stable: each group's runs stay in run order
    a, b, c = ratio[order], n[order], lash[order]
    new = np.ones(order.size, bool)
    new[1:] = (a[1:] != a[:-1]) | (b[1:] != b[:-1]) | (c[1:] != c[:-1])
    starts = np.nonzero(new)[0]
    ends = np.append(starts[1:], order.size)
    groups = sorted(zip(order[starts].tolist(), starts.tolist(), ends.tolist()))  # by first run
    return {(float(ratio[f]), int(n[f]), float(lash[f])): order[i:j].astype(np.int64) for f, i, j in groups}


def _take_ups(pairs, shared) -> dict:
    """{(ratio, lash): [first take-up angle]} of a chunk's runs (pairs: their (ratio, lash)), the
    lashes found together (mechanics.kinematics.lash_take_ups: lash_crossings' root to brentq's tolerance): a tolerance
    study's runs each draw their own lash, and one Brent search per lash cost ten times the
    compiled revolution. Every lash takes this one search whatever else its chunk holds, so a table
    does not depend on how it was cut into chunks (each lane of the search is elementwise)."""
    out: dict = {}
    wanted: dict[float, set] = {}
    for ratio, lash in pairs:
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
