"""What the viewers (the browser's Checks panel, rerun recordings) are handed about a design's
checks (issue #26.3), without importing the checks: the checks layer sits above view
(tests/test_layers.py), so `explorer serve` and `explorer record` give the viewer a CheckRunner
built on explorer.checks (explorer.checks.viewer.evaluate) and the viewer only reads these
frozen dataclasses.

- CheckLine: one rule's verdict, its worst value (SI, with the text shown), where it is (camshaft
  speed in rpm, cam angle in degrees; either None when the rule does not locate it) and the
  limits as lines on the plotted columns they concern (Threshold).
- CheckSummary: every rule's line for one scene, the operating range judged, how long it took.
- CheckRunner: scene -> CheckSummary. It must pickle by reference (a module-level function): the
  browser runs it in its compute child, off the server's threads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

VERDICTS = ("pass", "warn", "fail")
# traffic lights, as viser's (Mantine's) button colours; a rule that cannot judge or is off: grey
COLOURS = {"pass": "green", "warn": "yellow", "fail": "red"}
NO_VERDICT_COLOUR = "gray"
# the same as RGB for rerun and for the plots' threshold lines
RGB = {"pass": (39, 174, 96), "warn": (214, 137, 16), "fail": (192, 57, 43)}
# a recording's marker level per verdict (rerun's TextLog levels)
LEVELS = {"warn": "WARN", "fail": "ERROR"}


@dataclass(frozen=True)
class Threshold:
    """A limit drawn as a horizontal line on the plot of a result column.

    `column` is the result's column the rule judges (valve_velocity_m_s, pressure_angle_deg,
    hertz_stress_Pa, ...); `values` the line's heights in that column's own unit (SI, degrees for
    a *_deg column) and sign -- a closing velocity limit of 1 m/s is the line at -1 m/s of the
    valve's velocity, an |angle| limit two lines at -a and +a. `limit` says which: "fail" or
    "warn"."""

    column: str
    values: tuple[float, ...]
    limit: str  # "fail" | "warn"

    def __post_init__(self):
        if self.limit not in ("fail", "warn"):
            raise ValueError(f"limit must be 'fail' or 'warn', not {self.limit!r}")


@dataclass(frozen=True)
class CheckLine:
    rule: str  # the rule's name ([checks] key)
    title: str
    verdict: str  # "pass" | "warn" | "fail" | "n/a" | "off"
    value: float | None  # SI, the worst over the operating range
    shown: str  # the worst as shown, with its unit ("6.214 m/s"); "" without one
    speed_rpm: float | None  # where: the camshaft speed of the worst (None: any speed)
    cam_angle_deg: float | None  # where: the cam angle of the worst (None: not located)
    limit: str = ""  # the limits as shown ("fail 1 / warn 0.76 m/s")
    source: str = ""  # of the limit that judged
    reason: str = ""  # why n/a or off
    thresholds: tuple[Threshold, ...] = ()

    @property
    def colour(self) -> str:
        return COLOURS.get(self.verdict, NO_VERDICT_COLOUR)

    @property
    def judged(self) -> bool:
        return self.verdict in VERDICTS

    def target(self) -> tuple[float | None, float | None]:
        """(speed rpm, cam angle deg) a click moves the gear and the plots to: the worst's; None
        for what the rule does not locate (a speed-independent figure keeps the speed shown)."""
        if not self.judged:
            return None, None
        speed = self.speed_rpm if _finite(self.speed_rpm) and self.speed_rpm > 0.0 else None
        angle = self.cam_angle_deg % 360.0 if _finite(self.cam_angle_deg) else None
        return speed, angle

    def where(self) -> str:
        speed, angle = self.target()
        parts = ([f"{speed:.6g} rpm"] if speed is not None else []) + ([f"{angle:.2f}°"] if angle is not None else [])
        return ", ".join(parts)

    def label(self) -> str:
        """The line in one string: verdict, rule, worst and where (the browser's panel shows it in
        two rows, explorer.view.browser.checks_panel.button_text and detail_text)."""
        if not self.judged:
            return f"{self.verdict} · {self.title}"
        where = self.where()
        return f"{self.verdict.upper()} · {self.title}: {self.shown}" + (f" at {where}" if where else "")


@dataclass(frozen=True)
class CheckSummary:
    scene: str
    range_text: str  # the operating range judged ("800..6500 rpm, 200 speeds (from --rpm)")
    lines: tuple[CheckLine, ...]
    seconds: float = 0.0  # the checks' wall time where they ran

    @property
    def verdict(self) -> str:
        worst = max((VERDICTS.index(line.verdict) for line in self.lines if line.judged), default=-1)
        return VERDICTS[worst] if worst >= 0 else "n/a"

    def line(self, rule: str) -> CheckLine | None:
        return next((line for line in self.lines if line.rule == rule), None)

    def counts(self) -> dict[str, int]:
        return {v: sum(line.verdict == v for line in self.lines) for v in (*VERDICTS, "n/a")}

    def thresholds(self, column: str) -> list[tuple[CheckLine, Threshold]]:
        """The limits drawn on `column`'s plot, with the rule of each."""
        return [(line, t) for line in self.lines if line.judged for t in line.thresholds if t.column == column]


class CheckRunner(Protocol):
    """Checks a scene: every design rule over its operating range (what `explorer check` does).
    Pure, picklable by reference; raises explorer.core.errors.InputError for a scene whose
    [checks] cannot be used."""

    def __call__(self, scene) -> CheckSummary:
        ...


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)
