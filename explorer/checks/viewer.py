"""The checks as the viewers read them (explorer.view.verdicts, issue #26.3): `evaluate(scene)` is
the CheckRunner `explorer serve` hands the browser and `explorer record --checks` the
recordings -- `check(scene)` over the scene's operating range, as `explorer check SCENE` does,
each rule's result a CheckLine with its limits on the plotted columns they concern (its table
line's `plotted`: a rule declares them where it is registered).
"""

from __future__ import annotations

import math
import time

from ..view.verdicts import CheckLine, CheckSummary, Threshold
from .registry import rule, rule_names
from .report import CheckReport, RuleResult
from .run import check


def _plotted(name: str):
    """The columns rule `name` draws its limits on (its table line's `plotted`; none for a rule
    no longer in the table)."""
    return rule(name).plotted if name in rule_names() else ()


def thresholds(result: RuleResult) -> tuple[Threshold, ...]:
    out = []
    for plotted in _plotted(result.name):
        for limit in ("fail", "warn"):
            value = getattr(result, limit)
            if value is None or not math.isfinite(value):
                continue
            height = plotted.sign * plotted.factor * value
            values = (-height, height) if plotted.mirrored else (height,)
            out.append(Threshold(plotted.column, values, limit))
    return tuple(out)


def line(result: RuleResult) -> CheckLine:
    shown = result.shown(result.value)
    text = "" if shown is None else (f"{result.bound_mark}{shown:.4g} {result.unit}".strip() if math.isfinite(shown)
                                     else str(shown))
    if text and result.qualifier:  # which side or sign, as the report's table
        text += f" ({result.qualifier})"
    limits = [f"{name} {result.shown(v):.4g}" for name, v in (("fail", result.fail), ("warn", result.warn))
              if v is not None and math.isfinite(v)]
    return CheckLine(
        rule=result.name, title=result.title, verdict=result.verdict, value=result.value, shown=text,
        speed_rpm=result.speed_rpm, cam_angle_deg=result.cam_angle_deg,
        limit=(" / ".join(limits) + f" {result.unit}").strip() if limits else "",
        source=result.source, reason=result.reason, thresholds=thresholds(result))


def summary(report: CheckReport, seconds: float | None = None) -> CheckSummary:
    low, high, count = min(report.speeds_rpm), max(report.speeds_rpm), len(report.speeds_rpm)
    span = f"{low:g} rpm" if count == 1 else f"{low:g}..{high:g} rpm, {count} speeds"
    return CheckSummary(scene=report.scene, range_text=f"{span} (from {report.range_from})",
                        lines=tuple(line(r) for r in report.results),
                        seconds=report.seconds if seconds is None else seconds)


def evaluate(scene) -> CheckSummary:
    """The CheckRunner: every rule over the scene's operating range, one worker process (the
    browser's compute child is one process already; the sweep engine runs in it)."""
    started = time.perf_counter()
    report = check(scene, workers=1)
    return summary(report, time.perf_counter() - started)
