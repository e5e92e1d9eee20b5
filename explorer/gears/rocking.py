"""Rocking cam driven by an eccentric (seed 004 "Schwingdaumen"; seed 000 section 4).

The eccentric on the shaft swings, through its rod, a rocking lever about the pivot C (an
eccentric four-bar, linkage.EccentricDrive). The rocking cam is part of that lever: a contour
swinging about C, which works on the roller of a roller lever (pivot O1, arm a); the roller
lever drives the valve (linkage.RockerDrive / RodLeverDrive).

Contour, in the rocking body's frame, as its pitch curve (the roller-centre path, the contour
offset by the roller radius) in polar form about C:
    rho(phi) = rho0                                   before the flank   (dwell arc: valve shut)
    rho(phi) = rho0 + H f((w(phi) - w_s) / W)          on the flank
    rho(phi) = rho0 + H                                after it          (arc concentric to C)
with f a normalised lift law (explorer.laws) and w(phi) the swing at which body angle phi would
come under the roller at rest: the valve starts to lift when the rocking cam has swung w_s from
its closed end. The same flank serves opening and closing: the valve lift depends only on the
rocking angle chi, so s(theta) = F(chi(theta)).

Contact: the roller centre lies on the pitch curve and on the roller lever's circle about O1,
    |C + rho(phi) e(phi + chi) - O1| = a,
one equation for the body angle phi of the contact, solved by Newton (continued from the dwell
position) and extended to a jet by Newton on jets.

Symmetry: for the ideal (infinitely long) rod chi(theta) is even about the eccentric's dead
centre, so s, v and the acceleration are mirror images (p1 = p2): Schenker's best spring use,
p2 - p1 = 2R/M, cannot be had. For a real rod the two shaft angles with the same chi are mirror
images about the line O -> B(chi) (B the rod pin), so opening and closing differ in timing by
2 [angle(B(chi_open)) - angle(B(chi_dead))]: fixed by the linkage, not by the contour.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.optimize import brentq

from ..errors import InputError
from ..laws import law as normalised_law
from . import jet as J
from .jet import Jet
from .linkage import circle_intersection, polar, polar_curvature, wrap

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class RockingContour:
    """Pitch curve of the rocking cam: dwell radius rho0, rise H over the flank, law f."""

    dwell_radius: float  # rho0, m: pitch radius of the dwell arc (contour radius + roller radius)
    rise: float  # H, m
    lift_start: float  # w_s, rad of swing from the closed end
    flank: float  # W, rad
    law: str
    reference: float = 0.0  # phi_c, body angle under the roller at the closed end
    sense: int = 1  # +1: the valve opens as the rocking cam turns counter-clockwise

    def swing_of(self, phi):
        return self.sense * (self.reference - phi)

    def radius(self, phi) -> Jet:
        """rho(phi) as a jet in whatever phi is a jet of (piecewise by the value of phi)."""
        phi = J.as_jet(phi)
        w = self.swing_of(phi)
        u = (w - self.lift_start) / self.flank
        uv = u.c[0]
        out = np.zeros_like(u.c)
        out[0] = self.dwell_radius
        top = uv >= 1.0
        out[0][top] = self.dwell_radius + self.rise
        mid = (uv > 0.0) & (uv < 1.0)
        if np.any(mid):
            f = normalised_law(self.law)(uv[mid])
            piece = Jet(u.c[:, mid]).compose(f[0], f[1], f[2], f[3])
            out[:, mid] = piece.c * self.rise
            out[0][mid] += self.dwell_radius
        return Jet(out)

    def pitch_curvature(self, phi) -> np.ndarray:
        """Signed curvature of the pitch curve at body angle phi (> 0 convex, as the dwell arc)."""
        return polar_curvature(self.radius(Jet.variable(np.asarray(phi, dtype=float))))

    def contour_points(self, roller_radius: float, n: int = 721, margin: float = 0.3):
        """Contour (metal surface) in the body frame, relative to the pivot, over the flank and
        `margin` rad either side: the pitch curve offset inwards by the roller radius."""
        w = np.linspace(self.lift_start - margin, self.lift_start + self.flank + margin, n)
        phi = Jet.variable(self.reference - self.sense * w)
        rho = self.radius(phi)
        x, y = rho * J.cos(phi), rho * J.sin(phi)
        tx, ty = x.c[1], y.c[1]
        speed = np.hypot(tx, ty)
        nx, ny = -ty / speed, tx / speed
        sign = np.sign(nx * x.c[0] + ny * y.c[0])  # outward: away from the pivot
        nx, ny = nx * sign, ny * sign
        return np.column_stack([x.c[0] - roller_radius * nx, y.c[0] - roller_radius * ny]), w


@dataclass(frozen=True)
class RockingCamGear:
    drive: Any  # EccentricDrive | IdealEccentricDrive: chi(theta)
    cam_pivot: tuple[float, float]  # C (the rocking lever's pivot)
    contour: RockingContour
    roller_radius: float
    lever_pivot: tuple[float, float]  # O1
    lever_arm: float  # a
    roller_branch: int  # roller left/right of O1 -> C
    valve: Any  # RockerDrive | RodLeverDrive on the roller lever, rest = rest lever angle
    closed_end: float  # chi at the closed end of the swing
    dead_centre: float  # theta (rad) where the swing reaches its open end
    file: str = "<memory>"

    # -- set-up -----------------------------------------------------------------------------
    @staticmethod
    def rest_roller(cam_pivot, dwell_radius, lever_pivot, lever_arm, branch, file="<memory>"):
        x, y, q = circle_intersection(lever_pivot, lever_arm, cam_pivot, dwell_radius, branch)
        if x is None or q < 1e-6:
            raise InputError(file, "gear.lever.arm", "the roller lever cannot reach the rocking cam's dwell arc")
        return float(x), float(y)

    # -- contact ----------------------------------------------------------------------------
    def _residual(self, phi, chi):
        rho = self.contour.radius(phi)
        x = self.cam_pivot[0] + rho * J.cos(phi + chi) - self.lever_pivot[0]
        y = self.cam_pivot[1] + rho * J.sin(phi + chi) - self.lever_pivot[1]
        return x * x + y * y - self.lever_arm**2

    def contact_angle(self, theta) -> tuple[Jet, Jet]:
        """(phi, chi) jets in theta: body angle of the contact on the pitch curve, lever angle."""
        theta = np.asarray(theta, dtype=float)
        chi = self.drive.angle(Jet.variable(theta))
        rest = self.rest_position()
        guess = math.atan2(rest[1] - self.cam_pivot[1], rest[0] - self.cam_pivot[0]) - chi.c[0]
        # first-order jets: the values and slopes Newton uses are the full jets' bit for bit
        phi0, ok = J.newton(lambda p: self._residual(p, chi.c[0]), guess, step_limit=0.05, order=1)
        # the roller must stay on the near intersection: within a flank's span of the dwell guess
        far = np.abs(wrap(phi0 - guess)) > self.contour.flank + 0.5
        if not np.all(ok) or np.any(far):
            bad = int(np.argmax(~ok | far))
            raise InputError(
                self.file, "gear.rocking_cam",
                f"the roller loses the rocking cam at shaft angle {math.degrees(theta.flat[bad]) % 360:.2f} deg "
                "(contour rise too large for the roller lever)",
            )
        phi = J.solve_implicit(self._residual, phi0, args=(chi,))
        return phi, chi

    def rest_position(self):
        return self.rest_roller(self.cam_pivot, self.contour.dwell_radius, self.lever_pivot, self.lever_arm,
                                self.roller_branch, self.file)

    def roller_centre(self, theta):
        phi, chi = self.contact_angle(theta)
        rho = self.contour.radius(phi)
        return polar(self.cam_pivot, rho, phi + chi), phi, chi, rho

    def lever_angle(self, theta) -> Jet:
        (rx, ry), *_ = self.roller_centre(theta)
        return J.atan2(ry - self.lever_pivot[1], rx - self.lever_pivot[0])

    def lift_jet(self, theta) -> Jet:
        """Valve-referred lift of the linkage end (lash included), jets in theta."""
        return self.valve.travel(self.lever_angle(theta))

    def swing(self, theta) -> Jet:
        """Swing of the rocking cam from its closed end, w = sense (chi - chi_closed) >= 0."""
        return self.contour.sense * (self.drive.angle(Jet.variable(np.asarray(theta, dtype=float))) - self.closed_end)

    # -- breakpoints: where the contact enters and leaves the flank -----------------------------
    def flank_angles(self) -> np.ndarray:
        """Shaft angles where the contact crosses the flank's ends (law derivatives may jump)."""
        grid = np.linspace(0.0, TWO_PI, 2881)
        out = []
        phi_grid = self.contact_angle(grid)[0].c[0]
        for w_mark in (self.contour.lift_start, self.contour.lift_start + self.contour.flank):
            target = self.contour.reference - self.contour.sense * w_mark

            def g(th):
                return float(wrap(self.contact_angle(np.array([th]))[0].c[0][0] - target))

            vals = wrap(phi_grid - target)
            for i in np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)[0]:
                if abs(vals[i] - vals[i + 1]) > 1.0:
                    continue  # wrap-around, not a crossing
                out.append(brentq(g, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15) % TWO_PI)
        return np.unique(np.array(out))

    # -- pressure angle and forces ---------------------------------------------------------------
    def contact_details(self, theta) -> dict:
        """Per-angle geometry for reports: rocking angle, contact body angle, roller lever angle
        and its rate, pressure angle at the roller (normal vs roller travel), ratio ds/dpsi."""
        theta = np.asarray(theta, dtype=float)
        (rx, ry), phi, chi, rho = self.roller_centre(theta)
        psi = J.atan2(ry - self.lever_pivot[1], rx - self.lever_pivot[0])
        # pitch-curve tangent in ground frame: d/dphi [rho e(phi + chi)] at fixed chi
        phi_v = Jet.variable(phi.c[0])
        rho_v = self.contour.radius(phi_v)
        ang = phi_v + chi.c[0]
        px, py = rho_v * J.cos(ang), rho_v * J.sin(ang)
        tx, ty = px.c[1], py.c[1]
        speed = np.hypot(tx, ty)
        nx, ny = -ty / speed, tx / speed
        outward = np.sign(nx * px.c[0] + ny * py.c[0])
        nx, ny = nx * outward, ny * outward
        lift_dir = self.valve.slope_sign()  # + if increasing psi opens the valve
        ex, ey = -np.sin(psi.c[0]) * lift_dir, np.cos(psi.c[0]) * lift_dir
        # the cam pushes the roller along +n; the angle between n and the roller's lifting travel
        pressure = np.arctan2(ex * ny - ey * nx, ex * nx + ey * ny)
        ds_dpsi = self.valve.travel(Jet.variable(psi.c[0])).c[1]
        return {
            "rocking_angle": chi.c[0], "rocking_rate": chi.c[1], "contact_body_angle": phi.c[0],
            "pitch_radius_at_contact": rho.c[0], "lever_angle": psi.c[0], "lever_rate": psi.c[1],
            "pressure_angle": pressure, "valve_per_lever": ds_dpsi, "ratio": np.abs(ds_dpsi) / self.lever_arm,
            "roller_centre": np.column_stack([rx.c[0], ry.c[0]]), "normal": np.column_stack([nx, ny]),
        }

    def contact_geometry(self, theta):
        """explorer.contact's view of the rocking-cam contact: pressure angle referred to the roller
        lever, ratio |ds/dpsi| / a, the normal's moment arm (R - C) x n about the rocking cam's pivot
        C, carried to the eccentric shaft by the four-bar's dchi/dtheta (massless rod: T = M_C chi'),
        and the contour radius at the contact (pitch-curve radius less the roller's)."""
        from ..contact import ContactGeometry

        d = self.contact_details(theta)
        r = self.roller_radius
        n = d["normal"]
        rx = d["roller_centre"][:, 0] - self.cam_pivot[0]
        ry = d["roller_centre"][:, 1] - self.cam_pivot[1]
        arm = rx * n[:, 1] - ry * n[:, 0]
        with np.errstate(divide="ignore"):
            contour_radius = 1.0 / self.contour.pitch_curvature(d["contact_body_angle"]) - r
        return ContactGeometry(
            pressure_angle=d["pressure_angle"], ratio=d["ratio"], torque_arm=arm * d["rocking_rate"], body_arm=arm,
            body_radius=np.hypot(rx - r * n[:, 0], ry - r * n[:, 1]), contour_radius=contour_radius,
            counter_radius=r, roller_diameter=2.0 * r,
        )

    def rod_pin_angle(self, chi: np.ndarray) -> np.ndarray:
        """Direction of O -> B for rocking angle chi (B the rod pin on the rocking lever)."""
        arm = self.drive.arm
        bx = self.cam_pivot[0] + arm * np.cos(chi)
        by = self.cam_pivot[1] + arm * np.sin(chi)
        return np.arctan2(by, bx)


def build_rocking_gear(*, drive, cam_pivot, contour: RockingContour, roller_radius, lever_pivot, lever_arm,
                       roller_branch, make_valve, file="<memory>") -> RockingCamGear:
    """Assemble a rocking-cam gear: finds the swing's ends, the rest roller position and the body
    angle under it at the closed end, and builds the valve drive from the rest lever angle."""
    centres = drive.dead_centres()
    chis = [float(drive.angle(np.array([c]))[0]) for c in centres]
    if contour.sense > 0:
        closed_i, open_i = (0, 1) if chis[0] < chis[1] else (1, 0)
    else:
        closed_i, open_i = (0, 1) if chis[0] > chis[1] else (1, 0)
    chi_closed = chis[closed_i]
    swing_total = abs(chis[open_i] - chis[closed_i])
    if contour.lift_start >= swing_total:
        raise InputError(file, "gear.rocking_cam.lift_start",
                         f"the rocking cam swings only {math.degrees(swing_total):.3f} deg: the flank never reaches the roller")
    rest = RockingCamGear.rest_roller(cam_pivot, contour.dwell_radius, lever_pivot, lever_arm, roller_branch, file)
    reference = math.atan2(rest[1] - cam_pivot[1], rest[0] - cam_pivot[0]) - chi_closed
    contour = replace(contour, reference=reference)
    psi0 = math.atan2(rest[1] - lever_pivot[1], rest[0] - lever_pivot[0])
    valve = make_valve(psi0)
    gear = RockingCamGear(drive=drive, cam_pivot=cam_pivot, contour=contour, roller_radius=roller_radius,
                          lever_pivot=lever_pivot, lever_arm=lever_arm, roller_branch=roller_branch, valve=valve,
                          closed_end=chi_closed, dead_centre=centres[open_i], file=file)
    # the valve must open as the roller climbs the flank (away from the cam pivot)
    rx, ry = rest
    climb = np.array([rx - cam_pivot[0], ry - cam_pivot[1]])
    tangent = np.array([-(ry - lever_pivot[1]), rx - lever_pivot[0]])  # d R / d psi
    if np.sign(climb @ tangent) * valve.slope_sign() < 0:
        raise InputError(file, "gear.valve.axis", "the valve would close as the roller climbs the rocking cam; reverse the axis")
    return gear


def swing_increments(gear, theta_start: float, theta_end: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Equal arcs of the eccentric (equal times) and the rocking cam's swing over each: seed 004's
    point that equal eccentric arcs give unequal swings."""
    theta = np.linspace(theta_start, theta_end, n + 1)
    chi = np.unwrap(gear.drive.angle(theta))
    return theta, np.diff(chi)


def fit_contour(gear: RockingCamGear, target_lift: float, target_open_angle: float, lash: float = 0.0,
                make_gear=None) -> RockingCamGear:
    """Choose the flank's rise H and start w_s so that the valve lifts `target_lift` (after
    `lash`) and stays open for `target_open_angle` of shaft rotation. Two equations, two
    unknowns: Newton on (w_s, H) with a difference Jacobian (a design aid, not a derivative of a
    lift curve); each evaluation is an exact analysis of the trial contour: the lift at the
    eccentric's dead centre (the open end of the swing) and the opening and closing angles found
    by Brent's method on the analytic lift."""
    make_gear = make_gear or (lambda c: replace(gear, contour=c))

    def measure(ws, h):
        trial = make_gear(replace(gear.contour, lift_start=ws, rise=h))
        td = trial.dead_centre

        def f(th):
            return float(trial.lift_jet(np.array([th])).c[0][0]) - lash

        top = f(td)
        if top <= 0.0:
            return top, 0.0
        # the valve is open on an interval around the dead centre: bracket each end
        span = np.linspace(0.0, math.pi, 181)
        vals_open = trial.lift_jet(td - span).c[0] - lash
        vals_close = trial.lift_jet(td + span).c[0] - lash
        i = int(np.argmax(vals_open <= 0.0))
        j = int(np.argmax(vals_close <= 0.0))
        a = brentq(lambda u: f(td - u), span[i - 1], span[i], xtol=1e-14)
        b = brentq(lambda u: f(td + u), span[j - 1], span[j], xtol=1e-14)
        return top, a + b

    x = np.array([gear.contour.lift_start, gear.contour.rise], dtype=float)
    target = np.array([target_lift, target_open_angle])
    for _ in range(40):
        f = np.array(measure(*x)) - target
        if abs(f[0]) < 1e-10 * target_lift and abs(f[1]) < 1e-9:
            break
        jac = np.empty((2, 2))
        for k, h in enumerate((1e-6, 1e-7)):
            xp = x.copy()
            xp[k] += h
            jac[:, k] = (np.array(measure(*xp)) - target - f) / h
        step = np.linalg.solve(jac, f)
        scale = min(1.0, 0.05 / max(abs(step[0]), 1e-300), 0.5 * x[1] / max(abs(step[1]), 1e-300))
        x = x - scale * step
        x[1] = max(x[1], 1e-6)
    return make_gear(replace(gear.contour, lift_start=float(x[0]), rise=float(x[1])))
