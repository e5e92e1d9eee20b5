"""The design checks in a recording (issue #26.3; `explorer record --checks`): each violation a
marker on the timelines, each limit a line beside the quantity it concerns.

- /events/checks  TextLog entries, one per rule that warns (level WARN) or fails (level ERROR), at
                  the cam angle of its worst value on every timeline (the step at or before it;
                  on `time`, the instant of that angle in this run) -- in the event log beside the
                  run's own events. The text names the rule, its worst with the speed and the
                  angle where it is, the limits and their source. A rule whose worst has no cam
                  angle (a figure of the whole revolution) is marked at 0.
- <series>/limit_<rule>_<fail|warn>[_<k>]  a constant series (two rows: the revolution's first
                  and last step) at the limit's height, in the series' display unit, as a child of
                  the series it concerns (/valve/velocity, /angles/pressure, /stress/hertz):
                  drawn in the same plot, red for fail, amber for warn.
The checks come as an explorer.view.verdicts.CheckSummary (the checks layer builds it). What to
log is worked out here; explorer.view.rerun.recording logs it (log_result's `checks`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

from ..verdicts import LEVELS, RGB, CheckSummary

CHECKS_PATH = "/events/checks"


@dataclass(frozen=True)
class LimitSeries:
    path: str
    name: str
    value: float  # in the series' display unit
    rgb: tuple[int, int, int]


@dataclass(frozen=True)
class Marker:
    text: str
    level: str  # "WARN" | "ERROR"
    angle_deg: float


def limit_series(series: Iterable, checks: CheckSummary | None) -> list[LimitSeries]:
    """The limits of `checks` on the recording's series (recording.Series: column, path, scale)."""
    if checks is None:
        return []
    out = []
    for s in series:
        for line, threshold in checks.thresholds(s.column):
            values = threshold.values
            for k, value in enumerate(values):
                suffix = f"_{k + 1}" if len(values) > 1 else ""
                shown = value * s.scale
                out.append(LimitSeries(f"{s.path}/limit_{line.rule}_{threshold.limit}{suffix}",
                                       f"{line.title}: {threshold.limit} limit {shown:.4g}", shown,
                                       RGB[threshold.limit]))
    return out


def markers(checks: CheckSummary | None) -> list[Marker]:
    """One marker per rule that warns or fails, at the cam angle of its worst (0 when none)."""
    if checks is None:
        return []
    out = []
    for line in checks.lines:
        if line.verdict not in LEVELS:
            continue
        _, angle = line.target()
        text = f"check {line.verdict.upper()}: {line.title} ({line.rule}) {line.shown}"
        text += f" at {line.where()}" if line.where() else " (no cam angle: the whole revolution)"
        if line.limit:
            text += f"; limits {line.limit}"
        if line.source:
            text += f"; source: {line.source}"
        out.append(Marker(text, LEVELS[line.verdict], 0.0 if angle is None else angle))
    return out


def check_paths(series: Iterable, checks: CheckSummary | None) -> list[str]:
    """The entity paths the checks add (for the layout)."""
    if checks is None:
        return []
    return [s.path for s in limit_series(series, checks)] + [CHECKS_PATH]
