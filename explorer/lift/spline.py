"""`spline` law: a lift through stations with conditions on s, v, a, j (Norton's SVAJ design) and
the fourth derivative `snap` (the wanted lift of a polydyne cam needs it: explorer.lift.polydyne).

The event runs from the first station (at lift.start) to the last; between consecutive stations
the lift is one polynomial. The conditions:

- at a station, each value given (s, v, a, j or snap) holds for the polynomials on both sides;
- at an interior station, every derivative up to `continuity` (default 3, the jerk; at most
  MAX_CONTINUITY) that is not given is continuous.

Each condition is one linear equation in the polynomials' coefficients. The degrees follow from
the count (Norton: one coefficient per condition): with C conditions on n segments the segments
get C // n coefficients, the longest C mod n one more. The square system is solved once, exactly
(a singular one is an error naming the stations). With s, v, a given at both ends of one segment
this is the 3-4-5 polynomial, with s, v, a, j the 4-5-6-7 (tests).

Velocity, acceleration, jerk and snap are given in time units at `reference_rpm` (default the
file's own drive.rpm, Drive.cam_omega, whatever speed an override runs it at) and stored per
radian (v/w, a/w^2, j/w^3, snap/w^4), so the cam does not change when the speed is changed.
The event must start and end on the base circle: s = 0 given at the first and last station.
Outside the event the lift is 0. Derivatives come from the polynomials, exactly, to any order.

A station value may be `"free"`: a value for `explorer design` to choose (explorer/studies/design.py);
until then it is what a cycloidal event of the same height, rise, dwell and return has there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..core.units import to_si
from .curves import LawLift
from .validity import cam_fault, computed_error, lift_fault

TWO_PI = 2.0 * math.pi
NAMES = ("s", "v", "a", "j", "snap")
DIMENSIONS = ("length", "velocity", "acceleration", "jerk", "snap")
UNITS = ("m", "m/s", "m/s**2", "m/s**3", "m/s**4")
MAX_CONTINUITY = 6  # C6 needs >= 14 coefficients a segment: beyond, the monomial system loses digits
FREE_ORDERS = 4  # s, v, a, j may be "free" (explorer design); snap is given or left to continuity
UNUSED_KEYS = ("height", "rise", "dwell", "return", "return_law")
MAX_STATIONS = 64
FREE = "free"


@dataclass(frozen=True)
class Station:
    angle: float  # rad since lift.start
    values: tuple  # per derivative k = 0..4 (NAMES): value per rad^k, or None (not given)
    free: tuple = (False,) * len(NAMES)  # values the designer may move


@dataclass(frozen=True)
class SplineOptions:
    stations: tuple[Station, ...]
    continuity: int = 3
    reference_rpm: float = 0.0


@dataclass(frozen=True)
class SplineLift:
    """A LiftCurve: piecewise polynomials in the local coordinate u = (x - x_i)/(x_{i+1} - x_i)."""

    start: float  # rad
    knots: np.ndarray  # (n + 1,) rad since start
    coefficients: tuple  # n arrays, ascending powers of u

    def local_derivatives(self, x, order: int = 3) -> np.ndarray:
        """(order + 1, N): lift and its derivatives per radian at event angles x (0 outside)."""
        x = np.asarray(x, dtype=float).reshape(-1)
        out = np.zeros((order + 1, x.size))
        knots = self.knots
        inside = (x >= knots[0]) & (x < knots[-1])
        index = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, len(self.coefficients) - 1)
        for i, c in enumerate(self.coefficients):
            mask = inside & (index == i)
            if not np.any(mask):
                continue
            width = knots[i + 1] - knots[i]
            u = (x[mask] - knots[i]) / width
            for k, p in enumerate(self._chain(i, order)[:order + 1]):
                out[k, mask] = p(u) / width**k
        return out

    def _chain(self, segment: int, order: int) -> list:
        """Segment's polynomial and its first `order` derivatives, each the .deriv() of the one
        before: made once per lift and kept (the same coefficients every call; making them was
        half the cost of evaluating a spline lift at one angle, which the root searches do)."""
        chains = self.__dict__.setdefault("_chains", {})  # (a frozen dataclass: not a field)
        chain = chains.get(segment)
        if chain is None:
            chain = [np.polynomial.Polynomial(self.coefficients[segment])]
        while len(chain) <= order:
            chain = [*chain, chain[-1].deriv()]
        chains[segment] = chain
        return chain

    def segment_derivatives(self, segment: int, u: float, order: int) -> np.ndarray:
        """(order + 1,): derivatives per radian of one segment's polynomial at its local u (its own
        end at u = 1, where local_derivatives would take the next segment)."""
        width = self.knots[segment + 1] - self.knots[segment]
        out = np.zeros(order + 1)
        for k, p in enumerate(self._chain(segment, order)[:order + 1]):
            out[k] = p(u) / width**k
        return out

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        x = np.mod(theta.reshape(-1) - self.start, TWO_PI)
        return self.local_derivatives(x).reshape((4,) + theta.shape)

    def breakpoints(self) -> np.ndarray:
        return np.unique(np.mod(self.start + self.knots, TWO_PI))


def _degrees(widths: np.ndarray, conditions: int) -> list[int]:
    n = len(widths)
    base, extra = divmod(conditions, n)
    sizes = [base] * n
    for i in np.argsort(-widths, kind="stable")[:extra]:
        sizes[i] += 1
    return sizes  # coefficients per segment


def solve_spline(stations, continuity: int = 3, start: float = 0.0, file: str = "<memory>",
                 key: str = "lift.stations") -> SplineLift:
    """The piecewise polynomial meeting the stations' conditions exactly (see the module doc)."""
    knots = np.array([s.angle for s in stations])
    widths = np.diff(knots)
    n = len(widths)
    last = len(stations) - 1
    # conditions: (segment, side 0/1, k, value) for a given value; ("cont", i, k) for continuity
    rows: list[tuple] = []
    for i, st in enumerate(stations):
        orders = max(len(st.values), continuity + 1)  # continuity may reach past the orders a station can give
        for k, value in enumerate(st.values + (None,) * (orders - len(st.values))):
            if value is not None:
                if i > 0:
                    rows.append(("value", i - 1, 1.0, k, value))
                if i < last:
                    rows.append(("value", i, 0.0, k, value))
            elif 0 < i < last and k <= continuity:
                rows.append(("cont", i, k))
    sizes = _degrees(widths, len(rows))
    if min(sizes) < 1:
        raise InputError(file, key, f"{len(rows)} conditions on {n} segments leave a segment without a polynomial; "
                         "give more conditions or fewer stations")
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    size = int(offsets[-1])
    matrix = np.zeros((size, size))
    rhs = np.zeros(size)
    scale = float(np.mean(widths))  # rows in units of the mean width: well-conditioned for any angle unit

    def basis(m: int, u: float, k: int) -> np.ndarray:
        # k-th derivative of u^p (p < m) at u
        out = np.zeros(m)
        for p in range(k, m):
            out[p] = math.perm(p, k) * u ** (p - k)
        return out

    for r, row in enumerate(rows):
        if row[0] == "value":
            _, seg, u, k, value = row
            w = widths[seg]
            matrix[r, offsets[seg]:offsets[seg + 1]] = basis(sizes[seg], u, k) * (scale / w) ** k
            rhs[r] = value * scale**k
        else:
            _, i, k = row
            left, right = i - 1, i
            matrix[r, offsets[left]:offsets[left + 1]] = basis(sizes[left], 1.0, k) * (scale / widths[left]) ** k
            matrix[r, offsets[right]:offsets[right + 1]] -= basis(sizes[right], 0.0, k) * (scale / widths[right]) ** k
    rank_tol = 1e-12 * max(1.0, float(np.abs(matrix).max()))
    singular = np.linalg.svd(matrix, compute_uv=False)
    if singular[-1] <= rank_tol * size:
        raise InputError(file, key, "the stations' conditions are not independent (or too few for the segments they "
                         "share): no unique lift; give each segment its own conditions")
    coefficients = np.linalg.solve(matrix, rhs)
    return SplineLift(start, knots, tuple(coefficients[offsets[i]:offsets[i + 1]] for i in range(n)))


def build_spline_lift(scene) -> SplineLift:
    o = scene.lift.options
    return solve_spline(o.stations, o.continuity, scene.lift.start, scene.source)


def parse_spline_options(table, fields: dict[str, Any]) -> SplineOptions:
    """[lift] keys of the spline law; solves once at load so that a bad set of conditions fails here."""
    for name in UNUSED_KEYS:
        if table.has(name):
            raise table.error(name, "not used by law 'spline' (the stations give the lift); remove it")
    continuity = int(table.number("continuity", 3, integer=True, minimum=0, maximum=MAX_CONTINUITY))
    if table.has("reference_rpm"):
        omega = table.quantity("reference_rpm", "speed", positive=True)
    else:
        omega = fields["drive"].cam_omega
    options, lift = parse_stations(table, continuity, omega)
    check_spline_shape(table, lift, fields["follower"], fields["lift"].start)
    return options


def parse_stations(table, continuity: int, omega: float) -> tuple[SplineOptions, SplineLift]:
    """The [[lift.stations]] (values per radian at reference speed omega) and their lift (event
    coordinates: start 0), solved at load so that a bad set of conditions fails there; shared with
    the polydyne law's wanted spline."""
    raw = table.raw("stations")
    where = table.key("stations")
    if not isinstance(raw, list) or not 2 <= len(raw) <= MAX_STATIONS or not all(isinstance(r, dict) for r in raw):
        raise table.error("stations", f"expected 2 to {MAX_STATIONS} [[lift.stations]] tables (angle, and any of s, v, a, j, snap)")
    stations = []
    for n_st, item in enumerate(raw):
        key = f"{where}[{n_st}]"
        unknown = set(item) - {"angle", *NAMES}
        if unknown:
            raise InputError(table.file, f"{key}.{sorted(unknown)[0]}", "unknown key; a station takes angle, s, v, a, j, snap")
        if "angle" not in item:
            raise InputError(table.file, f"{key}.angle", "missing key")
        angle = to_si(item["angle"], "angle", file=table.file, key=f"{key}.angle")
        values, free = [], []
        for k, (name, dim) in enumerate(zip(NAMES, DIMENSIONS)):
            value = item.get(name)
            if value is None:
                values.append(None)
                free.append(False)
            elif value == FREE:
                if k >= FREE_ORDERS:
                    raise InputError(table.file, f"{key}.{name}", "only s, v, a and j can be \"free\"; give snap a value "
                                     "or leave it out (then continuity decides it)")
                values.append(None)  # placeholder: see _initial_free_values
                free.append(True)
            else:
                si = to_si(value, dim, file=table.file, key=f"{key}.{name}")
                values.append(si / omega**k)
                free.append(False)
        stations.append(Station(angle, tuple(values), tuple(free)))
    angles = np.array([s.angle for s in stations])
    if angles[0] != 0.0:
        raise InputError(table.file, f"{where}[0].angle", "the first station is the start of the event: angle 0 "
                         "(lift.start places it on the cam)")
    if np.any(np.diff(angles) <= 0.0):
        i = int(np.argmax(np.diff(angles) <= 0.0))
        raise InputError(table.file, f"{where}[{i + 1}].angle", "station angles must increase")
    if angles[-1] > TWO_PI * (1.0 + 1e-12):
        raise InputError(table.file, f"{where}[{len(angles) - 1}].angle", "the event spans more than 360 deg")
    for i in (0, len(stations) - 1):
        if stations[i].free[0] or stations[i].values[0] != 0.0:
            raise InputError(table.file, f"{where}[{i}].s", "the event starts and ends on the base circle: give s = 0 "
                             "at the first and last station")
    stations = _initial_free_values(stations, continuity, table.file, where)
    options = SplineOptions(tuple(stations), continuity, omega * 60.0 / TWO_PI)
    return options, solve_spline(options.stations, continuity, 0.0, table.file, where)


def check_spline_shape(table, lift: SplineLift, follower=None, start: float = 0.0) -> None:
    """The lift through the stations leaves the base circle and passes the checks every cam passes
    (explorer.lift.validity: finite, lift range; with the follower's geometry when `follower` is
    given: pressure angle and undercut, with the lift placed at cam angle `start`). A polydyne's
    wanted spline, a valve lift and no cam, is checked without a follower."""
    where = table.key("stations")
    x = np.linspace(0.0, lift.knots[-1], 20001)
    with np.errstate(over="ignore", invalid="ignore"):
        jet = lift.local_derivatives(x, 3)
    fault = cam_fault(x, jet, where="{} after the start")
    if fault is None and follower is not None:
        fault = lift_fault(replace(lift, start=start), follower)
    if fault is not None:
        remedy = {"undercut": "reduce the roller, enlarge the base circle or move the stations apart",
                  "lift range": "check the units, or add conditions (such as v and a at the top)",
                  "": "check the units"}
        raise computed_error(fault, table.file, where, "the lift through these stations", remedy)
    if not jet[0].max() > 0.0:
        raise InputError(table.file, where, "the lift through these stations never leaves the base circle")


def _initial_free_values(stations, continuity: int, file: str, key: str) -> list:
    """Free values start as a cycloidal event of the same shape gives them (its height the largest
    s given; the first station with it ends the rise, the last starts the return): a sensible,
    constraint-abiding start for `explorer design`, and the lift the scene runs until then."""
    if not any(any(st.free) for st in stations):
        return stations
    given = [(st.angle, st.values[0]) for st in stations if st.values[0] is not None and not st.free[0]]
    height = max(v for _, v in given)
    tops = [a for a, v in given if v == height]
    end = stations[-1].angle
    law = None
    if height > 0.0 and 0.0 < tops[0] and tops[-1] < end:
        law = LawLift(height, 0.0, tops[0], tops[-1] - tops[0], end - tops[-1], "cycloidal", "cycloidal")
    out = []
    for st in stations:
        if any(st.free):
            d = law.derivatives(np.array([st.angle]))[:, 0] if law is not None else np.zeros(4)
            st = replace(st, values=tuple(float(d[k]) if st.free[k] else st.values[k] for k in range(FREE_ORDERS))
                         + st.values[FREE_ORDERS:])
        out.append(st)
    return out


def with_values(options: SplineOptions, values: dict) -> SplineOptions:
    """A copy with some station values replaced: {(station, k): value per rad^k}."""
    stations = list(options.stations)
    for (i, k), value in values.items():
        v = list(stations[i].values)
        v[k] = float(value)
        stations[i] = replace(stations[i], values=tuple(v))
    return replace(options, stations=tuple(stations))
