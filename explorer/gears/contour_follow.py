"""Analysis: a follower's motion over a given cam contour (arcs or points), for any follower.

The given contour is a parametric curve C(t) in the cam frame (explorer.lift.contours.parametric's
protocol: `period`, `order`, `jets(t, rows)`); arcs come through `ArcChain`, which gives a chain of
tangent arcs (explorer.lift.contours.arcs.ArcContour) exact derivatives of any order.

Each follower states, in closed form on jets in t, at which cam angle theta(t) the contour point
C(t) is the contact and what its own coordinate q(t) is then (a `Relation`): the seed's
"arcs about O and O1" construction for a roller or curved pad on a pivoted arm, the support
function for a flat face (the face touches where the contour's normal is the face's). For a cam
angle theta* the parameter solves theta(t) = theta* (mod 2 pi): a table of theta(t) gives the
start, Newton's method (theta'(t) exact from the jets) polishes it to rounding; q and its
derivatives with respect to theta follow by the inverse-function rule (envelope.derivatives_along).
explorer.lift.contours.parametric.ParametricLift does the same for the translating roller.

A follower that cannot follow the contour (a flat face on a concave stretch, a roller in a hollow
narrower than itself) makes theta(t) run backwards somewhere: refused with the cam angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..core.errors import InputError
from ..lift.contours.arcs import ArcContour
from ..lift.contours.parametric import orientation
from . import jet as J
from .envelope import derivatives_along
from .jet import Jet

TWO_PI = 2.0 * math.pi

# (t) -> (theta(t), q(t)): jets in the contour parameter, 4 rows (rows beyond the contour's order NaN)
Relation = Callable[[np.ndarray], tuple[Jet, Jet]]


@dataclass(frozen=True, eq=False)
class ArcChain:
    """A closed chain of tangent arcs as a parametric contour: parameter = arc length in the order
    the follower meets them (clockwise in the cam frame), exact derivatives of any order."""

    arcs: object  # explorer.lift.contours.arcs.ArcContour
    order: int = 8
    period: float = field(init=False)
    edges: np.ndarray = field(init=False, repr=False)
    _table: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        c = self.arcs
        lengths = np.array([a.radius * abs(s) for a, s in zip(c.arcs, c.sweep)])
        edges = np.concatenate([[0.0], np.cumsum(lengths)])
        table = np.array([[a.x, a.y, a.radius, c.start_angle[k], np.sign(c.sweep[k])] for k, a in enumerate(c.arcs)])
        object.__setattr__(self, "period", float(edges[-1]))
        object.__setattr__(self, "edges", edges)
        object.__setattr__(self, "_table", table)

    def arc_index(self, t) -> np.ndarray:
        t = np.mod(np.asarray(t, dtype=float), self.period)
        return np.clip(np.searchsorted(self.edges, t, side="right") - 1, 0, len(self._table) - 1)

    def jets(self, t, rows: int) -> np.ndarray:
        """(rows, 2, N): C, C', ... at t. On arc k, C = c + R e(a), a = a_k + sign (t - t_k) / R, so
        the m-th derivative is R (sign / R)^m e(a + m pi / 2)."""
        t = np.mod(np.asarray(t, dtype=float).reshape(-1), self.period)
        k = self.arc_index(t)
        cx, cy, radius, start, sign = self._table[k].T
        angle = start + sign * (t - self.edges[k]) / radius
        out = np.empty((rows, 2, t.size))
        scale = radius.copy()
        for m in range(rows):
            out[m, 0] = scale * np.cos(angle + 0.5 * math.pi * m)
            out[m, 1] = scale * np.sin(angle + 0.5 * math.pi * m)
            scale = scale * sign / radius
        out[0, 0] += cx
        out[0, 1] += cy
        return out

    def junctions(self) -> np.ndarray:
        """Parameter values where one arc meets the next (the curvature jumps there)."""
        return self.edges[:-1].copy() if len(self._table) > 1 else np.zeros(0)


def cam_contour(cam):
    """The scene's [cam] contour (explorer.lift.contours.spec.CamSpec) as the gears' analyses take
    it: the arcs, or the parametric contour through the points."""
    return cam.arcs if cam.kind == "arcs" else cam.contour_geometry()


def as_parametric(contour):
    """ArcContour -> ArcChain; a parametric contour (SplineContour, ...) as it is."""
    return ArcChain(contour) if isinstance(contour, ArcContour) else contour


def contour_jets(contour, t: np.ndarray, sign: float) -> tuple[Jet, Jet, Jet, Jet]:
    """(Cx, Cy, nx, ny) as 4-row jets in t: the point and its outward unit normal. The normal is
    built from the jet of C' itself (rows 1..4 of the contour), so it keeps all four rows where
    the contour has four derivatives beyond the point; missing rows are NaN, never guessed."""
    rows = min(contour.order + 1, 5)
    raw = contour.jets(t, rows)
    full = np.full((5, 2, raw.shape[-1]), np.nan)
    full[:rows] = raw
    cx, cy = Jet(full[:4, 0]), Jet(full[:4, 1])
    dx, dy = Jet(full[1:, 0]), Jet(full[1:, 1])
    speed = J.hypot(dx, dy)
    return cx, cy, sign * dy / speed, -sign * dx / speed


DWELL_ULPS = 256.0  # a value within this many ulps of its revolution's largest is rounding


def dwell_floors(derivatives, n_grid: int = 4096) -> np.ndarray:
    """Per derivative row of a lift analysed over a contour, the size below which a value is
    rounding: DWELL_ULPS ulps of the row's largest magnitude over a revolution (a 10 mm lift:
    ~5e-16 m). On the base circle the geometry's lift and velocity are not exactly zero but
    +-1e-17 of rounding (the contact solved by Newton, the arm's angle from the loop); their sign
    changes would each be a take-up, a seating and a velocity zero to polish (hundreds a
    revolution: tens of seconds of the lash and forces effects)."""
    theta = np.linspace(0.0, TWO_PI, n_grid, endpoint=False)
    d = np.asarray(derivatives(theta), dtype=float)
    return DWELL_ULPS * np.finfo(float).eps * np.max(np.abs(d), axis=1)


def exact_dwell(d: np.ndarray, floors: np.ndarray) -> np.ndarray:
    """`d` (rows: lift and its derivatives at some angles) with the dwell stated exactly: where
    the lift and the velocity are both rounding (at most `floors`), every row is 0 -- the valve
    rests on its seat and the base circle, as a lift law's dwell is exactly 0."""
    rest = (np.abs(d[0]) <= floors[0]) & (np.abs(d[1]) <= floors[1])
    if not np.any(rest):
        return d
    d = np.array(d, dtype=float, copy=True)
    d[:, rest] = 0.0
    return d


@dataclass(frozen=True, eq=False)
class ContourMotion:
    """A follower coordinate q(theta) over a contour (a LiftCurve-like: `derivatives(theta)` gives
    q, dq/dtheta, d2q/dtheta2, d3q/dtheta3 as rows; `breakpoints()` the cam angles of arc junctions)."""

    relation: Relation
    period: float
    table_t: np.ndarray  # start values: parameter ...
    table_theta: np.ndarray  # ... against unwrapped, increasing cam angle
    kinks: np.ndarray
    iterations: int = 40
    file: str = "<memory>"
    key: str = "cam"

    def breakpoints(self) -> np.ndarray:
        return np.asarray(self.kinks, dtype=float)

    def parameter(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float).reshape(-1)
        lo = self.table_theta[0]
        target = lo + np.mod(theta - lo, TWO_PI)
        t = np.interp(target, self.table_theta, self.table_t)
        spacing = 4.0 * abs(self.table_t[1] - self.table_t[0])
        for _ in range(self.iterations):
            th, _q = self.relation(t)
            miss = np.mod(th.c[0] - target + math.pi, TWO_PI) - math.pi
            t = t - np.clip(miss / th.c[1], -spacing, spacing)
            # quadratic convergence from the table's start: a miss of 1e-12 rad before this step
            # leaves ~1e-24 after it, far below rounding
            if np.max(np.abs(miss)) < 1e-12:
                return t
        worst = int(np.nanargmax(np.where(np.isfinite(miss), np.abs(miss), np.inf)))
        if not abs(miss[worst]) < 1e-9:  # bounded: a contact not found is said, never returned
            raise InputError(self.file, self.key, f"the follower's contact on the contour was not found near cam angle "
                             f"{math.degrees(float(theta[worst])) % 360.0:.2f} deg (miss {abs(miss[worst]):.2g} rad)")
        return t

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        t = self.parameter(theta)
        th, q = self.relation(t)
        out = derivatives_along(q.c, th.c)
        return out.reshape((4,) + theta.shape)


def make_contour_motion(relation: Relation, contour, *, file: str, key: str, what: str,
                        table_size: int = 4096) -> ContourMotion:
    """Tabulate theta(t) once round the contour; it must rise steadily through one turn, else the
    follower cannot follow the contour (named by `key`, with the cam angle)."""
    t = np.arange(table_size + 1) * contour.period / table_size
    with np.errstate(invalid="ignore", divide="ignore"):
        th, _q = relation(t)
    theta = np.unwrap(th.c[0])
    if not np.all(np.isfinite(theta)):
        i = int(np.argmax(~np.isfinite(theta)))
        raise InputError(file, key, f"{what} cannot reach the contour near contour point {i} of {table_size}: "
                         "the linkage does not close there")
    if theta[-1] < theta[0]:
        theta, t = theta[::-1], t[::-1]
    step = np.diff(theta)
    if np.any(step <= 0.0) or abs(theta[-1] - theta[0] - TWO_PI) > 1e-6:
        i = int(np.argmax(step <= 0.0)) if np.any(step <= 0.0) else 0
        raise InputError(
            file, key,
            f"{what} cannot follow the contour near cam angle {math.degrees(np.mod(theta[i], TWO_PI)):.2f} deg: its "
            "contact runs backwards there (a concave stretch under a flat face, a hollow narrower than the roller or "
            "pad, or a pressure angle of 90 deg)",
        )
    kinks = np.zeros(0)
    if hasattr(contour, "junctions"):
        tj = contour.junctions()
        if tj.size:
            kinks = np.unique(np.mod(relation(tj)[0].c[0], TWO_PI))
    elif hasattr(contour, "spline") and getattr(contour, "degree", 5) == 3:
        knots = np.unique(np.mod(contour.spline.t, contour.period))
        kinks = np.unique(np.mod(relation(knots)[0].c[0], TWO_PI))
    return ContourMotion(relation, contour.period, t, theta, kinks, file=file, key=key)


def contour_sign(contour) -> float:
    """+1 if the contour's parameter runs counter-clockwise, -1 clockwise."""
    return orientation(contour)


BASE_SAMPLES = 2048  # angles at which a given contour's lowest lift is found
BASE_TOLERANCE = 1e-6  # m: a rest this far off is a contour drawn for another base circle


def check_base_circle(lift_of: Callable[[np.ndarray], np.ndarray], *, file: str, rests: str) -> None:
    """A gear analysed over a given contour rests where follower.base_radius says: its lowest lift
    over a revolution (`lift_of(theta)` -> lift) is 0 within BASE_TOLERANCE, else one line naming
    follower.base_radius; `rests` says what would rest off what ("the valve would rest {} off its
    seat", the offset in mm filled in)."""
    base = float(np.min(lift_of(np.linspace(0.0, TWO_PI, BASE_SAMPLES, endpoint=False))))
    if abs(base) > BASE_TOLERANCE:
        raise InputError(file, "follower.base_radius", "the contour's base circle does not match follower.base_radius "
                         f"({rests.format(f'{base * 1e3:.4g} mm')})")
