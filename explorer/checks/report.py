"""What `explorer check` returns: a CheckReport -- one RuleResult per rule -- as a table, JSON and CSV.

Values are SI in the dataclasses (the browser panel reads them) with each rule's display unit
beside them; the table and the CSV show the display units.
"""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import asdict, dataclass

from .registry import SI_UNITS, show


_BOUND_MARKS = {"at least": ">= ", "at most": "<= "}


@dataclass(frozen=True)
class RuleResult:
    name: str
    title: str
    group: str
    quantity: str
    unit: str  # display unit of value, fail, warn
    sense: str  # "max" | "min"
    verdict: str  # "pass" | "warn" | "fail" | "n/a" | "off"
    value: float | None  # SI: the worst over the operating range (nominal design)
    speed_rpm: float | None  # where: the camshaft speed of the worst value (None: any speed)
    cam_angle_deg: float | None  # where: the cam angle (None: not located)
    fail: float | None  # SI
    warn: float | None  # SI
    source: str  # of the limit that judged
    firmness: str
    note: str = ""
    details: tuple[str, ...] = ()
    reason: str = ""  # why n/a or off
    samples: int | None = None  # draws judged (tolerance study)
    p_fail: float | None = None  # share of the draws that fail
    p_fail_interval: tuple[float, float] | None = None  # 95 % Wilson score interval
    p_warn: float | None = None  # share that warn or fail
    p_warn_interval: tuple[float, float] | None = None
    sample_note: str = ""
    # how the probabilities were found: "exact: ..." (every draw's worst over the range) or
    # "two-phase: ..." (explorer.checks.run: draws at the nominal's worst speeds, a subset verified
    # over every speed; the interval then bounds what phase one misses); "" without draws
    sample_method: str = ""
    sample_verified: int | None = None  # two-phase: draws run over every speed of the range
    sample_missed: int | None = None  # two-phase: of those, failing there though not at the nominal's worst speeds
    bound: str = ""  # "at least" / "at most": value is a bound (rule.Measure.bound), shown as >= / <=
    qualifier: str = ""  # the rule's (RuleSpec.qualifier): which side, which sign
    # tolerance study: the draw whose worst value is the worst of all draws (its index in the
    # study's draws, the same with the same command and --seed), that value (SI) and the draw's
    # values of the sampled keys (SI); and every draw known to fail (two-phase: found by either
    # phase -- a draw phase one ran at a few speeds only may fail at others)
    worst_draw: int | None = None
    worst_draw_value: float | None = None
    worst_draw_values: tuple[tuple[str, float], ...] = ()
    failing_draws: tuple[int, ...] = ()

    @property
    def bound_mark(self) -> str:
        """">= " / "<= " before the value where it is a bound (`bound`), else ""."""
        return _BOUND_MARKS.get(self.bound, "")

    def shown(self, value: float | None) -> float | None:
        if value is None or not math.isfinite(value):
            return value
        return show(value, self.unit)


@dataclass(frozen=True)
class CheckReport:
    scene: str
    source: str
    speeds_rpm: tuple[float, ...]  # the operating range's speeds checked
    range_from: str  # "[drive] operating_range" | "--rpm" | "the scene's speed"
    results: tuple[RuleResult, ...]
    samples: tuple[str, ...] = ()  # the tolerance distributions, as given
    runs: int = 0  # draws
    seed: int | None = None
    interval: str = "Wilson score interval, 95 %"
    seconds: float = 0.0

    @property
    def verdict(self) -> str:
        order = {"fail": 3, "warn": 2, "pass": 1}
        worst = max((order.get(r.verdict, 0) for r in self.results), default=0)
        return {3: "fail", 2: "warn", 1: "pass", 0: "n/a"}[worst]

    @property
    def exit_status(self) -> int:
        """0: no rule fails (warnings allowed); 1: a rule fails."""
        return 1 if any(r.verdict == "fail" for r in self.results) else 0

    def result(self, name: str) -> RuleResult:
        return next(r for r in self.results if r.name == name)

    # -- output --------------------------------------------------------------------------------
    def as_dict(self) -> dict:
        def clean(x):
            if isinstance(x, float) and not math.isfinite(x):
                return None if math.isnan(x) else ("inf" if x > 0 else "-inf")
            if isinstance(x, dict):
                return {k: clean(v) for k, v in x.items()}
            if isinstance(x, (list, tuple)):
                return [clean(v) for v in x]
            return x

        out = asdict(self)
        out["speeds_rpm"] = {"low": min(self.speeds_rpm), "high": max(self.speeds_rpm), "count": len(self.speeds_rpm)}
        out["verdict"] = self.verdict
        results = []
        for r, d in zip(self.results, out["results"]):
            # value, fail and warn are SI: their unit beside value (the display unit, `unit`, is
            # that of the *_shown figures)
            ordered = {}
            for key, value in d.items():
                ordered[key] = value
                if key == "value":
                    ordered["si_unit"] = SI_UNITS[r.unit]
            for key in ("value", "fail", "warn"):
                ordered[f"{key}_shown"] = r.shown(getattr(r, key))
            results.append(ordered)
        out["results"] = results
        return clean(out)

    def to_json(self) -> str:
        return json.dumps(self.as_dict(), indent=2) + "\n"

    CSV_COLUMNS = ("rule", "verdict", "value", "unit", "speed_rpm", "cam_angle_deg", "fail", "warn", "source",
                   "firmness", "samples", "p_fail", "p_fail_low", "p_fail_high", "p_warn", "p_warn_low", "p_warn_high",
                   "sample_method", "note", "bound")

    def to_csv(self) -> str:
        buf = io.StringIO()
        buf.write(f"# scene: {self.scene}\n# speeds: {min(self.speeds_rpm):g}..{max(self.speeds_rpm):g} rpm, "
                  f"{len(self.speeds_rpm)} (from {self.range_from})\n")
        if self.samples:
            buf.write(f"# samples: {'; '.join(self.samples)}; {self.runs} draws, seed {self.seed}; {self.interval}\n")
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.CSV_COLUMNS)
        for r in self.results:
            lo, hi = r.p_fail_interval or (None, None)
            wlo, whi = r.p_warn_interval or (None, None)
            w.writerow([r.name, r.verdict, _num(r.shown(r.value)), r.unit, _num(r.speed_rpm), _num(r.cam_angle_deg),
                        _num(r.shown(r.fail)), _num(r.shown(r.warn)), r.source, r.firmness, r.samples or "",
                        _num(r.p_fail), _num(lo), _num(hi), _num(r.p_warn), _num(wlo), _num(whi),
                        r.sample_method, r.note or r.reason, r.bound])
        return buf.getvalue()

    def table_text(self) -> str:
        count = len(self.speeds_rpm)
        lines = [f"{self.scene}: design checks over {min(self.speeds_rpm):g}..{max(self.speeds_rpm):g} rpm "
                 f"({count} speed{'s' if count != 1 else ''}; from {self.range_from})"]
        if self.samples:
            lines.append(f"tolerances: {'; '.join(self.samples)}; {self.runs} draws (seed {self.seed}); probability "
                         f"of failing with its {self.interval}")
        head = ["rule", "verdict", "worst", "where", "limit (fail / warn)"]
        if self.samples:
            head.append("P(fail) [95 %]")
        head.append("source")
        rows = [head]
        for r in self.results:
            if r.verdict in ("n/a", "off"):
                rows.append([r.name, r.verdict, "", "", "", *([""] if self.samples else []), r.reason[:70]])
                continue
            where = []
            if r.speed_rpm is not None and math.isfinite(r.speed_rpm):
                where.append(f"{r.speed_rpm:.6g} rpm")
            if r.cam_angle_deg is not None and math.isfinite(r.cam_angle_deg):
                where.append(f"{r.cam_angle_deg:.2f} deg")
            limit = f"{_fmt(r.shown(r.fail))} / {_fmt(r.shown(r.warn))} {r.unit}".replace("- / - ", "- / -")
            worst = f"{r.bound_mark}{_fmt(r.shown(r.value))} {r.unit}"
            if r.qualifier:
                worst = f"{worst.rstrip()} ({r.qualifier})"
            row = [r.name, r.verdict.upper() if r.verdict == "fail" else r.verdict, worst,
                   ", ".join(where), limit]
            if self.samples:
                mark = "~" if r.sample_method.startswith("two-phase") else ""
                # a judged rule without a probability did not propagate the tolerances (its
                # sample_note says why): the cell says so rather than stay empty
                row.append(("nominal only" if r.verdict in ("pass", "warn", "fail") else "") if r.p_fail is None else
                           f"{mark}{r.p_fail:.3g} [{r.p_fail_interval[0]:.3g}, {r.p_fail_interval[1]:.3g}]")
            row.append(_short(r.source))
            rows.append(row)
        widths = [max(len(str(row[i])) for row in rows) for i in range(len(head))]
        for row in rows:
            lines.append("  ".join(str(c).ljust(widths[i]) for i, c in enumerate(row)).rstrip())
        worst = [r for r in self.results if r.worst_draw is not None and r.verdict in ("pass", "warn", "fail")]
        if worst:
            lines.append("worst draw of each rule (index in the draws; the sampled keys' values):")
            for r in worst:
                keys = ", ".join(f"{key} = {draw_text(key, value)}" for key, value in r.worst_draw_values)
                lines.append(f"  {r.name}: draw {r.worst_draw}, {_fmt(r.shown(r.worst_draw_value))} {r.unit}".rstrip()
                             + f" ({keys}); {len(r.failing_draws)} draw(s) known to fail")
        if any(r.sample_method.startswith("two-phase") for r in self.results):
            lines.append("~ two-phase estimate: every draw judged at the nominal design's worst speeds, a subset over "
                         "every speed of the range to bound what that misses (sample_method in the JSON)")
        lines.append(f"verdict: {self.verdict.upper()} ({sum(r.verdict == 'fail' for r in self.results)} fail, "
                     f"{sum(r.verdict == 'warn' for r in self.results)} warn, "
                     f"{sum(r.verdict == 'pass' for r in self.results)} pass, "
                     f"{sum(r.verdict == 'n/a' for r in self.results)} n/a); {self.seconds:.2f} s")
        return "\n".join(lines) + "\n"


# a sampled key's value as an engineer reads it (the sweep keys' dimensions: explorer.studies.sweep_spec)
DRAW_UNITS = {"length": ("mm", 1e3), "stiffness": ("N/mm", 1e-3), "force": ("N", 1.0), "mass": ("g", 1e3),
              "damping": ("N*s/m", 1.0), "dimensionless": ("", 1.0), "speed": ("rpm", 30.0 / math.pi)}


def draw_text(key: str, value: float) -> str:
    """A sampled key's SI value in its display unit, e.g. "0.2713 mm"."""
    from ..studies.sweep_spec import SWEEP_KEYS

    unit, factor = DRAW_UNITS.get(SWEEP_KEYS[key].dimension, ("", 1.0)) if key in SWEEP_KEYS else ("", 1.0)
    return f"{value * factor:.6g} {unit}".rstrip()


def _num(x):
    if x is None:
        return ""
    if isinstance(x, float) and not math.isfinite(x):
        return "" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return f"{x:.10g}" if isinstance(x, float) else x


def _fmt(x) -> str:
    if x is None:
        return "-"
    if not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    return f"{x:.4g}"


def _short(text: str, n: int = 60) -> str:
    return text if len(text) <= n else text[: n - 3] + "..."
