"""The valve end of an arm: a curved pad rolling and sliding on the flat valve tip.

The arm (finger or rocker) turns about its pivot O by the angle psi. Its valve pad is a circle
of radius Rv about a point C of the arm (the pad's centre of curvature), at distance `arm` from O
and at `angle` from the arm's reference direction. The valve moves along its axis u (the
direction in which it opens); its tip is the plane perpendicular to u. The pad touches the tip at
the circle's point furthest along u,
    X = C + Rv u,
so the tip's plane, and with it the valve, is at u . C + Rv: the valve travel is
    s(psi) = u . (C(psi) - C(psi0)),
the pad radius cancels, and the travel is explorer.gears.linkage.RockerDrive's (a pin at C
moving the valve along u), whose closed-form inverse psi(s) is the synthesis' first step. The
ratio ds/dpsi = u . J (C - O) changes with the arm angle.

Across the tip the contact sits at w = t . (X - A) from the stem's axis (t = J u, A a point of
the axis): w(psi) = t . (C(psi) - A), the tip's contact travel ("scrub"); the pad must stay on the
tip, |w| below the tip's radius.

Velocities along the tip (per unit camshaft speed, psi' = dpsi/dtheta): the contact moves along
the tip at w' = psi' t . J (C - O); the pad's material point at X moves along it at
psi' t . J (X - O) = w' + psi' Rv; the valve's not at all. Relative to the contact point the tip
surface moves at -w' and the pad's at psi' Rv: the sliding velocity (valve minus pad) is
-(w' + psi' Rv) = -psi' t . J (X - O), the entrainment velocity (psi' Rv - w')/2. A pad rolls
without sliding only where its contact stays put on the arm's pivot line, t . (X - O) = 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from . import jet as J
from .envelope import SurfaceVelocities
from .jet import Jet
from .linkage import RockerDrive


@dataclass(frozen=True)
class TipContact:
    """The pad on the valve tip, per cam angle (rates per radian of cam angle)."""

    point: np.ndarray  # (N, 2) ground, the contact X
    scrub: np.ndarray  # m, w: the contact's distance across the tip from the stem's axis
    scrub_rate: np.ndarray  # m/rad, dw/dtheta
    valve_per_arm: np.ndarray  # m/rad, ds/dpsi
    arm_jacobian: np.ndarray  # (N, 2) m/rad: the arm's material velocity at X per unit dpsi, J (X - O)
    velocities: SurfaceVelocities  # valve (first) and pad (second) relative to the contact, m/rad
    tangent: np.ndarray  # (N, 2) unit t = J u (along the tip)


@dataclass(frozen=True)
class ValveEnd:
    """The pad at the valve end of an arm (module docstring). `drive.arm`, `drive.angle`: the pad's
    centre of curvature on the arm; `drive.axis`: the opening direction u; `drive.rest`: the arm
    angle with the valve closed (lash included in the travel, as in every gear here)."""

    drive: RockerDrive
    pad_radius: float  # m
    axis_point: tuple[float, float]  # a point of the valve stem's axis (ground)
    tip_radius: float | None = None  # m, the valve tip face's radius; None: not checked
    file: str = "<memory>"
    key: str = "gear.valve_pad"
    tip_key: str = "gear.valve.tip_radius"  # the scene key of tip_radius ([gear.valve], not the pad's table)

    @property
    def pivot(self) -> tuple[float, float]:
        return self.drive.pivot

    @property
    def axis(self) -> np.ndarray:
        return np.array([math.cos(self.drive.axis), math.sin(self.drive.axis)])

    def centre(self, psi):
        d = self.drive
        return d.pivot[0] + d.arm * J.cos(psi + d.angle), d.pivot[1] + d.arm * J.sin(psi + d.angle)

    def travel(self, psi):
        """Valve travel s(psi) (m), jets if psi is a jet."""
        return self.drive.travel(psi)

    def inverse(self, s):
        """psi(s) on the rest branch (closed form); InputError when the pad passes its dead point."""
        return self.drive.inverse(s)

    def valve_per_arm(self, psi, centre=None):
        """ds/dpsi = u . J (C - O) as a function of psi (a jet in theta if psi is one): its
        derivatives are the ratio's. `centre`: C(psi) if already at hand."""
        u = self.axis
        cx, cy = self.centre(psi) if centre is None else centre
        o = self.pivot
        return u[1] * (cx - o[0]) - u[0] * (cy - o[1])

    def rest_contact(self) -> np.ndarray:
        cx, cy = self.centre(self.drive.rest)
        return np.array([float(cx), float(cy)]) + self.pad_radius * self.axis

    def contact(self, psi: Jet, centre=None) -> TipContact:
        """The tip contact for arm angles given as a jet in the cam angle (`centre`: the pad's
        centre C(psi) as jets, if already at hand)."""
        u = self.axis
        t = np.array([-u[1], u[0]])
        cx, cy = self.centre(psi) if centre is None else centre
        x = cx.c[0] + self.pad_radius * u[0]
        y = cy.c[0] + self.pad_radius * u[1]
        point = np.column_stack([x, y])
        a = self.axis_point
        scrub = t[0] * (x - a[0]) + t[1] * (y - a[1])
        scrub_rate = t[0] * cx.c[1] + t[1] * cy.c[1]
        o = self.pivot
        jac = np.column_stack([-(y - o[1]), x - o[0]])
        rate = psi.c[1]
        n = len(x)
        tangents = np.tile(t, (n, 1))
        # relative to the contact point: the tip's surface at -w', the pad's at psi' Rv (module docstring)
        velocities = SurfaceVelocities(-scrub_rate, rate * self.pad_radius)
        valve_per_arm = jac @ u  # u . J (X - O) = u . J (C - O): u . J u = 0
        return TipContact(point=point, scrub=scrub, scrub_rate=scrub_rate, valve_per_arm=valve_per_arm,
                          arm_jacobian=jac, velocities=velocities, tangent=tangents)

    def check_on_tip(self, theta: np.ndarray, tip: TipContact) -> None:
        """The pad must not run off the valve tip: |w| < tip radius at every cam angle."""
        if self.tip_radius is None:
            return
        far = np.abs(tip.scrub)
        i = int(np.argmax(far))
        if far[i] >= self.tip_radius:
            raise InputError(
                self.file, self.tip_key,
                f"the pad does not reach the valve tip: its contact is {far[i] * 1e3:.3g} mm from the stem's axis at cam "
                f"angle {math.degrees(float(theta[i])) % 360.0:.2f} deg, beyond the tip's radius "
                f"{self.tip_radius * 1e3:.3g} mm (move the valve axis or the pad, or enlarge the pad radius)",
            )


def make_valve_end(*, pivot, rest: float, lifting: float, arm: float, angle: float, pad_radius: float,
                   axis: float | None = None, axis_point=None, tip_radius: float | None = None,
                   file: str = "<memory>", key: str = "gear.valve_pad",
                   tip_key: str = "gear.valve.tip_radius") -> ValveEnd:
    """The valve end for an arm at rest angle `rest` whose angle grows (lifting = +1) or falls
    (-1) as the cam lifts it. Default axis: the way the pad's centre moves when the arm lifts;
    default axis point: through the contact at rest (no scrub offset at the closed valve)."""
    for name, value in (("arm", arm), ("radius", pad_radius)):
        if not (math.isfinite(value) and value > 0.0):
            raise InputError(file, f"{key}.{name}", f"must be greater than zero, got {value!r}")
    if tip_radius is not None and not tip_radius > 0.0:
        raise InputError(file, tip_key, f"must be greater than zero, got {tip_radius!r}")
    direction = rest + angle + 0.5 * math.pi  # d C / d psi
    dx, dy = lifting * math.cos(direction), lifting * math.sin(direction)
    if axis is None:
        axis = math.atan2(dy, dx)
    along = dx * math.cos(axis) + dy * math.sin(axis)
    if along <= 0.0:
        raise InputError(file, "gear.valve.axis", "the valve would close as the arm lifts: reverse the axis (add 180 deg)")
    if along < 1e-3:
        raise InputError(file, f"{key}.angle", "the pad moves across the valve axis at rest (dead point)")
    drive = RockerDrive(pivot=tuple(pivot), arm=arm, angle=angle, axis=axis, rest=rest, file=file, key=key)
    end = ValveEnd(drive=drive, pad_radius=pad_radius, axis_point=(0.0, 0.0), tip_radius=tip_radius, file=file, key=key,
                   tip_key=tip_key)
    if axis_point is None:
        axis_point = tuple(end.rest_contact())
    return ValveEnd(drive=drive, pad_radius=pad_radius, axis_point=tuple(axis_point), tip_radius=tip_radius,
                    file=file, key=key, tip_key=tip_key)
