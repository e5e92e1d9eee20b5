"""A design rule: the contract a rule implements (Rule), its table line (RuleSpec), its settings
(Setting), what it measures (Measure), and the verdict and interval arithmetic they share."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Protocol

import numpy as np

VERDICTS = ("pass", "warn", "fail")  # in order of severity
NOT_APPLICABLE = "n/a"


class Rule(Protocol):
    """The base of the design rules: what a rule is to the checks machinery.

    Implementing a rule -- what a rule provides (the checks machinery does the rest: the settings'
    defaults and overrides, the operating range, the tolerance samples, the verdicts, the report):

    1. A module under explorer/checks/rules/ with one function `measure(case, settings) -> Measure`.
       `case` (explorer.checks.case.Case) holds the scene and the runs to judge -- the speeds of the
       operating range, or draws of the tolerances (N) at a few speeds (S) -- and the quantities the
       rules share, computed once and cached: the lift and its derivatives on the grid, the gear's
       contact (GearContact), the rigid contact forces, the elastic figures from the sweep engine.
       `settings` maps each Setting's name to its value (SI; the user's overrides applied).
    2. The Measure: per run, the rule's value at the run's worst cam angle (`value`, shape (N, S')),
       that angle (`angle`, degrees, NaN where none) and the speeds the columns are at (`speeds`,
       rpm; None for a figure that does not depend on the speed: S' = 1), the fail and warn limits it
       judged against (normally `settings["fail"]`, `settings["warn"]`; a rule may choose, such as the
       pressure angle's 30 deg for a straight guide and 35 deg for a lever), and a note (the model,
       the approximations). Not judgeable: `Measure.not_applicable(reason)` (no roller, no spring
       geometry, no [lubricant], ...). Pure: read the case, write nothing; no exceptions but
       InputError for a setting the rule cannot use. With tolerance draws a rule may judge them at a
   few speeds (case.rule_speeds: where the nominal design was worst); unless its worst over those
   speeds is provably its worst over the range it says so (Measure.speed_exact = False) and the
   checks judge a random subset of the draws over the whole range to bound what it misses.
    3. One line of RULES (explorer/checks/registry.py), or one call `register_rule(spec)`: a
       RuleSpec with the rule's name (the key of [checks] and --rules files), the
       "module:function" of its measure (or the function), its title, the quantity
       and the unit it is shown in, its sense ("max": the value must stay at or below the limits, a
       stress; "min": at or above, a margin) and its settings.
    4. Each Setting: a name ("fail" and "warn" are the limits; others are options: a margin, a
       band, a material), its default in SI (None: off unless given), its dimension for parsing
       (explorer.core.units; "number" for a plain number, "choice" with `choices`, "bool"), the unit
       it is shown in, the source of the default (book, paper or standard with page or table; or a
       trade source) and how firm it is. `minimum` bounds a setting from below (a margin cannot be
       negative).

    The verdict of a run: "fail" beyond the fail limit, "warn" beyond the warn limit, else "pass"
    (beyond: above for sense "max", below for "min"; a NaN value is no verdict).
    """

    def __call__(self, case, settings: "Settings") -> "Measure":  # the rule's `measure` function
        ...


@dataclass(frozen=True)
class Setting:
    name: str
    default: Any  # SI float, str or bool; None: no default (off unless given)
    dimension: str  # explorer.core.units dimension, or "number", "choice", "bool"
    unit: str  # display unit ("deg", "m/s", "MPa", "" for plain numbers)
    source: str
    firmness: str
    choices: tuple[str, ...] = ()
    minimum: float | None = None  # SI; a margin, a band: >= 0


@dataclass(frozen=True)
class Plotted:
    """A result column a rule's limits are drawn on in the viewers (explorer.checks.viewer): line
    height = sign * factor * limit (the limit in SI; `factor` to the column's unit), and at -height
    too when `mirrored` (a limit on a magnitude, |alpha|, of a signed column)."""

    column: str
    factor: float = 1.0
    sign: float = 1.0
    mirrored: bool = False


@dataclass(frozen=True)
class RuleSpec:
    """One line of the rule table."""

    name: str
    measure: str | Callable  # "module:function" (a built-in rule), or the function itself (a plug-in)
    title: str
    quantity: str  # what the value is
    unit: str  # display unit of the value (a key of UNITS)
    sense: str  # "max" or "min"
    settings: tuple[Setting, ...]
    group: str = ""  # the family: kinematics, dynamics, contact, tribology, spring, gear
    # the result columns its limits are drawn on, each where a result has it; none: a quantity no
    # column holds (a margin, a ratio, a film parameter) -- its line still moves the gear to its worst
    plotted: tuple[Plotted, ...] = ()
    # what the value is measured as where a reader could take it otherwise (a side of a lever, a
    # sign): shown beside the value in the report's table ("downward, magnitude"; "lifter side")
    qualifier: str = ""

    def setting(self, name: str) -> Setting | None:
        return next((s for s in self.settings if s.name == name), None)


@dataclass(frozen=True)
class Measure:
    value: np.ndarray  # (N, S') per run
    angle: np.ndarray  # (N, S') cam angle, deg
    speeds: np.ndarray | None  # (S',) rpm; None: independent of the speed
    fail: float | None
    warn: float | None
    note: str = ""
    limit_source: str | None = None  # where the limit chosen comes from, when not the setting's own
    details: tuple[str, ...] = ()  # further lines for the report (angles of a reversal, ...)
    # with tolerance draws: whether each draw's worst over the speeds it ran is its worst over the
    # whole range (speed-independent figures; figures extremal at the range's ends, at each angle).
    # False: the rule ran the draws at a few speeds only; the checks then bound what that misses
    # (explorer.checks.run: two phases).
    speed_exact: bool = True
    applicable: bool = True
    reason: str = ""
    # "at least" / "at most": the value is a bound, not the figure itself (a search that ended
    # before it found what it looked for: no separation up to the highest speed searched)
    bound: str = ""
    # which side or sign the value is, where it depends on the scene (a lever's lifter or valve
    # side); "" the rule's own (RuleSpec.qualifier)
    qualifier: str = ""

    @staticmethod
    def not_applicable(reason: str) -> "Measure":
        empty = np.zeros((0, 0))
        return Measure(empty, empty, None, None, None, applicable=False, reason=reason)

    @staticmethod
    def of(value, angle, speeds, settings, **kw) -> "Measure":
        """A Measure with the settings' own fail and warn limits."""
        value = np.atleast_2d(np.asarray(value, dtype=float))
        angle = np.broadcast_to(np.atleast_2d(np.asarray(angle, dtype=float)), value.shape).copy()
        return Measure(value, angle, None if speeds is None else np.asarray(speeds, dtype=float),
                       kw.pop("fail", settings.get("fail")), kw.pop("warn", settings.get("warn")), **kw)


def beyond(value, limit, sense: str) -> np.ndarray:
    """Whether value is beyond the limit (above for "max", below for "min"); False for NaN."""
    v = np.asarray(value, dtype=float)
    if limit is None:
        return np.zeros(v.shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        return (v > limit) if sense == "max" else (v < limit)


def verdicts(value, fail, warn, sense: str) -> np.ndarray:
    """0 pass, 1 warn, 2 fail per element; -1 where the value is NaN (no verdict)."""
    v = np.asarray(value, dtype=float)
    out = np.zeros(v.shape, dtype=np.int8)
    out[beyond(v, warn, sense)] = 1
    out[beyond(v, fail, sense)] = 2
    out[np.isnan(v)] = -1
    return out


def worst_index(value, sense: str) -> int | None:
    """Flat index of the worst value (max or min; of equal ones the last: the highest speed),
    None when all are NaN."""
    v = np.asarray(value, dtype=float).ravel()[::-1]
    if v.size == 0 or np.all(np.isnan(v)):
        return None
    return v.size - 1 - int(np.nanargmax(v) if sense == "max" else np.nanargmin(v))


def wilson_interval(k: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """Wilson's score interval for a binomial proportion k/n (95 % by default): the bounds
    (p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n). Keeps within [0, 1] and stays
    informative at k = 0 or k = n, where the normal (Wald) interval collapses to a point."""
    if n <= 0:
        return math.nan, math.nan
    p = k / n
    z2 = z * z
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = z * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return (0.0 if k == 0 else max(0.0, centre - half)), (1.0 if k == n else min(1.0, centre + half))


class Settings(dict):
    """A rule's resolved settings (name -> SI value) and where each came from (`origin`: name ->
    "default" or (file, dotted key) of the override)."""

    def __init__(self, values: dict, origin: dict):
        super().__init__(values)
        self.origin = dict(origin)
