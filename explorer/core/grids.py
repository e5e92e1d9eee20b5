"""The one grammar of value ranges, for every command and the Python API.

    START:STOP:COUNT        COUNT values from START to STOP, both ends included (COUNT >= 2)
    START:STOP:COUNT:log    the same, spaced geometrically (START > 0); ":lin" is the default
    V1,V2,...               the values as given
    START:STOP              an interval (where a command takes one: `explorer design --band`)

Each value is written as in a scene file ("0.3 mm", "3000 rpm", bare numbers in the key's own
unit); a unit written at one end of a range applies to both ("0.1:0.5 mm:5"). A range runs
upwards: STOP below START is refused (write the values as a list for another order), and so is
START equal to STOP in a counted range. COUNT is a plain whole number, at most the command's
`max_points`, and so is the length of a list.

`read` splits the text and checks its shape (no value is converted); `values` converts the
values with the command's own converter (units, the key's range) and builds the grid; `texts`
gives the values as strings in the unit they were written in, for commands that hand each value
to the scene loader (`explorer record --sweep`). Every failure is one InputError naming the
option (`file`) and the key.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .errors import InputError, echo

FORMS = "START:STOP:COUNT[:log] or V1,V2,..."
_NUMBER = re.compile(r"^\s*[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_COUNT = re.compile(r"^[0-9]{1,12}$")
# "inf", "-Infinity", "nan" as an end: no number pattern matches them, so without this check the
# word was read as the other end's unit ("1000:inf:3" -> "unknown unit 'inf'")
_NON_FINITE = re.compile(r"^\s*[+-]?(?:inf(?:inity)?|nan)(?![a-z])", re.IGNORECASE)


@dataclass(frozen=True)
class Span:
    """START:STOP[:COUNT[:log]] as written (count None: an interval)."""

    start: str
    stop: str
    count: int | None
    log: bool = False


@dataclass(frozen=True)
class Listed:
    """V1,V2,... as written."""

    values: tuple[str, ...]


def _count(text: str, *, file: str, key: str, max_points: int) -> int:
    text = text.strip()
    if not _COUNT.match(text):
        if re.fullmatch(r"[0-9]+", text):  # a whole number, just far too many
            raise InputError(file, key, f"at most {max_points} points, got a number of {len(text)} digits")
        raise InputError(file, key, f"the number of points must be a plain whole number, got {echo(text)}")
    count = int(text)
    if count == 0:
        raise InputError(file, key, "zero steps: the number of points must be at least 2, got 0")
    if count == 1:
        raise InputError(file, key, "a range of 1 point: give at least 2 points, or the one value alone")
    if count > max_points:
        raise InputError(file, key, f"at most {max_points} points, got {count}")
    return count


def _finite_ends(parts: list[str], *, file: str, key: str) -> None:
    for end in parts[:2]:
        if _NON_FINITE.match(end):
            raise InputError(file, key, f"the ends of a range must be finite numbers, got {echo(end)}")


def read(text, *, file: str, key: str, max_points: int, interval: bool = False, lists: bool = True) -> Span | Listed:
    """The shape of a range (module docstring). `interval`: the form START:STOP instead of a
    counted range; `lists`: whether V1,V2,... is accepted."""
    text = str(text).strip()
    forms = "START:STOP" if interval else (FORMS if lists else "START:STOP:COUNT[:log]")
    if not text:
        raise InputError(file, key, f"empty range; write {forms}")
    if ":" in text:
        parts = [p.strip() for p in text.split(":", 4)]
        if interval:
            if len(parts) != 2 or not all(parts):
                raise InputError(file, key, f"cannot read {echo(text)}: write {forms}")
            _finite_ends(parts, file=file, key=key)
            return Span(parts[0], parts[1], None)
        log = False
        if len(parts) == 4 and parts[3].lower() in ("log", "lin"):
            log = parts.pop().lower() == "log"
        if len(parts) != 3 or not all(parts):
            raise InputError(file, key, f"cannot read {echo(text)}: write {forms}")
        _finite_ends(parts, file=file, key=key)
        return Span(parts[0], parts[1], _count(parts[2], file=file, key=key, max_points=max_points), log)
    if not lists or interval:
        raise InputError(file, key, f"cannot read {echo(text)}: write {forms}")
    if text.count(",") >= max_points:
        raise InputError(file, key, f"at most {max_points} values, got {text.count(',') + 1}")
    values = tuple(v.strip() for v in text.split(","))
    if any(not v for v in values):
        raise InputError(file, key, f"empty value in {echo(text)}; write V1,V2,...")
    return Listed(values)


def share_unit(a: str, b: str) -> tuple[str, str]:
    """'0.1' and '0.5 mm': a unit written at one end applies to the other ('0.1:0.5 mm:5')."""
    unit_a, unit_b = _unit(a), _unit(b)
    if unit_b and not unit_a:
        a = f"{a.strip()} {unit_b}"
    elif unit_a and not unit_b:
        b = f"{b.strip()} {unit_a}"
    return a, b


def _unit(text: str) -> str:
    m = _NUMBER.match(text)
    return (text[m.end():] if m else text).strip()


def values(spec: Span | Listed, convert: Callable[[str], float], *, file: str, key: str,
           log: bool = False) -> np.ndarray:
    """The range's values as floats: `convert` reads one value (units, the key's range: it raises
    InputError itself); a counted range is linear, or geometric (":log" or `log`), with its ends
    exactly as given; an interval is its two ends."""
    if isinstance(spec, Listed):
        return np.array([convert(v) for v in spec.values], dtype=float)
    if log and not spec.log:
        spec = Span(spec.start, spec.stop, spec.count, True)
    a_text, b_text = share_unit(spec.start, spec.stop)
    return _grid(float(convert(a_text)), float(convert(b_text)), spec, file=file, key=key)


def _grid(start: float, stop: float, spec: Span, *, file: str, key: str) -> np.ndarray:
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise InputError(file, key, "the ends of a range must be finite")
    if stop < start:
        hint = "a range runs upwards" + ("" if spec.count is None else "; list the values V1,V2,... for another order")
        raise InputError(file, key, f"backwards range: stop {stop:.6g} is below start {start:.6g} ({hint})")
    if spec.count is None:
        return np.array([start, stop])
    if start == stop:
        raise InputError(file, key, f"empty range: start equals stop ({start:.6g})")
    if spec.log:
        if start <= 0.0:
            raise InputError(file, key, f"a log range needs a start > 0, got {start:.6g}")
        grid = np.geomspace(start, stop, spec.count)
    else:
        grid = np.linspace(start, stop, spec.count)
    grid[0], grid[-1] = start, stop  # the ends exactly as given
    return grid


def texts(spec: Span | Listed, *, file: str, key: str) -> list[str]:
    """The range's values as strings in the unit they were written in (for the scene loader, which
    checks each): a list as given; a counted range from its ends' numbers, with their unit."""
    if isinstance(spec, Listed):
        return list(spec.values)
    a_text, b_text = share_unit(spec.start, spec.stop)
    unit = _unit(a_text)
    if unit != _unit(b_text):
        raise InputError(file, key, f"write both ends in one unit here, got {echo(a_text)} and {echo(b_text)}")
    ends = []
    for end in (a_text, b_text):
        m = _NUMBER.match(end)
        if m is None:
            raise InputError(file, key, f"cannot read {echo(end)} as a number with a unit")
        ends.append(float(m.group(0)))
    suffix = f" {unit}" if unit else ""
    return [f"{x:.12g}{suffix}" for x in _grid(ends[0], ends[1], spec, file=file, key=key)]
