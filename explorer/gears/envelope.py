"""The cam as the envelope of the follower's working surface (Schenker's "Rueckwaertskonstruktion").

Backwards synthesis: once the follower's pose is known at every cam angle theta (from the wanted
valve lift, through the valve train's closed forms), the cam is what the follower's working
surface sweeps out in the cam's frame. Two kinds of working surface cover every follower here:

circle  a roller, a curved pad or a crowned face, seen in the cam plane: a circle of radius r
        about a point C(theta) that moves with the follower (the pad's centre of curvature). The
        cam is the pitch curve P = Rot(-theta) C moved by r towards the cam.
line    a flat face or flat pad: the line {X : n(phi) . X = h} with unit normal n(phi) pointing
        from the cam to the follower. In the cam frame its normal angle is beta = phi - theta and
        h is the line's support value; the cam is the envelope of these lines,
            X = h n(beta) + h_beta t(beta),   t = dn/dbeta,   rho = h + h_beta_beta,
        the support-function form of a convex curve (h_beta = dh/dbeta). For the translating flat
        face, phi = 90 deg and h = Rb + s, so X = (s', Rb + s) in the ground frame (the contact's
        offset on the face is ds/dtheta) and rho = Rb + s + s''.

Conventions as in explorer.lift.contours.translating: cam centre at the origin, the cam turns
counter-clockwise by theta; a ground point X is Rot(-theta) X in the cam frame. Inputs are jets in
theta (explorer.gears.jet); every formula is closed form on them, so the contour, its curvature
and the contact point's velocity carry the exact derivatives of the valve lift.

A circle's centre path in the ground frame, C(theta), gives the pitch curve's tangent and second
derivative without turning the frame: P' = Rot(-theta) D, D = C' - J C, and the cross product
P' x P'' = D x (C'' - 2 J C' - C) (J = rotation by +90 deg), since rotations keep both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..core import jets
from ..core.errors import InputError
from . import jet as J
from .jet import Jet

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class CamSurface:
    """The cam at the contact with the follower, per cam angle (arrays of the grid's length)."""

    theta: np.ndarray  # rad
    contour: np.ndarray  # (N, 2) m, cam frame: the contact point on the cam
    radius: np.ndarray  # m, signed radius of curvature of the cam there (> 0 convex, < 0 concave)
    contact: np.ndarray  # (N, 2) m, ground frame
    contact_rate: np.ndarray  # (N, 2) m/rad, d(contact)/dtheta in the ground frame
    normal: np.ndarray  # (N, 2) ground frame, unit, from the cam towards the follower

    @property
    def tangent(self) -> np.ndarray:
        """(N, 2) unit tangent: the normal turned by -90 deg (along the cam's surface motion at the
        contact for a cam turning counter-clockwise under a follower on its outside)."""
        return np.column_stack([self.normal[:, 1], -self.normal[:, 0]])


def _rotate_to_cam(theta, xy: np.ndarray) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.column_stack([c * xy[:, 0] + s * xy[:, 1], -s * xy[:, 0] + c * xy[:, 1]])


def derivatives_along(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """explorer.core.jets.reparametrize(y, x) taken along increasing x: where x' < 0 the jets are
    turned to -x and the odd rows turned back (multiplying by -1 is exact). The same numbers,
    but numpy's float power of a negative base (x'^3 in the inverse-function rule) takes the
    C library's slow path, about a hundred times slower than of a positive one."""
    sign = np.where(x[1] < 0.0, -1.0, 1.0)
    out = jets.reparametrize(y, x * sign)
    out[1::2] *= sign
    return out


def line_contact(theta, normal_angle: Jet, support: Jet) -> tuple[Jet, Jet]:
    """The contact point (x, y) of a flat working surface, ground frame, as jets in theta (valid to
    the second derivative): X = h n(phi) + w t(phi), w = h_beta = h' / beta'."""
    beta = normal_angle - Jet.variable(np.asarray(theta, dtype=float))
    w = support.shift() / beta.shift()  # h_beta as a jet in theta (known to the 2nd derivative)
    c, s = J.cos(normal_angle), J.sin(normal_angle)
    return support * c - w * s, support * s + w * c


def line_envelope(theta, normal_angle: Jet, support: Jet) -> CamSurface:
    """Cam of a flat working surface: the envelope of the lines n(phi) . X = h (module docstring).

    normal_angle phi and support h are jets in theta. The contact's distance along the face from
    the foot of the perpendicular through the cam centre is w = h_beta = h' / beta'."""
    theta = np.asarray(theta, dtype=float)
    x, y = line_contact(theta, normal_angle, support)
    beta = normal_angle - Jet.variable(theta)
    h_beta = derivatives_along(support.c, beta.c)  # h, h_beta, h_beta_beta, ...
    radius = h_beta[0] + h_beta[2]
    contact = np.column_stack([x.c[0], y.c[0]])
    n = normal_angle.c[0]
    return CamSurface(
        theta=theta, contour=_rotate_to_cam(theta, contact), radius=radius, contact=contact,
        contact_rate=np.column_stack([x.c[1], y.c[1]]), normal=np.column_stack([np.cos(n), np.sin(n)]),
    )


def _circle_normal(cx: Jet, cy: Jet) -> tuple[Jet, Jet, Jet, Jet, Jet]:
    """D = C' - J C (the pitch curve's tangent in the ground frame), its length and the outward
    unit normal J D / |D| (the cam turns ccw: the pitch curve runs clockwise in the cam frame)."""
    dx = cx.shift() + cy
    dy = cy.shift() - cx
    speed = J.hypot(dx, dy)
    return dx, dy, speed, -dy / speed, dx / speed


def circle_contact(theta, cx: Jet, cy: Jet, radius: float) -> tuple[Jet, Jet]:
    """The contact point (x, y) of a circular working surface, ground frame, as jets in theta
    (valid to the second derivative): the centre moved by the radius towards the cam."""
    _dx, _dy, _speed, nx, ny = _circle_normal(cx, cy)
    return cx - radius * nx, cy - radius * ny


def circle_envelope(theta, cx: Jet, cy: Jet, radius: float) -> CamSurface:
    """Cam of a circular working surface of `radius` about the ground point (cx, cy)(theta): the
    pitch curve moved by the radius towards the cam (the envelope of the circles)."""
    theta = np.asarray(theta, dtype=float)
    dx, dy, speed, nx, ny = _circle_normal(cx, cy)
    bx = cx.c[2] + 2.0 * cy.c[1] - cx.c[0]  # C'' - 2 J C' - C
    by = cy.c[2] - 2.0 * cx.c[1] - cy.c[0]
    cross = dx.c[0] * by - dy.c[0] * bx
    with np.errstate(divide="ignore"):
        pitch_radius = -(speed.c[0] ** 3) / cross  # > 0 where the pitch curve is convex
    x = cx - radius * nx
    y = cy - radius * ny
    contact = np.column_stack([x.c[0], y.c[0]])
    return CamSurface(
        theta=theta, contour=_rotate_to_cam(theta, contact), radius=pitch_radius - radius, contact=contact,
        contact_rate=np.column_stack([x.c[1], y.c[1]]), normal=np.column_stack([nx.c[0], ny.c[0]]),
    )


@dataclass(frozen=True)
class EnvelopeContour:
    """A synthesised cam as a parametric contour (explorer.lift.contours.parametric's protocol),
    the parameter being the synthesis cam angle: the contact point turned into the cam frame,
    X(t) = Rot(-t) X_ground(t), exact to the second derivative. For exports at any density and for
    the analysis round trip (synthesis -> contour -> analysis)."""

    contact: Callable[[np.ndarray], tuple[Jet, Jet]]  # theta -> ground contact point jets
    period: float = TWO_PI
    order: int = 2

    def jets(self, t, rows: int) -> np.ndarray:
        t = np.asarray(t, dtype=float).reshape(-1)
        x, y = self.contact(t)
        tj = Jet.variable(t)
        c, s = J.cos(tj), J.sin(tj)
        cam_x, cam_y = c * x + s * y, c * y - s * x
        return np.stack([cam_x.c[:rows], cam_y.c[:rows]], axis=1)


# --------------------------------------------------------------------------------------------
# surface velocities at a contact (for the tribology: entrainment and sliding)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SurfaceVelocities:
    """Velocities along the common tangent at a contact, per unit camshaft speed (m/rad; times
    omega gives m/s). u1, u2: each surface's velocity relative to the contact point; the
    entrainment (rolling) velocity is their mean, the sliding velocity their difference."""

    first: np.ndarray
    second: np.ndarray

    @property
    def entrainment(self) -> np.ndarray:
        return 0.5 * (self.first + self.second)

    @property
    def sliding(self) -> np.ndarray:
        return self.first - self.second


def surface_velocities(tangent: np.ndarray, contact_rate: np.ndarray, first_velocity: np.ndarray,
                       second_velocity: np.ndarray) -> SurfaceVelocities:
    """Tangential surface velocities of two bodies at a contact relative to the moving contact
    point: u_i = t . (V_i(X) - dX/dtheta), V_i the velocity of body i's material point at X."""
    def along(v):
        return np.einsum("ij,ij->i", tangent, v - contact_rate)

    return SurfaceVelocities(along(first_velocity), along(second_velocity))


def cam_velocity(contact: np.ndarray) -> np.ndarray:
    """Velocity of the cam's material point at the ground point X per unit camshaft speed: J X."""
    return np.column_stack([-contact[:, 1], contact[:, 0]])


# --------------------------------------------------------------------------------------------
# checks
# --------------------------------------------------------------------------------------------


def check_no_cusp(surface: CamSurface, file: str, key: str, remedy: str, what: str = "the cam") -> None:
    """A flat working surface needs a convex cam everywhere: rho <= 0 is a cusp (the envelope
    folds back, the cam cannot be ground). One line naming the worst cam angle."""
    bad = ~(surface.radius > 0.0)
    if np.any(bad):
        i = int(np.argmin(np.where(bad, surface.radius, np.inf)))
        raise InputError(
            file, key,
            f"{what} would have a cusp: its radius of curvature is {surface.radius[i] * 1e3:.4g} mm (must be > 0) at "
            f"cam angle {math.degrees(float(surface.theta[i])) % 360.0:.2f} deg ({remedy})",
        )


def check_no_undercut(surface: CamSurface, circle_radius: float, file: str, key: str, remedy: str,
                      what: str = "roller") -> None:
    """A circle (roller, curved pad) rolls on a convex or concave cam, but a concave stretch must be
    wider than the circle: the cam's radius must not lie in (-r, 0] (the pitch curve would be
    sharper than the circle, the envelope folds: undercut)."""
    r = circle_radius
    bad = ((surface.radius <= 0.0) & (surface.radius > -r)) | np.isnan(surface.radius)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise InputError(
            file, key,
            f"undercut: the {what} (radius {r * 1e3:.4g} mm) is sharper than the cam can follow at cam angle "
            f"{math.degrees(float(surface.theta[i])) % 360.0:.2f} deg ({remedy})",
        )


def first_crossing(theta, contour: np.ndarray, start: np.ndarray, end: np.ndarray) -> int | None:
    """Index of the first cam angle at which the segment start -> end (ground, one per angle)
    properly crosses the cam's contour (cam frame polygon, turned by the angle), else None.
    Touching is not crossing: a working surface resting on the cam is fine.

    Only the angles where some edge can cross are tested (_may_cross: an arm clear of the cam
    passes every angle's prefilter in one vectorised step); those are tested on every edge in
    exactly the arithmetic they always were, so the answer is the same index."""
    p = np.asarray(contour, dtype=float)
    q = np.roll(p, -1, axis=0)
    theta = np.asarray(theta, dtype=float)
    start, end = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    for i in np.nonzero(_may_cross(theta, p, q, start, end))[0]:
        c, s = math.cos(theta[i]), math.sin(theta[i])
        rot = np.array([[c, -s], [s, c]])
        a, b = start[i], end[i]
        pa, qa = p @ rot.T, q @ rot.T
        d1 = _orient(pa, qa, a)
        d2 = _orient(pa, qa, b)
        d3 = _orient(a[None, :], b[None, :], pa)
        d4 = _orient(a[None, :], b[None, :], qa)
        if np.any((d1 * d2 < 0.0) & (d3 * d4 < 0.0)):
            return int(i)
    return None


# The prefilter's margin, relative to the figure's size: the crossing test's rounding (a few ulps
# of the coordinates, ~1e-16 of them) moves a crossing by far less, so an angle it passes over
# has no crossing in floating point either.
CROSSING_MARGIN = 1e-9


def _may_cross(theta: np.ndarray, p: np.ndarray, q: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Per angle, False only where no edge p_j -> q_j of the contour (cam frame) can cross the
    segment start -> end turned into the cam frame: a crossing point X lies on both, so its
    distance from the cam centre is at most the edge's far end's, R_j, and at least the segment's
    nearest point's, D; and its polar angle lies in both their angular spans. So an angle is
    passed over when every edge within the segment's angular span (widened by the margin) has
    R_j < D - margin. Where that cannot be told (a segment or an edge through or near the centre,
    wide edges, non-finite values) the angle is kept: a conservative filter, never a verdict."""
    n = len(theta)
    keep = np.ones(n, dtype=bool)
    if n == 0 or len(p) < 3 or not (np.isfinite(p).all() and np.isfinite(theta).all()):
        return keep
    scale = max(float(np.abs(p).max()), float(np.abs(start).max(initial=0.0)), float(np.abs(end).max(initial=0.0)))
    if not math.isfinite(scale) or scale == 0.0:
        return keep
    margin = CROSSING_MARGIN * scale
    # the edges' angular spans [lo, lo + width] (< pi: an edge clear of the centre) and far radii
    alpha = np.arctan2(p[:, 1], p[:, 0])
    turn = np.mod(np.roll(alpha, -1) - alpha + math.pi, TWO_PI) - math.pi  # in [-pi, pi)
    lo = np.mod(alpha + np.minimum(turn, 0.0), TWO_PI)
    width = np.abs(turn).max()
    if _distance_to_centre(p, q).min() <= 1e3 * margin or width > 0.25 * math.pi:
        return keep  # an edge near the centre sweeps any angle: no filter
    far = np.maximum(np.hypot(p[:, 0], p[:, 1]), np.hypot(q[:, 0], q[:, 1]))
    order = np.argsort(lo, kind="stable")
    lo_all = np.concatenate([lo[order] - TWO_PI, lo[order], lo[order] + TWO_PI])  # windows across 0 are one run
    far_all = np.tile(far[order], 3)
    # the segments' angular spans in the cam frame and their distances from the centre
    near = _distance_to_centre(start, end)
    ga = np.arctan2(start[:, 1], start[:, 0]) - theta
    turn = np.mod(np.arctan2(end[:, 1], end[:, 0]) - theta - ga + math.pi, TWO_PI) - math.pi
    s0 = np.mod(ga + np.minimum(turn, 0.0), TWO_PI)
    spread = margin / np.maximum(near, margin) + 1e-9  # the margin as an angle at the segment (rad)
    k0 = np.searchsorted(lo_all, s0 - width - spread)
    k1 = np.searchsorted(lo_all, s0 + np.abs(turn) + spread, side="right")
    clear = (near > 1e3 * margin) & (np.abs(turn) < 0.9 * math.pi) & np.isfinite(near) & np.isfinite(turn)
    nonempty = k1 > k0
    top = np.full(n, -np.inf)  # the largest far radius of the edges in each window
    if nonempty.any():
        bounds = np.stack([k0[nonempty], k1[nonempty]], axis=1).reshape(-1)
        top[nonempty] = np.maximum.reduceat(np.append(far_all, -np.inf), bounds)[0::2]
    keep[clear] = ~(top[clear] < near[clear] - margin)
    return keep


def _distance_to_centre(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from the origin to each segment a_i -> b_i (rows of (N, 2) arrays)."""
    d = b - a
    length2 = np.einsum("ij,ij->i", d, d)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(-np.einsum("ij,ij->i", a, d) / length2, 0.0, 1.0)
    t = np.where(length2 > 0.0, t, 0.0)
    x = a + t[:, None] * d
    return np.hypot(x[:, 0], x[:, 1])


def _orient(u, v, w):
    return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])
