"""Cams made of tangent circular arcs, and the exact lift of a translating roller follower on them.

Conventions (as in translating.py): the cam turns counter-clockwise by theta about the origin;
the follower axis is parallel to y at x = e (the offset); a cam-frame point X is at R(theta) X
in the ground frame. The roller therefore runs over the contour clockwise in the cam frame, and
the arcs are kept in that order ("the order the roller meets them").

Analysis, closed form per arc: while the roller touches arc k (centre c, radius R), its centre
lies on the offset circle of radius rho = R + r (convex arc) or R - r (concave arc) about c.
With c(theta) = R(theta) c0 and the roller centre on x = e,
    y = c_y + s sqrt(rho^2 - (e - c_x)^2),   s = +1 convex (upper root), -1 concave (lower root),
and the lift is L = y - y0, y0 = sqrt((base_radius + r)^2 - e^2). Its derivatives come from the
exact jets of cos/sin (explorer/core/jets.py), not from differences. The active arc changes exactly
when the contact point passes a junction: those cam angles are the curve's breakpoints, where L'' jumps
(the radius of curvature jumps) and L' has a kink - Schenker's velocity cusp at F.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ...core import jets
from ..curves import wrap_two_pi

TWO_PI = 2.0 * math.pi


class ContourError(ValueError):
    """Bad contour geometry; `index` is the arc (or None for the whole contour), `field` the key."""

    def __init__(self, reason: str, index: int | None = None, field: str | None = None):
        super().__init__(reason)
        self.reason = reason
        self.index = index
        self.field = field


@dataclass(frozen=True)
class Arc:
    x: float  # m, centre in the cam frame
    y: float  # m
    radius: float  # m, > 0
    concave: bool = False  # concave: centre outside the cam material
    name: str = ""

    @property
    def centre(self) -> np.ndarray:
        return np.array([self.x, self.y])

    @property
    def sign(self) -> float:
        return -1.0 if self.concave else 1.0

    def label(self, index: int) -> str:
        return f"arc {index} ({self.name})" if self.name else f"arc {index}"


@dataclass(frozen=True, eq=False)
class ArcContour:
    """A closed chain of tangent arcs, in the order the roller meets them (clockwise, cam frame).

    start[k] is the junction where arc k begins (shared with the end of arc k-1); start_angle[k]
    its polar angle about arc k's centre, sweep[k] the signed angle arc k turns through about its
    centre (negative for convex arcs, which run clockwise about their centre, positive for concave).
    """

    arcs: tuple[Arc, ...]
    start: np.ndarray  # (n, 2)
    start_angle: np.ndarray  # (n,) rad
    sweep: np.ndarray  # (n,) rad, signed
    gap: np.ndarray  # (n,) m, misfit of the tangency at the start of each arc
    reversed_input: bool = False  # the arcs were given counter-clockwise and have been reversed

    @property
    def n(self) -> int:
        return len(self.arcs)

    def outward_normal(self, k: int, point: np.ndarray) -> np.ndarray:
        arc = self.arcs[k]
        u = (np.asarray(point) - arc.centre) / arc.radius
        return u * arc.sign

    def min_radius(self) -> float:
        """Smallest distance of the contour from the cam centre (the base circle for usual cams)."""
        best = math.inf
        for k, arc in enumerate(self.arcs):
            d = math.hypot(arc.x, arc.y)
            candidates = [np.hypot(*self.start[k]), np.hypot(*self.start[(k + 1) % self.n])]
            if d == 0.0:
                candidates.append(arc.radius)
            else:
                nearest = math.atan2(-arc.y, -arc.x)  # direction from the centre towards the origin
                if _in_span(nearest, self.start_angle[k], self.sweep[k]):
                    candidates.append(abs(d - arc.radius))
            best = min(best, float(min(candidates)))
        return best

    def sample(self, per_arc: int = 64) -> np.ndarray:
        """Points along the contour in roller order (clockwise), `per_arc` per arc, no repeats."""
        out = []
        for k, arc in enumerate(self.arcs):
            a = self.start_angle[k] + self.sweep[k] * np.arange(per_arc) / per_arc
            out.append(arc.centre + arc.radius * np.column_stack([np.cos(a), np.sin(a)]))
        return np.concatenate(out)

    def points_by_arc_length(self, n: int) -> np.ndarray:
        """n points evenly spaced by arc length along the contour, roller order, from arc 0's start."""
        lengths = np.array([a.radius * abs(s) for a, s in zip(self.arcs, self.sweep)])
        edges = np.concatenate([[0.0], np.cumsum(lengths)])
        s = np.arange(n) * edges[-1] / n
        k = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, self.n - 1)
        frac = (s - edges[k]) / lengths[k]
        angle = self.start_angle[k] + self.sweep[k] * frac
        radius = np.array([a.radius for a in self.arcs])[k]
        centres = np.array([[a.x, a.y] for a in self.arcs])[k]
        return centres + radius[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])


def _in_span(angle, start, sweep, slack: float = 1e-12):
    """Whether polar angle `angle` (about the arc centre) lies on an arc from `start` through `sweep`."""
    if abs(sweep) >= TWO_PI - 1e-15:
        return np.ones_like(np.asarray(angle, dtype=float), dtype=bool)
    offset = np.mod((np.asarray(angle) - start) * np.sign(sweep), TWO_PI)
    return (offset <= abs(sweep) + slack) | (offset >= TWO_PI - slack)


def _junction(a: Arc, b: Arc) -> tuple[np.ndarray, float]:
    """Tangent point of consecutive arcs a -> b and the tangency misfit (m).

    Arcs of the same kind touch internally (|ca - cb| = |Ra - Rb|), a convex and a concave arc
    externally (|ca - cb| = Ra + Rb); the tangent point lies on the line of centres."""
    ca, cb = a.centre, b.centre
    dist = float(np.hypot(*(cb - ca)))
    if a.concave == b.concave:
        if a.radius == b.radius:
            raise ValueError("same kind and radius: the arcs are one circle or never touch tangentially")
        big, small = (a, b) if a.radius > b.radius else (b, a)
        direction = small.centre - big.centre
        norm = float(np.hypot(*direction))
        expected = big.radius - small.radius
        if norm == 0.0:
            raise ValueError("concentric arcs of different radii never touch")
        point = big.centre + big.radius * direction / norm
    else:
        expected = a.radius + b.radius
        direction = cb - ca
        if dist == 0.0:
            raise ValueError("a convex and a concave arc with the same centre never touch")
        point = ca + a.radius * direction / dist
    return point, abs(dist - expected)


def build_arc_contour(arcs: list[Arc] | tuple[Arc, ...], tolerance: float = 1e-6) -> ArcContour:
    """Validate a closed chain of arcs (either direction) and compute junctions and spans."""
    arcs = tuple(arcs)
    if not arcs:
        raise ContourError("list at least one arc", None, "arcs")
    for k, arc in enumerate(arcs):
        if not (math.isfinite(arc.radius) and arc.radius > 0.0):
            raise ContourError(f"radius must be positive, got {arc.radius!r}", k, "radius")
    if len(arcs) == 1:
        if arcs[0].concave:
            raise ContourError("a cam of one arc must be convex", 0, "kind")
        a = arcs[0]
        start = a.centre + np.array([0.0, a.radius])
        contour = ArcContour(arcs, start[None, :], np.array([math.pi / 2]), np.array([-TWO_PI]), np.zeros(1))
        _check_star_shaped(contour)
        return contour
    last_error = None
    for reverse in (False, True):
        chain = arcs[::-1] if reverse else arcs
        n = len(chain)
        starts, gaps = [], []
        for k in range(n):
            prev = chain[k - 1]
            # tangency does not depend on the direction, so these errors come from the first pass,
            # where chain == arcs and k is the index the user wrote
            try:
                point, gap = _junction(prev, chain[k])
            except ValueError as exc:
                raise ContourError(f"{chain[k].label(k)} cannot follow {prev.label((k - 1) % n)}: {exc}", k, "radius") from None
            if gap > tolerance:
                kind = "internally" if prev.concave == chain[k].concave else "externally"
                raise ContourError(
                    f"{chain[k].label(k)} is not tangent to the arc before it: the circles should touch {kind} "
                    f"but miss by {gap * 1e3:.6g} mm (tolerance {tolerance * 1e3:.3g} mm)",
                    k,
                    "x",
                )
            starts.append(point)
            gaps.append(gap)
        starts = np.array(starts)
        angle_start = np.array([math.atan2(*(starts[k] - chain[k].centre)[::-1]) for k in range(n)])
        angle_end = np.array([math.atan2(*(starts[(k + 1) % n] - chain[k].centre)[::-1]) for k in range(n)])
        sweep = np.empty(n)
        for k, arc in enumerate(chain):
            if arc.concave:  # runs counter-clockwise about its own centre
                sweep[k] = np.mod(angle_end[k] - angle_start[k], TWO_PI)
            else:  # convex: clockwise about its own centre
                sweep[k] = -np.mod(angle_start[k] - angle_end[k], TWO_PI)
        turning = float(sweep.sum())
        if abs(turning + TWO_PI) < 1e-6:
            contour = ArcContour(chain, starts, angle_start, sweep, np.array(gaps), reversed_input=reverse)
            _check_star_shaped(contour)
            return contour
        last_error = turning
    raise ContourError(
        "the arcs do not form one closed contour around the cam: following them, the tangent turns "
        f"{math.degrees(last_error):.6g} deg instead of 360 deg (check each arc's kind convex/concave and the order)",
        None,
        "arcs",
    )


def _check_star_shaped(contour: ArcContour) -> None:
    """Every ray from the cam centre must cross the contour once: the polar angle of the contour
    falls steadily (roller order is clockwise) through exactly one turn."""
    per_arc = 96
    pts = contour.sample(per_arc=per_arc)
    ang = np.arctan2(pts[:, 1], pts[:, 0])
    step = np.mod(np.roll(ang, -1) - ang + math.pi, TWO_PI) - math.pi  # wrapped to [-pi, pi)
    # a tolerated tangency misfit may step back by up to gap / radius at a junction
    slack = 2.0 * float(contour.gap.max()) / float(np.hypot(*pts.T).min())
    back = step >= slack
    if np.any(back) or abs(step.sum() + TWO_PI) > 1e-6:
        k = int(np.argmax(back)) // per_arc if np.any(back) else None
        if k is not None and contour.reversed_input:
            k = contour.n - 1 - k
        raise ContourError(
            "the contour must wind once around the cam centre with every ray from the centre meeting it once "
            "(is the cam centre inside the contour?)",
            k,
            "x" if k is not None else "arcs",
        )


@dataclass(frozen=True, eq=False)
class ArcLift:
    """Exact roller-centre lift of a translating roller follower over an arc contour (a LiftCurve)."""

    contour: ArcContour
    roller_radius: float
    offset: float
    base_radius: float
    # computed by make_arc_lift:
    junction_angles: np.ndarray  # (n,) cam angle at which the contact reaches the start of arc k, in [0, 2 pi)
    order: np.ndarray  # arc indices sorted by junction angle
    sorted_angles: np.ndarray

    @property
    def y0(self) -> float:
        rp = self.base_radius + self.roller_radius
        return math.sqrt(rp * rp - self.offset * self.offset)

    def breakpoints(self) -> np.ndarray:
        if self.contour.n == 1:  # a single circle (an eccentric) has no junction
            return np.zeros(0)
        return np.sort(self.junction_angles)

    def active_arc(self, theta) -> np.ndarray:
        """Index of the arc the roller touches at cam angle theta (the later arc at a junction)."""
        x = wrap_two_pi(np.asarray(theta, dtype=float))
        i = self.sorted_angles.searchsorted(x, side="right") - 1  # -1 wraps to the last
        return self.order[i]

    def arc_candidate(self, k: int, theta: np.ndarray, rows: int = 4) -> np.ndarray:
        """Jet (rows, N) of the roller-centre height y if the roller touched arc k (full circle)."""
        return roller_height_on_arc(self.contour.arcs[k], theta, self.roller_radius, self.offset, rows)

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        flat = theta.reshape(-1)
        # Each angle gets its active arc's parameters, then one evaluation serves all arcs: the
        # same arithmetic as roller_height_on_arc (written out in _roller_height4), without a pass
        # per arc (the elastic solver evaluates this drive every revolution).
        x, y, rho, sign = self._arc_parameters.take(self.active_arc(flat), axis=1)  # (faster than [:, i])
        out = _roller_height4(x, y, rho, sign, flat, self.offset, self.y0)
        return out.reshape((4,) + theta.shape)

    @cached_property
    def _arc_parameters(self) -> np.ndarray:
        """(4, n): centre x, centre y, offset radius rho = R +- r and branch sign of every arc."""
        return np.array([[a.x, a.y, _offset_radius(a, self.roller_radius), a.sign] for a in self.contour.arcs]).T

    def contact_angle_on_arc(self, k: int, theta: np.ndarray) -> np.ndarray:
        """Polar angle (cam frame, about arc k's centre) of the contact point if arc k is touched."""
        arc = self.contour.arcs[k]
        y = self.arc_candidate(k, theta, rows=1)[0]
        c, s = np.cos(theta), np.sin(theta)
        gx, gy = arc.x * c - arc.y * s, arc.x * s + arc.y * c
        # contact and roller centre lie on the same ray from the arc centre (see module docstring)
        return np.arctan2(y - gy, self.offset - gx) - theta


def roller_height_on_arc(arc: Arc, theta, roller_radius: float, offset: float, rows: int = 4) -> np.ndarray:
    """Jet (rows, N) in theta of the roller-centre height y while the roller touches `arc`:
    y = c_y + s sqrt(rho^2 - (e - c_x)^2), c = R(theta) c0, rho = R +- r (module docstring)."""
    return _roller_height(arc.x, arc.y, _offset_radius(arc, roller_radius), arc.sign, theta, offset, rows)


def _offset_radius(arc: Arc, roller_radius: float) -> float:
    """Radius of the roller-centre path about the arc's centre."""
    return arc.radius + roller_radius if not arc.concave else arc.radius - roller_radius


def _roller_height(x, y, rho, sign, theta, offset: float, rows: int) -> np.ndarray:
    """Jet of y = c_y + sign sqrt(rho^2 - (e - c_x)^2) for centre(s) (x, y) turned by theta;
    x, y, rho, sign are scalars or arrays shaped like theta."""
    cos_t, sin_t = jets.rotation(np.asarray(theta, dtype=float), rows)
    cx = x * cos_t - y * sin_t  # ground-frame centre, exact jets in theta
    cy = x * sin_t + y * cos_t
    u = -cx
    u[0] = u[0] + offset
    radicand = -jets.mul(u, u)
    radicand[0] = radicand[0] + rho * rho
    return cy + sign * jets.sqrt(radicand)


def _roller_height4(x, y, rho, sign, theta, offset: float, y0: float) -> np.ndarray:
    """_roller_height for four rows, minus y0, written out: the same operations in the same order
    (bit-identical), on rows instead of jets. The elastic solver evaluates the drive at every node
    of every revolution, and the jet version spent most of its time on (4, N) temporaries.

    With A = c_x, B = c_y (the centre turned by theta) the rows of the centre are c_x: A, -B, -A, B
    and c_y: B, A, -B, -A; u = e - c_x: e - A, B, A, -B; the radicand f = rho^2 - u^2 (Leibniz)
    and g = sqrt(f) follow jets.mul and jets.sqrt term by term."""
    c, s = np.cos(theta), np.sin(theta)
    A = x * c
    A -= y * s
    B = x * s
    B += y * c
    u0 = offset - A
    p = u0 * B
    q = u0 * A
    # radicand rows: -(u u)^(n), (u u)^(n) = sum_k C(n, k) u_k u_(n-k) accumulated as in jets.mul
    f0 = rho * rho
    f0 -= u0 * u0
    f1 = -2.0 * p  # -(u0 B + B u0)
    f2 = 2.0 * B
    f2 *= B
    f2 += q
    f2 += q
    np.negative(f2, out=f2)  # -((u0 A + 2 B B) + A u0)
    f3 = 3.0 * B
    f3 *= A
    f3 -= p
    t3 = 3.0 * A
    t3 *= B
    f3 += t3
    f3 -= p
    np.negative(f3, out=f3)  # -((((-B) u0 + 3 B A) + 3 A B) + (-B) u0)
    # g = sqrt(f): g1 = f1 / 2g0, g2 = (f2 - 2 g1 g1) / 2g0, g3 = (f3 - (3 g1 g2 + 3 g2 g1)) / 2g0
    g0 = np.sqrt(f0)
    twice = 2.0 * g0
    g1 = f1 / twice
    g2 = 2.0 * g1
    g2 *= g1
    np.subtract(f2, g2, out=g2)
    g2 /= twice
    g3 = 3.0 * g1
    g3 *= g2
    t3 = np.multiply(3.0, g2, out=t3)
    t3 *= g1
    g3 += t3
    np.subtract(f3, g3, out=g3)
    g3 /= twice
    out = np.empty((4,) + theta.shape)
    o0, o1, o2, o3 = out
    np.multiply(sign, g0, out=o0)
    o0 += B
    o0 -= y0
    np.multiply(sign, g1, out=o1)
    o1 += A
    np.multiply(sign, g2, out=o2)
    np.subtract(o2, B, out=o2)  # -B + sign g2
    np.multiply(sign, g3, out=o3)
    np.subtract(o3, A, out=o3)
    return out


def make_arc_lift(contour: ArcContour, roller_radius: float, offset: float, base_radius: float) -> ArcLift:
    """The lift over `contour`, checked so that the roller can follow every arc in order.

    Raises ContourError (field "roller_radius" or "offset") when it cannot."""
    r, e = roller_radius, offset
    for k, arc in enumerate(contour.arcs):
        if arc.concave and arc.radius <= r:
            raise ContourError(
                f"undercut: the roller (radius {r * 1e3:.6g} mm) does not fit into concave {arc.label(k)} "
                f"of radius {arc.radius * 1e3:.6g} mm",
                k,
                "roller_radius",
            )
    angles = np.empty(contour.n)
    for k in range(contour.n):
        point = contour.start[k]
        q = point + r * contour.outward_normal(k, point)
        rq = float(np.hypot(*q))
        if rq <= abs(e):
            raise ContourError(f"the follower axis (offset {e * 1e3:.6g} mm) misses the roller path at {contour.arcs[k].label(k)}", k, "offset")
        y = math.sqrt(rq * rq - e * e)
        angles[k] = math.atan2(y, e) - math.atan2(q[1], q[0])
    unwrapped = angles[0] + np.mod(angles - angles[0], TWO_PI)
    if contour.n > 1 and np.any(np.diff(unwrapped) <= 0.0):
        k = int(np.argmax(np.diff(unwrapped) <= 0.0)) + 1
        raise ContourError(
            f"the roller (radius {r * 1e3:.6g} mm) cannot follow the contour at {contour.arcs[k].label(k)}: "
            "it would touch the arcs out of order (undercut or a hollow narrower than the roller)",
            k,
            "roller_radius",
        )
    junction = np.mod(angles, TWO_PI)
    order = np.argsort(junction, kind="stable")
    lift = ArcLift(contour, r, e, base_radius, junction, order, junction[order])
    _check_contacts(lift)
    return lift


def _check_contacts(lift: ArcLift, samples: int = 33) -> None:
    """Inside each arc's interval of cam angles the contact must stay on that arc and move along it
    steadily; otherwise the roller leaves the contour (pressure angle reaching 90 deg)."""
    contour = lift.contour
    n = contour.n
    for k in range(n):
        a = lift.junction_angles[k]
        b = lift.junction_angles[(k + 1) % n] if n > 1 else a + TWO_PI
        span = np.mod(b - a, TWO_PI) if n > 1 else TWO_PI
        theta = a + span * (np.arange(1, samples) / samples)
        arc = contour.arcs[k]
        rho = arc.radius + arc.sign * lift.roller_radius
        ground = np.column_stack([arc.x * np.cos(theta) - arc.y * np.sin(theta), arc.x * np.sin(theta) + arc.y * np.cos(theta)])
        if np.any(np.abs(lift.offset - ground[:, 0]) >= rho):
            raise ContourError(f"the roller loses {arc.label(k)} (follower axis too far from it)", k, "offset")
        phi = lift.contact_angle_on_arc(k, theta)
        progress = np.mod((phi - contour.start_angle[k]) * np.sign(contour.sweep[k]), TWO_PI)
        if n > 1 and (np.any(progress > abs(contour.sweep[k]) + 1e-9) or np.any(np.diff(progress) <= 0.0)):
            raise ContourError(
                f"the roller cannot follow {arc.label(k)}: its contact point leaves the arc "
                "(pressure angle reaches 90 deg, or the roller is too large for this contour)",
                k,
                "roller_radius",
            )
