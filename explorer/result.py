"""What a simulation returns: column arrays over one revolution and a JSON-able summary."""

from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Mapping

import numpy as np


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
        names = list(self.columns)
        table = np.column_stack([np.asarray(self.columns[n], dtype=float) for n in names])
        lines = [",".join(names)]
        lines.extend(",".join(repr(float(x)) for x in row) for row in table)
        return "\n".join(lines) + "\n"

    def json_text(self) -> str:
        return json.dumps(_jsonable(dict(self.summary)), indent=2, allow_nan=False) + "\n"


def _jsonable(value):
    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def write_atomic(path: str | os.PathLike, text: str | bytes) -> None:
    """Write to a temporary file beside the target, then rename: never a half-written target."""
    path = Path(path)
    mode = "wb" if isinstance(text, bytes) else "w"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent or ".")
    try:
        with os.fdopen(fd, mode) as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
