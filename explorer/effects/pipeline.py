"""The effects pipeline: run exactly the effects a scene lists (plus what they need), timed.

Effects run in dependency order (explorer/effects/registry.py); each gets a Context (the scene,
the sampling grid, the lift curve, the columns and summary so far) and returns an EffectOutput.
Columns of later effects replace earlier ones of the same name, which is how `valve_*` always holds
the most detailed motion. A gear's own variant of an effect (its `effects`) runs instead of the
generic function.

Two runs share this one loop: `simulate` (every effect whole, timed) and `figures` (each effect's
figures-only form where it has one, with caches shared across the runs of a sweep: the sweep
engine's shared path and its rigid figures).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Callable

import numpy as np

from ..core import plugins
from ..core.errors import InputError
from ..lift.curves import LiftCurve
from ..result import NAN_MEANINGS, EffectOutput, EffectTiming, Event, Result
from . import registry
from .context import Context, sample_grid  # noqa: F401 (Context: the effects' API, imported from here too)
from .lift import build_lift

# Results are checked behind the valid ranges: NaN (inf - inf, 0 / 0: an overflow inside an
# effect) is refused except in the columns that mark with NaN where they are not defined, each with
# its documented meaning (result.NAN_MEANINGS); infinity is a result for forces (a self-locking cam
# needs an infinite push), never for the motion.
NAN_WHERE_UNDEFINED = frozenset(NAN_MEANINGS)
MOTION_PREFIXES = ("cam_angle", "time_", "follower_", "valve_lift", "valve_velocity", "valve_accel", "valve_jerk",
                   "rigid_valve_")


@dataclass
class RunCache:
    """What the runs of one scene share in `figures` (a sweep's chunk, the browser's speed sweep):
    the lift curve (the same cam in every run) and each effect's own bounded memo
    (explorer.core.memo.remember). The sweep engine's cache extends it."""

    lift: LiftCurve | None = None
    memo: dict = field(default_factory=dict)

    def of(self, effect: str) -> dict:
        """The memo of one effect (each bounded on its own: a tolerance study's new lash per run
        must not push out another effect's entries)."""
        return self.memo.setdefault(effect, {})


def effect_function(name: str, gear=None) -> Callable[[Context], EffectOutput]:
    """The function of effect `name`: the gear's own variant when it has one, else the generic
    effect (with the sections' summary blocks)."""
    variant = gear.effect(name) if gear is not None else None
    if variant is not None:
        return variant
    spec = registry.effect_spec(name)
    function = spec.run()
    return function if not spec.sections else _with_sections(function, spec.sections)


def _with_sections(function, sections):
    def run(ctx: Context) -> EffectOutput:
        out = function(ctx)
        for section, target in sections:
            if getattr(ctx.scene, section, None) is None:
                continue
            block, extra_warnings = plugins.resolve(target)(ctx.scene, ctx.lift)
            out = EffectOutput(columns=out.columns, summary={**out.summary, section: block}, events=out.events,
                               warnings=tuple(out.warnings) + tuple(extra_warnings))
        return out

    return run


def _figures_function(name: str, gear, cache: RunCache) -> Callable[[Context], EffectOutput]:
    """The figures-only form of effect `name` (its own function where it has none, or where the
    gear has a variant of it)."""
    spec = registry.effect_spec(name)
    if gear.effect(name) is None and spec.figures is not None:
        form = plugins.resolve(spec.figures)
        return lambda ctx: form(ctx, cache)
    return effect_function(name, gear)


def _check_columns(scene, name: str, gear, out: EffectOutput, shape) -> None:
    spec = registry.effect_spec(name)
    own = gear.columns.get(name, ())
    for column, values in out.columns.items():
        if not (spec.declares(column) or registry.declared(column, own)):
            raise RuntimeError(f"effect {name} returned column {column}, which neither the effect table nor the "
                               f"{gear.type} gear declares")
        values = np.asarray(values, dtype=float)
        if values.shape != shape:
            raise RuntimeError(f"effect {name} returned column {column} of shape {values.shape}")
        if column not in NAN_WHERE_UNDEFINED and np.any(np.isnan(values)) \
                or column.startswith(MOTION_PREFIXES) and np.any(np.isinf(values)):
            # behind the valid ranges of the scene: an overflow must not end as a file of NaN
            raise InputError(scene.source, name, f"the {name} effect's results are not finite ({column}): "
                             "the scene's values are beyond what the model can compute")


def _run(scene, lift, effects, function_of, timed: bool) -> Result:
    theta, t_time = sample_grid(scene)
    started = time.perf_counter()
    lift_curve = lift if lift is not None else build_lift(scene)
    lift_seconds = time.perf_counter() - started
    gear = scene.gear_plugin

    columns: dict[str, np.ndarray] = {"cam_angle_deg": np.degrees(theta), "time_s": t_time}
    summary: dict[str, Any] = {
        "scene": scene.name,
        "rpm": scene.drive.rpm,
        "steps_per_revolution": scene.solver.steps_per_revolution,
        "revolution_time_s": 2.0 * np.pi / scene.drive.omega,
    }
    timings: dict[str, EffectTiming] = {}
    events: list[Event] = []
    warnings: list[str] = []
    done: list[str] = []
    for name in registry.order(effects):
        ctx = Context(scene, theta, t_time, lift_curve, MappingProxyType(columns), MappingProxyType(summary),
                      tuple(done))
        # import outside the timing: cost of the effect, not of Python
        function = function_of(name, gear)
        started = time.perf_counter()
        out = function(ctx)
        seconds = time.perf_counter() - started
        if name == "kinematics":
            seconds += lift_seconds  # building the lift curve is part of the kinematics cost
        _check_columns(scene, name, gear, out, theta.shape)
        columns.update((column, np.asarray(values, dtype=float)) for column, values in out.columns.items())
        summary.update(out.summary)
        events.extend(e.with_effect(name) for e in out.events)
        warnings.extend(out.warnings)
        if timed:
            timings[name] = EffectTiming(compute_time_s=seconds, requested=name in scene.effects)
        done.append(name)
    return Result.build(scene, columns, summary, sorted(events, key=lambda e: e.time_s), warnings, timings)


def simulate(scene, lift=None) -> Result:
    """Run the scene's effects over one revolution; `lift` may pass a prebuilt lift curve."""
    return _run(scene, lift, scene.effects, effect_function, timed=True)


def figures(scene, cache: RunCache, effects=None) -> Result:
    """The figures-only run of the scene's effects (or of `effects`): each effect's figures form
    where it has one (explorer/effects/registry.py, item 6), sharing `cache` across the runs of a
    sweep (the lift curve is built once, into cache.lift). Its Result holds what sweep rows and
    later effects read, computed as `simulate` computes them; no timings."""
    if cache.lift is None:
        cache.lift = build_lift(scene)
    return _run(scene, cache.lift, scene.effects if effects is None else effects,
                lambda name, gear: _figures_function(name, gear, cache), timed=False)
