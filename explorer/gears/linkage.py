"""Planar linkage pieces in closed form, on jets: circle intersections, the eccentric four-bar,
and the valve drives that turn a lever angle into valve travel.

Every loop closure here is a circle-circle intersection (a dyad): the point at distance r1 from
p1 and r2 from p2, on a chosen side. That is exact and has a closed form, so no iteration is
needed; the jets carry the derivatives through. A closure that does not exist (the circles
miss each other) or that sits at a dead point (the two links in line, where the derivative is
infinite) is reported with the scene key of the offending part.

Conventions: x to the right, y up, angles counter-clockwise from +x, the camshaft (eccentric
shaft) at the origin turning counter-clockwise with angle theta.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from . import jet as J
from .jet import Jet

# A closure whose triangle height is below this fraction of the link lengths is treated as a
# dead point: derivatives there grow without bound (1/h), so the gear cannot be driven through it.
DEAD_POINT_MARGIN = 1e-6


def side_sign(name: str) -> int:
    return {"left": 1, "right": -1}[name]


def circle_intersection(p1, r1: float, p2, r2: float, branch: int):
    """Point P with |P - p1| = r1 and |P - p2| = r2, to the left (branch +1) or right (-1) of the
    directed line p1 -> p2. Returns (x, y, q) with q = (h / d)^2 the squared relative height of
    the triangle (q < 0: no closure; q ~ 0: dead point)."""
    dx = p2[0] - p1[0]
    dy = p2[1] - p1[1]
    d2 = dx * dx + dy * dy
    d2v = J.value(d2)
    if np.any(np.asarray(d2v) <= 0.0):  # concentric circles (a pivot on the shaft centre): no closure
        return None, None, np.where(np.asarray(d2v) <= 0.0, -1.0, 0.0) if np.ndim(d2v) else -1.0
    a = (r1 * r1 - r2 * r2 + d2) / (2.0 * d2)
    q = r1 * r1 / d2 - a * a
    qv = J.value(q)
    if np.any(qv <= 0.0):
        return None, None, qv
    h = J.sqrt(q)
    x = p1[0] + a * dx - branch * (h * dy)
    y = p1[1] + a * dy + branch * (h * dx)
    return x, y, qv


def closure_or_error(p1, r1, p2, r2, branch, *, file, key, what, theta=None):
    """circle_intersection that raises InputError naming `key` when the loop cannot close."""
    x, y, q = circle_intersection(p1, r1, p2, r2, branch)
    if x is None or np.any(q < DEAD_POINT_MARGIN):
        bad = int(np.argmin(q)) if np.ndim(q) else 0
        where = ""
        if theta is not None and np.ndim(theta):
            where = f" at shaft angle {math.degrees(float(np.asarray(theta)[bad]) % 360.0):.2f} deg"
        if x is None or np.min(q) <= 0.0:
            raise InputError(file, key, f"{what} cannot close{where}: the links do not reach each other")
        raise InputError(file, key, f"{what} passes through a dead point{where} (links in line)")
    return x, y


def polar(centre, radius, angle):
    return centre[0] + radius * J.cos(angle), centre[1] + radius * J.sin(angle)


def polar_curvature(r) -> np.ndarray:
    """Signed curvature of a curve given in polar form about a pivot, r as a jet in the polar angle:
    kappa = (r^2 + 2 r'^2 - r r'') / (r^2 + r'^2)^(3/2); > 0 where the curve bends round the pivot
    as a circle about it does (convex seen from outside), 1/r for that circle."""
    r0, r1, r2 = r.c[0], r.c[1], r.c[2]
    return (r0**2 + 2.0 * r1**2 - r0 * r2) / (r0**2 + r1**2) ** 1.5


def wrap(angle):
    """Angle in (-pi, pi]."""
    return np.mod(np.asarray(angle) + math.pi, 2.0 * math.pi) - math.pi


# --------------------------------------------------------------------------------------------
# The eccentric four-bar: eccentric (crank) e at the shaft, rod l, rocking lever b about C.
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class EccentricDrive:
    """Eccentric of throw `radius` and phase `phase` (angle of the eccentric centre at theta = 0),
    rod of length `rod` to the pin of a rocking lever of arm `arm` pivoted at `pivot`; `branch`
    +1 puts the pin to the left of the line pivot -> eccentric centre. Output: lever angle chi."""

    radius: float
    phase: float
    rod: float
    pivot: tuple[float, float]
    arm: float
    branch: int
    file: str = "<memory>"
    key: str = "gear.eccentric"

    def centre(self, theta):
        """Eccentric centre E(theta) (jets if theta is a jet)."""
        return polar((0.0, 0.0), self.radius, theta + self.phase)

    def pin(self, theta):
        e = self.centre(theta)
        return closure_or_error(
            self.pivot, self.arm, e, self.rod, self.branch, file=self.file, key=f"{self.key}.rod",
            what="the eccentric rod", theta=J.value(theta),
        )

    def angle(self, theta):
        """Rocking-lever angle chi(theta) as a jet (or array)."""
        bx, by = self.pin(theta)
        return J.atan2(by - self.pivot[1], bx - self.pivot[0])

    def check(self) -> None:
        """The four-bar must close at every shaft angle (the eccentric turns fully)."""
        pivot_distance = math.hypot(*self.pivot)
        if pivot_distance <= self.radius:
            raise InputError(self.file, f"{self.key}.lever_pivot", "the lever pivot lies inside the eccentric circle")
        self.angle(np.linspace(0.0, 2.0 * math.pi, 1441))

    def dead_centres(self) -> tuple[float, float]:
        """Shaft angles (rad, [0, 2 pi)) where the rocking lever reverses: eccentric centre, rod
        and pin in line (rod extended / folded). At a reversal the pin velocity is zero, which for
        a rigid rod means the eccentric velocity is perpendicular to the rod: E, B and O collinear."""
        # |OB| at the two reversals is rod + radius (extended) and rod - radius (folded).
        out = []
        for reach in (self.rod + self.radius, abs(self.rod - self.radius)):
            bx, by = circle_intersection(self.pivot, self.arm, (0.0, 0.0), reach, self.branch)[:2]
            if bx is None:
                raise InputError(self.file, f"{self.key}.rod", "the eccentric rod cannot reach the rocking lever")
            angle = math.atan2(float(by), float(bx))
            if reach == self.rod + self.radius:
                e_angle = angle  # E between O and B
            else:
                e_angle = angle if self.rod < self.radius else angle + math.pi
            out.append(float(np.mod(e_angle - self.phase, 2.0 * math.pi)))
        return out[0], out[1]


@dataclass(frozen=True)
class IdealEccentricDrive:
    """The infinitely long eccentric rod: the rod keeps its direction `direction`, so the pin's
    coordinate along it follows the eccentric's harmonic motion exactly:
        u . (B - C) = arm cos(chi - lambda_u) = radius cos(theta + phase - lambda_u) + offset.
    chi is then an even function of theta about the dead centre theta_d = lambda_u - phase: the
    reference case in which opening and closing are exact mirror images."""

    radius: float
    phase: float
    direction: float  # lambda_u, rad
    pivot: tuple[float, float]
    arm: float
    offset: float  # m, pin coordinate along u (relative to the pivot) at eccentric quadrature
    branch: int  # +1: chi = lambda_u + acos(.), -1: lambda_u - acos(.)

    def angle(self, theta):
        q = (self.radius * J.cos(theta + self.phase - self.direction) + self.offset) / self.arm
        qv = J.value(q)
        if np.any(np.abs(qv) >= 1.0 - DEAD_POINT_MARGIN):
            raise InputError("<memory>", "gear.eccentric", "the ideal rod drive leaves the lever's reach")
        return self.direction + self.branch * J.acos(q)

    def dead_centres(self) -> tuple[float, float]:
        first = float(np.mod(self.direction - self.phase, 2.0 * math.pi))
        return first, float(np.mod(first + math.pi, 2.0 * math.pi))


# --------------------------------------------------------------------------------------------
# Valve drives: lever angle -> valve travel (valve-referred lift of the linkage end).
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RockerDrive:
    """The valve pin f sits on the lever itself (pivot `pivot`, lever angle psi): at distance
    `arm` and angle `angle` from the lever's reference direction. The valve stem, axis `axis`
    (unit direction in which the valve opens), is moved by f through a pin in a slot, so only
    f's displacement along the axis counts: s = u . (f(psi) - f(psi0))."""

    pivot: tuple[float, float]
    arm: float
    angle: float  # rad, f relative to the lever reference direction
    axis: float  # rad, direction of valve opening
    rest: float  # psi0, lever angle at closed valve (linkage end at zero travel)
    file: str = "<memory>"
    key: str = "gear.valve"

    def _projection(self, psi):
        # u . (f - pivot) = arm cos(psi + angle - axis)
        return self.arm * J.cos(psi + self.angle - self.axis)

    def travel(self, psi):
        return self._projection(psi) - float(self._projection(self.rest))

    def slope_sign(self) -> float:
        """Sign of ds/dpsi at rest (the lever direction that opens the valve)."""
        return float(np.sign(-math.sin(self.rest + self.angle - self.axis)))

    def inverse(self, s):
        """psi(s): cos(psi + angle - axis) = (s + p0) / arm, on the rest branch."""
        p0 = float(self._projection(self.rest))
        q = (s + p0) / self.arm
        qv = J.value(q)
        if np.any(np.abs(qv) >= 1.0 - DEAD_POINT_MARGIN):
            raise InputError(self.file, f"{self.key}.arm", "valve arm too short for the lift: the valve pin would pass its dead point")
        branch = 1.0 if wrap(self.rest + self.angle - self.axis) >= 0.0 else -1.0
        psi = self.axis - self.angle + branch * J.acos(q)
        return psi + _turns(self.rest, psi)


@dataclass(frozen=True)
class RodLeverDrive:
    """Schenker's Fig. 3: a rod of length `rod` from the roller axle (point R on the roller lever
    at distance `lever_arm` from `lever_pivot`) to pin d of the valve lever d-e-f (pivot e =
    `valve_pivot`, arm e-d = `arm_in`, arm e-f = `arm_out`, angle d-e-f = `bend`); f moves the
    valve stem along `axis` (pin in slot). `branch` places d left (+1) / right (-1) of e -> R."""

    lever_pivot: tuple[float, float]
    lever_arm: float
    rod: float
    valve_pivot: tuple[float, float]
    arm_in: float
    arm_out: float
    bend: float
    axis: float
    branch: int
    rest: float  # psi0
    file: str = "<memory>"
    key: str = "gear.valve"

    def pin_d(self, psi):
        r = polar(self.lever_pivot, self.lever_arm, psi)
        return closure_or_error(
            self.valve_pivot, self.arm_in, r, self.rod, self.branch, file=self.file, key=f"{self.key}.rod",
            what="the rod d-a between roller lever and valve lever",
        )

    def valve_lever_angle(self, psi):
        dx, dy = self.pin_d(psi)
        return J.atan2(dy - self.valve_pivot[1], dx - self.valve_pivot[0])

    def _projection(self, beta):
        return self.arm_out * J.cos(beta + self.bend - self.axis)

    def travel(self, psi):
        beta = self.valve_lever_angle(psi)
        beta0 = float(self.valve_lever_angle(np.array(self.rest)))
        return self._projection(beta) - float(self._projection(beta0))

    def slope_sign(self) -> float:
        j = self.travel(Jet.variable(np.array([self.rest])))
        return float(np.sign(j.c[1][0]))

    def inverse(self, s):
        """psi(s): valve lever angle from the travel (acos), pin d, then the roller axle as the
        intersection of the rod circle about d and the lever circle about its pivot."""
        beta0 = float(self.valve_lever_angle(np.array(self.rest)))
        p0 = float(self._projection(beta0))
        q = (s + p0) / self.arm_out
        qv = J.value(q)
        if np.any(np.abs(qv) >= 1.0 - DEAD_POINT_MARGIN):
            raise InputError(self.file, f"{self.key}.arm_out", "valve lever arm too short for the lift (passes its dead point)")
        branch = 1.0 if wrap(beta0 + self.bend - self.axis) >= 0.0 else -1.0
        beta = self.axis - self.bend + branch * J.acos(q)
        d = polar(self.valve_pivot, self.arm_in, beta)
        r0 = polar(self.lever_pivot, self.lever_arm, self.rest)
        d0 = polar(self.valve_pivot, self.arm_in, beta0)
        # the side of the roller axle relative to pivot -> d, taken from the rest configuration
        side = (d0[0] - self.lever_pivot[0]) * (r0[1] - self.lever_pivot[1]) - (d0[1] - self.lever_pivot[1]) * (r0[0] - self.lever_pivot[0])
        rx, ry = closure_or_error(
            self.lever_pivot, self.lever_arm, d, self.rod, 1 if side > 0 else -1, file=self.file,
            key=f"{self.key}.rod", what="the rod d-a between roller lever and valve lever",
        )
        psi = J.atan2(ry - self.lever_pivot[1], rx - self.lever_pivot[0])
        return psi + _turns(self.rest, psi)


def _turns(reference: float, angle) -> float:
    """Whole turns that bring the angle's first value next to the reference (branch bookkeeping)."""
    first = float(np.ravel(J.value(angle))[0])
    return 2.0 * math.pi * round((reference - first) / (2.0 * math.pi))
