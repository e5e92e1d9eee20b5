"""Checking a design: every rule of the table over the scene's operating range, and over its
tolerances when draws are asked for.

1. The operating range: `rpm` ("START:STOP:COUNT" or a list, the sweep's grammar), else the
   scene's [drive] operating_range (DEFAULT_SPEEDS speeds), else the scene's own speed.
2. The settings: the table's defaults, the scene's [checks], then a --rules file.
3. The nominal design: each rule's measure over the range; the worst value, where (speed and cam
   angle) and the verdict.
4. Tolerances (`sample`, `runs`, `seed`: the sweep's --sample grammar): N draws of the varied keys;
   each rule judges every draw at the speeds where the nominal design was worst for it and at the
   range's ends (the elastic rules at the worst speed only; the float margin at the first
   separation and the highest speed plus the margin) -- the worst over those speeds per draw. The
   share of draws that fail (and that warn or fail), with Wilson's 95 % score interval.
"""

from __future__ import annotations

import math
import time
from typing import Callable

import numpy as np

from ..core.errors import InputError
from .case import RPM, Case, Draws
from .registry import RULES, measure_function
from .report import CheckReport, RuleResult
from .rule import NOT_APPLICABLE, VERDICTS, Measure, verdicts, wilson_interval, worst_index

DEFAULT_SPEEDS = 200


def operating_speeds(scene, rpm=None) -> tuple[np.ndarray, str]:
    """(speeds in rev/min, where they came from)."""
    from ..studies.sweep_spec import parse_axis

    if rpm is not None:
        if isinstance(rpm, str) and ":" not in rpm and "," not in rpm:
            values = np.array([parse_axis("drive.rpm", [rpm], file="--rpm").values[0]])
        else:
            values = parse_axis("drive.rpm", rpm, file="--rpm").values
        return np.unique(values), "--rpm"
    if scene.drive.operating_range is not None:
        lo, hi = scene.drive.operating_range
        return np.linspace(lo, hi, DEFAULT_SPEEDS), "[drive] operating_range"
    return np.array([scene.drive.rpm]), "the scene's own speed: give [drive] operating_range or --rpm for a range"


def check(scene, rpm=None, sample=None, *, runs: int | None = None, seed: int | None = None, rules=None,
          workers: int | None = None, progress: Callable | None = None, yes: bool = False,
          only=None) -> CheckReport:
    """Check a design (a Scene or a scene file's path); see the module docstring. `sample`:
    {key: "normal(MEAN, SD)" | "uniform(LOW, HIGH)"}; `rules`: a --rules file's path; `only`:
    the names of the rules to judge (the others are reported "off"). Bad input raises
    InputError before any work."""
    from ..studies.sweep_spec import check_scene, make_plan, parse_sample
    from .settings import load_rules_file, resolve

    started = time.perf_counter()
    if not hasattr(scene, "effects"):
        from ..scene.scene import load_scene

        scene = load_scene(scene)
    speeds, range_from = operating_speeds(scene, rpm)
    settings, off = resolve([scene.checks, load_rules_file(rules) if rules is not None else None])
    if only is not None:
        unknown = [name for name in only if name not in settings]
        if unknown:
            raise InputError("<arguments>", "only", f"unknown rule {unknown[0]!r}; known: {', '.join(settings)}")
        off = tuple(name for name in settings if name in off or name not in only)
    draws = None
    if sample:
        samples = [parse_sample(k, v) for k, v in sample.items()]
        if any(s.key == "drive.rpm" for s in samples):
            raise InputError("--sample", "drive.rpm", "the speed is the operating range's (--rpm), not a tolerance")
        plan = make_plan((), samples, runs=runs, seed=seed, yes=yes, file="--sample")
        check_scene(scene, plan)
        draws = Draws(plan.keys, plan.values, tuple(f"{s.key} = {s.text}" for s in samples))
    elif runs is not None:
        raise InputError("--runs", str(runs), "--runs sets the number of draws: give --sample too")

    nominal = Case(scene, speeds, workers=workers, progress=progress)
    measures: dict[str, Measure] = {}
    for spec in RULES:
        if spec.name not in off:
            measures[spec.name] = measure_function(spec)(nominal, settings[spec.name])
    results = {spec.name: _result(spec, settings[spec.name], measures.get(spec.name), spec.name in off)
               for spec in RULES}

    if draws is not None:
        focus = {spec.name: _focus_speeds(spec, measures[spec.name], speeds) for spec in RULES
                 if spec.name in measures and measures[spec.name].applicable}
        sampled = Case(scene, np.array([speeds.min(), speeds.max()]), draws, focus, workers, progress)
        for spec in RULES:
            m = measures.get(spec.name)
            if m is None or not m.applicable:
                continue
            drawn = measure_function(spec)(sampled, settings[spec.name])
            results[spec.name] = _with_probability(results[spec.name], spec, drawn, draws.values.shape[0])
    return CheckReport(
        scene=scene.name, source=scene.source, speeds_rpm=tuple(float(s) for s in speeds), range_from=range_from,
        results=tuple(results[spec.name] for spec in RULES),
        samples=draws.text if draws is not None else (), runs=int(draws.values.shape[0]) if draws is not None else 0,
        seed=seed, seconds=time.perf_counter() - started,
    )


def _focus_speeds(spec, m: Measure, speeds) -> np.ndarray:
    """The speed where the nominal design is worst for the rule (its own speeds' worst)."""
    if m.speeds is None or m.value.size == 0:
        return np.array([float(np.max(speeds))])
    i = worst_index(m.value[0], spec.sense)
    return np.asarray(m.speeds, dtype=float)[[i if i is not None else -1]]


def _result(spec, settings, m: Measure | None, off: bool) -> RuleResult:
    def base(**kw):
        fail = settings.get("fail")
        warn = settings.get("warn")
        s = spec.setting("fail")
        return RuleResult(name=spec.name, title=spec.title, group=spec.group, quantity=spec.quantity, unit=spec.unit,
                          sense=spec.sense, fail=fail, warn=warn, source=s.source if s is not None else "",
                          firmness=s.firmness if s is not None else "", **kw)

    if off:
        return base(verdict="off", value=None, speed_rpm=None, cam_angle_deg=None, reason="switched off")
    if not m.applicable:
        return base(verdict=NOT_APPLICABLE, value=None, speed_rpm=None, cam_angle_deg=None, reason=m.reason)
    value = m.value[0]
    i = worst_index(value, spec.sense)
    if i is None:
        return base(verdict=NOT_APPLICABLE, value=None, speed_rpm=None, cam_angle_deg=None,
                    reason=m.note or "no value at any speed", note=m.note)
    v = verdicts(value, m.fail, m.warn, spec.sense)
    verdict = VERDICTS[int(v[i])] if v[i] >= 0 else NOT_APPLICABLE
    source, firmness = _limit_source(spec, settings, m)
    speed = float(m.speeds[i]) if m.speeds is not None and m.speeds.size > i else None
    angle = float(m.angle[0, i])
    return RuleResult(name=spec.name, title=spec.title, group=spec.group, quantity=spec.quantity, unit=spec.unit,
                      sense=spec.sense, verdict=verdict, value=float(value[i]), speed_rpm=speed,
                      cam_angle_deg=None if math.isnan(angle) else angle, fail=m.fail, warn=m.warn, source=source,
                      firmness=firmness, note=m.note, details=m.details)


def _limit_source(spec, settings, m: Measure) -> tuple[str, str]:
    """The source and firmness of the limit that judged: the user's override, the rule's own choice
    (a material, a wire), or the setting's default source."""
    chosen = m.limit_source
    names = {s.name for s in spec.settings}
    name = chosen if chosen in names else ("warn" if m.fail is None and m.warn is not None else "fail")
    where = settings.origin.get(name)
    if isinstance(where, tuple):
        return f"set in {where[0]} ({where[1]})", "the user's"
    s = spec.setting(name)
    if chosen is not None and chosen not in names:
        return chosen, s.firmness if s is not None else ""
    return (s.source, s.firmness) if s is not None else ("", "")


def _with_probability(result: RuleResult, spec, m: Measure, n: int) -> RuleResult:
    """The result with the shares of the draws that fail and that warn or fail (Wilson's 95 %)."""
    from dataclasses import replace

    if not m.applicable or m.value.size == 0:
        return replace(result, sample_note="tolerances not propagated: " + (m.reason or "no value"))
    v = verdicts(m.value, m.fail, m.warn, spec.sense)  # (N, S')
    v = np.broadcast_to(v, (n, v.shape[1])) if v.shape[0] == 1 else v
    worst = v.max(axis=1)
    judged = worst >= 0
    k = int(judged.sum())
    if k == 0:
        return replace(result, samples=n, sample_note="no draw could be judged")
    fails = int((worst == 2).sum())
    warns = int((worst >= 1).sum())
    return replace(result, samples=k, p_fail=fails / k, p_fail_interval=wilson_interval(fails, k),
                   p_warn=warns / k, p_warn_interval=wilson_interval(warns, k), sample_note=m.note)
