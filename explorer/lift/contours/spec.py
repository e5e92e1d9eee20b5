"""The [cam] section: a cam contour given as tangent circular arcs or as a point list.

    [cam]                         # used with [lift] law = "contour"
    rotation = "0 deg"            # optional: turn the whole contour counter-clockwise (cam frame)
    tolerance = "0.001 mm"        # arcs: largest misfit allowed where consecutive circles touch

    [[cam.arcs]]                  # one table per arc, in order around the cam (either direction)
    name = "base"                 # optional, used in messages
    x = "0 mm"                    # centre in the cam frame (bare numbers: metres)
    y = "0 mm"
    radius = "100 mm"
    kind = "convex"               # convex (centre inside the cam) | concave (centre outside)

or, instead of arcs,

    points = [[100.0, 0.0], [99.9, 4.4], ...]   # (x, y) once around the cam, either direction
    file = "contour.csv"          # or: two columns x, y; relative to the scene file
    unit = "mm"                   # unit of the point coordinates (default m)
    spline_degree = 5             # periodic interpolating spline through the points: 3 or 5

Cam frame: the cam turns counter-clockwise about the origin; at cam angle 0 the follower axis
is parallel to +y at x = follower.offset, so the roller meets the contour point at polar angle
about 90 deg first and then runs clockwise around the cam (arcs at larger cam angles sit at
smaller polar angles). Consecutive arcs must be tangent: circles of the same kind touch
internally (|c1 - c2| = |R1 - R2|), a convex and a concave one externally (|c1 - c2| = R1 + R2).
The lift is measured from the base circle follower.base_radius, which must equal the contour's
smallest distance from the cam centre (the message gives the value when it does not).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from ...core.errors import InputError, echo
from ...core.files import data_folder, read_text
from ...core.reader import Table
from ...core.units import plain_number, unit_scale
from .arcs import Arc, ArcContour, ContourError, build_arc_contour
from .parametric import SplineContour

# Arcs below a micron or centres beyond 10 m are no valve-gear cam; they also push the tangency
# arithmetic into subnormal or overflowing floats, so they are refused at load time.
MIN_ARC_RADIUS = 1e-6  # m
MAX_CENTRE_DISTANCE = 10.0  # m
MIN_POINTS = 12
MIN_POINT_RADIUS = 1e-9  # m: a contour point at the cam centre (closer than the smallest length) is no contour


@dataclass(frozen=True, eq=False)
class CamSpec:
    kind: str  # "arcs" | "points"
    arcs: ArcContour | None = None
    points: np.ndarray | None = None  # (N, 2) m, cam frame, as given (after rotation)
    spline_degree: int = 5
    rotation: float = 0.0  # rad, already applied to arcs/points
    source: str = "inline"  # where the points came from
    min_radius: float = 0.0  # m, smallest distance of the contour from the cam centre

    def __eq__(self, other) -> bool:
        """Same contour (so viewers can keep a cam mesh when only other sections change)."""
        if not isinstance(other, CamSpec):
            return NotImplemented
        if (self.kind, self.spline_degree, self.rotation) != (other.kind, other.spline_degree, other.rotation):
            return False
        if self.kind == "arcs":
            return self.arcs.arcs == other.arcs.arcs
        return self.points.shape == other.points.shape and bool(np.array_equal(self.points, other.points))

    def __hash__(self) -> int:
        return hash((self.kind, self.arcs.arcs if self.kind == "arcs" else len(self.points)))

    def contour_geometry(self):
        """ArcContour or SplineContour (the spline is built once, on first use)."""
        if self.kind == "arcs":
            return self.arcs
        return self._spline

    @cached_property
    def _spline(self):
        return SplineContour(self.points, self.spline_degree)


def parse_cam_section(table: Table | None, fields: dict) -> CamSpec | None:
    if table is None:
        return None
    file = table.file
    lift = fields.get("lift")
    if lift is not None and lift.law != "contour":
        raise InputError(file, table.prefix, f"[cam] describes a contour, used only with [lift] law = \"contour\" (law is {echo(lift.law)})")
    table.reject_unknown(("rotation", "tolerance", "arcs", "points", "file", "unit", "spline_degree"))
    rotation = table.quantity("rotation", "angle", 0.0)
    given = [k for k in ("arcs", "points", "file") if table.has(k)]
    if len(given) != 1:
        raise InputError(file, table.prefix, "give the contour as exactly one of: arcs ([[cam.arcs]] tables), points, file"
                         + (f" (found {', '.join(given)})" if given else ""))
    if given[0] == "arcs":
        for key in ("unit", "spline_degree"):
            if table.has(key):
                raise table.error(key, "applies to point lists only; arcs take units in each value")
        spec = _parse_arcs(table, rotation)
    else:
        if table.has("tolerance"):
            raise table.error("tolerance", "applies to arcs only")
        spec = _parse_points(table, rotation, fields)
    return spec  # the follower-dependent checks are its gear's (contour_lift), at load time too


def _parse_arcs(table: Table, rotation: float) -> CamSpec:
    raw = table.raw("arcs")
    key = table.key("arcs")
    if not isinstance(raw, list) or not raw or not all(isinstance(a, dict) for a in raw):
        raise InputError(table.file, key, "expected a list of arc tables ([[cam.arcs]] with x, y, radius, kind)")
    c, s = math.cos(rotation), math.sin(rotation)
    arcs = []
    for i, item in enumerate(raw):
        t = Table(item, table.file, f"{key}[{i}]")
        t.reject_unknown(("name", "x", "y", "radius", "kind"))
        x = t.quantity("x", "length", minimum=-MAX_CENTRE_DISTANCE, maximum=MAX_CENTRE_DISTANCE)
        y = t.quantity("y", "length", minimum=-MAX_CENTRE_DISTANCE, maximum=MAX_CENTRE_DISTANCE)
        arcs.append(
            Arc(
                x=c * x - s * y,
                y=s * x + c * y,
                radius=t.quantity("radius", "length", positive=True, minimum=MIN_ARC_RADIUS, maximum=MAX_CENTRE_DISTANCE),
                concave=t.string("kind", "convex", choices=("convex", "concave")) == "concave",
                name=t.string("name", ""),
            )
        )
    tolerance = table.quantity("tolerance", "length", 1e-6, positive=True)
    try:
        contour = build_arc_contour(arcs, tolerance)
    except ContourError as exc:
        where = f"{key}[{exc.index}].{exc.field}" if exc.index is not None else key
        raise InputError(table.file, where, exc.reason) from None
    return CamSpec(kind="arcs", arcs=contour, rotation=rotation, min_radius=contour.min_radius())


_SPLIT = re.compile(r"[,;\s]+")


def _read_points_file(path: Path, file: str, key: str, scale: float) -> np.ndarray:
    """(N, 2) points in the file's unit, or InputError naming the line of the first bad row (a row
    it cannot read, or one outside the physical range: first_bad_point), never the row's content."""
    if not path.exists():
        raise InputError(file, key, f"point file {str(path)!r} not found")

    text = read_text(path, file=file, key=key, prefix=f"point file {path.name}: ")
    rows, lines = [], []
    unreadable = None  # (line, reason) of the first line that is no row: rows before it are checked first
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [p for p in _SPLIT.split(line) if p]
        try:
            values = [float(p) for p in parts]
        except ValueError:
            if not rows:  # a header line
                continue
            unreadable = (number, "expected two numbers x, y")
            break
        if len(values) != 2:
            unreadable = (number, f"expected two numbers x, y, got {len(values)}")
            break
        rows.append(values)
        lines.append(number)
    pts = np.array(rows, dtype=float).reshape(-1, 2)
    bad = first_bad_point(pts, scale)
    if bad is not None and (unreadable is None or lines[bad[0]] < unreadable[0]):
        raise InputError(file, key, f"{path.name} line {lines[bad[0]]}: {bad[1]}")
    if unreadable is not None:
        raise InputError(file, key, f"{path.name} line {unreadable[0]}: {unreadable[1]}")
    return pts


def first_bad_point(pts: np.ndarray, scale: float) -> tuple[int, str] | None:
    """(index, reason) of the first contour point outside the physical range, or None: finite, and
    (in metres, after `unit`) at most MAX_CENTRE_DISTANCE from the cam centre and at least
    MIN_POINT_RADIUS from it (the contour goes round the centre). The reason states the range,
    never the point."""
    with np.errstate(over="ignore", invalid="ignore"):
        metres = np.asarray(pts, dtype=float).reshape(-1, 2) * scale
        finite = np.all(np.isfinite(metres), axis=1)
        radius = np.where(finite, np.hypot(metres[:, 0], metres[:, 1]), 1.0)
    tests = (
        (~finite, "coordinates must be finite numbers (after unit)"),
        (radius > MAX_CENTRE_DISTANCE, f"the point lies more than {MAX_CENTRE_DISTANCE:g} m from the cam centre; check unit"),
        (radius < MIN_POINT_RADIUS, f"the point lies within {MIN_POINT_RADIUS * 1e9:g} nm of the cam centre; a contour "
         "goes round the centre"),
    )
    found = [(int(np.argmax(mask)), reason) for mask, reason in tests if np.any(mask)]
    return min(found, key=lambda item: item[0]) if found else None


def _parse_points(table: Table, rotation: float, fields: dict) -> CamSpec:
    file = table.file
    unit_text = table.string("unit", "m")
    scale = unit_scale(unit_text, "length", file=file, key=table.key("unit"))
    if not scale > 0.0:
        raise table.error("unit", f"not a length unit: {echo(unit_text)}")
    degree = table.number("spline_degree", 5, integer=True)
    if degree not in (3, 5):
        raise table.error("spline_degree", f"must be 3 or 5, got {degree}")
    if table.has("points"):
        key = table.key("points")
        raw = table.raw("points")
        ok = isinstance(raw, list) and all(
            isinstance(p, list) and len(p) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in p)
            for p in raw
        )
        if not ok:
            raise InputError(file, key, f"expected a list of [x, y] number pairs in {unit_text}")
        try:  # a 400-digit int does not fit a float
            pts = np.array([[plain_number(v, file=file, key=key) for v in p] for p in raw], dtype=float).reshape(-1, 2)
        except InputError as exc:
            raise InputError(file, key, exc.reason) from None
        bad = first_bad_point(pts, scale)
        if bad is not None:
            raise InputError(file, f"{key}[{bad[0]}]", bad[1])
        source = "inline"
    else:
        key = table.key("file")
        name = table.string("file")
        path = (data_folder(fields) / name) if not Path(name).is_absolute() else Path(name)
        pts = _read_points_file(path, file, key, scale)
        source = str(path)
    if len(pts) >= 2 and np.allclose(pts[0], pts[-1], rtol=0.0, atol=1e-12 * max(1.0, float(np.abs(pts).max()))):
        pts = pts[:-1]  # a closed list repeats its first point; the spline closes itself
    if len(pts) < MIN_POINTS:
        raise InputError(file, key, f"need at least {MIN_POINTS} points around the cam, got {len(pts)}")
    pts = pts * scale
    c, s = math.cos(rotation), math.sin(rotation)
    pts = np.column_stack([c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1]])
    chord = np.hypot(*(np.roll(pts, -1, axis=0) - pts).T)
    if np.any(chord <= 0.0):
        i = int(np.argmin(chord))
        raise InputError(file, key, f"points {i} and {(i + 1) % len(pts)} coincide")
    ang = np.arctan2(pts[:, 1], pts[:, 0])
    step = np.mod(np.roll(ang, -1) - ang + math.pi, 2.0 * math.pi) - math.pi
    if not (np.all(step < 0.0) or np.all(step > 0.0)) or abs(abs(step.sum()) - 2.0 * math.pi) > 1e-6:
        raise InputError(file, key, "the points must go once around the cam centre, in order (every ray from the centre meeting the contour once)")

    contour = SplineContour(pts, int(degree))
    t = np.arange(16 * len(pts)) * contour.period / (16 * len(pts))  # spacing ~ chord/16: min found to ~(h/16)^2 kappa
    radius = np.hypot(*contour.jets(t, 1)[0])
    spec = CamSpec(kind="points", points=pts, spline_degree=int(degree), rotation=rotation, source=source,
                   min_radius=float(radius.min()))
    spec.__dict__["_spline"] = contour  # the cached_property's slot: reuse, do not rebuild
    return spec


def describe(spec: CamSpec) -> dict[str, Any]:
    """A JSON-able summary of the contour (for summaries and viewers)."""
    if spec.kind == "arcs":
        c = spec.arcs
        return {
            "kind": "arcs",
            "arcs": [
                {"name": a.name, "x_m": a.x, "y_m": a.y, "radius_m": a.radius, "kind": "concave" if a.concave else "convex",
                 "sweep_deg": math.degrees(abs(s))}
                for a, s in zip(c.arcs, c.sweep)
            ],
            "min_radius_m": spec.min_radius,
            "largest_tangency_misfit_m": float(c.gap.max()),
        }
    return {"kind": "points", "count": int(len(spec.points)), "spline_degree": spec.spline_degree,
            "source": spec.source, "min_radius_m": spec.min_radius}
