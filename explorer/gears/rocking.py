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
with f a normalised lift law (explorer.lift.laws) and w(phi) the swing at which body angle phi would
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

Inverse problem ([gear.target], `explorer fit`): the flank start w_s and rise H that give a
wanted valve lift and open angle, the flank's length and law kept (fit_target, see there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from ..core.roots import NoBracket, root_in

from ..core.errors import InputError
from ..lift.registry import normalised as normalised_law
from ..mechanics.contact import ContactGeometry
from . import jet as J
from .jet import Jet
from .linkage import circle_intersection, polar, polar_curvature, wrap

TWO_PI = 2.0 * math.pi
_EPS = 4.0 * np.finfo(float).eps  # brentq's smallest relative tolerance


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
                out.append(root_in(g, grid[i], grid[i + 1], fa=vals[i], fb=vals[i + 1], xtol=1e-15, rtol=1e-15) % TWO_PI)
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
        """explorer.mechanics.contact's view of the rocking-cam contact: pressure angle referred to the roller
        lever, ratio |ds/dpsi| / a, the normal's moment arm (R - C) x n about the rocking cam's pivot
        C, carried to the eccentric shaft by the four-bar's dchi/dtheta (massless rod: T = M_C chi'),
        and the contour radius at the contact (pitch-curve radius less the roller's)."""
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

    # -- the motion as a function of the swing (the fit's domain) ----------------------------------
    def closed_dead_centre(self) -> float:
        """Shaft angle (rad, [0, 2 pi)) where the swing reaches its closed end."""
        centres = self.drive.dead_centres()
        far = [abs(wrap(c - self.dead_centre)) for c in centres]
        return centres[0] if far[0] > far[1] else centres[1]

    def total_swing(self) -> float:
        """Omega: the swing from the closed end to the open end, rad."""
        return float(self.swing_values(np.array([self.dead_centre]))[0])

    def swing_values(self, theta) -> np.ndarray:
        """w(theta) as plain values (wrapped: the rocking angle may pass +-pi)."""
        chi = self.drive.angle(np.atleast_1d(np.asarray(theta, dtype=float)))
        return self.contour.sense * wrap(chi - self.closed_end)

    def shaft_angles_at_swing(self, w: float) -> tuple[float, float]:
        """The two shaft angles at which the swing is w (0 <= w <= Omega): rising towards the
        dead centre (opening) and falling after it (closing); the four-bar's swing is monotone
        between its dead centres, so each is one bracketed root."""
        td = self.dead_centre
        lead = float(np.mod(td - self.closed_dead_centre(), TWO_PI))
        omega = self.total_swing()

        def g(th):
            return float(self.swing_values(np.array([th]))[0]) - w

        if w <= 0.0:
            return td - lead, td - lead + TWO_PI
        if w >= omega:
            return td, td
        # the swing rises from 0 to omega and falls back between the dead centres: -w and omega - w
        opening = root_in(g, td - lead, td, fa=-w, fb=omega - w, xtol=1e-15, rtol=_EPS)
        closing = root_in(g, td, td - lead + TWO_PI, fa=omega - w, fb=-w, xtol=1e-15, rtol=_EPS)
        return opening, closing

    def open_angle_at_swing(self, w: float) -> float:
        """Shaft angle over which the swing exceeds w (2 pi at w = 0, 0 at w = Omega)."""
        opening, closing = self.shaft_angles_at_swing(w)
        return closing - opening

    def top_arc_swing(self) -> float:
        """Swing at which the roller reaches the top arc. On an arc concentric to C the contact
        sits where the roller stands, so the flank's end arrives not at w_s + W (measured with
        the roller at rest) but later or earlier by the angle, about C, between the rest roller
        and the roller on the top arc (radius rho0 + H); infinite when the roller lever cannot
        reach the top arc (the roller then never leaves the flank)."""
        c = self.contour
        rest = self.rest_position()
        x, y, q = circle_intersection(self.lever_pivot, self.lever_arm, self.cam_pivot, c.dwell_radius + c.rise,
                                      self.roller_branch)
        if x is None or q < 1e-6:
            return math.inf
        top = (float(x), float(y))
        turn = math.atan2(top[1] - self.cam_pivot[1], top[0] - self.cam_pivot[0]) - math.atan2(
            rest[1] - self.cam_pivot[1], rest[0] - self.cam_pivot[0])
        return c.lift_start + c.flank + c.sense * float(wrap(turn))

    def full_lift_dwell(self) -> float:
        """Shaft angle with the roller on the top arc (0 when the swing ends on the flank)."""
        w_top = self.top_arc_swing()
        return self.open_angle_at_swing(w_top) if w_top < self.total_swing() else 0.0

    def lift_at_swing(self, w) -> np.ndarray:
        """Valve-referred lift (lash included) at swing w: the contact solved at the rocking angle
        chi = chi_closed + sense w, without the eccentric. Values only (the fit's measure)."""
        w = np.atleast_1d(np.asarray(w, dtype=float))
        chi = self.closed_end + self.contour.sense * w
        rest = self.rest_position()
        guess = math.atan2(rest[1] - self.cam_pivot[1], rest[0] - self.cam_pivot[0]) - chi
        phi, ok = J.newton(lambda p: self._residual(p, chi), guess, step_limit=0.05, order=1)
        far = np.abs(wrap(phi - guess)) > self.contour.flank + 0.5
        if not np.all(ok) or np.any(far):
            bad = int(np.argmax(~ok | far))
            raise InputError(self.file, "gear.rocking_cam",
                             f"the roller loses the rocking cam at a swing of {math.degrees(w[bad]):.3f} deg "
                             "(contour rise too large for the roller lever)")
        rho = self.contour.radius(phi).c[0]
        rx, ry = polar(self.cam_pivot, rho, phi + chi)
        psi = np.arctan2(ry - self.lever_pivot[1], rx - self.lever_pivot[0])
        return np.asarray(self.valve.travel(psi), dtype=float)

    def rod_pin_angle(self, chi: np.ndarray) -> np.ndarray:
        """Direction of O -> B for rocking angle chi (B the rod pin on the rocking lever)."""
        arm = self.drive.arm
        bx = self.cam_pivot[0] + arm * np.cos(chi)
        by = self.cam_pivot[1] + arm * np.sin(chi)
        return np.arctan2(by, bx)


def check_one_turn(lift_start: float, flank: float, file: str) -> None:
    """A rocking cam's contour is one polar curve about its pivot: the dwell before the flank and
    the flank itself must fit in one turn of the body, or the contour overlaps itself."""
    if lift_start + flank >= TWO_PI:
        raise InputError(file, "gear.rocking_cam.flank", f"lift_start + flank = {math.degrees(lift_start + flank):.6g} "
                         "deg: the contour would overlap itself (it must fit in one turn of the rocking cam, < 360 deg)")


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


# --------------------------------------------------------------------------------------------
# Choosing the contour for a wanted valve lift and open angle ("given a target, help choose it")
# --------------------------------------------------------------------------------------------
#
# The lift depends on the swing alone, s = F(w), and F rises monotonically over the flank (every
# law in explorer.lift.laws is monotone, and raising the pitch curve pushes the roller out). So the
# valve is open exactly while the swing exceeds w_o, the swing at which F reaches the lash, and
#   open angle = theta_close(w_o) - theta_open(w_o)
# is the four-bar's business alone: the wanted open angle fixes w_o by one bracketed root on the
# drive. Two conditions on the contour remain, both at fixed rocking angles (no eccentric):
#   F(Omega; w_s, H) = lift + lash      (the open end of the swing, at the dead centre)
#   F(w_o;   w_s, H) = lash
# F increases with H at every swing and decreases as the flank starts later, so nested Brent
# solves find H(w_s) from the first and then w_s from the second; with no lash the second reads
# w_s = w_o. The flank's length W, its law and the dwell radius are kept: they are the designer's
# choices of shape, the fit places and scales the flank.

KEY_LIFT = "gear.target.lift"
KEY_OPEN = "gear.target.open_angle"


@dataclass(frozen=True)
class ContourFit:
    """Flank start w_s and rise H for the wanted lift and open angle (flank length and law kept),
    and what a flank of this length can reach at that lift."""

    lift_start: float  # w_s, rad
    rise: float  # H, m (pitch curve and contour alike)
    open_swing: float  # w_o, rad: the swing at which the valve leaves and regains its seat
    full_lift_dwell: float  # rad of shaft angle with the roller on the top arc (0: the swing ends on the flank)
    max_open_angle: float  # rad: the flank starting at the closed end, the longest opening reachable
    full_flank_open_angle: float | None  # rad: the roller reaching the top arc just at the open end of
    # the swing; shorter openings are reachable but the swing then ends on the flank (no dwell at
    # full lift); None when even a flank starting at the closed end never brings the top arc


def valve_opening(gear: RockingCamGear, lash: float = 0.0) -> tuple[float, float]:
    """(largest valve lift s = L - lash, shaft angle over which the valve is open) of a gear's
    contour, measured at fixed rocking angles: the lift at the open end of the swing and the
    swing at which the lift reaches the lash."""
    omega = gear.total_swing()
    top = float(gear.lift_at_swing([omega])[0]) - lash
    if top <= 0.0:
        return 0.0, 0.0  # the lash is never taken up
    if lash <= 0.0:
        w_open = gear.contour.lift_start
    else:
        w_open = root_in(lambda w: float(gear.lift_at_swing([w])[0]) - lash, 0.0, omega, xtol=1e-15, rtol=_EPS)
    return top, gear.open_angle_at_swing(w_open)


def fit_target(gear: RockingCamGear, target_lift: float, target_open_angle: float, lash: float = 0.0) -> ContourFit:
    """Flank start and rise for the wanted valve lift (after `lash`) and open angle; InputError
    naming gear.target.* when no flank of this length and law reaches them."""
    try:
        return _fit_target(gear, target_lift, target_open_angle, lash)
    except NoBracket:  # every search below is bracketed by construction; should rounding say otherwise
        raise InputError(gear.file, "gear.target", "no contour of this flank reaches the target (no bracket for "
                         "the fit's root search)") from None
    except InputError as exc:
        if exc.key.startswith("gear.target"):
            raise
        # a trial contour the roller lever cannot follow between the checked swings: still the target's fault
        raise InputError(gear.file, "gear.target",
                         f"no contour of this flank reaches the target: {exc.reason}") from None


def _fit_target(gear, target_lift, target_open_angle, lash) -> ContourFit:
    file = gear.file
    omega = gear.total_swing()
    flank = gear.contour.flank
    top = target_lift + lash
    if not 0.0 < target_open_angle < TWO_PI:
        raise InputError(file, KEY_OPEN, "must lie between 0 and 360 deg")
    if not target_lift > 0.0:
        raise InputError(file, KEY_LIFT, "must be greater than zero")

    swings = np.linspace(0.0, omega, 49)  # the roller must follow all along, not only at the open end

    def trial(ws, h):
        return replace(gear, contour=replace(gear.contour, lift_start=ws, rise=h))

    def lift(ws, h, w):
        return trial(ws, h).lift_at_swing(w)

    def rise_for(ws):
        """H giving the wanted lift at the open end for a flank starting at ws; None when the
        roller lever cannot follow (it loses the rocking cam first)."""
        if ws >= omega:
            return None

        def excess(h):  # None where the roller loses the cam anywhere on the swing (rises beyond a limit)
            try:
                return float(lift(ws, h, swings)[-1]) - top
            except InputError:
                return None

        h_lo, h_hi = 0.0, gear.contour.rise
        for _ in range(60):  # double until past the target; past the roller's limit, bisect towards it
            e = excess(h_hi)
            if e is not None and e > 0.0:
                break
            if e is not None:
                h_lo, h_hi = h_hi, 2.0 * h_hi
                continue
            lost = h_hi
            while lost - h_lo > 1e-12 * lost:
                mid = 0.5 * (h_lo + lost)
                e = excess(mid)
                if e is None:
                    lost = mid
                elif e > 0.0:
                    break
                else:
                    h_lo = mid
            else:
                return None
            h_hi = mid
            break
        else:
            return None

        def finite_excess(h):  # between a rise the roller follows and a larger one it follows too
            e = excess(h)
            return math.inf if e is None else e

        return root_in(finite_excess, h_lo, h_hi, xtol=1e-15, rtol=_EPS)

    def seat_swing(ws, h):
        """The swing at which the lift reaches the lash for this flank."""
        if lash <= 0.0:
            return ws
        return root_in(lambda w: float(lift(ws, h, [w])[0]) - lash, ws, omega, xtol=1e-15, rtol=_EPS)

    h0 = rise_for(0.0)
    if h0 is None:
        raise InputError(file, KEY_LIFT, f"{target_lift * 1e3:.4g} mm is out of reach: the roller lever cannot follow "
                         "a flank that high (the roller would lose the rocking cam)")
    max_open = gear.open_angle_at_swing(seat_swing(0.0, h0))
    full_open = None
    # with the top arc reached the lift depends on the rise alone (h0); the top arc's swing moves
    # with the flank's start, so the flank that reaches it just at the open end starts at
    late = omega - trial(0.0, h0).top_arc_swing()
    if late >= 0.0:
        full_open = gear.open_angle_at_swing(seat_swing(late, h0))
    if target_open_angle > max_open:
        raise InputError(file, KEY_OPEN, f"{math.degrees(target_open_angle):.4g} deg is longer than a "
                         f"{math.degrees(flank):.4g} deg flank can keep the valve open at this lift (at most "
                         f"{math.degrees(max_open):.4g} deg, the flank starting at the closed end): shorten "
                         "gear.rocking_cam.flank")
    # the linkage alone: the swing at which the valve must leave its seat
    w_o = root_in(lambda w: gear.open_angle_at_swing(w) - target_open_angle, 0.0, omega, xtol=1e-15, rtol=_EPS)
    if lash <= 0.0:
        ws = w_o
    else:
        def excess(ws):
            h = rise_for(ws)
            # a flank the roller lever cannot follow counts as one that opens too late
            return -lash if h is None else float(lift(ws, h, [w_o])[0]) - lash

        ws = root_in(excess, 0.0, w_o, xtol=1e-15, rtol=_EPS) if excess(0.0) > 0.0 else 0.0
    h = rise_for(ws)
    if h is not None:
        got = lift(ws, h, [w_o, omega])
    if h is None or abs(got[0] - lash) > 1e-9 * top or abs(got[1] - top) > 1e-9 * top:
        raise InputError(file, KEY_OPEN, f"{math.degrees(target_open_angle):.4g} deg is too short for "
                         f"{target_lift * 1e3:.4g} mm of lift: the flank would have to rise more steeply than "
                         "the roller lever can follow; lengthen open_angle or lower the lift")
    check_one_turn(float(ws), flank, file)  # the fitted contour is checked as a written one
    return ContourFit(lift_start=float(ws), rise=float(h), open_swing=float(w_o),
                      full_lift_dwell=trial(ws, h).full_lift_dwell(), max_open_angle=float(max_open),
                      full_flank_open_angle=full_open)


def fit_contour(gear: RockingCamGear, target_lift: float, target_open_angle: float, lash: float = 0.0,
                make_gear=None) -> RockingCamGear:
    """The gear with its flank placed and scaled (fit_target) so that the valve lifts
    `target_lift` after `lash` and stays open for `target_open_angle` of shaft rotation;
    `make_gear(contour)` rebuilds the gear (default: the same linkage, new contour)."""
    fit = fit_target(gear, target_lift, target_open_angle, lash)
    make_gear = make_gear or (lambda c: replace(gear, contour=c))
    return make_gear(replace(gear.contour, lift_start=fit.lift_start, rise=fit.rise))


def max_pressure_angle(gear: RockingCamGear, theta) -> float:
    """Largest |pressure angle| at the roller over the shaft angles theta, rad."""
    return float(np.max(np.abs(gear.contact_details(theta)["pressure_angle"])))


def rocking_cam_toml(part, lift_start: float, rise: float) -> str:
    """[gear.rocking_cam] in scene-file syntax with the flank start and rise replaced: the written
    part's other keys as they are (SI values from the spec, printed in mm and deg). Ten significant
    digits keep the pasted contour within ~1e-9 of the fitted one."""

    def mm(x):
        return f'"{x * 1e3:.10g} mm"'

    def deg(x):
        return f'"{math.degrees(x):.10g} deg"'

    return "\n".join([
        "[gear.rocking_cam]",
        f"dwell_radius = {mm(part['dwell_radius'])}",
        f"rise = {mm(rise)}",
        f"lift_start = {deg(lift_start)}",
        f"flank = {deg(part['flank'])}",
        f'law = "{part["law"]}"',
        f'opens = "{part["opens"]}"',
    ]) + "\n"


def target_report(given: RockingCamGear, fit: ContourFit, fitted: RockingCamGear, target, part, lash: float,
                  theta) -> tuple[dict, list[str]]:
    """Summary of [gear.target]: wanted, what the written contour achieves, the fitted contour and
    what it achieves (re-measured on the rebuilt gear, not taken from the fit), the open angles a
    flank of this length reaches at the wanted lift, and the fitted table in scene syntax."""

    def contour(gear):
        lift, open_angle = valve_opening(gear, lash)
        c = gear.contour
        return {
            "lift_start_deg": math.degrees(c.lift_start),
            "rise_m": c.rise,
            "valve_lift_m": lift,
            "open_angle_deg": math.degrees(open_angle),
            "full_lift_dwell_deg": math.degrees(gear.full_lift_dwell()),
            "max_pressure_angle_deg": math.degrees(max_pressure_angle(gear, theta)),
        }

    wanted = {"valve_lift_m": target["lift"], "open_angle_deg": math.degrees(target["open_angle"])}
    if target["max_pressure_angle"] is not None:
        wanted["max_pressure_angle_deg"] = math.degrees(target["max_pressure_angle"])
    report = {
        "use": target["use"],
        "lash_m": lash,
        "wanted": wanted,
        "given": contour(given),
        "fitted": contour(fitted),
        "max_open_angle_deg": math.degrees(fit.max_open_angle),
        "full_flank_open_angle_deg": None if fit.full_flank_open_angle is None
        else math.degrees(fit.full_flank_open_angle),
        "fitted_toml": rocking_cam_toml(part, fit.lift_start, fit.rise),
    }
    warnings = []
    limit = target["max_pressure_angle"]
    if limit is not None:
        # the fitted contour is the proposal; the written one matters while it is the one simulated
        for name in ("fitted", "given") if target["use"] == "given" else ("fitted",):
            got = report[name]["max_pressure_angle_deg"]
            if got > math.degrees(limit):
                warnings.append(f"the {name} rocking-cam contour's pressure angle reaches {got:.3f} deg, more than "
                                f"gear.target.max_pressure_angle {math.degrees(limit):.4g} deg")
    return report, warnings
