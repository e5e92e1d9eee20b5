"""What a simulation returns: column arrays over one revolution and a JSON-able summary."""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Iterator, Mapping

import numpy as np

CSV_CHUNK_ROWS = 20_000  # ~ 5 MB of text per piece at 30 columns

# The output columns that may hold NaN, each with what NaN means there (docs/reference/validity.md).
# Every other column of every scene is a number (or +-inf where the docs say so, a self-locked
# cam's force); the pipeline refuses a NaN elsewhere, and tests/test_nan_outputs.py runs every
# built-in scene against this table.
NAN_MEANINGS: Mapping[str, str] = MappingProxyType({
    "valve_referred_stiffness_N_m": "the rolling levers are apart: the valve is seated and the chain carries no "
                                    "load, so it has no stiffness to refer to the valve",
})

@dataclass(frozen=True)
class EffectOutput:
    """What one effect adds: columns (SI, unit in the name), scalar summary entries, events, warnings."""

    columns: Mapping[str, np.ndarray] = field(default_factory=dict)
    summary: Mapping[str, Any] = field(default_factory=dict)
    events: tuple[Mapping[str, Any], ...] = ()
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class Result:
    scene: Any
    columns: Mapping[str, np.ndarray]
    summary: Mapping[str, Any]

    @staticmethod
    def build(scene, columns: dict, summary: dict) -> "Result":
        frozen = {}
        for name, array in columns.items():
            array = np.asarray(array)
            array.setflags(write=False)
            frozen[name] = array
        return Result(scene=scene, columns=MappingProxyType(frozen), summary=MappingProxyType(summary))

    @property
    def events(self) -> list:
        return list(self.summary.get("events", []))

    def csv_text(self) -> str:
        return "".join(self.csv_chunks())

    def csv_chunks(self, rows: int = CSV_CHUNK_ROWS) -> Iterator[str]:
        """The CSV text in pieces of `rows` rows (the header first): at the largest step counts
        the whole text is gigabytes, a piece a few megabytes. Every value is repr() of the
        float64, which reads back exactly."""
        names = list(self.columns)
        arrays = [np.asarray(self.columns[n], dtype=float) for n in names]
        yield ",".join(names) + "\n"
        n = len(arrays[0]) if arrays else 0
        for lo in range(0, n, rows):
            block = np.column_stack([a[lo:lo + rows] for a in arrays]).tolist()
            yield "".join([",".join(map(repr, row)) + "\n" for row in block])

    def json_text(self) -> str:
        return json.dumps(_jsonable(dict(self.summary)), indent=2, allow_nan=False) + "\n"


def _jsonable(value, key: str = ""):
    """The summary as JSON values; floats without round-off noise (explorer.core.units.printable)."""
    from .core.units import printable

    if isinstance(value, Mapping):
        return {str(k): _jsonable(v, str(k)) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v, key) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v, key) for v in value.tolist()]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return printable(value, key) if math.isfinite(value) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_atomic(path: str | os.PathLike, text: str | bytes) -> None:
    """Write `text` to `path` by the rules of explorer.core.outputs (temporary file and rename for a
    regular file, the umask or the replaced file's mode; devices and pipes written through)."""
    from .core.outputs import write_output

    write_output(path, text)
