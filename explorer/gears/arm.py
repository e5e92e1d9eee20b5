"""Oscillating followers: an arm about a fixed pivot, driven by the cam through a roller, a curved
pad or a flat pad, opening the valve through its valve-end pad (explorer.gears.valve_end).

Two of today's valve trains are this gear with different proportions:
finger-follower  end pivot: the finger rests on the lash adjuster's ball (the pivot) at one end,
                 carries the roller (or a pad) between the ends and pushes the valve tip with its
                 pad at the other end;
rocker           centre pivot, driven from an overhead cam by a roller or a pad (no pushrod;
                 explorer.gears.pushrod adds the lifter and the pushrod).

Layout (explorer.gears.pivoted's conventions): cam centre O at the origin turning counter-
clockwise by theta; the arm turns about O1 by psi, the angle of its reference direction: from
O1 to the roller's centre, or to the pad's crown point (the pad's middle, where a flat pad's line
is at `arm` from the pivot). The cam-side working surface is
    roller      a circle of radius r about the point at `arm` along the reference direction;
    curved pad  a circle of radius Rp about C = P + Rp n_a (P the crown point, n_a the unit normal
                at `face_angle` from the reference direction, pointing from the cam into the arm:
                the centre of curvature lies inside the arm);
    flat pad    the line through P with normal n_a: in the ground frame n(phi) . X = h,
                phi = psi + face_angle, h = n . O1 + arm cos(face_angle).
A curved pad is kinematically a roller of radius Rp about C (only its sliding differs); as
Rp -> infinity it becomes the flat pad (the tests check the limit).

Synthesis (the backwards construction): valve lift S(theta) -> psi = valve_end^-1(S) (closed form,
explorer.gears.linkage.RockerDrive.inverse) -> the working surface's pose -> the cam as its
envelope (explorer.gears.envelope). Analysis: for a circle the pitch point P(t) = C(t) + r n(t) of
the contour is under the circle where the circle of radius |P| about O meets the centre's circle
about O1 (seed 004's "arcs about O and O1", explorer.gears.pivoted.analyse_pitch); for the flat
pad the contour's support value h(t) in the direction beta(t) fixes the face's angle in closed
form, |O1| cos(phi - phi_O1) = h - arm cos(face_angle), and theta = phi - beta. Both then go through
explorer.gears.contour_follow (Newton on theta(t) = theta*).

Ratios (per cam angle):
ratio         valve travel per travel of the arm's reference point (roller centre, pad crown),
              |ds/dpsi| / arm: the lever ratio (the pivoted-roller gear's);
normal_ratio  valve velocity per velocity of the follower along the contact normal at the cam,
              ds/dpsi / (n . J (X - O1)): the cam's normal force per newton at the valve without
              friction (virtual work), N / F.
Pressure angle: between the contact normal and the direction in which the follower's point on the
normal travels when it lifts: the roller's centre, or for a pad (curved or flat: the same limit)
the arm's point at the contact itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..mechanics.contact import hertz_line_stress
from . import jet as J
from .contour_follow import as_parametric, check_base_circle, contour_jets, contour_sign, make_contour_motion
from .envelope import (
    CamSurface,
    EnvelopeContour,
    SurfaceVelocities,
    cam_velocity,
    check_no_cusp,
    check_no_undercut,
    circle_contact,
    circle_envelope,
    first_crossing,
    line_contact,
    line_envelope,
    surface_velocities,
)
from .jet import Jet
from .linkage import DEAD_POINT_MARGIN, circle_intersection, wrap
from .pivoted import analyse_pitch
from .train_statics import ContactForces, cam_forces, point_velocity_about
from .valve_end import TipContact, ValveEnd, make_valve_end

TWO_PI = 2.0 * math.pi
ROLLER, PAD = "roller", "pad"
KINDS = ("finger", "rocker")  # the arm: an end-pivot finger or a centre-pivot rocker (its part name)


@dataclass(frozen=True)
class CamSide:
    """The arm's working surface on the cam (module docstring)."""

    kind: str  # "roller" | "pad"
    arm: float  # m, pivot -> roller centre or pad crown point (the arm's reference direction)
    radius: float  # m, roller radius, or pad radius (inf: a flat pad)
    face_angle: float = 0.5 * math.pi  # rad, pad: its normal from the cam into the arm, from the reference direction
    width: float | None = None  # m, the contact's width (roller or pad width), for Hertz

    @property
    def circular(self) -> bool:
        return self.kind == ROLLER or math.isfinite(self.radius)

    @property
    def sliding(self) -> bool:
        return self.kind == PAD

    def centre_polar(self) -> tuple[float, float]:
        """(distance, angle from the reference direction) of the circle's centre."""
        if self.kind == ROLLER:
            return self.arm, 0.0
        x = self.arm + self.radius * math.cos(self.face_angle)
        y = self.radius * math.sin(self.face_angle)
        return math.hypot(x, y), math.atan2(y, x)

    @property
    def face_support(self) -> float:
        """Flat pad: n_a . P, the face line's distance from the pivot along its normal."""
        return self.arm * math.cos(self.face_angle)


@dataclass(frozen=True)
class Arm:
    """An arm resting on the cam's base circle: pivot, working surface, rest angle."""

    base_radius: float
    pivot: tuple[float, float]
    cam_side: CamSide
    branch: int  # the circle's centre (a flat pad: its contact) left (+1) / right (-1) of the line O1 -> O
    rest: float  # psi0, rad
    lifting: float  # +1 if psi grows as the cam lifts the arm, else -1
    file: str = "<memory>"
    key: str = "gear.arm"
    radius_key: str = ""  # the key of the roller's or pad's radius ("": <key>.roller_radius / pad_radius)

    @property
    def radius_name(self) -> str:
        return self.radius_key or f"{self.key}.{'roller_radius' if self.cam_side.kind == ROLLER else 'pad_radius'}"

    def circle_centre(self, psi):
        a, delta = self.cam_side.centre_polar()
        return self.pivot[0] + a * J.cos(psi + delta), self.pivot[1] + a * J.sin(psi + delta)

    def face(self, psi):
        """Flat pad: (normal angle phi, support h) of the face line."""
        phi = psi + self.cam_side.face_angle
        o = self.pivot
        return phi, o[0] * J.cos(phi) + o[1] * J.sin(phi) + self.cam_side.face_support


def make_arm(*, base_radius: float, pivot, cam_side: CamSide, branch: int, file: str = "<memory>",
             key: str = "gear.arm", radius_key: str = "") -> Arm:
    """The arm's rest angle on the base circle, with one-line errors naming the key (`radius_key`:
    where the roller's or pad's radius was given, if not under `key`; a roller's is
    follower.roller_radius in a scene)."""
    pivot = (float(pivot[0]), float(pivot[1]))
    distance = math.hypot(*pivot)
    side = cam_side
    if not side.arm > 0.0:
        raise InputError(file, f"{key}.arm", f"must be greater than zero, got {side.arm!r}")
    if not side.radius > 0.0:
        raise InputError(file, radius_key or f"{key}.{'roller_radius' if side.kind == ROLLER else 'pad_radius'}",
                         f"must be greater than zero, got {side.radius!r}")
    if distance <= base_radius:
        raise InputError(file, f"{key}.pivot", f"the pivot lies inside the cam's base circle ({base_radius * 1e3:.4g} mm)")
    if side.circular:
        a, delta = side.centre_polar()
        reach = base_radius + side.radius
        what = "roller" if side.kind == ROLLER else "pad"
        if reach > distance + a:
            raise InputError(file, f"{key}.arm", f"the {what} would cut through the base circle at every arm angle: the "
                             f"arm keeps its centre within {(distance + a) * 1e3:.4g} mm of the cam centre, closer than "
                             f"base radius + {what} radius = {reach * 1e3:.4g} mm")
        x, y, q = circle_intersection(pivot, a, (0.0, 0.0), reach, branch)
        if x is None:
            raise InputError(file, f"{key}.arm", f"the {what} on this arm cannot reach the cam's base circle")
        if q < DEAD_POINT_MARGIN:
            raise InputError(file, f"{key}.arm", f"arm and cam radius in line at rest: the {what} would not lift")
        rest = math.atan2(float(y) - pivot[1], float(x) - pivot[0]) - delta
        centre = np.array([float(x), float(y)])
        tangent = np.array([-(centre[1] - pivot[1]), centre[0] - pivot[0]])  # d C / d psi
        lifting = float(np.sign(centre @ tangent))
    else:
        cos_arg = (base_radius - side.face_support) / distance
        if abs(cos_arg) >= 1.0 - DEAD_POINT_MARGIN:
            raise InputError(file, f"{key}.arm", "the flat pad cannot lie on the base circle from this pivot (move the "
                             "pivot, or change the arm or the pad's face angle)")
        # of the two tangent lines, the one whose contact (Rb n on the base circle) lies on the
        # `branch` side of the line from the pivot towards the cam centre, as for a circle's centre
        phi_o = math.atan2(pivot[1], pivot[0])
        for sign in (1.0, -1.0):
            phi0 = phi_o + sign * math.acos(cos_arg)
            contact = base_radius * np.array([math.cos(phi0), math.sin(phi0)])
            if np.sign(-pivot[0] * (contact[1] - pivot[1]) + pivot[1] * (contact[0] - pivot[0])) == branch:
                break
        rest = phi0 - side.face_angle
        lifting = float(np.sign(-pivot[0] * math.sin(phi0) + pivot[1] * math.cos(phi0)))  # dh / dpsi
    if lifting == 0.0:
        raise InputError(file, f"{key}.pivot", "the arm's working surface moves along the cam's surface at rest: it would not lift")
    return Arm(base_radius=base_radius, pivot=pivot, cam_side=cam_side, branch=branch, rest=float(wrap(rest)),
               lifting=lifting, file=file, key=key, radius_key=radius_key)


@dataclass(frozen=True)
class ArmKinematics:
    """Everything geometric about the arm train at each cam angle (rates per radian of cam angle)."""

    theta: np.ndarray
    lift: np.ndarray  # (4, N): valve travel s and its derivatives (lash included)
    arm_angle: np.ndarray  # (4, N): psi and its derivatives
    surface: CamSurface
    centre: np.ndarray | None  # (N, 2) ground: the circle's centre (roller axle, pad centre of curvature)
    pressure_angle: np.ndarray  # rad (module docstring)
    ratio: np.ndarray  # |ds/dpsi| / arm
    ratio_jet: np.ndarray  # (4, N): the ratio and its derivatives in theta (exact, jets)
    normal_ratio: np.ndarray  # N / F without friction
    cam_jacobian: np.ndarray  # (N, 2): the arm's velocity at the cam contact per unit dpsi, J (X - O1)
    cam_velocities: SurfaceVelocities  # cam (first), arm surface (second), m/rad; a roller rolls: equal
    roller_rate: np.ndarray | None  # rad/rad: the roller's spin relative to the arm, per radian of cam angle
    tip: TipContact

    def time_derivatives(self, omega: float) -> np.ndarray:
        return self.lift * (omega ** np.arange(4))[:, None]


@dataclass(frozen=True)
class ArmGear:
    """finger-follower or rocker (OHC): the arm, its valve end and its motion, from a valve-lift law
    (synthesis) or from a given contour (analysis, `motion` gives psi(theta))."""

    arm: Arm
    valve: ValveEnd
    law: Any = None  # LiftCurve: the valve-referred lift, lash included (synthesis)
    motion: Any = None  # ContourMotion of psi (analysis)
    contour: Any = None
    kind: str = "finger"  # KINDS

    def arm_angle(self, theta) -> Jet:
        theta = np.asarray(theta, dtype=float)
        if self.law is not None:
            return self.valve.inverse(Jet(self.law.derivatives(theta)))
        psi = Jet(self.motion.derivatives(theta))
        return psi + 2.0 * math.pi * np.round((self.arm.rest - psi.c[0]) / (2.0 * math.pi))

    def valve_lift(self, theta) -> np.ndarray:
        """(4, N): the valve travel and its derivatives (the law itself in synthesis)."""
        if self.law is not None:
            return self.law.derivatives(np.asarray(theta, dtype=float))
        return self.valve.travel(self.arm_angle(theta)).c

    def contact_jets(self, theta) -> tuple[Jet, Jet]:
        """The cam contact (ground frame) as jets in theta, to the second derivative."""
        psi = self.arm_angle(theta)
        side = self.arm.cam_side
        if side.circular:
            cx, cy = self.arm.circle_centre(psi)
            return circle_contact(theta, cx, cy, side.radius)
        phi, h = self.arm.face(psi)
        return line_contact(theta, phi, h)

    def synthesised_contour(self) -> EnvelopeContour:
        return EnvelopeContour(self.contact_jets)

    def surface(self, theta, psi: Jet | None = None) -> CamSurface:
        psi = self.arm_angle(theta) if psi is None else psi
        side = self.arm.cam_side
        if side.circular:
            cx, cy = self.arm.circle_centre(psi)
            return circle_envelope(theta, cx, cy, side.radius)
        phi, h = self.arm.face(psi)
        return line_envelope(theta, phi, h)

    def kinematics(self, theta) -> ArmKinematics:
        theta = np.asarray(theta, dtype=float)
        if self.law is not None:
            s = Jet(self.law.derivatives(theta))
            psi = self.valve.inverse(s)
        else:
            psi = self.arm_angle(theta)
            s = self.valve.travel(psi)
        arm, side = self.arm, self.arm.cam_side
        surface = self.surface(theta, psi)
        x = surface.contact
        jac = point_velocity_about(arm.pivot, x)
        centre = None
        if side.circular:
            cx, cy = arm.circle_centre(psi)
            centre = np.column_stack([cx.c[0], cy.c[0]])
        travel = arm.lifting * (point_velocity_about(arm.pivot, centre) if side.kind == ROLLER else jac)
        travel = travel / np.hypot(travel[:, 0], travel[:, 1])[:, None]
        n = surface.normal
        pressure = np.arctan2(travel[:, 0] * n[:, 1] - travel[:, 1] * n[:, 0], np.einsum("ij,ij->i", travel, n))
        pad = self.valve.centre(psi)
        tip = self.valve.contact(psi, pad)
        ds_dpsi = tip.valve_per_arm
        ratio_jet = self.valve.valve_per_arm(psi, pad).c * (arm.lifting / side.arm)
        normal_arm = np.einsum("ij,ij->i", n, jac)
        rate = psi.c[1]
        velocities = surface_velocities(surface.tangent, surface.contact_rate, cam_velocity(x), rate[:, None] * jac)
        roller_rate = None
        if side.kind == ROLLER:
            # rolling without slip: the roller's surface moves with the cam's relative to the contact
            velocities = SurfaceVelocities(velocities.first, velocities.first.copy())
            arm_surface = np.einsum("ij,ij->i", surface.tangent, rate[:, None] * jac - surface.contact_rate)
            roller_rate = (velocities.first - arm_surface) / side.radius
        with np.errstate(divide="ignore", invalid="ignore"):
            normal_ratio = ds_dpsi / normal_arm
        return ArmKinematics(
            theta=theta, lift=s.c, arm_angle=psi.c, surface=surface, centre=centre, pressure_angle=pressure,
            ratio=np.abs(ds_dpsi) / side.arm, ratio_jet=ratio_jet, normal_ratio=normal_ratio, cam_jacobian=jac, cam_velocities=velocities,
            roller_rate=roller_rate, tip=tip,
        )

    # -- checks ------------------------------------------------------------------------------------
    def check(self, n: int = 3600) -> ArmKinematics:
        """Undercut or cusp of the cam, the arm through the cam, the pad off the valve tip."""
        theta = np.linspace(0.0, TWO_PI, n, endpoint=False)
        k = self.kinematics(theta)
        arm, side = self.arm, self.arm.cam_side
        if self.contour is not None:
            pass  # a given contour: its analysis found the working surface's contact running round it steadily
        elif side.kind == ROLLER:
            check_no_undercut(k.surface, side.radius, arm.file, arm.radius_name,
                              "use a smaller roller, a larger base circle or a longer event")
        elif side.circular:
            check_no_undercut(k.surface, side.radius, arm.file, arm.radius_name,
                              "use a smaller pad radius, a larger base circle or a longer event", what="pad")
        else:
            worst = float(np.min(k.surface.radius))
            check_no_cusp(k.surface, arm.file, "follower.base_radius",
                          f"enlarge follower.base_radius by more than {max(-worst, 0.0) * 1e3:.3g} mm, give the pad a "
                          "radius, or soften the lift's negative acceleration there")
        outer = float(np.max(np.hypot(k.surface.contour[:, 0], k.surface.contour[:, 1])))
        if math.hypot(*arm.pivot) <= outer:
            raise InputError(arm.file, f"{arm.key}.pivot", f"the pivot lies inside the cam's sweep (cam nose radius "
                             f"{outer * 1e3:.4g} mm)")
        self._check_arm_clear(k)
        self.valve.check_on_tip(theta, k.tip)
        return k

    def body_segments(self, k: ArmKinematics) -> list[tuple[np.ndarray, np.ndarray]]:
        """The arm's centre line as segments (start (N, 2), end (N, 2)), kept off the working
        surfaces themselves: from the pivot to the roller's rim (for a pad: to the end of the pad's
        used stretch nearer the pivot, just inside the arm) and from the far side (rim, or the
        used stretch's other end) to the valve pad's centre."""
        arm, side = self.arm, self.arm.cam_side
        psi = k.arm_angle[0]
        o = np.tile(np.asarray(arm.pivot, dtype=float), (len(psi), 1))
        e = np.column_stack([np.cos(psi), np.sin(psi)])
        if side.kind == ROLLER:
            near = o + (side.arm - side.radius) * e
            far = o + (side.arm + side.radius) * e
        else:
            # the contacts in the arm's frame; their extreme ends, moved into the arm by 2 % of it
            c, s_ = np.cos(psi), np.sin(psi)
            rel = k.surface.contact - o
            local = np.column_stack([c * rel[:, 0] + s_ * rel[:, 1], -s_ * rel[:, 0] + c * rel[:, 1]])
            distance = np.hypot(local[:, 0], local[:, 1])
            if side.circular:
                a, delta = side.centre_polar()
                inward = a * np.array([math.cos(delta), math.sin(delta)]) - local
                inward /= np.hypot(inward[:, 0], inward[:, 1])[:, None]
            else:
                inward = np.tile([math.cos(side.face_angle), math.sin(side.face_angle)], (len(psi), 1))
            depth = 0.02 * side.arm
            ends = []
            for i in (int(np.argmin(distance)), int(np.argmax(distance))):
                p = local[i] + depth * inward[i]
                ends.append(o + np.column_stack([c * p[0] - s_ * p[1], s_ * p[0] + c * p[1]]))
            near, far = ends
        cx, cy = self.valve.centre(psi)
        pad = np.column_stack([cx, cy])
        return [(o, near), (far, pad)]

    def _check_arm_clear(self, k: ArmKinematics, samples: int = 360) -> None:
        step = max(1, len(k.theta) // samples)
        for start, end in self.body_segments(k):
            i = first_crossing(k.theta[::step], k.surface.contour, start[::step], end[::step])
            if i is not None:
                raise InputError(
                    self.arm.file, f"{self.arm.key}.pivot",
                    f"the arm would pass through the cam at cam angle {math.degrees(k.theta[::step][i]) % 360.0:.1f} deg "
                    "(move the pivot, or change the arm's proportions)",
                )

    # -- contact -----------------------------------------------------------------------------------
    def contact_forces(self, k: ArmKinematics, valve_force, cam_friction: float = 0.0,
                       tip_friction: float = 0.0) -> ContactForces:
        """Cam normal force, friction and camshaft torque for the valve force F (explorer.gears.
        train_statics). A roller rolls on the cam: no sliding friction there."""
        mu = cam_friction if self.arm.cam_side.sliding else 0.0
        n = len(k.theta)
        return cam_forces(valve_force, contact=k.surface.contact, normal=k.surface.normal, tangent=k.surface.tangent,
                          cam_jacobian=k.cam_jacobian, cam_sliding=k.cam_velocities.sliding, cam_friction=mu,
                          valve_axis=np.tile(self.valve.axis, (n, 1)), valve_jacobian=k.tip.arm_jacobian,
                          tip_tangent=k.tip.tangent, tip_sliding=k.tip.velocities.sliding, tip_friction=tip_friction)

    def hertz_stress(self, k: ArmKinematics, forces: ContactForces, e_star: float,
                     tip_width: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Peak Hertz pressure (Pa) at the cam (roller or pad of the given width on the cam: a line
        contact of two cylinders, a flat pad's radius infinite) and at the valve tip (the pad on the
        flat tip, over the chord of the tip's face that the contact line crosses, or `tip_width`)."""
        side = self.arm.cam_side
        if side.width is None:
            raise InputError(self.arm.file, f"{self.arm.key}.width", "the contact stress needs the roller's or pad's width")
        cam = hertz_line_stress(forces.normal, side.width, side.radius, k.surface.radius, e_star)
        return cam, tip_stress(self.valve, k.tip, forces.tip_normal, e_star, tip_width)


def tip_stress(valve: ValveEnd, tip: TipContact, force, e_star: float, width: float | None) -> np.ndarray:
    """Hertz line stress of the valve pad on the flat tip: the contact line crosses the round tip
    face as a chord 2 sqrt(r_tip^2 - w^2) at the scrub w (or over `width` if given)."""
    if width is None:
        if valve.tip_radius is None:
            raise InputError(valve.file, valve.tip_key, "the tip's contact stress needs the tip's radius")
        chord = 2.0 * np.sqrt(np.maximum(valve.tip_radius**2 - tip.scrub**2, 0.0))
    else:
        chord = np.full(len(tip.scrub), float(width))
    stress = hertz_line_stress(force, np.maximum(chord, 1e-300), valve.pad_radius, math.inf, e_star)
    return np.where(chord > 0.0, stress, np.inf)


# --------------------------------------------------------------------------------------------
# building, synthesis, analysis
# --------------------------------------------------------------------------------------------


def make_arm_gear(*, base_radius: float, pivot, cam_side: CamSide, branch: int, valve_arm: float,
                  valve_angle: float, valve_pad_radius: float, valve_axis: float | None = None,
                  valve_axis_point=None, tip_radius: float | None = None, law=None, contour=None,
                  kind: str = "finger", file: str = "<memory>", arm_key: str = "gear.arm",
                  pad_key: str = "gear.valve_pad", radius_key: str = "", check: bool = True,
                  n: int = 3600) -> ArmGear:
    """The arm gear from its geometry and either a valve-lift law (synthesis) or a contour
    (analysis: ArcContour or parametric), checked over a revolution."""
    if kind not in KINDS:
        raise ValueError(kind)
    if (law is None) == (contour is None):
        raise ValueError("give either a lift law (synthesis) or a contour (analysis)")
    arm = make_arm(base_radius=base_radius, pivot=pivot, cam_side=cam_side, branch=branch, file=file, key=arm_key,
                   radius_key=radius_key)
    valve = make_valve_end(pivot=arm.pivot, rest=arm.rest, lifting=arm.lifting, arm=valve_arm, angle=valve_angle,
                           pad_radius=valve_pad_radius, axis=valve_axis, axis_point=valve_axis_point,
                           tip_radius=tip_radius, file=file, key=pad_key)
    gear = ArmGear(arm=arm, valve=valve, law=law, kind=kind)
    if contour is not None:
        param = as_parametric(contour)
        motion = make_contour_motion(arm_relation(arm, param), param, file=file, key="cam",
                                     what="the arm's " + ("roller" if cam_side.kind == ROLLER else "pad"))
        gear = replace(gear, motion=motion, contour=contour)
        check_base_circle(lambda theta: gear.valve_lift(theta)[0], file=file, rests="the valve would rest {} off its seat")
    if check:
        gear.check(n)
    return gear


def arm_relation(arm: Arm, contour):
    """(theta(t), psi(t)) of the arm over a parametric contour (module docstring)."""
    sign = contour_sign(contour)
    side = arm.cam_side
    if side.circular:
        a, delta = side.centre_polar()

        def relation(t):
            cx, cy, nx, ny = contour_jets(contour, t, sign)
            try:
                theta, psi_c = analyse_pitch(cx + side.radius * nx, cy + side.radius * ny, arm.pivot, a, arm.branch)
            except ValueError:
                nan = Jet(np.full((4, np.size(t)), np.nan))
                return nan, nan
            return theta, psi_c - delta

        return relation
    o = arm.pivot
    distance = math.hypot(*o)
    phi_o = math.atan2(o[1], o[0])
    phi0 = arm.rest + side.face_angle
    b = 1.0 if wrap(phi0 - phi_o) >= 0.0 else -1.0

    def relation(t):
        cx, cy, nx, ny = contour_jets(contour, t, sign)
        beta = J.atan2(ny, nx)
        support = cx * nx + cy * ny
        with np.errstate(invalid="ignore"):
            phi = phi_o + b * J.acos((support - side.face_support) / distance)
        return phi - beta, phi - side.face_angle

    return relation
