"""The batch engine of a sweep: the scalars of many runs of one scene, one row per run.

A run is `simulate(scene with the run's values)` reduced to the figures a designer reads
(row_scalars). The engine computes the same figures without the parts of `simulate` that no
row needs, and shares across runs everything that does not depend on the varied values:

- the lift curve (built once: the cam is the same in every run; for the gears whose lift a
  builder assembles from the scene, and for the trip gear's own effects, each run goes through
  `simulate` whole -- correct, and as slow as a loop);
- the rigid float speed and the smooth pieces of the lift (they depend on lash, masses and
  loads, not on the speed: cached per distinct set of those), the lash take-up angles (per lash);
- the forces effect's side figures and loss intervals, which no row holds, are not computed.

Which engine computes a chunk's rows is a registry (ENGINES, the first that accepts the scene):
- "compiled" (effects/elastic_batch.py): the elastic figures from the compiled exact solver
  (dynamics/exact_kernel.py), for the scenes whose elastic effect solves the LinkageModel with the
  exact solver and a constant stiffness; equal to simulate's within 1e-12 m of lift, 1e-12 s of
  event time and ~1e-9 relative of a figure (rounding of another order of the same operations;
  tests/test_effects/elastic_batch.py);
- "shared": the elastic effect itself (elastic_effect), each row equal to simulate's to the bit
  (tests/test_sweep_engine.py), for the other non-gear scenes (a spring chain, another solver);
- "simulate": simulate whole (the gears).

Columns (SI units in the names, as in `simulate`'s CSV), by effect:
  forces   min_contact_force_N (rigid, refined), float_speed_rpm (rigid; NaN: never floats)
  contact  max_camshaft_torque_Nm
  elastic  first_separation_deg (cam angle; NaN: none), separations, flight_time_s (time with the
           valve open and the linkage unloaded, on the output grid), max_deviation_m,
           peak_linkage_force_N, peak_camshaft_back_pressure_N, lift_off_delay_s (from the lash
           take-up to the valve's lift-off: Schenker's t0), seating_velocity_m_s (the hardest seat
           impact, < 0; NaN: none), seat_impacts, largest_bounce_m (highest rise after a seat
           impact before the next event, on the output grid; 0: none), residual_deviation_m and
           residual_amplitude_m (from the lift the cam is made for: explorer.effects.residual; NaN
           where the effect does not compute them, the spring chain's)
and always run_failed (1: the run raised; its figures NaN) after the varied inputs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..core.memo import CACHE_ENTRIES, remember as _remember  # noqa: F401 (CACHE_ENTRIES: the tests')
from ..effects.elastic_batch import BatchCache
from .sweep_spec import scene_for

EFFECT_COLUMNS: dict[str, tuple[str, ...]] = {
    "forces": ("min_contact_force_N", "float_speed_rpm"),
    "contact": ("max_camshaft_torque_Nm",),
    "elastic": ("first_separation_deg", "separations", "flight_time_s", "max_deviation_m", "peak_linkage_force_N",
                "peak_camshaft_back_pressure_N", "lift_off_delay_s", "seating_velocity_m_s", "seat_impacts",
                "largest_bounce_m", "residual_deviation_m", "residual_amplitude_m"),
}
# with a hydraulic lash adjuster ([hla], effects/train_elastic.py), the elastic effect's adjuster figures:
# how far the valve stays off its seat over the last revolution's base circle (0: it seats; where a
# speed sweep shows pump-up beginning), the lash the adjuster took up, its plunger's travel over that
# revolution and its chamber's peak pressure
HLA_COLUMNS = ("pump_up_valve_lift_m", "hla_lash_taken_up_m", "hla_plunger_travel_per_revolution_m",
               "hla_chamber_pressure_max_Pa")


def result_columns(scene) -> tuple[str, ...]:
    """The figures a row of this scene holds: those of the effects it computes, and run_failed."""
    from ..effects.pipeline import resolve

    effects = resolve(scene.effects)
    out: list[str] = []
    for effect, cols in EFFECT_COLUMNS.items():
        if effect in effects:
            out.extend(cols)
    if "elastic" in effects and getattr(scene, "hla", None) is not None:
        out.extend(HLA_COLUMNS)
    return tuple(out) + ("run_failed",)


def _nan_none(x) -> float:
    return math.nan if x is None else float(x)


def row_scalars(names, summary, events, columns) -> dict[str, float]:
    """The row of one run from what its effects returned (a Result's summary, events and
    columns, or the engine's own): one definition for `simulate` and the engine."""
    row: dict[str, float] = {}
    names = set(names)
    if "min_contact_force_N" in names:
        row["min_contact_force_N"] = _nan_none(summary.get("min_contact_force_N"))
        if summary.get("min_contact_force_N") is None:
            row["min_contact_force_N"] = math.inf  # the valve never opens: no contact to lose
        row["float_speed_rpm"] = _nan_none(summary.get("jump_speed_rpm"))
    if "max_camshaft_torque_Nm" in names:
        row["max_camshaft_torque_Nm"] = _nan_none(summary.get("max_camshaft_torque_Nm"))
    if "separations" in names:
        elastic = [e for e in events if e.get("effect", "elastic") == "elastic"]
        period = float(summary["revolution_time_s"])
        seps = [e for e in elastic if e["kind"] == "separation"]
        seats = [e for e in elastic if e["kind"] == "seat"]
        lift_offs = [float(e["time_s"]) for e in elastic if e["kind"] == "lift-off"]
        row["first_separation_deg"] = float(seps[0]["cam_angle_deg"]) if seps else math.nan
        row["separations"] = float(len(seps))
        row["flight_time_s"] = float(summary["separated_angle_deg"]) / 360.0 * period
        row["max_deviation_m"] = float(summary["max_deviation_m"])
        row["peak_linkage_force_N"] = float(summary["peak_linkage_force_N"])
        row["peak_camshaft_back_pressure_N"] = float(summary["peak_camshaft_back_pressure_N"])
        ups = summary.get("take_up_times_s")
        if ups is None:
            ups = [float(e["time_s"]) for e in events if e["kind"] == "lash-take-up"]
        if ups and lift_offs:
            row["lift_off_delay_s"] = min(math.fmod(t - ups[0] + period, period) for t in lift_offs)
        else:
            row["lift_off_delay_s"] = math.nan
        row["seating_velocity_m_s"] = min(float(e["velocity_m_s"]) for e in seats) if seats else math.nan
        row["seat_impacts"] = float(len(seats))
        row["largest_bounce_m"] = _largest_bounce(elastic, seats, columns)
        for name in ("residual_deviation_m", "residual_amplitude_m"):  # the elastic effect's (effects/residual.py)
            row[name] = _nan_none(summary.get(name))
    if "pump_up_valve_lift_m" in names:
        hla = summary.get("hla") or {}
        row["pump_up_valve_lift_m"] = _nan_none(hla.get("pump_up_valve_lift_m"))
        row["hla_lash_taken_up_m"] = _nan_none(hla.get("lash_taken_up_m"))
        row["hla_plunger_travel_per_revolution_m"] = _nan_none(hla.get("plunger_travel_per_revolution_m"))
        row["hla_chamber_pressure_max_Pa"] = _nan_none(hla.get("chamber_pressure_max_Pa"))
    return row


def _largest_bounce(elastic, seats, columns) -> float:
    """Highest valve lift on the output grid after a seat impact, before the next elastic event."""
    if not seats:
        return 0.0
    t, s = np.asarray(columns["time_s"]), np.asarray(columns["valve_lift_m"])
    times = [float(e["time_s"]) for e in elastic]
    best = 0.0
    for ev in seats:
        t0 = float(ev["time_s"])
        later = [x for x in times if x > t0]
        t1 = min(later) if later else float(t[-1]) + 1.0
        inside = (t > t0) & (t < t1)
        if inside.any():
            best = max(best, float(s[inside].max()))
    return best


def reference_row(scene, names) -> dict[str, float]:
    """The row from `simulate` itself (the tests' oracle and the gears' path)."""
    from ..effects.pipeline import simulate

    result = simulate(scene)
    return row_scalars(names, result.summary, result.summary["events"], result.columns)


@dataclass
class _Shared(BatchCache):
    """What the runs of one chunk share (built on first use): the compiled path's (lift, revolution
    grids, take-up angles: effects/elastic_batch.py) and the rigid figures' smooth pieces and
    float speeds."""

    pieces: dict = field(default_factory=dict)
    jumps: dict = field(default_factory=dict)


def _batchable(scene) -> bool:
    """True when the lift is the same curve in every run and the effects are the generic ones."""
    from ..gears.registry import GEARS

    return scene.follower.type not in GEARS


def engine_row(scene, names, shared: _Shared) -> dict[str, float]:
    """The row of one run, computed as simulate computes it, sharing `shared` across runs."""
    summary, events, columns = engine_outputs(scene, shared)
    return row_scalars(set(names), summary, events, columns)


def engine_outputs(scene, shared: _Shared) -> tuple[dict, list, dict]:
    """(summary, elastic events, columns) of one run: what the rows are read from."""
    from ..effects.pipeline import Context, effect_function, resolve
    from ..effects.lift import build_lift

    if shared.lift is None:
        shared.lift = build_lift(scene)
    lift = shared.lift
    effects = resolve(scene.effects)
    n = scene.solver.steps_per_revolution
    theta = np.arange(n) * (2.0 * math.pi / n)  # as simulate builds them: the same floats
    omega = scene.drive.omega
    t_time = theta / omega
    columns: dict[str, np.ndarray] = {"cam_angle_deg": np.degrees(theta), "time_s": t_time}
    summary: dict[str, Any] = {"revolution_time_s": 2.0 * math.pi / omega}
    events: list[dict] = []

    def ctx():
        return Context(scene, theta, t_time, lift, MappingProxyType(columns), MappingProxyType(summary))

    rigid = "forces" in effects or "contact" in effects
    if rigid:
        out = effect_function("kinematics", scene.follower.type)(ctx())
        columns.update(out.columns)
    if "forces" in effects:
        summary.update(_forces_scalars(scene, lift, omega, shared, columns))
    if "contact" in effects:
        out = effect_function("contact", scene.follower.type)(ctx())
        summary["max_camshaft_torque_Nm"] = out.summary.get("max_camshaft_torque_Nm")
    if "elastic" in effects:
        ratio, lash = scene.follower.ratio, scene.valve.lash
        from ..mechanics.kinematics import lash_crossings

        ups = _remember(shared.take_ups, (ratio, lash), lambda: lash_crossings(lift, ratio, lash)[0])
        summary["take_up_times_s"] = [th / omega for th in ups]  # lash_effect's time_s, same arithmetic
        out = effect_function("elastic", scene.follower.type)(ctx())
        columns.update(out.columns)
        summary.update(out.summary)
        events.extend(dict(e, effect="elastic") for e in out.events)
        events.sort(key=lambda e: e["time_s"])
    return summary, events, columns


def _forces_scalars(scene, lift, omega, shared: _Shared, columns) -> dict:
    """The forces effect's columns (into `columns`), its refined minimum contact force at this
    speed and the float speed (cached: it does not depend on the speed)."""
    from ..mechanics.forces import TrainLoads, float_speed, min_contact_force, rigid_train_forces, smooth_pieces

    loads = TrainLoads.from_scene(scene)
    ratio, lash = scene.follower.ratio, scene.valve.lash
    n_grid = max(4096, scene.solver.steps_per_revolution)
    columns.update(rigid_train_forces(columns["rigid_valve_lift_m"], columns["rigid_valve_velocity_m_s"],
                                      columns["rigid_valve_accel_m_s2"], loads, ratio))
    pieces = _remember(shared.pieces, (ratio, lash, n_grid), lambda: smooth_pieces(lift, ratio, lash, n_grid))
    f_min, _ = min_contact_force(lift, loads, omega, ratio, lash, pieces, n_grid)
    jump = _remember(shared.jumps, (ratio, lash, n_grid, loads), lambda: float_speed(lift, loads, ratio, lash, pieces, n_grid))
    return {"min_contact_force_N": f_min if math.isfinite(f_min) else None,
            "jump_speed_rpm": jump.rpm if math.isfinite(jump.omega) else None}


@dataclass(frozen=True)
class RowEngine:
    """One way to compute a run's row: `accepts(base scene, shared)` says whether it takes the
    runs of that scene, `row(scene, names, shared)` computes one. compute_chunk takes the first
    engine of ENGINES that accepts the chunk's scene."""

    name: str
    accepts: Any
    row: Any
    # optional: chunk(scenes, names, shared, groups) -> (runs x names) figures with run_failed, all
    # the runs at once (the compiled engine's batches; groups: speed_groups); None: row by row
    chunk: Any = None
    # fewest runs for which a local pool of processes beats one process: a worker pays its start
    # (fork, and for the compiled engine ~1.3 s to import numba and load the compiled solver)
    pool_min_runs: int = 1
    # most runs in one chunk (one task of a pool or a cluster): a task should be well above a
    # round trip's ~1-5 ms, yet short enough for progress, Ctrl-C and load balance
    max_chunk: int = 64


def _kernel_accepts(scene, shared) -> bool:
    from ..effects.elastic_batch import accepts

    return accepts(scene, shared)


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
    from ..effects.elastic_batch import ELASTIC, elastic_run

    names = set(names)
    row: dict[str, float] = {}
    rigid = names - set(ELASTIC) - {"run_failed"}
    if rigid:
        from .sweep_rigid import rigid_over_speeds

        row.update({name: float(v[0]) for name, v in rigid_over_speeds([scene], rigid, shared).items()})
    figures, _, _ = elastic_run(scene, shared)
    row.update(figures)
    return row


def _kernel_chunk(scenes, names, shared, groups=None) -> np.ndarray:
    """The rows of many runs: the elastic figures in compiled batches (elastic_batch.elastic_chunk),
    the rigid ones (forces, contact) per group of runs that differ in speed only, all its speeds at
    once (sweep_rigid.py; groups: index arrays, default each run alone). Every run's rigid figures
    take the same arithmetic whatever else its chunk holds, so a table does not depend on how it
    was cut into chunks (the cluster's equals the serial one bit for bit)."""
    from ..effects.elastic_batch import ELASTIC, elastic_chunk
    from .sweep_rigid import rigid_over_speeds

    names = tuple(names)
    out = np.full((len(scenes), len(names)), math.nan)
    fail = names.index("run_failed")
    failed = np.zeros(len(scenes), bool)
    rigid = [n for n in names if n not in ELASTIC and n != "run_failed"]
    if rigid:
        for group in (groups if groups is not None else [np.array([i]) for i in range(len(scenes))]):
            try:
                figures = rigid_over_speeds([scenes[i] for i in group], rigid, shared)
            except (InputError, RuntimeError, ValueError, ArithmeticError):
                failed[group] = True
                continue
            for name, values in figures.items():
                out[group, names.index(name)] = values
    if any(n in ELASTIC for n in names):
        figures, elastic_failed = elastic_chunk(scenes, shared)
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
    # simulate itself (the gears, whose lift or effects are their own)
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
        scenes = [scene_for(base, keys, row_values) for row_values in np.asarray(values, dtype=float)]
        return engine.chunk(scenes, names, shared, speed_groups(keys, values))
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
