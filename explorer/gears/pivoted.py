"""Pivoted roller lever on a rotating cam (seed 004; Schenker's Fig. 3), synthesis and analysis.

Layout: cam centre O at the origin, turning counter-clockwise by theta. The roller (radius r)
sits on a lever of arm a about the pivot O1; the lever drives the valve through a valve drive
(linkage.RockerDrive: valve pin on the same lever; linkage.RodLeverDrive: Fig. 3's rod d-a and
valve lever d-e-f). The valve-referred lift L(theta) (lash included) is prescribed.

Synthesis (exact, closed form on jets):  L -> lever angle psi = drive^-1(L) -> roller centre
R = O1 + a e(psi) -> pitch curve in the cam frame P = Rot(-theta) R -> contour = P - r n (the
envelope of the roller circles; n the outward unit normal of the pitch curve).

Analysis (seed 004's construction): a pitch-curve point at radius rho from O is under the
roller when it lies on the circle of radius a about O1: "arcs about O and O1". That gives the
roller centre and the cam angle for each contour point in closed form (`analyse_pitch`), and
`analyse_contour` finds the roller circle tangent to a contour by Newton, independently.

Velocity from the contact normal (seed 004): the relative instant centre I of cam and lever lies
on the line O-O1 and on the contact normal; psi' = lambda / (lambda - 1) with I = O + lambda O1.
Pressure angle referred to the lever: angle between the contact normal and the roller centre's
direction of travel (perpendicular to O1-R); self-locking at alpha + rho = 90 deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..lift.validity import cam_fault, entered_error
from ..mechanics.contact import ContactGeometry
from . import jet as J
from .jet import Jet
from .linkage import circle_intersection, polar


@dataclass(frozen=True)
class PivotedRollerGear:
    lift: Any  # LiftCurve, valve-referred, lash included
    base_radius: float  # m, base circle of the contour
    roller_radius: float  # m
    pivot: tuple[float, float]  # O1, m
    arm: float  # a, m: O1 -> roller centre
    branch: int  # roller left (+1) / right (-1) of the line O1 -> O
    drive: Any  # RockerDrive | RodLeverDrive, rest = rest_angle
    file: str = "<memory>"

    # -- rest configuration -----------------------------------------------------------------
    @staticmethod
    def rest_angle_for(base_radius, roller_radius, pivot, arm, branch, file="<memory>") -> float:
        x, y, q = circle_intersection(pivot, arm, (0.0, 0.0), base_radius + roller_radius, branch)
        if x is None:
            raise InputError(file, "gear.lever.arm", "the roller on this lever cannot reach the cam's base circle")
        if q < 1e-6:
            raise InputError(file, "gear.lever.arm", "lever and cam radius in line: the roller would not lift")
        return math.atan2(float(y) - pivot[1], float(x) - pivot[0])

    @property
    def rest_angle(self) -> float:
        return self.drive.rest

    # -- synthesis --------------------------------------------------------------------------
    def lift_jet(self, theta) -> Jet:
        return Jet(self.lift.derivatives(np.asarray(theta, dtype=float)))

    def lever_angle(self, theta) -> Jet:
        """psi(theta) as a jet in theta."""
        return self.drive.inverse(self.lift_jet(theta))

    def roller_centre(self, theta):
        return polar(self.pivot, self.arm, self.lever_angle(theta))

    def pitch(self, theta):
        """Roller centre in the cam frame, P = Rot(-theta) R, as jets in theta."""
        t = Jet.variable(np.asarray(theta, dtype=float))
        rx, ry = self.roller_centre(theta)
        c, s = J.cos(t), J.sin(t)
        return c * rx + s * ry, c * ry - s * rx

    def contour_jets(self, theta):
        """Contour point (x, y) in the cam frame as jets in the synthesis angle: the pitch point
        moved by the roller radius along the inward normal. Valid to the second derivative (the
        normal needs the pitch curve's derivative, so the third is NaN)."""
        px, py = self.pitch(theta)
        tx, ty = px.shift(), py.shift()
        speed = J.hypot(tx, ty)
        r = self.roller_radius
        return px + r * ty / speed, py - r * tx / speed

    def geometry(self, theta) -> "LeverGeometry":
        theta = np.asarray(theta, dtype=float)
        psi = self.lever_angle(theta)
        rx, ry = polar(self.pivot, self.arm, psi)
        t = Jet.variable(theta)
        c, s = J.cos(t), J.sin(t)
        px, py = c * rx + s * ry, c * ry - s * rx
        # tangent of the pitch curve; the cam turns ccw so the curve is traced clockwise in the
        # cam frame and the outward normal is the tangent turned +90 deg
        tx, ty = px.c[1], py.c[1]
        speed = np.hypot(tx, ty)
        nx, ny = -ty / speed, tx / speed
        cross = tx * py.c[2] - ty * px.c[2]
        with np.errstate(divide="ignore"):
            pitch_radius = -(speed**3) / cross  # > 0 where the pitch curve is convex
        r = self.roller_radius
        contour = np.column_stack([px.c[0] - r * nx, py.c[0] - r * ny])
        # ground frame: contact normal, contact point
        cth, sth = np.cos(theta), np.sin(theta)
        ngx, ngy = cth * nx - sth * ny, sth * nx + cth * ny
        R = np.column_stack([rx.c[0], ry.c[0]])
        contact = R - r * np.column_stack([ngx, ngy])
        # roller travel direction for increasing psi, and the direction in which it lifts
        ex, ey = -np.sin(psi.c[0]), np.cos(psi.c[0])
        lifting = self.lifting_sign()
        tlx, tly = lifting * ex, lifting * ey
        pressure = np.arctan2(tlx * ngy - tly * ngx, tlx * ngx + tly * ngy)
        s = self.drive.travel(psi)
        # the valve drive's ratio straight from the drive, independent of the cam
        ds_dpsi = self.drive.travel(Jet.variable(psi.c[0])).c[1]
        return LeverGeometry(
            theta=theta, lever_angle=psi.c[0], lever_rate=psi.c[1], lever_accel=psi.c[2],
            roller_centre=R, pitch=np.column_stack([px.c[0], py.c[0]]), normal=np.column_stack([nx, ny]),
            contour=contour, pitch_radius=pitch_radius, contour_radius=pitch_radius - r,
            contact=contact, normal_ground=np.column_stack([ngx, ngy]), pressure_angle=pressure,
            valve_per_lever=ds_dpsi, ratio=np.abs(ds_dpsi) / self.arm, lift=s.c[0],
        )

    def contact_geometry(self, theta):
        """explorer.mechanics.contact's view of the cam-roller contact: pressure angle referred to the lever,
        ratio |ds/dpsi| / a (valve travel per roller-centre travel), and the torque arm R x n of
        the normal through the roller centre about the camshaft."""
        g = self.geometry(theta)
        r, n = g.roller_centre, g.normal_ground
        arm = r[:, 0] * n[:, 1] - r[:, 1] * n[:, 0]
        return ContactGeometry(
            pressure_angle=g.pressure_angle, ratio=g.ratio, torque_arm=arm, body_arm=arm,
            body_radius=np.hypot(g.contact[:, 0], g.contact[:, 1]), contour_radius=g.contour_radius,
            counter_radius=self.roller_radius, roller_diameter=2.0 * self.roller_radius,
        )

    def lifting_sign(self) -> float:
        """+1 if increasing psi moves the roller away from the cam centre at rest, else -1."""
        psi0 = self.rest_angle
        rx, ry = polar(self.pivot, self.arm, psi0)
        return float(np.sign(rx * -math.sin(psi0) + ry * math.cos(psi0)))

    # -- velocity by the instant centre (seed 004) -------------------------------------------
    @staticmethod
    def instant_centre_rate(pivot, roller_centre, normal_ground) -> np.ndarray:
        """d psi / d theta from the contact normal: I = lambda O1 on line O-O1 and on the normal
        R + mu n; Kennedy's theorem gives omega_lever / omega_cam = lambda / (lambda - 1)."""
        ox, oy = pivot
        rx, ry = roller_centre[:, 0], roller_centre[:, 1]
        nx, ny = normal_ground[:, 0], normal_ground[:, 1]
        # lambda (ox, oy) - mu (nx, ny) = (rx, ry)
        det = -ox * ny + oy * nx
        lam = (-rx * ny + ry * nx) / det
        return lam / (lam - 1.0)

    # -- checks -----------------------------------------------------------------------------
    def check(self, n: int = 1440) -> "LeverGeometry":
        theta = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
        g = self.geometry(theta)
        r = self.roller_radius
        # the checks every cam passes (explorer.lift.validity): the valve-referred lift, the
        # pressure angle at the roller and the undercut of the cam this lever needs
        fault = cam_fault(theta, g.lift, pressure_angle=g.pressure_angle, pitch_radius=g.pitch_radius, roller_radius=r)
        if fault is not None:
            raise entered_error(fault, self.file)
        outer = float(np.max(np.hypot(g.contour[:, 0], g.contour[:, 1])))
        if math.hypot(*self.pivot) <= outer:
            raise InputError(self.file, "gear.lever.pivot", "the lever pivot lies inside the cam's sweep (cam nose radius "
                             f"{outer * 1e3:.4g} mm)")
        check_arm_clear(g, self.pivot, r, self.file)
        return g


@dataclass(frozen=True)
class LeverGeometry:
    theta: np.ndarray
    lever_angle: np.ndarray  # psi, rad (ground)
    lever_rate: np.ndarray  # d psi / d theta
    lever_accel: np.ndarray  # d2 psi / d theta2
    roller_centre: np.ndarray  # (N, 2) ground
    pitch: np.ndarray  # (N, 2) cam frame
    normal: np.ndarray  # (N, 2) cam frame, outward
    contour: np.ndarray  # (N, 2) cam frame
    pitch_radius: np.ndarray  # m, > 0 convex
    contour_radius: np.ndarray  # m
    contact: np.ndarray  # (N, 2) ground
    normal_ground: np.ndarray  # (N, 2) ground, from cam towards roller centre
    pressure_angle: np.ndarray  # rad, normal vs the roller's lifting direction
    valve_per_lever: np.ndarray  # ds/dpsi, m/rad
    ratio: np.ndarray  # valve travel per roller-centre arc travel, |ds/dpsi| / a
    lift: np.ndarray  # valve-referred lift from the linkage (equals the prescribed law)


def check_arm_clear(g: LeverGeometry, pivot, roller_radius: float, file: str, key: str = "gear.lever.pivot",
                    n_theta: int = 360) -> None:
    """The lever arm (pivot to the roller's rim) must not cut the cam at any cam angle: test the
    arm segment against every edge of the contour polygon, turned to each cam angle."""
    step = max(1, len(g.theta) // n_theta)
    contour = g.contour
    a0, a1 = contour, np.roll(contour, -1, axis=0)
    for i in range(0, len(g.theta), step):
        th = g.theta[i]
        c, s = math.cos(th), math.sin(th)
        rot = np.array([[c, -s], [s, c]])
        p = a0 @ rot.T
        q = a1 @ rot.T
        R = g.roller_centre[i]
        O1 = np.asarray(pivot, dtype=float)
        d = R - O1
        length = math.hypot(*d)
        if length <= roller_radius:
            continue
        end = O1 + d * (1.0 - roller_radius / length)  # where the arm meets the roller rim
        if _segment_hits_polyline(O1, end, p, q):
            raise InputError(
                file, key,
                f"the lever arm would pass through the cam at cam angle {math.degrees(th):.1f} deg "
                "(move the pivot or shorten the lift)",
            )


def _segment_hits_polyline(a, b, p, q) -> bool:
    def orient(u, v, w):
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])

    d1 = orient(p, q, a)
    d2 = orient(p, q, b)
    d3 = orient(a[None, :], b[None, :], p)
    d4 = orient(a[None, :], b[None, :], q)
    return bool(np.any((d1 * d2 < 0.0) & (d3 * d4 < 0.0)))


# --------------------------------------------------------------------------------------------
# Analysis: from a pitch curve / a contour back to the lever motion.
# --------------------------------------------------------------------------------------------


def analyse_pitch(pitch_x: Jet, pitch_y: Jet, pivot, arm: float, branch: int):
    """Seed 004's construction for pitch points given as jets in a curve parameter phi: the point
    at radius rho = |P| lies under the roller where the circle of radius rho about O meets the
    lever circle about O1. Returns (theta(phi), psi(phi)) jets: the cam angle at which this
    point is under the roller, and the lever angle then."""
    rho = J.hypot(pitch_x, pitch_y)
    rx, ry, q = circle_intersection(pivot, arm, (0.0, 0.0), rho, branch)
    if rx is None:
        raise ValueError("pitch point out of the lever's reach")
    theta = J.atan2(ry, rx) - J.atan2(pitch_y, pitch_x)
    psi = J.atan2(ry - pivot[1], rx - pivot[0])
    return theta, psi


def analyse_contour(contour_point, theta: np.ndarray, psi_guess: np.ndarray, phi_guess: np.ndarray,
                    pivot, arm: float, roller_radius: float, tol: float = 1e-15, max_iter: int = 60):
    """Lever angle for each cam angle from the contour alone: the roller circle (centre on the
    lever circle) tangent to the contour. `contour_point(phi)` returns (x, y) jets in phi of the
    contour in the cam frame. Unknowns (phi, psi) per cam angle; 2-D Newton with the analytic
    Jacobian, started from the guesses (continuation from a neighbouring solution).

    Conditions: with C = Rot(theta) c(phi), T = Rot(theta) c'(phi), R = O1 + a e(psi):
        (R - C) . T = 0          (centre on the contour normal)
        |R - C|^2 - r^2 = 0      (at roller-radius distance)
    """
    phi = np.array(phi_guess, dtype=float, copy=True)
    psi = np.array(psi_guess, dtype=float, copy=True)
    cth, sth = np.cos(theta), np.sin(theta)
    for _ in range(max_iter):
        cx, cy = contour_point(Jet.variable(phi))
        C = (cth * cx.c[0] - sth * cy.c[0], sth * cx.c[0] + cth * cy.c[0])
        T = (cth * cx.c[1] - sth * cy.c[1], sth * cx.c[1] + cth * cy.c[1])
        K = (cth * cx.c[2] - sth * cy.c[2], sth * cx.c[2] + cth * cy.c[2])
        R = (pivot[0] + arm * np.cos(psi), pivot[1] + arm * np.sin(psi))
        Rp = (-arm * np.sin(psi), arm * np.cos(psi))
        D = (R[0] - C[0], R[1] - C[1])
        f1 = D[0] * T[0] + D[1] * T[1]
        f2 = D[0] ** 2 + D[1] ** 2 - roller_radius**2
        # Jacobian: d/dphi and d/dpsi
        a11 = -(T[0] ** 2 + T[1] ** 2) + D[0] * K[0] + D[1] * K[1]
        a12 = Rp[0] * T[0] + Rp[1] * T[1]
        a21 = -2.0 * (D[0] * T[0] + D[1] * T[1])
        a22 = 2.0 * (D[0] * Rp[0] + D[1] * Rp[1])
        det = a11 * a22 - a12 * a21
        dphi = (f1 * a22 - f2 * a12) / det
        dpsi = (a11 * f2 - a21 * f1) / det
        phi -= dphi
        psi -= dpsi
        if np.all(np.abs(dphi) < tol * 10) and np.all(np.abs(dpsi) < tol * 10):
            break
    return phi, psi
