"""The OHV pushrod train: cam -> lifter (flat face or roller, translating) -> pushrod (a straight
link between ball ends) -> centre-pivot rocker -> valve pad on the valve tip.

Layout (explorer.lift.contours.translating's conventions): cam centre at the origin turning
counter-clockwise by theta, the lifter's axis along +y at x = e (a roller lifter's offset; a flat
lifter's in-plane offset changes nothing and is 0), the lifter above the cam. The pushrod's lower
ball centre rides on the lifter, `socket_height` above the roller's centre or the face:
    B_L(L) = (e, y_L + L),   y_L = sqrt((Rb + r)^2 - e^2) + socket   (roller; flat: Rb + socket).
The rocker turns about O_r by psi; its pushrod cup (the upper ball's centre) B_R and its valve pad's
centre of curvature are given where they are with the valve closed. The pushrod keeps
|B_R - B_L| = l (its length, from the rest positions) and the rocker |B_R - O_r| = a.

Forward (analysis, and every check): the lifter's lift L -> B_L -> B_R as the intersection of the
circles of radius l about B_L and a about O_r (explorer.gears.linkage, on the side of the rest
configuration) -> psi -> the valve travel s(psi) of the valve end (explorer.gears.valve_end).
Backwards (synthesis, Schenker's construction from the wanted valve lift): s -> psi (closed form)
-> B_R(psi) -> the lifter's lift in closed form, the lower ball being on the lifter's axis:
    L = B_R,y - sigma sqrt(l^2 - (e - B_R,x)^2) - y_L    (sigma = +1: the lower ball below the cup)
-> the cam as the envelope of the lifter's face or roller (explorer.gears.envelope). Every step is
a closed form on jets, so the cam and the valve's motion carry exact derivatives.

ratio = ds/dL: valve travel per lifter travel (the "rocker ratio" seen from the lifter, which is
what a pushrod train's ratio is quoted as); rocker_ratio = |ds/dpsi| / a, the rocker's own lever
ratio; pushrod_angle: the pushrod's inclination to the lifter's axis (its side load on the lifter).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..lift.contours.arcs import ArcContour, ContourError, make_arc_lift
from ..lift.contours.parametric import ContourFollowError, make_parametric_lift
from ..mechanics.contact import hertz_line_stress
from . import jet as J
from .arm import tip_stress
from .contour_follow import as_parametric, check_base_circle, make_contour_motion
from .envelope import (
    CamSurface,
    EnvelopeContour,
    SurfaceVelocities,
    cam_velocity,
    check_no_cusp,
    check_no_undercut,
    circle_contact,
    circle_envelope,
    line_contact,
    surface_velocities,
)
from .flat_face import crown_stress, crowned_contact, crowned_face_surface, flat_face_relation, flat_face_surface
from .jet import Jet
from .linkage import DEAD_POINT_MARGIN, circle_intersection, closure_or_error
from .train_statics import ContactForces, cam_forces, point_velocity_about
from .valve_end import TipContact, ValveEnd, make_valve_end

TWO_PI = 2.0 * math.pi
LIFTER_KINDS = ("flat", "roller")


@dataclass(frozen=True)
class Lifter:
    kind: str  # "flat" | "roller"
    radius: float = math.inf  # m: roller radius; flat lifter: the face's crown radius (inf: flat)
    offset: float = 0.0  # m, roller lifter: its axis from the cam centre (x = offset)
    socket_height: float = 0.0  # m, from the roller's centre (or the face) up to the pushrod's lower ball
    width: float | None = None  # m, roller or lobe width for Hertz

    @property
    def circular(self) -> bool:
        return self.kind == "roller" or math.isfinite(self.radius)

    def rest_height(self, base_radius: float) -> float:
        """y of the lower ball's centre with the lifter on the base circle."""
        if self.kind == "roller":
            return math.sqrt((base_radius + self.radius) ** 2 - self.offset**2) + self.socket_height
        return base_radius + self.socket_height


@dataclass(frozen=True)
class PushrodKinematics:
    theta: np.ndarray
    lift: np.ndarray  # (4, N): valve travel (lash included) and its derivatives
    lifter_lift: np.ndarray  # (4, N): L and its derivatives
    rocker_angle: np.ndarray  # (4, N): psi
    surface: CamSurface  # the lifter on the cam
    lifter_pressure_angle: np.ndarray  # rad: the cam's normal vs the lifter's axis
    pushrod_angle: np.ndarray  # rad: the pushrod vs the lifter's axis
    ratio: np.ndarray  # ds/dL
    ratio_jet: np.ndarray  # (4, N): ds/dL and its derivatives in theta (exact, jets)
    rocker_ratio: np.ndarray  # |ds/dpsi| / a
    cam_velocities: SurfaceVelocities  # cam (first), lifter (second), m/rad
    roller_rate: np.ndarray | None  # rad/rad, the lifter roller's spin per radian of cam angle
    lower_ball: np.ndarray  # (N, 2)
    upper_ball: np.ndarray  # (N, 2)
    rocker_per_lift: np.ndarray  # dpsi/dL, rad/m
    tip: TipContact

    def time_derivatives(self, omega: float) -> np.ndarray:
        return self.lift * (omega ** np.arange(4))[:, None]


@dataclass(frozen=True)
class PushrodTrain:
    base_radius: float
    lifter: Lifter
    pushrod_length: float  # l, m
    rocker_pivot: tuple[float, float]
    rocker_arm: float  # a, m: pivot -> cup
    branch: int  # the cup's side of the line lower ball -> rocker pivot
    below: float  # +1: the lower ball is below the cup (the root of the backwards construction)
    rest: float  # psi0
    valve: ValveEnd
    law: Any = None  # LiftCurve: the valve-referred lift, lash included (synthesis)
    motion: Any = None  # LiftCurve of the lifter over a given contour (analysis)
    contour: Any = None
    file: str = "<memory>"
    key: str = "gear"

    def lower_ball(self, lifter_lift):
        return self.lifter.offset, self.lifter.rest_height(self.base_radius) + lifter_lift

    def rocker_angle_of_lift(self, lifter_lift, theta=None) -> Jet:
        """psi(L) through the pushrod's closure (forward), jets if L is a jet."""
        bx, by = self.lower_ball(lifter_lift)
        if not isinstance(by, Jet):
            by = np.asarray(by, dtype=float)
            bx = np.full(by.shape, bx)
        x, y = closure_or_error((bx, by), self.pushrod_length, self.rocker_pivot, self.rocker_arm, self.branch,
                                file=self.file, key=f"{self.key}.rocker.cup", what="the loop of pushrod and rocker",
                                theta=theta)
        psi = J.atan2(y - self.rocker_pivot[1], x - self.rocker_pivot[0])
        return psi + 2.0 * math.pi * np.round((self.rest - J.value(psi)) / (2.0 * math.pi))

    def lifter_lift_of_rocker(self, psi):
        """L(psi), the backwards construction's closed form (module docstring)."""
        o, a = self.rocker_pivot, self.rocker_arm
        cx, cy = o[0] + a * J.cos(psi), o[1] + a * J.sin(psi)
        dx = cx - self.lifter.offset
        radicand = self.pushrod_length**2 - dx * dx
        if np.any(J.value(radicand) <= 0.0):
            raise InputError(self.file, f"{self.key}.rocker.cup", "the pushrod (its length fixed by the cup's rest "
                             "position) is too short to reach the lifter's axis from the rocker's cup for this lift")
        return cy - self.below * J.sqrt(radicand) - self.lifter.rest_height(self.base_radius)

    def lifter_lift(self, theta) -> Jet:
        theta = np.asarray(theta, dtype=float)
        if self.law is not None:
            return self.lifter_lift_of_rocker(self.valve.inverse(Jet(self.law.derivatives(theta))))
        return Jet(self.motion.derivatives(theta))

    def valve_lift(self, theta) -> np.ndarray:
        if self.law is not None:
            return self.law.derivatives(np.asarray(theta, dtype=float))
        return self.valve.travel(self.rocker_angle_of_lift(self.lifter_lift(theta))).c

    def contact_jets(self, theta) -> tuple[Jet, Jet]:
        """The lifter's contact on the cam (ground frame) as jets in theta, to the second derivative."""
        L = self.lifter_lift(theta)
        f = self.lifter
        if f.kind == "roller":
            y0 = math.sqrt((self.base_radius + f.radius) ** 2 - f.offset**2)
            return circle_contact(theta, Jet.constant(np.full(L.c.shape[1:], f.offset)), L + y0, f.radius)
        if f.circular:
            return crowned_contact(L, self.base_radius, f.radius)
        return line_contact(theta, Jet.constant(np.full(L.c.shape[1:], 0.5 * math.pi)), L + self.base_radius)

    def synthesised_contour(self) -> EnvelopeContour:
        return EnvelopeContour(self.contact_jets)

    def surface(self, theta, lifter_lift: Jet | None = None) -> CamSurface:
        L = self.lifter_lift(theta) if lifter_lift is None else lifter_lift
        f = self.lifter
        if f.kind == "roller":
            y0 = math.sqrt((self.base_radius + f.radius) ** 2 - f.offset**2)
            return circle_envelope(theta, Jet.constant(np.full(L.c.shape[1:], f.offset)), L + y0, f.radius)
        if f.circular:
            return crowned_face_surface(theta, L, self.base_radius, f.radius)
        return flat_face_surface(theta, L, self.base_radius)

    def kinematics(self, theta) -> PushrodKinematics:
        theta = np.asarray(theta, dtype=float)
        if self.law is not None:
            s = Jet(self.law.derivatives(theta))
            psi = self.valve.inverse(s)
            L = self.lifter_lift_of_rocker(psi)
        else:
            L = self.lifter_lift(theta)
            psi = self.rocker_angle_of_lift(L, theta)
            s = self.valve.travel(psi)
        surface = self.surface(theta, L)
        n = surface.normal
        pressure = np.arctan2(-n[:, 0], n[:, 1])
        lifter_velocity = np.column_stack([np.zeros_like(theta), L.c[1]])
        velocities = surface_velocities(surface.tangent, surface.contact_rate, cam_velocity(surface.contact), lifter_velocity)
        roller_rate = None
        if self.lifter.kind == "roller":
            lifter_surface = velocities.second
            velocities = SurfaceVelocities(velocities.first, velocities.first.copy())
            roller_rate = (velocities.first - lifter_surface) / self.lifter.radius
        bx, by = self.lower_ball(L.c[0])
        lower = np.column_stack([np.full_like(theta, bx), by])
        o, a = self.rocker_pivot, self.rocker_arm
        upper = np.column_stack([o[0] + a * np.cos(psi.c[0]), o[1] + a * np.sin(psi.c[0])])
        rod = upper - lower
        pushrod_angle = np.arctan2(rod[:, 0], rod[:, 1])
        # dpsi/dL from the closure |B_R - B_L| = l differentiated (not psi'/L', which is 0/0 on the
        # base circle): rod . (J (B_R - O_r) dpsi - e_y dL) = 0; on jets, for the ratio's derivatives
        ux, uy = o[0] + a * J.cos(psi), o[1] + a * J.sin(psi)
        rx, ry = ux - bx, uy - (L + self.lifter.rest_height(self.base_radius))
        per_lift = ry / (rx * (o[1] - uy) + ry * (ux - o[0]))
        pad = self.valve.centre(psi)
        ratio_jet = (self.valve.valve_per_arm(psi, pad) * per_lift).c
        psi_per_lift = per_lift.c[0]
        tip = self.valve.contact(psi, pad)
        ds_dpsi = tip.valve_per_arm
        return PushrodKinematics(
            theta=theta, lift=s.c, lifter_lift=L.c, rocker_angle=psi.c, surface=surface, lifter_pressure_angle=pressure,
            pushrod_angle=pushrod_angle, ratio=ds_dpsi * psi_per_lift, ratio_jet=ratio_jet,
            rocker_ratio=np.abs(ds_dpsi) / a,
            cam_velocities=velocities, roller_rate=roller_rate, lower_ball=lower, upper_ball=upper,
            rocker_per_lift=psi_per_lift, tip=tip,
        )

    def check(self, n: int = 3600) -> PushrodKinematics:
        theta = np.linspace(0.0, TWO_PI, n, endpoint=False)
        k = self.kinematics(theta)
        f = self.lifter
        if self.contour is not None:
            pass  # a given contour: its analysis found the lifter's contact running round it steadily
        elif f.kind == "roller":
            check_no_undercut(k.surface, f.radius, self.file, f"{self.key}.lifter.roller_radius",
                              "use a smaller roller, a larger base circle or a longer event")
        else:
            worst = float(np.min(k.surface.radius))
            check_no_cusp(k.surface, self.file, "follower.base_radius",
                          f"enlarge follower.base_radius by more than {max(-worst, 0.0) * 1e3:.3g} mm, or soften the "
                          "lift's negative acceleration there")
        # the closure along the way (dead point of pushrod and rocker in line)
        self.rocker_angle_of_lift(k.lifter_lift[0], theta)
        self.valve.check_on_tip(theta, k.tip)
        return k

    def contact_forces(self, k: PushrodKinematics, valve_force, cam_friction: float = 0.0,
                       tip_friction: float = 0.0) -> ContactForces:
        """The train's statics (explorer.gears.train_statics), coordinate q = the lifter's lift:
        the lifter moves along its axis, the rocker's tip point at J (X_t - O_r) dpsi/dL. The bore,
        the ball ends and the rocker's pivot are frictionless; a roller lifter rolls."""
        mu = cam_friction if self.lifter.kind == "flat" else 0.0
        m = len(k.theta)
        valve_jac = point_velocity_about(self.rocker_pivot, k.tip.point) * k.rocker_per_lift[:, None]
        return cam_forces(valve_force, contact=k.surface.contact, normal=k.surface.normal, tangent=k.surface.tangent,
                          cam_jacobian=np.tile([0.0, 1.0], (m, 1)), cam_sliding=k.cam_velocities.sliding, cam_friction=mu,
                          valve_axis=np.tile(self.valve.axis, (m, 1)), valve_jacobian=valve_jac,
                          tip_tangent=k.tip.tangent, tip_sliding=k.tip.velocities.sliding, tip_friction=tip_friction)

    def pushrod_force(self, k: PushrodKinematics, forces: ContactForces) -> np.ndarray:
        """Compression of the pushrod (N) from the rocker's moments about its pivot: the pushrod
        pushes the cup along the rod, the valve pushes back at the tip (with its friction)."""
        o = np.asarray(self.rocker_pivot)
        rod = k.upper_ball - k.lower_ball
        e = rod / np.hypot(rod[:, 0], rod[:, 1])[:, None]
        arm = k.upper_ball - o
        u = self.valve.axis
        tip_force = -forces.tip_normal[:, None] * u + forces.tip_friction[:, None] * k.tip.tangent
        lever = k.tip.point - o
        moment_tip = lever[:, 0] * tip_force[:, 1] - lever[:, 1] * tip_force[:, 0]
        per_newton = arm[:, 0] * e[:, 1] - arm[:, 1] * e[:, 0]
        return -moment_tip / per_newton

    def hertz_stress(self, k: PushrodKinematics, forces: ContactForces, e_star: float,
                     tip_width: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Peak Hertz pressure at the cam (the lifter's roller or face on the lobe: a line contact of
        the lifter's width; a crowned face: the point contact as for the bucket tappet, at least the
        line contact where its ellipse would overrun the width, explorer.gears.flat_face.crown_stress)
        and at the valve tip (explorer.gears.arm.tip_stress)."""
        f = self.lifter
        if f.width is None:
            raise InputError(self.file, f"{self.key}.lifter.width", "the contact stress needs the roller's or lobe's width")
        rho = k.surface.radius
        if f.kind == "flat" and f.circular:
            cam = crown_stress(forces.normal, f.radius, rho, e_star, f.width)[0]
        else:
            cam = hertz_line_stress(forces.normal, f.width, f.radius, rho, e_star)
        return cam, tip_stress(self.valve, k.tip, forces.tip_normal, e_star, tip_width)


def make_pushrod_train(*, base_radius: float, lifter: Lifter, rocker_pivot, cup, valve_pad_centre,
                       valve_pad_radius: float, valve_axis: float | None = None, valve_axis_point=None,
                       tip_radius: float | None = None, law=None, contour=None, file: str = "<memory>",
                       key: str = "gear", check: bool = True, n: int = 3600) -> PushrodTrain:
    """The pushrod train from its rest layout (points with the valve closed) and a valve-lift law
    (synthesis) or a contour (analysis), checked over a revolution."""
    if (law is None) == (contour is None):
        raise ValueError("give either a lift law (synthesis) or a contour (analysis)")
    if lifter.kind not in LIFTER_KINDS:
        raise InputError(file, f"{key}.lifter.type", f"unknown value {lifter.kind!r}; choose one of: {', '.join(LIFTER_KINDS)}")
    if lifter.kind == "roller":
        if not (math.isfinite(lifter.radius) and lifter.radius > 0.0):
            raise InputError(file, f"{key}.lifter.roller_radius", f"must be greater than zero, got {lifter.radius!r}")
        if abs(lifter.offset) >= base_radius + lifter.radius:
            raise InputError(file, f"{key}.lifter.offset", "the lifter's axis misses the roller's path round the base circle")
    elif lifter.offset != 0.0:
        raise InputError(file, f"{key}.lifter.offset", "a flat lifter's in-plane offset does not change its motion: leave it 0")
    pivot = (float(rocker_pivot[0]), float(rocker_pivot[1]))
    cup = np.asarray(cup, dtype=float)
    lower = np.array([lifter.offset, lifter.rest_height(base_radius)])
    length = float(np.hypot(*(cup - lower)))
    arm = float(np.hypot(*(cup - np.asarray(pivot))))
    if length <= 0.0 or arm <= 0.0:
        raise InputError(file, f"{key}.rocker.cup", "the cup must lie away from the rocker's pivot and the lifter's ball")
    to_pivot = np.asarray(pivot) - lower
    side = to_pivot[0] * (cup - lower)[1] - to_pivot[1] * (cup - lower)[0]
    branch = 1 if side > 0.0 else -1
    x, y, q = circle_intersection(tuple(lower), length, pivot, arm, branch)
    if x is None or q < DEAD_POINT_MARGIN:
        raise InputError(file, f"{key}.rocker.cup", "pushrod and rocker arm are in line at rest (dead point)")
    rest = math.atan2(cup[1] - pivot[1], cup[0] - pivot[0])
    below = 1.0 if cup[1] > lower[1] else -1.0
    # the rocker's angle grows or falls as the lifter rises: from the closure, exactly
    train0 = PushrodTrain(base_radius=base_radius, lifter=lifter, pushrod_length=length, rocker_pivot=pivot,
                          rocker_arm=arm, branch=branch, below=below, rest=rest, valve=None, file=file, key=key)
    slope = float(train0.rocker_angle_of_lift(Jet.variable(np.array([0.0]))).c[1][0])
    lifting = 1.0 if slope > 0.0 else -1.0
    centre = np.asarray(valve_pad_centre, dtype=float) - np.asarray(pivot)
    valve = make_valve_end(pivot=pivot, rest=rest, lifting=lifting, arm=float(np.hypot(*centre)),
                           angle=math.atan2(centre[1], centre[0]) - rest, pad_radius=valve_pad_radius, axis=valve_axis,
                           axis_point=valve_axis_point, tip_radius=tip_radius, file=file, key=f"{key}.valve_pad",
                           tip_key=f"{key}.valve.tip_radius")
    train = replace(train0, valve=valve, law=law)
    if contour is not None:
        train = replace(train, motion=_lifter_motion(train, contour), contour=contour)
        check_base_circle(lambda theta: train.lifter_lift(theta).c[0], file=file, rests="the lifter would rest {} off it")
    if check:
        train.check(n)
    return train


def _lifter_motion(train: PushrodTrain, contour):
    """The lifter's lift over a given contour: a flat face by the support function
    (explorer.gears.flat_face), a roller or a crowned face by explorer.lift.contours' roller analysis."""
    f, file = train.lifter, train.file
    if f.circular:
        try:
            if isinstance(contour, ArcContour):
                return make_arc_lift(contour, f.radius, f.offset, train.base_radius)
            return make_parametric_lift(contour, f.radius, f.offset, train.base_radius)
        except (ContourError, ContourFollowError) as exc:
            raise InputError(file, f"{train.key}.lifter.{'roller_radius' if f.kind == 'roller' else 'face_radius'}",
                             f"the lifter cannot follow the contour: {exc}") from None
    param = as_parametric(contour)
    return make_contour_motion(flat_face_relation(param, train.base_radius), param, file=file, key="cam",
                               what="the flat lifter")
