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
The checks come as an explorer.view.verdicts.CheckSummary (the checks layer builds it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

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


def limit_series(result, checks: CheckSummary | None) -> list[LimitSeries]:
    """The limits of `checks` on the series the recording of `result` has."""
    from .recording import series_layout

    if checks is None:
        return []
    out = []
    for series in series_layout(result.columns):
        for line, threshold in checks.thresholds(series.column):
            values = threshold.values
            for k, value in enumerate(values):
                suffix = f"_{k + 1}" if len(values) > 1 else ""
                shown = value * series.scale
                out.append(LimitSeries(f"{series.path}/limit_{line.rule}_{threshold.limit}{suffix}",
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


def check_paths(result, checks: CheckSummary | None) -> list[str]:
    """The entity paths the checks add (for the layout)."""
    if checks is None:
        return []
    return [s.path for s in limit_series(result, checks)] + [CHECKS_PATH]


def log_checks(rec, rr, result, checks: CheckSummary | None, index: Mapping[str, np.ndarray]) -> None:
    """Log the markers and the limit lines of `checks` into the recording `rec` of `result`
    (`index`: its timelines, recording.step_indexes)."""
    from .recording import TIMELINE_ANGLE, TIMELINE_STEP, TIMELINE_TIME, angle_sequence, duration_ns

    if checks is None:
        return
    steps = index[TIMELINE_STEP]
    ends = np.array([0, steps.size - 1])
    ends_index = [rr.TimeColumn(TIMELINE_TIME, duration=duration_ns(index[TIMELINE_TIME][ends])),
                  rr.TimeColumn(TIMELINE_STEP, sequence=steps[ends]),
                  rr.TimeColumn(TIMELINE_ANGLE, sequence=index[TIMELINE_ANGLE][ends])]
    for series in limit_series(result, checks):
        rec.log(series.path, rr.SeriesLines(names=series.name, colors=[series.rgb], widths=1.0), static=True)
        rec.send_columns(series.path, indexes=ends_index,
                         columns=rr.Scalars.columns(scalars=np.full(2, series.value, dtype=np.float64)))
    marks = markers(checks)
    if not marks:
        return
    angle = np.asarray(result.columns["cam_angle_deg"], dtype=float)
    time_s = np.asarray(result.columns["time_s"], dtype=float)
    n = steps.size
    at = np.array([m.angle_deg for m in marks])
    step = np.array([min(n - 1, max(0, int(math.floor(a / 360.0 * n + 1e-9)))) for a in at], dtype=np.int64)
    rec.send_columns(
        CHECKS_PATH,
        indexes=[rr.TimeColumn(TIMELINE_TIME, duration=duration_ns(np.interp(at, angle, time_s))),
                 rr.TimeColumn(TIMELINE_STEP, sequence=step),
                 rr.TimeColumn(TIMELINE_ANGLE, sequence=angle_sequence(at))],
        columns=rr.TextLog.columns(text=[m.text for m in marks], level=[m.level for m in marks]),
    )
