"""What a sweep varies: grids (`--vary KEY=START:STOP:COUNT`, linear or log, or `KEY=V1,V2,...`)
and seeded random samples (`--sample KEY="normal(MEAN, SD)"` or `"uniform(LOW, HIGH)"`), read
into a plan of runs x keys in SI before any work.

The sweepable keys are the scene values the batch engine varies without rebuilding the lift
curve (the cam is the same in every run): speed, linkage stiffness and damping, masses, lash,
spring preload and rate, friction, seat restitution. Each has the dimension its scene key has,
the range the scene loader enforces, and an SI column name. Every bad value ends in one
InputError (the CLI: `error: FILE: KEY: reason`, exit status 2) before anything is computed.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

import numpy as np

from ..core import grids
from ..core.errors import InputError, echo
from ..core.memory import available_bytes, size_text
from ..core.ranges import check_range
from ..core.units import to_si
from ..scene.scene import MAX_RPM

# more runs than this need --yes (yes=True): 10^7 rows are ~1 GB of table and hours of CPU
MAX_RUNS_UNASKED = 10_000_000
MAX_GRID_POINTS = 10_000_000  # one axis: beyond it the grid itself would be gigabytes


@dataclass(frozen=True)
class SweepKey:
    key: str  # dotted scene key
    dimension: str  # explorer.core.units dimension
    column: str  # table column, SI unit in the name
    positive: bool  # > 0 (else >= 0)
    upper: float | None = None  # exclusive upper bound (restitution < 1)


# figures whose sign a reader could take otherwise: the table's metadata (`conventions`), the plots'
# titles and the browser's label say it (explorer check's seating_velocity is the magnitude)
SIGN_CONVENTIONS = {
    "seating_velocity_m_s": "signed: the valve's velocity at the hardest seat impact, < 0 = downward "
                            "(closing); explorer check's seating_velocity shows its magnitude",
}
SIGN_LABELS = {"seating_velocity_m_s": "signed, < 0 = downward"}


SWEEP_KEYS: dict[str, SweepKey] = {k.key: k for k in (
    SweepKey("drive.rpm", "speed", "drive_rpm", True),
    SweepKey("linkage.stiffness", "stiffness", "linkage_stiffness_N_m", True),
    SweepKey("linkage.damping", "damping", "linkage_damping_N_s_m", False),
    SweepKey("valve.mass", "mass", "valve_mass_kg", True),
    SweepKey("valve.oscillating_mass", "mass", "valve_oscillating_mass_kg", True),
    SweepKey("valve.lash", "length", "valve_lash_m", False),
    SweepKey("spring.preload", "force", "spring_preload_N", False),
    SweepKey("spring.rate", "stiffness", "spring_rate_N_m", False),
    SweepKey("loads.friction", "force", "loads_friction_N", False),
    SweepKey("seat.restitution", "dimensionless", "seat_restitution", False, upper=1.0),
)}

DISTRIBUTIONS = ("normal", "uniform")
_RPM = 60.0 / (2.0 * math.pi)  # rev/min per rad/s


@dataclass(frozen=True)
class Axis:
    """A grid over one key: `values` in SI (drive.rpm: rev/min, as in a scene and the tables)."""

    key: str
    values: np.ndarray
    log: bool = False


@dataclass(frozen=True)
class Sample:
    """A random draw per run: distribution and its two parameters in SI."""

    key: str
    distribution: str
    a: float  # normal: mean, uniform: low
    b: float  # normal: standard deviation, uniform: high
    text: str  # as given, for the table's metadata


@dataclass(frozen=True)
class Plan:
    """The runs of a sweep: `values` (runs x keys, SI) in the order the table keeps."""

    keys: tuple[str, ...]
    values: np.ndarray
    axes: tuple[Axis, ...]
    samples: tuple[Sample, ...]
    seed: int | None

    @property
    def runs(self) -> int:
        return int(self.values.shape[0])

    @property
    def columns(self) -> tuple[str, ...]:
        return tuple(SWEEP_KEYS[k].column for k in self.keys)

    def kind(self) -> str:
        """'grid-1d', 'grid-2d', 'grid-nd', 'samples' or 'mixed' (what the pictures show)."""
        if self.samples:
            return "samples" if not self.axes else "mixed"
        return {1: "grid-1d", 2: "grid-2d"}.get(len(self.axes), "grid-nd")


def sweep_key(key: str, file: str = "--vary") -> SweepKey:
    key = key.strip()
    info = SWEEP_KEYS.get(key)
    if info is None:
        raise InputError(file, key or "-", f"cannot sweep this key; sweepable: {', '.join(SWEEP_KEYS)}")
    return info


def quantity(text, info: SweepKey, file: str) -> float:
    """One value of a key in SI (drive.rpm in rev/min), by the scene files' rules."""
    if isinstance(text, str):
        text = text.strip()
        try:  # a bare number, as in a scene file: the key's own unit for bare numbers
            value = float(text)
        except ValueError:
            value = text
        else:
            if not math.isfinite(value):
                raise InputError(file, info.key, f"value must be finite, got {echo(text)}")
    else:
        value = text
    if info.dimension == "dimensionless":
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise InputError(file, info.key, f"expected a plain number, got {echo(value)}") from None
        if not math.isfinite(number):
            raise InputError(file, info.key, f"value must be finite, got {echo(value)}")
        return number
    number = to_si(value, info.dimension, file=file, key=info.key)
    if info.key == "drive.rpm":
        # a bare number is rev/min already: kept exact, as the scene loader keeps it
        return float(value) if isinstance(value, (int, float)) else number * _RPM
    return number


def check_values(info: SweepKey, values: np.ndarray, file: str, what: str = "value") -> None:
    """The key's valid range (the scene loader's, explorer.core.ranges) for every value; a sampled
    distribution that reaches outside it is refused with the share of bad draws."""
    values = np.asarray(values, dtype=float)
    bad = ~np.isfinite(values)
    bad |= values <= 0.0 if info.positive else values < 0.0
    if info.upper is not None:
        bad |= values >= info.upper
    if info.key == "drive.rpm":
        bad |= values > MAX_RPM
    if bad.any():
        first = float(values[bad][0])
        bound = ("> 0" if info.positive else ">= 0") + (f" and < {info.upper:g}" if info.upper is not None else "")
        if what == "draw":
            share = 100.0 * np.count_nonzero(bad) / values.size
            raise InputError(file, info.key, f"{share:.3g} % of the draws fall outside the valid range (must be "
                             f"{bound}; e.g. {first:.6g}): narrow the distribution")
        raise InputError(file, info.key, f"must be {bound}, got {first:.6g}")
    if info.dimension not in ("dimensionless",) and values.size:
        si = values / _RPM if info.key == "drive.rpm" else values
        for v in (float(si.min()), float(si.max())):
            check_range(v, info.dimension, file=file, key=info.key, shown=v, zero_allowed=not info.positive)


def parse_axis(key: str, spec, log: bool = False, file: str = "--vary") -> Axis:
    """A grid in the grammar of explorer.core.grids: "START:STOP:COUNT" (COUNT points, ends
    included; ":log" or log=True for geometric spacing), "V1,V2,..." (the values as given), or a
    sequence of values."""
    info = sweep_key(key, file)
    if isinstance(spec, (list, tuple, np.ndarray)):
        parts = list(spec)
        if not parts:
            raise InputError(file, info.key, "empty list of values")
        if len(parts) > MAX_GRID_POINTS:
            raise InputError(file, info.key, f"at most {MAX_GRID_POINTS:g} values per key, got {len(parts)}")
        values = np.array([quantity(p, info, file) for p in parts], dtype=float)
        check_values(info, values, file)
        return Axis(info.key, values, False)
    shape = grids.read(spec, file=file, key=info.key, max_points=MAX_GRID_POINTS)
    if log and isinstance(shape, grids.Listed):
        raise InputError(file, info.key, "--log spaces a START:STOP:COUNT range; a list V1,V2,... keeps its values")
    values = grids.values(shape, lambda text: quantity(text, info, file), file=file, key=info.key, log=log)
    check_values(info, values, file)
    return Axis(info.key, values, isinstance(shape, grids.Span) and (log or shape.log))


_DIST = re.compile(r"^\s*(?P<name>[A-Za-z_]+)\s*\((?P<args>.*)\)\s*$", re.DOTALL)


def parse_sample(key: str, spec: str, file: str = "--sample") -> Sample:
    """"normal(MEAN, SD)" or "uniform(LOW, HIGH)", each with units as in a scene file."""
    info = sweep_key(key, file)
    text = str(spec).strip()
    m = _DIST.match(text)
    if m is None:
        raise InputError(file, info.key, f"cannot read {echo(text)}: write normal(MEAN, SD) or uniform(LOW, HIGH)")
    name = m.group("name").lower()
    if name not in DISTRIBUTIONS:
        raise InputError(file, info.key, f"unknown distribution {echo(m.group('name'))}; known: {', '.join(DISTRIBUTIONS)}")
    args = [x.strip() for x in m.group("args").split(",")]
    if len(args) != 2 or not all(args):
        raise InputError(file, info.key, f"{name}() takes two values, got {echo(m.group('args'))}")
    a_text, b_text = grids.share_unit(*args)
    a = quantity(a_text, info, file)
    if name == "normal":
        b = quantity(b_text, SweepKey(info.key, info.dimension, info.column, False), file) \
            if not b_text.lstrip().startswith("-") else -1.0
        if b < 0.0:
            raise InputError(file, info.key, f"negative standard deviation {echo(args[1])}")
    else:
        b = quantity(b_text, info, file)
        if b <= a:
            raise InputError(file, info.key, f"uniform(LOW, HIGH) needs LOW < HIGH, got {echo(args[0])}, {echo(args[1])}")
    return Sample(info.key, name, a, b, text)


def draw(sample: Sample, rng: np.random.Generator, n: int) -> np.ndarray:
    if sample.distribution == "normal":
        return rng.normal(sample.a, sample.b, n)
    return rng.uniform(sample.a, sample.b, n)


MAX_SEED = 2**128  # numpy's SeedSequence takes any whole number >= 0; 128 bits are all its entropy
TABLE_COPIES = 3  # the plan's values, the gathered figures and the table's columns, at once at the end


def plan_bytes(runs: int, keys: int, figures: int) -> float:
    """Memory a sweep of `runs` rows holds at its end: TABLE_COPIES float64 copies of a row of
    the run index, the keys and the figures (as float: the count may be astronomical)."""
    return float(TABLE_COPIES) * float(runs) * 8.0 * (1 + keys + figures)


def check_seed(seed, samples) -> None:
    if seed is None:
        return
    if not samples:
        raise InputError("<command line>", "--seed", "seeds the random draws: give --sample too")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= int(seed) < MAX_SEED:
        raise InputError("<command line>", "--seed", f"must be a whole number from 0 to 2**128 - 1, got {echo(seed)}")


def make_plan(axes=(), samples=(), runs: int | None = None, seed: int | None = None, yes: bool = False,
              file: str = "--vary", figures: int = 0) -> Plan:
    """The runs: the product of the axes (the first key varies slowest), each grid point repeated
    `runs` times with fresh draws of the samples (runs defaults to 1 without samples). `figures`:
    the columns each run adds to the table, for the memory check (a plan whose table would not
    fit in the available memory is refused before anything is allocated, --yes or not)."""
    axes, samples = tuple(axes), tuple(samples)
    keys = [a.key for a in axes] + [s.key for s in samples]
    # --runs before "nothing to sweep": `--runs 5` alone is a mistake about --runs, not --vary
    if runs is not None and (runs < 1 or int(runs) != runs):
        raise InputError("<command line>", "--runs", f"must be a whole number >= 1, got {echo(runs)}")
    if runs is not None and not samples:
        raise InputError("<command line>", "--runs", "sets the number of random draws per grid point: give --sample too")
    if samples and runs is None:
        raise InputError("<command line>", "--runs", "missing: a --sample needs --runs N (how many draws)")
    if not keys:
        raise InputError(file, "-", "nothing to sweep: give --vary KEY=START:STOP:COUNT or --sample KEY=\"normal(...)\"")
    dup = next((k for k in keys if keys.count(k) > 1), None)
    if dup is not None:
        raise InputError(file, dup, "varied twice")
    check_seed(seed, samples)
    reps = int(runs) if samples else 1
    grid = math.prod(a.values.size for a in axes)
    total = grid * reps
    if total > MAX_RUNS_UNASKED and not yes:
        raise InputError(file, ", ".join(keys), f"{float(total):.4g} runs; more than {MAX_RUNS_UNASKED:g} need --yes")
    need, room = plan_bytes(total, len(keys), figures), available_bytes()
    if need > room:
        raise InputError("--runs" if samples else file, ", ".join(keys), f"{float(total):.4g} runs: the table needs about {size_text(need)} of "
                         f"memory ({TABLE_COPIES} copies of {8 * (1 + len(keys) + figures)} bytes per run), "
                         f"{size_text(room)} are available; sweep fewer runs, or in parts")
    values = np.empty((total, len(keys)))
    if axes:
        mesh = np.meshgrid(*[a.values for a in axes], indexing="ij")
        for j, m in enumerate(mesh):
            values[:, j] = np.repeat(m.ravel(), reps)
    if samples:
        rng = np.random.default_rng(seed)
        for j, s in enumerate(samples, start=len(axes)):
            values[:, j] = draw(s, rng, total)
            check_values(SWEEP_KEYS[s.key], values[:, j], "--sample", what="draw")
    return Plan(tuple(keys), values, axes, samples, seed)


def check_scene(scene, plan: Plan) -> None:
    """The keys must be in the scene (a linkage to vary, a valve), and the combinations valid:
    valve.oscillating_mass <= valve.mass in every run."""
    for key in plan.keys:
        section = key.split(".")[0]
        if section in ("valve", "spring", "linkage") and getattr(scene, section) is None:
            raise InputError(scene.source, key, f"the scene has no [{section}] section to vary")
    cols = dict(zip(plan.keys, plan.values.T))
    if scene.valve is not None and ("valve.mass" in cols or "valve.oscillating_mass" in cols):
        m = cols.get("valve.mass", np.full(plan.runs, scene.valve.mass))
        m1 = cols.get("valve.oscillating_mass")
        if m1 is None and scene.valve.oscillating_mass is not None:
            m1 = np.full(plan.runs, scene.valve.oscillating_mass)
        if m1 is not None and np.any(m1 > m):
            raise InputError(scene.source, "valve.oscillating_mass", "cannot exceed valve.mass (in some runs it does)")


def scene_for(base, keys, row):
    """The base scene with the run's values (SI) in place."""
    changes: dict[str, dict] = {}
    for key, value in zip(keys, row):
        section, field = key.split(".")
        changes.setdefault(section, {})[field] = float(value)
    sections = {}
    for section, fields in changes.items():
        sections[section] = replace(getattr(base, section), **fields)
    return replace(base, **sections) if sections else base
