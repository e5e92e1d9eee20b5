"""Checking a design: every rule of the table over the scene's operating range, and over its
tolerances when draws are asked for.

1. The operating range: `rpm` ("START:STOP:COUNT" or a list, the sweep's grammar), else the
   scene's [drive] operating_range (DEFAULT_SPEEDS speeds), else the scene's own speed.
2. The settings: the table's defaults, the scene's [checks], then a --rules file.
3. The nominal design: each rule's measure over the range; the worst value, where (speed and cam
   angle) and the verdict.
4. Tolerances (`sample`, `runs`, `seed`: the sweep's --sample grammar): N draws of the varied keys.
   Phase one: each rule judges every draw at the speeds where the nominal design was worst for it
   and at the range's ends (the elastic rules at the worst speed only; the float margin at the
   first separation and the highest speed plus the margin) -- the worst over those speeds per
   draw. That is the draw's worst over the whole range for the rules whose measure says so
   (Measure.speed_exact: speed-independent figures, figures extremal at the range's ends); the
   share of draws that fail (and that warn or fail) then has Wilson's 95 % score interval.
   Phase two, for the other rules: a draw that fails at some of its speeds fails (the whole range
   holds them), but one that passes there may fail at a speed it did not run. M draws (all of
   them when N x speeds <= CHECK_RUNS, else a seeded uniform subset of CHECK_RUNS / speeds) run
   over every speed of the range (and the rule's own speeds); among those that did not fail in
   phase one, the share q that fails there estimates what phase one misses:
       P(fail) = P1 + (1 - P1) q,
   its interval [L1 + (1 - L1) L2, U1 + (1 - U1) U2] from the two Wilson intervals at 97.5 %
   (together at least 95 %: the union bound); the same for warn-or-fail. The result says which
   (RuleResult.sample_method) and how many draws were verified and missed. `verify` sets M.
"""

from __future__ import annotations

import math
import time
import warnings
from typing import Callable

import numpy as np

from ..core.errors import InputError
from ..scene.scene import load_scene
from ..studies.sweep_spec import check_scene, make_plan, parse_axis, parse_sample
from .case import RPM, Case, Draws
from .registry import measure_function, rules as all_rules
from .report import CheckReport, RuleResult
from .rule import NOT_APPLICABLE, VERDICTS, Measure, verdicts, wilson_interval, worst_index
from .settings import load_rules_file, resolve

DEFAULT_SPEEDS = 200
# Phase two's runs (verified draws x speeds): at ~0.25 ms a compiled elastic run, ~2.5 s on one
# core; 50 draws over 200 speeds. Below it every draw runs over the whole range.
CHECK_RUNS = 10_000
VERIFY_MIN = 10  # verified draws at least, whatever the range (a gear's run costs ~100 x a compiled one)
Z_975 = 2.241402727604947  # two-sided 97.5 % normal quantile: two such intervals hold together at >= 95 %


def operating_speeds(scene, rpm=None) -> tuple[np.ndarray, str]:
    """(speeds in rev/min, where they came from)."""
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
          only=None, verify: int | None = None) -> CheckReport:
    """Check a design (a Scene or a scene file's path); see the module docstring. `sample`:
    {key: "normal(MEAN, SD)" | "uniform(LOW, HIGH)"}; `rules`: a --rules file's path; `only`:
    the names of the rules to judge (the others are reported "off"); `verify`: how many draws
    phase two runs over every speed of the range (default: as many as CHECK_RUNS runs allow, at
    least VERIFY_MIN; all of them: exact). Bad input raises InputError before any work."""
    started = time.perf_counter()
    if not hasattr(scene, "effects"):
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
    if verify is not None:
        if draws is None:
            raise InputError("--verify", str(verify), "--verify sets how many draws run over the whole range: give "
                             "--sample too")
        if isinstance(verify, bool) or not isinstance(verify, (int, np.integer)) or verify < 1:
            raise InputError("--verify", str(verify), "a whole number of draws, at least 1")

    specs = all_rules()  # the table as it is now (a plug-in may have registered a rule)
    speeds_from = (("--rpm", "drive.rpm") if range_from == "--rpm" else
                   (str(scene.source), "drive.operating_range" if scene.drive.operating_range is not None else "drive.rpm"))
    nominal = Case(scene, speeds, workers=workers, progress=progress, speeds_from=speeds_from)
    measures: dict[str, Measure] = {}
    for spec in specs:
        if spec.name not in off:
            measures[spec.name] = measure_function(spec)(nominal, settings[spec.name])
    results = {spec.name: _result(spec, settings[spec.name], measures.get(spec.name), spec.name in off)
               for spec in specs}

    if draws is not None:
        focus = {spec.name: _focus_speeds(spec, measures[spec.name], speeds) for spec in specs
                 if spec.name in measures and measures[spec.name].applicable}
        ends = np.array([speeds.min(), speeds.max()])
        sampled = Case(scene, ends, draws, focus, workers, progress, speeds_from=speeds_from)
        drawn = {spec.name: measure_function(spec)(sampled, settings[spec.name]) for spec in specs
                 if spec.name in measures and measures[spec.name].applicable}
        # one speed: every draw ran at it (and the float margin above it as every draw would)
        inexact = [spec for spec in specs if spec.name in drawn and drawn[spec.name].applicable
                   and not drawn[spec.name].speed_exact] if speeds.size > 1 else []
        verified = _whole_range(scene, speeds, ends, draws, focus, inexact, settings, workers, progress, seed, verify)
        for spec in specs:
            if spec.name in drawn:
                results[spec.name] = _with_probability(results[spec.name], spec, drawn[spec.name],
                                                       draws.values.shape[0], verified.get(spec.name),
                                                       one_speed=speeds.size == 1)
                results[spec.name] = _with_worst_draw(results[spec.name], spec, drawn[spec.name], draws,
                                                      verified.get(spec.name))
    return CheckReport(
        scene=scene.name, source=scene.source, speeds_rpm=tuple(float(s) for s in speeds), range_from=range_from,
        results=tuple(results[spec.name] for spec in specs),
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
                          firmness=s.firmness if s is not None else "", qualifier=spec.qualifier, **kw)

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
                      firmness=firmness, note=m.note, details=m.details, bound=m.bound,
                      qualifier=m.qualifier or spec.qualifier)


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


def _whole_range(scene, speeds, ends, draws: Draws, focus: dict, specs, settings, workers, progress,
                 seed, verify: int | None = None) -> dict:
    """Phase two (module docstring): rule name -> (indices of the verified draws, their Measure over
    every speed of the range and the rule's own speeds). One Case for all the rules: the elastic
    rules share its runs."""
    if not specs:
        return {}
    n = draws.values.shape[0]
    count = min(n, int(verify) if verify is not None else max(VERIFY_MIN, CHECK_RUNS // max(1, speeds.size + 2)))
    if count >= n:
        idx = np.arange(n)
    else:  # seeded from the study's seed: the same draws are verified again in a repeated check
        rng = np.random.default_rng(None if seed is None else [int(seed), 26])
        idx = np.sort(rng.choice(n, size=count, replace=False))
    subset = Draws(draws.keys, draws.values[idx], draws.text)
    full = {spec.name: np.union1d(speeds, np.asarray(focus.get(spec.name, ()), dtype=float)) for spec in specs}
    case = Case(scene, ends, subset, full, workers, progress)
    return {spec.name: (idx, measure_function(spec)(case, settings[spec.name])) for spec in specs}


def _worst_verdicts(spec, m: Measure, n: int) -> np.ndarray:
    """Per draw the worst verdict over the measure's speeds: 0 pass, 1 warn, 2 fail, -1 none."""
    v = verdicts(m.value, m.fail, m.warn, spec.sense)  # (N, S')
    v = np.broadcast_to(v, (n, v.shape[1])) if v.shape[0] == 1 else v
    return v.max(axis=1)


def _with_probability(result: RuleResult, spec, m: Measure, n: int, verified=None, one_speed=False) -> RuleResult:
    """The result with the shares of the draws that fail and that warn or fail: Wilson's 95 % when
    every draw's worst is exact (phase one exact, or every draw verified), else phase two's
    estimate (module docstring)."""
    from dataclasses import replace

    if not m.applicable or m.value.size == 0:
        return replace(result, sample_note="tolerances not propagated: " + (m.reason or "no value"))
    worst = _worst_verdicts(spec, m, n)
    method = ("exact: every draw's worst over the range" if m.speed_exact
              else "exact: one speed, every draw at it" if one_speed else "")
    if verified is not None:
        idx, m2 = verified
        worst2 = _worst_verdicts(spec, m2, idx.size) if m2.applicable and m2.value.size else np.full(idx.size, -1)
        if idx.size == n:  # every draw ran over the whole range
            worst, method = worst2, "exact: every draw over every speed of the range"
            verified = None
    judged = worst >= 0
    k = int(judged.sum())
    if k == 0:
        return replace(result, samples=n, sample_note="no draw could be judged", sample_method=method)
    fails = int((worst == 2).sum())
    warns = int((worst >= 1).sum())
    if verified is None:
        return replace(result, samples=k, p_fail=fails / k, p_fail_interval=wilson_interval(fails, k),
                       p_warn=warns / k, p_warn_interval=wilson_interval(warns, k), sample_note=m.note,
                       sample_method=method)
    # phase two: among the verified draws that phase one judged and did not fail (did not warn),
    # the share that fails (warns or fails) over the whole range
    sub = worst[idx]
    p_fail, i_fail, miss_fail, base_fail = _two_phase(fails, k, sub, worst2, lambda v: v == 2)
    p_warn, i_warn, _, _ = _two_phase(warns, k, sub, worst2, lambda v: v >= 1)
    method = (f"two-phase: {n} draws at the nominal's worst speeds ({fails} fail), {idx.size} of them over every "
              f"speed of the range: {miss_fail} of the {base_fail} that did not fail there fail")
    return replace(result, samples=k, p_fail=p_fail, p_fail_interval=i_fail, p_warn=p_warn, p_warn_interval=i_warn,
                   sample_note=m.note, sample_method=method, sample_verified=int(idx.size),
                   sample_missed=miss_fail)


def _draw_worst(spec, m: Measure, n: int) -> np.ndarray:
    """Per draw its worst value over the measure's speeds (NaN: none)."""
    v = np.asarray(m.value, dtype=float)
    v = np.broadcast_to(v, (n, v.shape[1])) if v.shape[0] == 1 else v
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a draw without any value: NaN, no verdict
        return np.nanmax(v, axis=1) if spec.sense == "max" else np.nanmin(v, axis=1)


def _with_worst_draw(result: RuleResult, spec, m: Measure, draws: Draws, verified=None) -> RuleResult:
    """The result with the tolerance study's worst draw (its index, value and sampled keys' values)
    and every draw known to fail: phase one's worst per draw, made worse where phase two ran the
    draw over the whole range. A measure that does not vary with the draws has no worst draw."""
    from dataclasses import replace

    n = draws.values.shape[0]
    if not m.applicable or m.value.size == 0 or m.value.shape[0] != n:
        return result
    per_draw = _draw_worst(spec, m, n).copy()
    fails = _worst_verdicts(spec, m, n) == 2
    if verified is not None:
        idx, m2 = verified
        if m2.applicable and m2.value.size and m2.value.shape[0] == idx.size:
            whole = _draw_worst(spec, m2, idx.size)
            pick = np.fmax if spec.sense == "max" else np.fmin
            per_draw[idx] = pick(per_draw[idx], whole)
            fails[idx] |= _worst_verdicts(spec, m2, idx.size) == 2
    i = worst_index(per_draw, spec.sense)
    if i is None or np.nanmax(per_draw) == np.nanmin(per_draw):  # no draw differs: none is the worst
        return result
    return replace(result, worst_draw=int(i), worst_draw_value=float(per_draw[i]),
                   worst_draw_values=tuple((key, float(v)) for key, v in zip(draws.keys, draws.values[i])),
                   failing_draws=tuple(int(k) for k in np.nonzero(fails)[0]))


def _two_phase(hits: int, k: int, sub, worst2, bad) -> tuple[float, tuple[float, float], int, int]:
    """(estimate, interval, missed, base) of P(bad) = P1 + (1 - P1) q (module docstring): P1 = hits/k
    from phase one, q the share of the verified draws not bad in phase one that are bad over the
    whole range (missed of base)."""
    base_mask = (sub >= 0) & ~bad(sub) & (worst2 >= 0)
    base = int(base_mask.sum())
    missed = int((base_mask & bad(worst2)).sum())
    p1 = hits / k
    q = missed / base if base else 0.0
    lo1, hi1 = wilson_interval(hits, k, Z_975)
    lo2, hi2 = wilson_interval(missed, base, Z_975) if base else (0.0, 0.0)
    return p1 + (1.0 - p1) * q, (lo1 + (1.0 - lo1) * lo2, hi1 + (1.0 - hi1) * hi2), missed, base
