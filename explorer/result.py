"""What a simulation returns (Result: columns over one revolution, summary figures, events,
warnings, timings) and what an effect hands the pipeline (EffectOutput, Event)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Iterator, Mapping

import numpy as np

from .core.units import printable

CSV_CHUNK_ROWS = 20_000  # ~ 5 MB of text per piece at 30 columns


# The output columns that may hold NaN, each with what NaN means there (docs/reference/validity.md).
# Every other column of every scene is a number (or +-inf where the docs say so, a self-locked
# cam's force); the pipeline refuses a NaN elsewhere, and tests/test_nan_outputs.py runs every
# built-in scene against this table.
NAN_MEANINGS: Mapping[str, str] = MappingProxyType({
    "valve_referred_stiffness_N_m": "the rolling levers are apart: the valve is seated and the chain carries no "
                                    "load, so it has no stiffness to refer to the valve",
})


@dataclass(frozen=True, eq=False)
class Event(Mapping):
    """One instant of a run that an effect reports: what happened (`kind`), when (`time_s` within
    the revolution, `cam_angle_deg`), the figures that go with it (`values`: an impact's
    velocity_m_s, a lift_m, ...; in the order written) and the effect that reported it (set by the
    pipeline). Read as a mapping it is its JSON object: kind, time_s, cam_angle_deg, the values,
    effect."""

    kind: str
    time_s: float
    cam_angle_deg: float | None = None
    values: Mapping[str, Any] = field(default_factory=dict)  # read-only by convention (a dict: it pickles)
    effect: str = ""

    @staticmethod
    def of(item: Mapping[str, Any], effect: str = "") -> "Event":
        """The event a mapping written as its JSON object describes (kind, time_s, cam_angle_deg,
        the rest its values)."""
        values = {k: v for k, v in item.items() if k not in ("kind", "time_s", "cam_angle_deg", "effect")}
        return Event(kind=str(item["kind"]), time_s=item["time_s"], cam_angle_deg=item.get("cam_angle_deg"),
                     values=values, effect=effect or str(item.get("effect", "")))

    def with_effect(self, effect: str) -> "Event":
        return replace(self, effect=effect)

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "time_s": self.time_s}
        if self.cam_angle_deg is not None:
            out["cam_angle_deg"] = self.cam_angle_deg
        out.update(self.values)
        if self.effect:
            out["effect"] = self.effect
        return out

    # the read-only mapping of its JSON object
    def __getitem__(self, key: str) -> Any:
        return self.as_dict()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.as_dict())

    def __len__(self) -> int:
        return len(self.as_dict())

    def __eq__(self, other) -> bool:
        return isinstance(other, Mapping) and self.as_dict() == dict(other)

    __hash__ = None  # type: ignore[assignment]



@dataclass(frozen=True)
class EffectOutput:
    """What one effect adds: columns (SI, unit in the name), summary entries, events, warnings."""

    columns: Mapping[str, np.ndarray] = field(default_factory=dict)
    summary: Mapping[str, Any] = field(default_factory=dict)
    events: tuple[Event, ...] = ()
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class EffectTiming:
    """How long an effect took in `simulate` (s), and whether the scene listed it (rather than
    another effect needing it)."""

    compute_time_s: float
    requested: bool


@dataclass(frozen=True)
class Result:
    """A run: the columns over one revolution, the effects' summary figures, the events in time
    order, the warnings and each effect's timing. The JSON report (`report`, `json_text`) is the
    summary followed by "effects" (the timings), "events" and "warnings"."""

    scene: Any
    columns: Mapping[str, np.ndarray]
    summary: Mapping[str, Any]
    events: tuple[Event, ...] = ()
    warnings: tuple[str, ...] = ()
    timings: Mapping[str, EffectTiming] = field(default_factory=lambda: MappingProxyType({}))

    @staticmethod
    def build(scene, columns: dict, summary: dict, events=(), warnings=(), timings=None) -> "Result":
        frozen = {}
        for name, array in columns.items():
            array = np.asarray(array)
            array.setflags(write=False)
            frozen[name] = array
        return Result(scene=scene, columns=MappingProxyType(frozen), summary=MappingProxyType(summary),
                      events=tuple(events), warnings=tuple(warnings), timings=MappingProxyType(dict(timings or {})))

    def report(self) -> dict[str, Any]:
        """The summary as written to JSON: its figures, then effects (timings), events, warnings."""
        return {
            **self.summary,
            "effects": {name: {"compute_time_s": t.compute_time_s, "requested": t.requested}
                        for name, t in self.timings.items()},
            "events": [e.as_dict() for e in self.events],
            "warnings": list(self.warnings),
        }

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
        return json.dumps(_jsonable(self.report()), indent=2, allow_nan=False) + "\n"


def _jsonable(value, key: str = ""):
    """The summary as JSON values; floats without round-off noise (explorer.core.units.printable)."""
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
