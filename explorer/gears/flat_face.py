"""The direct-acting bucket tappet: a translating follower with a flat face or a spherical crown.

Layout (explorer.lift.contours.translating's conventions): cam centre at the origin turning
counter-clockwise by theta, the tappet's axis along +y through the cam centre, the tappet above
the cam. The tappet lift s(theta) is the valve-referred lift (the tappet sits on the valve: ratio
1, lash included as in every gear here).

Flat face (face_radius infinite). The face is the line y = Rb + s; the cam is the envelope of
these lines (explorer.gears.envelope.line_envelope). Textbook closed forms (Norton, Cam Design and
Manufacturing Handbook, 2nd ed. 2009, ch. 7; Shigley & Uicker, Theory of Machines and Mechanisms,
flat-faced follower): in the ground frame the contact is at
    x = ds/dtheta (its offset from the tappet axis),  y = Rb + s,
the cam's radius of curvature there is rho = Rb + s + s'' (> 0, or the cam has a cusp), and the
pressure angle is zero. In the cam frame (turned back by theta) the contour is
    X = (Rb + s) sin(theta) + s' cos(theta),   Y = (Rb + s) cos(theta) - s' sin(theta).
The face must hold the contact on both sides: diameter >= 2 max|s'| plus a margin (with a cam
of width b offset by e along the camshaft, the contact line's far end: 2 max sqrt(s'^2 + (|e| + b/2)^2)).
The offset along the camshaft turns the tappet (the friction on the face has an arm e about its
axis); it does not enter the planar kinematics.

Crowned face (a sphere of radius Rf on the tappet axis). In the cam plane the crown is a circle of
radius Rf about a point on the axis at height y = Rb + Rf + s: kinematically a translating roller
of radius Rf (explorer.lift.contours.translating with roller radius Rf), so the pressure angle is
atan(s' / y) and the contact sits at Rf s'/|T| from the axis, |T| = sqrt(y^2 + s'^2). The cam's
radius of curvature rho = rho_pitch - Rf would subtract two numbers of the size of Rf (metres) to
get millimetres; written out it is free of that cancellation:
    rho = [y^2 (a + s'') + y (y^2 E - 2 s'^2) + a (2 s'^2 - y s'')] / (y^2 + 2 s'^2 - y s''),
    a = Rb + s,   E = (1 + s'^2/y^2)^(3/2) - 1 = expm1(1.5 log1p(s'^2/y^2)),
which tends to Rb + s + s'' as Rf -> infinity (the flat face). The crown touches the cam in the
plane through the tappet axis across the camshaft (a sphere meets the cam's straight generators
there), so the lobe must cover that plane: |e| < b/2.

Sliding and entrainment at the face (per unit camshaft speed; Dowson and Higginson's classic
result for the flat face): the cam surface moves past the contact at -(rho) and the face at -s'',
so the sliding velocity is -(Rb + s) and the entrainment velocity -(Rb + s + 2 s'')/2, zero where
rho = -s'' (the nose of a flat tappet runs with little oil film).

Analysis: a flat face touches a convex contour where the contour's normal points along the
tappet axis; the lift is the contour's support function, s(theta) = h(beta) - Rb with beta =
90 deg - theta the axis direction in the cam frame (explorer.gears.contour_follow). A crowned face
over a contour is the roller analysis of explorer.lift.contours with roller radius Rf.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..lift.contours.arcs import ArcContour, ContourError, make_arc_lift
from ..lift.contours.parametric import ContourFollowError, make_parametric_lift
from ..mechanics.contact import hertz_line_stress
from . import jet as J
from .contour_follow import as_parametric, contour_jets, contour_sign, make_contour_motion
from .envelope import (
    CamSurface,
    EnvelopeContour,
    SurfaceVelocities,
    _rotate_to_cam,
    cam_velocity,
    check_no_cusp,
    line_contact,
    surface_velocities,
)
from .jet import Jet
from .train_statics import ContactForces, cam_forces

TWO_PI = 2.0 * math.pi
AXIS = np.array([0.0, 1.0])  # the tappet's axis: it lifts along +y


@dataclass(frozen=True)
class Tappet:
    """The tappet's geometry (SI). face_radius = inf: flat face."""

    base_radius: float  # m, the cam's base circle
    face_radius: float = math.inf  # m, spherical crown
    face_diameter: float | None = None  # m, the tappet's face; None: not checked
    offset: float = 0.0  # m, the lobe's centre from the tappet axis along the camshaft
    cam_width: float | None = None  # m, the lobe's width (for the face and for Hertz)
    face_margin: float = 0.0  # m, added to the diameter the contact needs
    file: str = "<memory>"
    key: str = "gear.tappet"

    @property
    def crowned(self) -> bool:
        return math.isfinite(self.face_radius)

    def validate(self) -> None:
        if not self.base_radius > 0.0:
            raise InputError(self.file, "follower.base_radius", f"must be greater than zero, got {self.base_radius!r}")
        if not self.face_radius > 0.0:
            raise InputError(self.file, f"{self.key}.face_radius", f"must be greater than zero, got {self.face_radius!r}")
        for name, value in (("face_diameter", self.face_diameter), ("cam_width", self.cam_width)):
            if value is not None and not value > 0.0:
                raise InputError(self.file, f"{self.key}.{name}", f"must be greater than zero, got {value!r}")
        if not self.face_margin >= 0.0:
            raise InputError(self.file, f"{self.key}.face_margin", f"must not be negative, got {self.face_margin!r}")
        if self.crowned and self.cam_width is not None and abs(self.offset) >= 0.5 * self.cam_width:
            raise InputError(self.file, f"{self.key}.offset",
                             f"a crowned face touches the cam on the tappet axis, but the lobe ({self.cam_width * 1e3:.4g} mm "
                             f"wide, offset {self.offset * 1e3:.4g} mm) does not cover it: keep |offset| below half the cam width")


@dataclass(frozen=True)
class TappetKinematics:
    """Everything geometric about the tappet train at each cam angle (per radian of cam angle;
    `time_derivatives` turns the lift's rows into v, a, jerk at a camshaft speed)."""

    theta: np.ndarray
    lift: np.ndarray  # (4, N): s, ds/dtheta, d2s/dtheta2, d3s/dtheta3 (m, m/rad, ...)
    surface: CamSurface
    contact_offset: np.ndarray  # m, in-plane distance of the contact from the tappet axis (flat: ds/dtheta)
    pressure_angle: np.ndarray  # rad, contact normal vs the tappet axis (0 for a flat face)
    velocities: SurfaceVelocities  # cam (first) and face (second) at the contact, m/rad

    def time_derivatives(self, omega: float) -> np.ndarray:
        """(4, N): s (m), v (m/s), a (m/s^2), jerk (m/s^3) at camshaft speed omega (rad/s)."""
        return self.lift * (omega ** np.arange(4))[:, None]

    @property
    def ratio(self) -> np.ndarray:
        return np.ones_like(self.theta)

    @property
    def ratio_jet(self) -> np.ndarray:
        """(4, N): the tappet sits on the valve, ratio 1 and no derivatives."""
        out = np.zeros((4, len(self.theta)))
        out[0] = 1.0
        return out


def flat_face_surface(theta, s: Jet, base_radius: float) -> CamSurface:
    """The flat face's cam: line_envelope with phi = 90 deg and h = Rb + s, written out (the
    tests check the two against each other): contact (s', Rb + s), its rate (s'', s'),
    rho = Rb + s + s'', the normal the tappet's axis itself."""
    theta = np.asarray(theta, dtype=float)
    c = s.c
    height = c[0] + base_radius
    contact = np.column_stack([c[1], height])
    return CamSurface(
        theta=theta, contour=_rotate_to_cam(theta, contact), radius=height + c[2], contact=contact,
        contact_rate=np.column_stack([c[2], c[1]]), normal=np.tile(AXIS, (len(theta), 1)),
    )


def crowned_contact(s: Jet, base_radius: float, face_radius: float) -> tuple[Jet, Jet]:
    """The crown's contact point (ground frame) as jets in theta: Rf s'/|T| off the axis, at
    height y (|T| - Rf)/|T|, |T| - Rf written as a + s'^2/(|T| + y) (no cancellation)."""
    rf = face_radius
    a = s + base_radius
    y = a + rf  # the crown's centre height
    s1 = s.shift()
    length = J.hypot(y, s1)
    return rf * s1 / length, y * (a + s1 * s1 / (length + y)) / length


def crowned_face_surface(theta, s: Jet, base_radius: float, face_radius: float) -> CamSurface:
    """The crown's closed forms (module docstring), free of the cancellation of rho_pitch - Rf."""
    x_c, y_c = crowned_contact(s, base_radius, face_radius)
    yv = s.c[0] + base_radius + face_radius
    av, d1, d2 = s.c[0] + base_radius, s.c[1], s.c[2]
    big_e = np.expm1(1.5 * np.log1p((d1 / yv) ** 2))
    numerator = yv * yv * (av + d2) + yv * (yv * yv * big_e - 2.0 * d1 * d1) + av * (2.0 * d1 * d1 - yv * d2)
    with np.errstate(divide="ignore", invalid="ignore"):
        radius = numerator / (yv * yv + 2.0 * d1 * d1 - yv * d2)
    length = np.hypot(yv, d1)
    contact = np.column_stack([x_c.c[0], y_c.c[0]])
    return CamSurface(
        theta=np.asarray(theta, dtype=float), contour=_rotate_to_cam(theta, contact), radius=radius, contact=contact,
        contact_rate=np.column_stack([x_c.c[1], y_c.c[1]]), normal=np.column_stack([-d1 / length, yv / length]),
    )


@dataclass(frozen=True)
class BucketTappetGear:
    """The bucket-tappet gear: the tappet and its lift (a law, for synthesis, or the motion over a
    given contour, for analysis); `contour` is the given contour in analysis, else None."""

    tappet: Tappet
    lift: Any  # LiftCurve: the tappet (valve-referred) lift
    contour: Any = None

    def lift_jet(self, theta) -> Jet:
        return Jet(self.lift.derivatives(np.asarray(theta, dtype=float)))

    def valve_lift(self, theta) -> np.ndarray:
        """(4, N): the valve's (= the tappet's) lift and its derivatives."""
        return self.lift.derivatives(np.asarray(theta, dtype=float))

    def surface(self, theta) -> CamSurface:
        s = self.lift_jet(theta)
        if self.tappet.crowned:
            return crowned_face_surface(theta, s, self.tappet.base_radius, self.tappet.face_radius)
        return flat_face_surface(theta, s, self.tappet.base_radius)

    def contact_jets(self, theta) -> tuple[Jet, Jet]:
        """The contact point (ground frame) as jets in theta, to the second derivative."""
        s = self.lift_jet(theta)
        t = self.tappet
        if t.crowned:
            return crowned_contact(s, t.base_radius, t.face_radius)
        return line_contact(theta, Jet.constant(np.full(np.shape(theta), 0.5 * math.pi)), s + t.base_radius)

    def synthesised_contour(self) -> EnvelopeContour:
        """The cam as an exact parametric contour (explorer.gears.envelope.EnvelopeContour)."""
        return EnvelopeContour(self.contact_jets)

    def kinematics(self, theta) -> TappetKinematics:
        theta = np.asarray(theta, dtype=float)
        s = self.lift_jet(theta)
        t = self.tappet
        surface = (crowned_face_surface(theta, s, t.base_radius, t.face_radius) if t.crowned
                   else flat_face_surface(theta, s, t.base_radius))
        tappet_velocity = np.column_stack([np.zeros_like(theta), s.c[1]])
        velocities = surface_velocities(surface.tangent, surface.contact_rate, cam_velocity(surface.contact), tappet_velocity)
        pressure = np.arctan2(-surface.normal[:, 0], surface.normal[:, 1])
        return TappetKinematics(theta=theta, lift=s.c, surface=surface, contact_offset=surface.contact[:, 0].copy(),
                                pressure_angle=pressure, velocities=velocities)

    # -- the face ----------------------------------------------------------------------------------
    def face_reach(self, k: TappetKinematics) -> np.ndarray:
        """How far from the tappet's axis the contact reaches on the face, per angle (m): a flat
        face touches the lobe along a line across the camshaft, from the lobe's centre (offset e)
        out to |e| + b/2 (width b), so its far end is sqrt(s'^2 + (|e| + b/2)^2); without a width,
        or on a crown (which touches in the plane through the axis), |x_contact|. The one formula
        the face's diameter check, the gear's report and the face_width design rule read."""
        t = self.tappet
        across = 0.0 if t.crowned or t.cam_width is None else abs(t.offset) + 0.5 * t.cam_width
        return np.hypot(k.contact_offset, across)

    def face_diameter_needed(self, k: TappetKinematics) -> tuple[float, float]:
        """(diameter, cam angle of the widest contact): 2 max face_reach + face_margin (a flat
        face: the contact line's far end, 2 max sqrt(s'^2 + (|e| + b/2)^2) + margin; a crown:
        2 max|x_contact| + margin)."""
        reach = self.face_reach(k)
        i = int(np.argmax(reach))
        return 2.0 * float(reach[i]) + self.tappet.face_margin, float(k.theta[i])

    def check(self, n: int = 3600) -> TappetKinematics:
        """Cusp (rho <= 0) and the face's diameter over a revolution: one-line InputErrors. A given
        contour's convexity was checked by its analysis (the face's contact must run round it
        steadily), where the contour's derivatives may not reach rho."""
        t = self.tappet
        t.validate()
        theta = np.linspace(0.0, TWO_PI, n, endpoint=False)
        k = self.kinematics(theta)
        if self.contour is None:
            worst = float(np.min(k.surface.radius))
            remedy = (f"enlarge follower.base_radius by more than {max(-worst, 0.0) * 1e3:.3g} mm, or soften the lift's "
                      "negative acceleration there")
            check_no_cusp(k.surface, t.file, "follower.base_radius", remedy)
        if t.face_diameter is not None:
            need, at = self.face_diameter_needed(k)
            if need > t.face_diameter:
                raise InputError(
                    t.file, f"{t.key}.face_diameter",
                    f"the face ({t.face_diameter * 1e3:.4g} mm) is smaller than the {need * 1e3:.4g} mm the contact needs "
                    f"(widest contact at cam angle {math.degrees(at) % 360.0:.2f} deg): enlarge the face, or lower the "
                    "lift's largest ds/dtheta (a longer event)",
                )
        return k

    # -- contact ----------------------------------------------------------------------------------
    def contact_forces(self, k: TappetKinematics, valve_force, cam_friction: float = 0.0) -> ContactForces:
        """Normal force, face friction and camshaft torque for the valve force F (N, > 0 loads
        the tappet). The bore is a frictionless guide (it takes the side force of the face friction)."""
        n = len(k.theta)
        axis = np.tile(AXIS, (n, 1))
        return cam_forces(valve_force, contact=k.surface.contact, normal=k.surface.normal, tangent=k.surface.tangent,
                          cam_jacobian=axis, cam_sliding=k.velocities.sliding, cam_friction=cam_friction,
                          valve_axis=axis, valve_jacobian=axis)

    def hertz_stress(self, k: TappetKinematics, normal_force, e_star: float, width: float | None = None) -> np.ndarray:
        """Peak contact pressure (Pa). Flat face on the cam: a line contact of the lobe's width with
        the cam's radius (explorer.mechanics.contact.hertz_line_stress). Crown on the cam: the
        elliptical point contact of the sphere Rf on the cam (rho in the plane, straight across;
        explorer.mechanics.hertz.point_contact), and where its ellipse would run over the lobe's
        edges (`edge_loaded`) at least the line contact over the lobe's width (crown_stress: the
        real pressure is higher still at the edges; a crown is chosen to keep the ellipse on the
        lobe)."""
        t = self.tappet
        b = width if width is not None else t.cam_width
        if t.crowned:
            return crown_stress(normal_force, t.face_radius, k.surface.radius, e_star, b)[0]
        if b is None:
            raise InputError(t.file, f"{t.key}.cam_width", "the contact stress needs the lobe's width")
        return hertz_line_stress(normal_force, b, math.inf, k.surface.radius, e_star)

    def contact_ellipse(self, k: TappetKinematics, normal_force, e_star: float):
        """The crown's Hertz ellipse (explorer.mechanics.hertz.PointContact); its semi-major axis
        runs along the camshaft, to be compared with half the lobe's width (edge loading)."""
        from ..mechanics.hertz import point_contact  # heavy (scipy): imported on use

        rf = self.tappet.face_radius
        across = np.full(len(k.theta), 1.0 / rf)
        return point_contact(normal_force, 1.0 / rf + 1.0 / k.surface.radius, across, e_star)

    def edge_loaded(self, k: TappetKinematics, normal_force, e_star: float) -> np.ndarray:
        """Crown only: where the contact ellipse would be longer across the lobe than the lobe is wide."""
        t = self.tappet
        if t.cam_width is None:
            raise InputError(t.file, f"{t.key}.cam_width", "the edge-loading check needs the lobe's width")
        return crown_stress(normal_force, t.face_radius, k.surface.radius, e_star)[1] > 0.5 * t.cam_width


def crown_stress(normal_force, crown_radius: float, cam_radius, e_star: float, width: float | None = None):
    """(peak pressure Pa, the contact's half-length across the lobe m) of a spherical crown Rf on a
    cam of radius rho (straight across): Hertz's ellipse (explorer.mechanics.hertz.point_contact)
    with the curvature sums 1/Rf + 1/rho in the plane and 1/Rf across. Its long axis lies along the
    smaller sum: across the lobe on a convex cam, in the plane on a concave one. Where the ellipse
    would run over the lobe's edges (half-length across > width/2) the contact is cut to the width
    and carries the load on less than the ellipse: its peak is at least the larger of the ellipse's
    p0 and the line contact's over the width with the in-plane curvature (explorer.mechanics.
    contact.hertz_line_stress; the edges add more). That larger figure is returned there; as
    Rf -> inf it is the flat face's line contact, where the ellipse's p0 would fall to 0."""
    from ..mechanics.hertz import point_contact  # heavy (scipy): imported on use

    rho = np.asarray(cam_radius, dtype=float)
    in_plane = 1.0 / crown_radius + 1.0 / rho
    across_sum = np.full(rho.shape, 1.0 / crown_radius)
    ellipse = point_contact(normal_force, in_plane, across_sum, e_star)
    across = np.where(in_plane >= across_sum, ellipse.semi_major, ellipse.semi_minor)
    if width is None:
        return ellipse.peak_pressure, across
    line = hertz_line_stress(normal_force, width, crown_radius, rho, e_star)
    peak = np.where(across <= 0.5 * width, ellipse.peak_pressure, np.maximum(ellipse.peak_pressure, line))
    return peak, across


# --------------------------------------------------------------------------------------------
# synthesis and analysis
# --------------------------------------------------------------------------------------------


def synthesise_bucket(tappet: Tappet, lift, n: int = 3600) -> BucketTappetGear:
    """The bucket-tappet gear for a wanted lift (the cam is the face's envelope), checked."""
    gear = BucketTappetGear(tappet, lift)
    gear.check(n)
    return gear


def flat_face_relation(contour, base_radius: float):
    """(theta(t), s(t)) of a flat face on the tappet axis over a contour (module docstring)."""
    sign = contour_sign(contour)

    def relation(t):
        cx, cy, nx, ny = contour_jets(contour, t, sign)
        beta = J.atan2(ny, nx)
        support = cx * nx + cy * ny
        return 0.5 * math.pi - beta, support - base_radius

    return relation


def analyse_bucket(tappet: Tappet, contour, n: int = 3600) -> BucketTappetGear:
    """The tappet's lift over a given contour (an ArcContour or a parametric contour such as
    explorer.lift.contours.parametric.SplineContour), checked like a synthesised one."""
    tappet.validate()
    if tappet.crowned:
        try:
            if isinstance(contour, ArcContour):
                lift = make_arc_lift(contour, tappet.face_radius, 0.0, tappet.base_radius)
            else:
                lift = make_parametric_lift(contour, tappet.face_radius, 0.0, tappet.base_radius)
        except (ContourError, ContourFollowError) as exc:
            raise InputError(tappet.file, f"{tappet.key}.face_radius", f"the crown cannot follow the contour: {exc}") from None
    else:
        param = as_parametric(contour)
        lift = make_contour_motion(flat_face_relation(param, tappet.base_radius), param, file=tappet.file,
                                   key="cam", what="the flat face")
    gear = BucketTappetGear(tappet, lift, contour)
    base = float(np.min(gear.lift.derivatives(np.linspace(0.0, TWO_PI, 4096, endpoint=False))[0]))
    if abs(base) > 1e-6:
        raise InputError(tappet.file, "follower.base_radius",
                         f"the contour's base circle differs from follower.base_radius by {base * 1e3:.4g} mm (the tappet "
                         "would not rest at zero lift)")
    gear.check(n)
    return gear
