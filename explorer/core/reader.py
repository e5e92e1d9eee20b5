"""Typed access to one table of a scene file, with errors that name file and dotted key.

Every section parser (here and in the modules that own a section) reads through a `Table`, so
bad input always ends in the same one-line InputError.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

from .errors import InputError, echo
from .ranges import check_range
from .units import check_magnitude, plain_number, to_si


@dataclass(frozen=True)
class Table:
    data: Mapping[str, Any]
    file: str
    prefix: str  # dotted path of this table, "" at top level

    def key(self, name: str) -> str:
        return f"{self.prefix}.{name}" if self.prefix else name

    def error(self, name: str, reason: str) -> InputError:
        return InputError(self.file, self.key(name), reason)

    def has(self, name: str) -> bool:
        return name in self.data

    def table(self, name: str, required: bool = True) -> "Table | None":
        if name not in self.data:
            if required:
                raise self.error(name, "missing section")
            return None
        value = self.data[name]
        if not isinstance(value, Mapping):
            raise self.error(name, f"expected a table [{self.key(name)}], got {type(value).__name__}")
        return Table(value, self.file, self.key(name))

    def _lookup(self, name: str, default: Any) -> tuple[Any, bool]:
        """(value, present): the key's value, or `default` when absent; `...` means required."""
        if name in self.data:
            return self.data[name], True
        if default is ...:
            raise self.error(name, "missing key")
        return default, False

    def raw(self, name: str, default: Any = ...) -> Any:
        return self._lookup(name, default)[0]

    def quantity(
        self,
        name: str,
        dimension: str,
        default: Any = ...,
        *,
        minimum: float | None = None,
        maximum: float | None = None,
        positive: bool = False,
        nonnegative: bool = False,
    ) -> float:
        """SI value of `name`; `default` (SI float or scene string) when absent, error when `...`."""
        value, present = self._lookup(name, default)
        if not present and isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)  # a default already in SI
        number = to_si(value, dimension, file=self.file, key=self.key(name))
        if positive and not number > 0.0:
            raise self.error(name, f"must be greater than zero, got {echo(value)}")
        if nonnegative and not number >= 0.0:
            raise self.error(name, f"must not be negative, got {echo(value)}")
        if minimum is not None and number < minimum:
            raise self.error(name, f"must be at least {minimum:g} (SI), got {echo(value)}")
        if maximum is not None and number > maximum:
            raise self.error(name, f"must be at most {maximum:g} (SI), got {echo(value)}")
        return check_range(number, dimension, file=self.file, key=self.key(name), shown=value, zero_allowed=not positive)

    def number(
        self,
        name: str,
        default: Any = ...,
        *,
        minimum: float | None = None,
        maximum: float | None = None,
        integer: bool = False,
        open_minimum: bool = False,
        open_maximum: bool = False,
    ) -> float:
        value, present = self._lookup(name, default)
        if not present:
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(name, f"expected a plain number, got {echo(value)}")
        number = plain_number(value, file=self.file, key=self.key(name))
        if integer and not number.is_integer():
            raise self.error(name, f"expected a whole number, got {echo(value)}")
        if minimum is not None and (number < minimum or (open_minimum and number == minimum)):
            raise self.error(name, f"must be {'greater than' if open_minimum else 'at least'} {minimum:g}, got {echo(value)}")
        if maximum is not None and (number > maximum or (open_maximum and number == maximum)):
            raise self.error(name, f"must be {'less than' if open_maximum else 'at most'} {maximum:g}, got {echo(value)}")
        check_magnitude(number, value, file=self.file, key=self.key(name))
        return int(number) if integer else number

    def string(self, name: str, default: Any = ..., *, choices: Iterable[str] | None = None) -> str:
        value, present = self._lookup(name, default)
        if not present:
            return value
        if not isinstance(value, str):
            raise self.error(name, f"expected a string, got {echo(value)}")
        if choices is not None:
            options = list(choices)
            if value not in options:
                raise self.error(name, f"unknown value {echo(value)}; choose one of: {', '.join(options)}")
        return value

    def reject_unknown(self, known: Iterable[str]) -> None:
        """Typos in optional keys must not pass silently."""
        known = set(known)
        for name in self.data:
            if name not in known:
                raise self.error(name, f"unknown key; known keys here: {', '.join(sorted(known))}")


# An integer literal longer than this cannot be converted by Python (sys.get_int_max_str_digits,
# a guard against quadratic-time conversion): tomllib then raises a bare ValueError that names
# neither the line nor the key. No quantity needs more than a few digits.
_LONG_NUMBER = re.compile(r"[0-9][0-9_]{4299,}")
_TABLE_HEADER = re.compile(r"^\s*\[\[?\s*([^\]]+?)\s*\]\]?\s*(?:#.*)?$")


def toml_loads(text: str, file: str, key: str | None = None) -> dict:
    """tomllib.loads, with a number beyond Python's integer-conversion limit (4300 digits) turned
    into InputError naming the key (`key`, or the dotted key written on the offending line) and the
    line. tomllib's own TOMLDecodeError and RecursionError pass through (the caller words them)."""
    import tomllib

    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        raise
    except ValueError:
        match = _LONG_NUMBER.search(text)
        if match is None:
            raise
    line = text.count("\n", 0, match.start()) + 1
    where = key
    if where is None:
        table, written = "", "-"
        for number, row in enumerate(text.splitlines()[:line], start=1):
            header = _TABLE_HEADER.match(row)
            if header and number < line:
                table = header.group(1).replace(" ", "").replace('"', "")
            elif number == line and "=" in row:
                written = row.split("=", 1)[0].strip().replace(" ", "").replace('"', "")
        where = f"{table}.{written}" if table and written != "-" else written
    digits = sum(c.isdigit() for c in match.group(0))
    at = "" if key is not None else f" (line {line})"
    raise InputError(file, where, f"a number of {digits} digits{at}: out of range for every quantity "
                     "(Python reads at most 4300 digits)")
