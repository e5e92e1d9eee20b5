"""Eccentric rolling lever ("Waelzhebel", seed 000 sections 2-4).

The eccentric four-bar (linkage.EccentricDrive) swings the rolling lever about A (angle alpha).
Once it has swung `contact_swing` from its closed end it meets the valve lever (pivot B, angle
beta) and the two curved faces roll on each other without slipping until it swings back.

Pure rolling between two bodies turning about fixed pivots: the contact point is the relative
instant centre, so it lies on the line A-B (Kennedy), at distance rho from A, and
    d beta / d alpha = -rho / (d - rho),          d = |AB|
(opposite senses: external rolling). The faces are therefore the centrodes of the motion. We
prescribe rho to grow linearly with the rolling swing w = sense (alpha - alpha_contact) >= 0,
    rho(w) = rho_c + k w,
which makes both faces spirals and the transmission integrable in closed form:
    beta(w) = beta_rest - sense * I(w),  I(w) = -w + (d/k) ln((d - rho_c) / (d - rho_c - k w)).
The valve lever drives the valve (linkage.RockerDrive on B). At contact the valve lever is at
rest but the rolling lever is not: the valve is picked up with a finite velocity (Schenker:
the ratio at the start is already finite and the eccentric rod moves fastest there).

Elasticity: a torsional stiffness k_t of the rolling lever about A appears at the valve as
k_t / (ds/dalpha)^2, the eccentric rod's axial stiffness as k_rod / (ds/dl)^2 (l the rod
length): with a rod force far smaller than the valve force (times the ratio) and its stretch
reduced once more by the ratio, the rod contributes little - most of the elasticity sits in the
rolling lever (seed 000, section 3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from ..core.roots import root_in

from ..core.errors import InputError
from ..mechanics.contact import ContactGeometry
from . import jet as J
from .jet import Jet
from .linkage import polar_curvature

TWO_PI = 2.0 * math.pi


def log1p(x):
    if not isinstance(x, Jet):
        return np.log1p(x)
    v = x.c[0]
    w = 1.0 + v
    return x.compose(np.log1p(v), 1.0 / w, -1.0 / w**2, 2.0 / w**3)


@dataclass(frozen=True)
class RollingLaw:
    """rho(w) = rho_c + k w: contact distance from the rolling lever's pivot A."""

    distance: float  # d = |AB|, m
    contact_radius: float  # rho_c, m
    growth: float  # k, m/rad

    def rho(self, w):
        return self.contact_radius + self.growth * w

    def integral(self, w):
        """I(w) = integral_0^w rho / (d - rho) dw', closed form (log1p keeps small k exact)."""
        d, rc, k = self.distance, self.contact_radius, self.growth
        if k == 0.0:
            return w * (rc / (d - rc))
        return -w - (d / k) * log1p(-(k / (d - rc)) * w)

    def ratio(self, w):
        """|d beta / d alpha| = rho / (d - rho)."""
        r = self.rho(w)
        return r / (self.distance - r)


@dataclass(frozen=True)
class RollingLeverGear:
    drive: Any  # EccentricDrive: alpha(theta), pivot A = drive.pivot
    valve_pivot: tuple[float, float]  # B
    law: RollingLaw
    sense: int  # +1: the rolling lever lifts turning counter-clockwise
    closed_end: float  # alpha at the closed end of the swing
    contact_swing: float  # swing from the closed end at which the levers meet, rad
    rest: float  # beta at closed valve
    valve: Any  # RockerDrive on the valve lever (pivot B), rest = self.rest
    lever_stiffness: float | None = None  # N m / rad, rolling lever about A
    rod_stiffness: float | None = None  # N / m, eccentric rod, axial
    file: str = "<memory>"

    @property
    def pivot(self):
        return self.drive.pivot

    def rolling_swing(self, theta) -> Jet:
        alpha = self.drive.angle(Jet.variable(np.asarray(theta, dtype=float)))
        return self.sense * (alpha - self.closed_end) - self.contact_swing

    def valve_lever_angle(self, w) -> Jet:
        return self.rest - self.sense * self.law.integral(w)

    def virtual_lift(self, theta) -> Jet:
        """Valve travel if the faces stayed in contact (negative before contact)."""
        return self.valve.travel(self.valve_lever_angle(self.rolling_swing(theta)))

    def contact_angles(self) -> np.ndarray:
        """Shaft angles of pick-up and release: rolling swing w = 0, by Brent on the closed form."""
        grid = np.linspace(0.0, TWO_PI, 2881)
        w = self.rolling_swing(grid).c[0]
        out = []
        for i in np.nonzero(np.sign(w[:-1]) * np.sign(w[1:]) < 0)[0]:
            out.append(root_in(lambda t: float(self.rolling_swing(np.array([t])).c[0][0]), grid[i], grid[i + 1],
                               fa=w[i], fb=w[i + 1], xtol=1e-15, rtol=1e-15))
        return np.unique(np.mod(out, TWO_PI))

    def faces(self, n: int = 200):
        """The two rolling faces in their own body frames (relative to their pivots), over the
        swing in contact: (driving face (n,2), valve-lever face (n,2), w)."""
        w_max = self.max_rolling_swing()
        w = np.linspace(0.0, w_max, n)
        ax, ay = self.pivot
        bx, by = self.valve_pivot
        gamma = math.atan2(by - ay, bx - ax)
        alpha = self.closed_end + self.sense * (w + self.contact_swing)
        beta = self.valve_lever_angle(Jet.constant(w)).c[0]
        rho = self.law.rho(w)
        d = self.law.distance
        face_a = np.column_stack([rho * np.cos(gamma - alpha), rho * np.sin(gamma - alpha)])
        face_b = np.column_stack([(d - rho) * np.cos(gamma + math.pi - beta), (d - rho) * np.sin(gamma + math.pi - beta)])
        return face_a, face_b, w

    def max_rolling_swing(self) -> float:
        chis = [float(self.drive.angle(np.array([c]))[0]) for c in self.drive.dead_centres()]
        return abs(chis[1] - chis[0]) - self.contact_swing

    def stiffness(self, theta, with_derivative: bool = False) -> dict:
        """Valve-referred stiffness of the rolling lever and the eccentric rod along the cycle.

        ds/dalpha = sense ds/dw is taken from jets in the rolling swing w (not as s'(theta) /
        alpha'(theta), which is 0/0 at the eccentric's dead centres, i.e. at full lift). Before
        pick-up (w < 0) the faces do not touch: the values are those at the meeting point.
        with_derivative: also "d_lever", "d_rod", "d_total", the analytic d/dtheta (for the
        elastic solvers' k(t) and the jerk)."""
        theta = np.asarray(theta, dtype=float)
        swing = self.rolling_swing(theta)
        touching = swing.c[0] > 0.0
        w = np.where(touching, swing.c[0], 0.0)
        w1 = np.where(touching, swing.c[1], 0.0)  # dw/dtheta (frozen before pick-up)
        s_w = self.valve.travel(self.valve_lever_angle(Jet.variable(w)))
        ds_dalpha = self.sense * s_w.c[1]
        d_ds_dalpha = self.sense * s_w.c[2] * w1
        # rod: d alpha / d l at fixed eccentric = 1 / q, q = u_rod . dB/dalpha (jets in theta; the
        # lever angle frozen at the meeting point before pick-up, like w)
        th = Jet.variable(theta)
        bx, by = self.drive.pin(th)
        ex, ey = self.drive.centre(th)
        ux, uy = bx - ex, by - ey
        norm = J.hypot(ux, uy)
        alpha = self.drive.angle(th)
        q = (ux * (-self.drive.arm * J.sin(alpha)) + uy * (self.drive.arm * J.cos(alpha))) / norm
        q0 = q.c[0]
        q1 = q.c[1]
        if not np.all(touching):  # the rod geometry at the meeting point (alpha where w = 0)
            q0 = np.where(touching, q0, self._rod_projection_at_meeting)
            q1 = np.where(touching, q1, 0.0)
        ds_dl = ds_dalpha / q0
        out = {"ds_dalpha": ds_dalpha, "ds_drod": ds_dl}
        parts = []
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.lever_stiffness is not None:
                out["lever"] = self.lever_stiffness / ds_dalpha**2
                out["d_lever"] = -2.0 * self.lever_stiffness * d_ds_dalpha / ds_dalpha**3
                parts.append("lever")
            if self.rod_stiffness is not None:
                out["rod"] = self.rod_stiffness * q0**2 / ds_dalpha**2
                out["d_rod"] = 2.0 * self.rod_stiffness * q0 * (q1 * ds_dalpha - q0 * d_ds_dalpha) / ds_dalpha**3
                parts.append("rod")
            if parts:  # in series: 1/k = sum 1/k_i, k' = k^2 sum k_i' / k_i^2
                total = 1.0 / sum(1.0 / out[p] for p in parts)
                out["total"] = total
                out["d_total"] = total**2 * sum(out[f"d_{p}"] / out[p] ** 2 for p in parts)
        if not with_derivative:
            for key in [k for k in out if k.startswith("d_")]:
                del out[key]
        return out

    @cached_property
    def _rod_projection_at_meeting(self) -> float:
        """u_rod . dB/dalpha where the faces meet (rolling swing 0), on the opening side (a constant
        of the geometry, found by root-finding: computed once, not at every k(t) evaluation)."""
        marks = self.contact_angles()
        rate = self.rolling_swing(np.asarray(marks, dtype=float)).c[1]
        pick = float(marks[int(np.argmax(rate))])  # the pick-up: the swing grows there
        bx, by = self.drive.pin(np.array([pick]))
        ex, ey = self.drive.centre(np.array([pick]))
        alpha = float(self.drive.angle(np.array([pick]))[0])
        ux, uy = float(bx[0] - ex[0]), float(by[0] - ey[0])
        norm = math.hypot(ux, uy)
        return self.drive.arm * (-ux * math.sin(alpha) + uy * math.cos(alpha)) / norm

    def contact_geometry(self, theta):
        """explorer.mechanics.contact's view of the rolling faces. The contact P lies on A-B at rho from A; the
        valve lever's point there travels perpendicular to B-P. Face A, seen in the ground at the
        current swing, is A + rho(w') e(gamma - sense (w' - w)): tangent k e_AB - sense rho e_perp,
        so the common normal leans from A-B by atan(k / rho) and the pressure angle (normal against
        the valve lever's travel) is atan(rho / k): circular faces (k = 0) could drive only by
        friction. Radii of both faces from their polar forms about their own pivots (convex > 0).
        Before pick-up (no contact, no force) the values are those of the faces' meeting point."""
        theta = np.asarray(theta, dtype=float)
        swing = self.rolling_swing(theta)
        w = Jet.variable(np.maximum(swing.c[0], 0.0))  # jets in the rolling swing
        rho = self.law.rho(w)
        beta = self.valve_lever_angle(w)
        d, k, sense = self.law.distance, self.law.growth, self.sense
        (ax, ay), (bx, by) = self.pivot, self.valve_pivot
        gamma = math.atan2(by - ay, bx - ax)
        eg, ep = np.array([math.cos(gamma), math.sin(gamma)]), np.array([-math.sin(gamma), math.cos(gamma)])
        r = rho.c[0]
        tangent = k * eg[:, None] - sense * r * ep[:, None]  # (2, N)
        n = np.array([-tangent[1], tangent[0]]) / np.hypot(tangent[0], tangent[1])
        n = n * np.sign(eg @ n)  # from the rolling lever's face into the valve lever's
        # the valve lever's point P (P - B = -(d - rho) e_AB) travels along e_z x (P - B) for
        # increasing beta; the valve opens that way if ds/dbeta > 0
        ds_dbeta = self.valve.travel(Jet.variable(beta.c[0])).c[1]
        travel = -ep[:, None] * np.sign(ds_dbeta)
        pressure = np.arctan2(travel[0] * n[1] - travel[1] * n[0], travel[0] * n[0] + travel[1] * n[1])
        arm = r * (eg[0] * n[1] - eg[1] * n[0])  # (P - A) x n with P - A = rho e_AB
        alpha_rate = sense * swing.c[1]  # d alpha / d theta of the rolling lever
        face_a = polar_curvature(J.reparametrize(rho, gamma - (self.closed_end + sense * (w + self.contact_swing))))
        face_b = polar_curvature(J.reparametrize(d - rho, gamma + math.pi - beta))
        with np.errstate(divide="ignore"):
            radius_a, radius_b = 1.0 / face_a, 1.0 / face_b
        return ContactGeometry(
            pressure_angle=pressure, ratio=np.abs(ds_dbeta) / (d - r), torque_arm=arm * alpha_rate, body_arm=arm,
            body_radius=r, contour_radius=radius_a, counter_radius=radius_b, roller_diameter=None,
        )

    def check(self) -> None:
        w_max = self.max_rolling_swing()
        if w_max <= 0.0:
            raise InputError(self.file, "gear.rolling_lever.contact_swing",
                             "the rolling lever never reaches the valve lever (contact swing beyond its swing)")
        rho_end = self.law.rho(w_max)
        if not 0.0 < rho_end < self.law.distance:
            raise InputError(self.file, "gear.rolling_lever.growth",
                             f"the rolling point leaves the line between the pivots (rho = {rho_end * 1e3:.4g} mm at full swing, "
                             f"pivot distance {self.law.distance * 1e3:.4g} mm)")
        self.valve.travel(self.valve_lever_angle(Jet.constant(np.linspace(0.0, w_max, 50))))


@dataclass(frozen=True)
class RollingLeverLift:
    """Valve-referred lift of a rolling-lever gear: the virtual lift in contact, zero apart.
    At the pick-up and release angles the value is 0 and the derivatives are those of the
    contact branch, so the lash machinery finds the finite pick-up velocity exactly."""

    gear: RollingLeverGear
    marks: tuple[float, ...]

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        flat = theta.reshape(-1)
        s = self.gear.virtual_lift(flat)
        w = self.gear.rolling_swing(flat).c[0]
        at_mark = np.zeros(flat.shape, dtype=bool)
        tm = np.mod(flat, TWO_PI)
        for m in self.marks:
            at_mark |= np.abs(tm - m) <= 1e-14
        contact = (w > 0.0) | at_mark
        out = np.where(contact[None, :], s.c, 0.0)
        out[0] = np.where(at_mark, 0.0, np.maximum(out[0], 0.0))
        return out.reshape((4,) + theta.shape)

    def breakpoints(self) -> np.ndarray:
        return np.array(sorted(self.marks))

    @property
    def linkage_stiffness(self):
        """theta -> (k, dk/dtheta): the rolling lever's and the eccentric rod's elasticity referred
        to the valve (N/m), which changes with the ratio along the lift -- or None when the scene
        gives neither lever_stiffness nor rod_stiffness. The elastic effect puts it in series with
        [linkage] stiffness (the rest of the chain)."""
        if self.gear.lever_stiffness is None and self.gear.rod_stiffness is None:
            return None

        def of(theta):
            k = self.gear.stiffness(theta, with_derivative=True)
            return k["total"], k["d_total"]

        return of
