"""The batch engine of a sweep: the scalars of many runs of one scene, one row per run.

A run is `simulate(scene with the run's values)` reduced to the figures a designer reads: each
effect's row function (explorer/effects/registry.py: sweep_figures and row). The engine computes
the same figures without the parts of `simulate` that no row needs, and shares across runs
everything that does not depend on the varied values:

- the lift curve (built once: the cam is the same in every run, and so is a gear's lift when it
  reads none of the run's values and the gear brings no effect of its own, Gear.shares_lift; for a
  gear whose lift does (the trip gear's closing, a rocking cam fitted to its target after the lash)
  or that brings its own effects (the trip gear's), each run goes through `simulate` whole --
  correct, and as slow as a loop);
- what the effects' figures-only forms keep across runs (the pipeline's `figures` run: the rigid
  float speed and the smooth pieces of the lift, per distinct lash, masses and loads; the lash
  take-up angles per lash); what no row holds (the forces' side figures, the loss intervals) is not
  computed.

Which engine computes a chunk's rows is a table (ENGINES, the first that accepts the scene):
- "compiled" (effects/elastic_batch.py): the elastic figures from the solver's compiled batch module
  (explorer/dynamics/solvers.py: batch_entry, the exact solver's exact_kernel), for the scenes whose
  gear takes batches (Gear.batch_sweeps), whose elastic effect solves the LinkageModel with that
  solver and a constant stiffness and whose every figure it computes; equal to simulate's within
  1e-12 m of lift, 1e-12 s of event time and ~1e-9 relative of a figure (rounding of another order of
  the same operations; tests/test_sweep_kernel.py);
- "shared": the pipeline's figures-only run (effects/pipeline.figures), each row equal to simulate's
  to the bit (tests/test_sweep_engine.py), for the other scenes whose runs share a lift (a spring
  chain, another solver, a lever gear, an effect of the table that the compiled path does not know);
- "simulate": simulate whole (the gears whose lift reads the run's values or whose effects are their
  own).

Columns (SI units in the names, as in `simulate`'s CSV), by effect:
  forces   min_contact_force_N (rigid, refined), float_speed_rpm (rigid; NaN: never floats)
  contact  max_camshaft_torque_Nm
  elastic  first_separation_deg (cam angle; NaN: none) and separations, the valve's float (while
           it is open: from the rigid opening to its first seat impact, elastic_events.
           valve_periods), flight_time_s (the float's flight: from each of those separations to
           the next re-contact or seat impact, by the events' instants; the bounce's flights
           after the seat impact are not in it), max_deviation_m, peak_linkage_force_N, peak_camshaft_back_pressure_N,
           lift_off_delay_s (from the lash take-up to the valve's lift-off: Schenker's t0),
           seating_velocity_m_s (the hardest seat impact, < 0; NaN: none), seat_impacts,
           largest_bounce_m (highest lift after a seat impact before the cam opens the valve
           again, on the output grid; 0: none), residual_deviation_m and residual_amplitude_m
           (from the lift the cam is made for: explorer.effects.residual; NaN where the effect
           does not compute them, the spring chain's, and the amplitude where the lift has no
           dwell after the rise)
then, with a [hla] section, its figures (pump_up_valve_lift_m, hla_lash_taken_up_m,
hla_plunger_travel_per_revolution_m, hla_chamber_pressure_max_Pa), and always run_failed (1: the run
raised; its figures NaN), the last column (after run, the varied inputs and the figures).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..core.memo import CACHE_ENTRIES  # noqa: F401 (the tests')
from ..core.plugins import resolve
from ..effects import registry as effects
from ..effects.elastic_batch import BatchCache, ELASTIC, accepts, elastic_chunk_values, elastic_run
from ..effects.pipeline import RunCache, figures, simulate
from .sweep_rigid import RIGID, rigid_over_speeds, speeds_of
from .sweep_spec import scene_for


def result_columns(scene) -> tuple[str, ...]:
    """The figures a row of this scene holds: those of the effects it computes (the effect table's
    sweep_figures), and run_failed."""
    return effects.sweep_figures(scene.effects, scene) + ("run_failed",)


def row_figures(names, result) -> dict[str, float]:
    """The row of one run from its Result (of `simulate` or of the pipeline's figures-only run): each
    effect's row function (the effect table), one definition for both."""
    names = set(names)
    row: dict[str, float] = {}
    for name in effects.order(result.scene.effects):
        spec = effects.effect_spec(name)
        if spec.row is not None and names & set(spec.sweep_figures):
            row.update(resolve(spec.row)(result))
        for extra in spec.section_figures_of(result.scene):  # those of a section the scene has ([hla])
            if names & set(extra.figures):
                row.update(resolve(extra.row)(result))
    return row


def reference_row(scene, names) -> dict[str, float]:
    """The row from `simulate` itself (the tests' oracle and the path of the gears whose runs share
    no lift)."""
    return row_figures(names, simulate(scene))


@dataclass
class _Shared(RunCache, BatchCache):
    """What the runs of one chunk share (built on first use): the lift curve, each effect's memo of
    the figures-only run (effects/pipeline.RunCache: the forces' smooth pieces and float speeds, the
    lash take-ups) and the compiled path's revolution grids and take-up angles
    (effects/elastic_batch.BatchCache)."""


def _batchable(scene) -> bool:
    """True when the runs share one lift curve and the generic effects (the scene's gear says:
    Gear.shares_lift -- no variant of an effect, a lift that reads none of the sweep keys)."""
    return scene.gear_plugin.shares_lift(scene)


def engine_row(scene, names, shared: _Shared) -> dict[str, float]:
    """The row of one run: the pipeline's figures-only run, sharing `shared` across runs."""
    return row_figures(names, figures(scene, shared))


@dataclass(frozen=True)
class RowEngine:
    """One way to compute a run's row: `accepts(base scene, shared)` says whether it takes the
    runs of that scene, `row(scene, names, shared)` computes one. compute_chunk takes the first
    engine of ENGINES that accepts the chunk's scene."""

    name: str
    accepts: Any
    row: Any
    # optional: chunk(base, keys, values, names, shared, groups) -> (runs x names) figures with
    # run_failed, all the runs at once (the compiled engine's batches; groups: speed_groups); None:
    # row by row
    chunk: Any = None
    # fewest runs for which a local pool of processes beats one process: a worker pays its start
    # (fork, and for the compiled engine ~1.3 s to import numba and load the compiled solver)
    pool_min_runs: int = 1
    # most runs in one chunk (one task of a pool or a cluster): a task should be well above a
    # round trip's ~1-5 ms, yet short enough for progress, Ctrl-C and load balance
    max_chunk: int = 64


def _kernel_accepts(scene, shared) -> bool:
    """The compiled path computes every figure of the scene's row (its rigid and elastic ones)."""
    return set(result_columns(scene)) <= {*ELASTIC, *RIGID, "run_failed"} and accepts(scene, shared)


def speed_groups(keys, values) -> list[np.ndarray]:
    """The rows of `values` (runs x keys) grouped by every key but drive.rpm: the runs of a group
    are the same scene at different speeds (scene_for builds each from the base and its values)."""
    other = [j for j, key in enumerate(keys) if key != "drive.rpm"]
    if not other:
        return [np.arange(len(values))]
    groups: dict[tuple, list[int]] = {}
    for i, row in enumerate(np.asarray(values, dtype=float)[:, other].tolist()):
        groups.setdefault(tuple(row), []).append(i)
    return [np.asarray(g) for g in groups.values()]


def _kernel_row(scene, names, shared) -> dict[str, float]:
    """The row of one run: the elastic figures compiled (elastic_batch.elastic_run), the rigid ones
    (forces, contact) as the compiled chunk computes them (sweep_rigid.py, a group of one)."""
    names = set(names)
    row: dict[str, float] = {}
    rigid = names - set(ELASTIC) - {"run_failed"}
    if rigid:
        row.update({name: float(v[0]) for name, v in rigid_over_speeds(scene, [scene.drive.omega], rigid, shared).items()})
    figures, _, _ = elastic_run(scene, shared)
    row.update(figures)
    return row


def _kernel_chunk(base, keys, values, names, shared, groups=None) -> np.ndarray:
    """The rows of the runs `values` (runs x keys, SI) of scene `base`: the elastic figures in
    compiled batches from the runs' parameters (elastic_batch.elastic_chunk_values: no scene built
    per run), the rigid ones (forces, contact) per group of runs that differ in speed only, all its
    speeds at once (sweep_rigid.py; groups: index arrays, default each run alone). Every run's rigid
    figures take the same arithmetic whatever else its chunk holds, so a table does not depend on
    how it was cut into chunks (the cluster's equals the serial one bit for bit)."""
    names = tuple(names)
    values = np.asarray(values, dtype=float)
    out = np.full((len(values), len(names)), math.nan)
    fail = names.index("run_failed")
    failed = np.zeros(len(values), bool)
    rigid = [n for n in names if n not in ELASTIC and n != "run_failed"]
    speed = list(keys).index("drive.rpm") if "drive.rpm" in keys else None
    other = [j for j, key in enumerate(keys) if key != "drive.rpm"]
    if rigid:
        for group in (groups if groups is not None else [np.array([i]) for i in range(len(values))]):
            try:
                # the group's runs differ in speed only: one scene, and each run's speed
                scene = scene_for(base, keys, values[group[0]])
                omegas = (speeds_of(scene, values[group, speed]) if speed is not None
                          else np.full(len(group), scene.drive.omega))
                group_key = tuple(values[group[0], other].tolist())  # the group's values but the speed
                figures = rigid_over_speeds(scene, omegas, rigid, shared, group_key)
            except (InputError, RuntimeError, ValueError, ArithmeticError):
                failed[group] = True
                continue
            for name, column in figures.items():
                out[group, names.index(name)] = column
    if any(n in ELASTIC for n in names):
        figures, elastic_failed = elastic_chunk_values(base, keys, values, shared)
        for j, name in enumerate(ELASTIC):
            if name in names:
                out[:, names.index(name)] = figures[:, j]
        failed |= elastic_failed
    out[failed] = math.nan
    out[:, fail] = failed.astype(float)
    return out


ENGINES: tuple[RowEngine, ...] = (
    # the elastic figures from the compiled exact solver (explorer/dynamics/exact_kernel.py)
    # (~0.5-1 ms a run with the rigid effects, ~0.15 ms without: a pool pays off from ~10^4 runs)
    RowEngine("compiled", _kernel_accepts, _kernel_row, _kernel_chunk, pool_min_runs=10_000, max_chunk=4096),
    # the effects' own functions, sharing the lift and the rigid float speed across runs
    RowEngine("shared", lambda scene, shared: _batchable(scene), engine_row),
    # simulate itself (the gears whose lift reads the run's values or whose effects are their own)
    RowEngine("simulate", lambda scene, shared: True, lambda scene, names, shared: reference_row(scene, names)),
)


def engine_for(base, shared: _Shared) -> RowEngine:
    """The first engine of ENGINES that takes the runs of the scene `base`."""
    return next(engine for engine in ENGINES if engine.accepts(base, shared))


def compute_chunk(base, keys, values: np.ndarray, names, shared: _Shared | None = None,
                  engine: RowEngine | None = None) -> np.ndarray:
    """The figures (runs x names, float64) of the runs `values` (runs x keys, SI) of scene `base`.
    A run that raises (a speed too slow for the solver's step budget, a motion that does not
    settle) gets NaN and run_failed = 1; the others are unaffected."""
    names = tuple(names)
    out = np.full((values.shape[0], len(names)), math.nan)
    fail = names.index("run_failed")
    shared = shared if shared is not None else _Shared()
    engine = engine if engine is not None else engine_for(base, shared)
    if engine.chunk is not None:
        return engine.chunk(base, keys, values, names, shared, speed_groups(keys, values))
    for i, row_values in enumerate(np.asarray(values, dtype=float)):
        scene = scene_for(base, keys, row_values)
        try:
            row = engine.row(scene, names, shared)
        except (InputError, RuntimeError, ValueError, ArithmeticError):
            out[i, fail] = 1.0
            continue
        out[i, fail] = 0.0
        for j, name in enumerate(names):
            if name in row:
                out[i, j] = row[name]
    return out
