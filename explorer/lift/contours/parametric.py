"""Follower lift over a parametric contour C(t) (cam frame), by Newton iteration for the contact.

For a translating roller follower (offset e, roller radius r) the roller centre runs on the
pitch curve Q(t) = C(t) + r n(t), n the outward unit normal. Q(t) sits on the follower axis
x = e at the cam angle
    theta(t) = atan2(y, e) - atan2(Q_y, Q_x),   y = sqrt(|Q|^2 - e^2),
so for a cam angle theta* the contact parameter solves theta(t) = theta* (mod 2 pi). A table of
theta(t) gives the start, Newton's method (theta'(t) exact from the jets) polishes it to
rounding, and the lift L = y - y0 and its derivatives with respect to theta follow from the jets
of y(t) and theta(t) by the inverse-function rule (jets.reparametrize). One derivative is used up
by the normal, so a contour with derivatives up to order m gives L up to L^(m-1); missing rows
are NaN, never guessed.

Contours provided here:
- SplineContour: a periodic interpolating spline (degree 5 by default, chord-length parameter)
  through a point list; its accuracy depends on the point density (see points_accuracy()).
- SynthesizedContour: the exact envelope that synthesis (translating.py) produces from a lift
  curve, parametrised by the synthesis cam angle; used for the synthesis -> analysis round trip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from ...core import jets
from .translating import translating_profile

TWO_PI = 2.0 * math.pi


class ParametricContour(Protocol):
    period: float  # the parameter runs over [0, period) once around the cam
    order: int  # highest derivative of C(t) available

    def jets(self, t: np.ndarray, rows: int) -> np.ndarray:
        """(rows, 2, N): C, C', ... at t."""


@dataclass(frozen=True, eq=False)
class SplineContour:
    """Periodic interpolating spline through `points` (N, 2), parameter = chord length."""

    points: np.ndarray
    degree: int = 5
    period: float = field(init=False)
    order: int = field(init=False, default=4)
    spline: object = field(init=False, repr=False)

    def __post_init__(self):
        from scipy.interpolate import make_interp_spline

        pts = np.asarray(self.points, dtype=float)
        closed = np.vstack([pts, pts[:1]])
        t = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(closed, axis=0).T))])
        spline = make_interp_spline(t, closed, k=self.degree, bc_type="periodic")
        object.__setattr__(self, "period", float(t[-1]))
        object.__setattr__(self, "spline", spline)

    def jets(self, t, rows: int) -> np.ndarray:
        t = np.mod(np.asarray(t, dtype=float), self.period)
        return np.stack([self.spline(t, nu=k).T for k in range(rows)])


@dataclass(frozen=True)
class SynthesizedContour:
    """The envelope contour of a roller on `lift` (exact, from translating.py's construction),
    parametrised by the synthesis cam angle; derivatives up to C'' (they use L''')."""

    lift: object
    base_radius: float
    roller_radius: float
    offset: float = 0.0
    period: float = TWO_PI
    order: int = 2

    def jets(self, t, rows: int) -> np.ndarray:
        rows = min(rows, 3)
        t = np.asarray(t, dtype=float)
        d = self.lift.derivatives(t)
        e, r = self.offset, self.roller_radius
        y0 = math.sqrt((self.base_radius + r) ** 2 - e * e)
        y = d[:rows].copy()
        y[0] += y0
        slope = d[1 : rows + 1].copy()  # L' and its derivatives
        nx = -slope
        nx[0] += e
        norm = jets.sqrt(jets.mul(nx, nx) + jets.mul(y, y))
        gx = jets.constant(e, y) - r * jets.div(nx, norm)  # ground-frame contact point
        gy = y - r * jets.div(y, norm)
        cos_t, sin_t = jets.rotation(t, rows)
        cx = jets.mul(cos_t, gx) + jets.mul(sin_t, gy)  # R(-theta) applied
        cy = jets.mul(cos_t, gy) - jets.mul(sin_t, gx)
        return np.stack([cx, cy], axis=1)


def orientation(contour: ParametricContour, samples: int = 2048) -> float:
    """+1 if the parameter runs counter-clockwise (positive signed area), -1 if clockwise."""
    t = np.arange(samples) * contour.period / samples
    p = contour.jets(t, 1)[0]
    area = 0.5 * np.sum(p[0] * np.roll(p[1], -1) - np.roll(p[0], -1) * p[1])
    return 1.0 if area > 0.0 else -1.0


def pitch_jets(contour: ParametricContour, t: np.ndarray, rows: int, roller_radius: float, sign: float) -> np.ndarray:
    """(rows - 1, 2, N) jets of the roller centre Q = C + r n, n outward."""
    c = contour.jets(t, rows)
    dx, dy = c[1:, 0], c[1:, 1]
    speed = jets.sqrt(jets.mul(dx, dx) + jets.mul(dy, dy))
    nx, ny = sign * jets.div(dy, speed), -sign * jets.div(dx, speed)
    return np.stack([c[:-1, 0] + roller_radius * nx, c[:-1, 1] + roller_radius * ny], axis=1)


def _angle_and_height(q: np.ndarray, offset: float) -> tuple[np.ndarray, np.ndarray]:
    """Jets of the cam angle theta(t) at which Q(t) is on the follower axis, and of its height y."""
    qx, qy = q[:, 0], q[:, 1]
    radicand = jets.mul(qx, qx) + jets.mul(qy, qy)
    radicand[0] -= offset * offset
    y = jets.sqrt(radicand)
    theta = jets.atan2(y, jets.constant(offset, y)) - jets.atan2(qy, qx)
    return theta, y


@dataclass(frozen=True, eq=False)
class ParametricLift:
    """LiftCurve of a translating roller follower over a ParametricContour."""

    contour: object
    roller_radius: float
    offset: float
    base_radius: float
    sign: float  # orientation of the parameter
    table_t: np.ndarray  # start values: parameter ...
    table_theta: np.ndarray  # ... against unwrapped, increasing cam angle
    kinks: np.ndarray = field(default_factory=lambda: np.zeros(0))  # cam angles of known derivative jumps
    iterations: int = 40

    @property
    def y0(self) -> float:
        rp = self.base_radius + self.roller_radius
        return math.sqrt(rp * rp - self.offset**2)

    def breakpoints(self) -> np.ndarray:
        return np.asarray(self.kinks, dtype=float)

    def contact_parameter(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float).reshape(-1)
        lo = self.table_theta[0]
        target = lo + np.mod(theta - lo, TWO_PI)
        t = np.interp(target, self.table_theta, self.table_t)
        spacing = 4.0 * self.contour.period / (len(self.table_t) - 1)
        for _ in range(self.iterations):
            q = pitch_jets(self.contour, t, 3, self.roller_radius, self.sign)
            th, _y = _angle_and_height(q, self.offset)
            miss = np.mod(th[0] - target + math.pi, TWO_PI) - math.pi
            step = np.clip(miss / th[1], -spacing, spacing)
            t = t - step
            # quadratic convergence from the table's start: a miss of 1e-12 rad before this step
            # leaves ~1e-24 after it, far below rounding (~1e-14 rad for angles up to 2 pi)
            if np.max(np.abs(miss)) < 1e-12:
                break
        return t

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        t = self.contact_parameter(theta)
        rows = min(self.contour.order + 1, 5)
        q = pitch_jets(self.contour, t, rows, self.roller_radius, self.sign)
        th, y = _angle_and_height(q, self.offset)
        lifted = jets.reparametrize(y, th)
        out = np.full((4, t.size), np.nan)
        out[: min(4, len(lifted))] = lifted[:4]
        out[0] -= self.y0
        return out.reshape((4,) + theta.shape)


class ContourFollowError(ValueError):
    pass


def make_parametric_lift(contour, roller_radius: float, offset: float, base_radius: float,
                         table_size: int = 4096, kinks=()) -> ParametricLift:
    """Tabulate theta(t) for start values; the roller must meet the contour in one sweep."""
    sign = orientation(contour)
    t = np.arange(table_size + 1) * contour.period / table_size
    q = pitch_jets(contour, t, 2, roller_radius, sign)
    if np.any(np.hypot(q[0, 0], q[0, 1]) <= abs(offset)):
        raise ContourFollowError("the follower axis misses the roller path (offset too large)")
    th, _y = _angle_and_height(q, offset)
    theta = np.unwrap(th[0])
    if theta[-1] < theta[0]:
        theta, t = theta[::-1], t[::-1]
    step = np.diff(theta)
    if np.any(step <= 0.0) or abs(theta[-1] - theta[0] - TWO_PI) > 1e-6:
        i = int(np.argmax(step <= 0.0))
        raise ContourFollowError(
            f"the roller cannot follow the contour near cam angle {math.degrees(np.mod(theta[i], TWO_PI)):.3f} deg: "
            "the roller-centre path folds back (undercut, a hollow narrower than the roller, or a pressure angle of 90 deg)"
        )
    return ParametricLift(contour, roller_radius, offset, base_radius, sign, t, theta, np.asarray(kinks, dtype=float))


def points_accuracy(lift, base_radius: float, roller_radius: float, offset: float = 0.0,
                    counts=(90, 180, 360, 720, 1440), samples: int = 3600, degree: int = 5) -> list[dict]:
    """How a point-list cam reproduces the lift it was made from, against the point density.

    The exact contour of `lift` (synthesis) is sampled at n equally spaced cam angles, a periodic
    spline is run through the points, and the analysed lift is compared with `lift` at `samples`
    angles. Returns one row per n: largest lift error (m) and largest errors of L', L'', L'''
    relative to the largest |L'|, |L''|, |L'''|. Smooth contours converge like h^(degree+1) in the
    lift, one order less per derivative; jumps in the law's higher derivatives slow it down."""
    theta = np.arange(samples) * TWO_PI / samples
    exact = lift.derivatives(theta)
    rows = []
    for n in counts:
        grid = np.arange(n) * TWO_PI / n
        pts = translating_profile(lift, grid, base_radius, roller_radius, offset).contour
        analysed = make_parametric_lift(SplineContour(pts, degree), roller_radius, offset, base_radius)
        got = analysed.derivatives(theta)
        row = {"points": int(n), "max_lift_error_m": float(np.max(np.abs(got[0] - exact[0])))}
        for k, name in ((1, "max_velocity_error_rel"), (2, "max_accel_error_rel"), (3, "max_jerk_error_rel")):
            row[name] = float(np.max(np.abs(got[k] - exact[k])) / np.max(np.abs(exact[k])))
        rows.append(row)
    return rows
