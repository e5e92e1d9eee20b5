"""The effects pipeline: run exactly the effects a scene lists (plus what they need), timed.

Effects run in dependency order; each gets the scene, the shared sampling grid, the lift curve
and the columns computed so far, and returns an EffectOutput. Columns of later effects replace
earlier ones of the same name, which is how `valve_*` always holds the most detailed motion.
"""

from __future__ import annotations

import importlib
import math
import time
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Callable, Mapping

import numpy as np

from ..core.errors import InputError
from ..gears.registry import effect_variant
from ..result import NAN_MEANINGS, EffectOutput, Result
from ..scene.scene import EFFECT_DEPENDENCIES, Scene

# effect -> "module:function"; imported only when the effect runs, so a kinematics-only scene
# never even imports a dynamics solver. A gear's own variant of an effect is an entry of its
# line in explorer.gears.registry (effects), which replaces the generic function here.
EFFECT_FUNCTIONS: dict[str, str] = {
    "kinematics": "explorer.effects.kinematics:kinematics_effect",
    "lash": "explorer.effects.kinematics:lash_effect",
    "forces": "explorer.effects.forces:forces_effect",
    "contact": "explorer.effects.contact:contact_effect",
    "elastic": "explorer.effects.elastic:elastic_effect",
    "gear": "explorer.effects.gear:gear_effect",
}

# effect -> ((scene section, "module:function"), ...): the owner of an optional section adds a
# block to the generic effect's summary when the scene has that section, function(scene, lift)
# -> (block, warnings), stored as summary[section] after the effect's own entries (a gear's
# variant of the effect gets none).
SECTION_SUMMARIES: dict[str, tuple[tuple[str, str], ...]] = {
    "forces": (("spring_design", "explorer.effects.spring_design:spring_design_summary"),),
}


@dataclass(frozen=True)
class Context:
    """Read-only inputs of an effect."""

    scene: Scene
    theta: np.ndarray  # rad, 0 <= theta < 2 pi, one revolution
    time: np.ndarray  # s, theta / omega
    lift: Any  # LiftCurve
    columns: Mapping[str, np.ndarray]  # computed so far
    summary: Mapping[str, Any]  # computed so far

    @property
    def omega(self) -> float:
        return self.scene.drive.omega


def resolve(effects) -> list[str]:
    """Requested effects plus their dependencies, in an order where dependencies come first."""
    order: list[str] = []

    def visit(name: str, path: tuple[str, ...]) -> None:
        if name in order:
            return
        if name in path:
            raise RuntimeError(f"effect dependency cycle: {' -> '.join(path + (name,))}")
        for dep in EFFECT_DEPENDENCIES[name]:
            visit(dep, path + (name,))
        order.append(name)

    for effect in effects:
        visit(effect, ())
    return order


def _resolve(target: str):
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module), attr)


# Results are checked behind the valid ranges: NaN (inf - inf, 0 / 0: an overflow inside an
# effect) is refused except in the columns that mark with NaN where they are not defined, each with
# its documented meaning (result.NAN_MEANINGS); infinity is a result for forces (a self-locking cam
# needs an infinite push), never for the motion.
NAN_WHERE_UNDEFINED = frozenset(NAN_MEANINGS)
MOTION_PREFIXES = ("cam_angle", "time_", "follower_", "valve_lift", "valve_velocity", "valve_accel", "valve_jerk",
                   "rigid_valve_")


def effect_function(name: str, follower_type: str | None = None) -> Callable[[Context], EffectOutput]:
    """The function of effect `name`: the gear's variant for that follower type when its
    registry entry has one, else the generic effect (with the sections' summary blocks)."""
    variant = effect_variant(follower_type, name) if follower_type is not None else None
    if variant is not None:
        return _resolve(variant)
    function = _resolve(EFFECT_FUNCTIONS[name])
    sections = SECTION_SUMMARIES.get(name)
    return function if not sections else _with_sections(function, sections)


def _with_sections(function, sections):
    def run(ctx: Context) -> EffectOutput:
        out = function(ctx)
        for section, target in sections:
            if getattr(ctx.scene, section, None) is None:
                continue
            block, extra_warnings = _resolve(target)(ctx.scene, ctx.lift)
            out = EffectOutput(columns=out.columns, summary={**out.summary, section: block}, events=out.events,
                               warnings=tuple(out.warnings) + tuple(extra_warnings))
        return out

    return run


def simulate(scene: Scene, lift=None) -> Result:
    """Run the scene's effects over one revolution; `lift` may pass a prebuilt lift curve."""
    from .lift import build_lift

    n = scene.solver.steps_per_revolution
    theta = np.arange(n) * (2.0 * math.pi / n)
    t_time = theta / scene.drive.omega
    started = time.perf_counter()
    lift_curve = lift if lift is not None else build_lift(scene)
    lift_seconds = time.perf_counter() - started

    columns: dict[str, np.ndarray] = {"cam_angle_deg": np.degrees(theta), "time_s": t_time}
    summary: dict[str, Any] = {
        "scene": scene.name,
        "rpm": scene.drive.rpm,
        "steps_per_revolution": n,
        "revolution_time_s": 2.0 * math.pi / scene.drive.omega,
    }
    effect_info: dict[str, Any] = {}
    events: list[dict] = []
    warnings: list[str] = []
    for name in resolve(scene.effects):
        ctx = Context(scene, theta, t_time, lift_curve, MappingProxyType(columns), MappingProxyType(summary))
        # import outside the timing: cost of the effect, not of Python
        function = effect_function(name, scene.follower.type)
        started = time.perf_counter()
        out = function(ctx)
        seconds = time.perf_counter() - started
        if name == "kinematics":
            seconds += lift_seconds  # building the lift curve is part of the kinematics cost
        for column, values in out.columns.items():
            values = np.asarray(values, dtype=float)
            if values.shape != theta.shape:
                raise RuntimeError(f"effect {name} returned column {column} of shape {values.shape}")
            if column not in NAN_WHERE_UNDEFINED and np.any(np.isnan(values)) \
                    or column.startswith(MOTION_PREFIXES) and np.any(np.isinf(values)):
                # behind the valid ranges of the scene: an overflow must not end as a file of NaN
                raise InputError(scene.source, name, f"the {name} effect's results are not finite ({column}): "
                                 "the scene's values are beyond what the model can compute")
            columns[column] = values
        summary.update(out.summary)
        events.extend(dict(e, effect=name) for e in out.events)
        warnings.extend(out.warnings)
        effect_info[name] = {"compute_time_s": seconds, "requested": name in scene.effects}
    summary["effects"] = effect_info
    summary["events"] = sorted(events, key=lambda e: e["time_s"])
    summary["warnings"] = warnings
    return Result.build(scene, columns, summary)
