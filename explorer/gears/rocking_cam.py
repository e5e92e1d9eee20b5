"""The eccentric-driven rocking cam (seed 004, "Schwingdaumen"): an eccentric swings a rocking cam
about its pivot, whose flank lifts a roller lever that drives the valve (explorer.gears.rocking:
the contour, the gear's geometry, the fit of a flank to a wanted lift).

[gear.eccentric] radius, phase, rod, lever_pivot, lever_arm, pin_side      (explorer.gears.common)
[gear.rocking_cam] dwell_radius, rise, lift_start, flank, law, opens
[gear.lever] (pivot, arm, roller_side seen from the pivot towards the cam pivot), [gear.valve]
[gear.target] (optional) lift, open_angle, max_pressure_angle, use = "given" | "fitted": the flank
    (lift_start, rise) that gives the wanted valve lift and open angle; reported by the 'gear'
    effect and `explorer fit`, simulated only with use = "fitted"
follower.roller_radius; [lift] law = "gear" (the gear makes its lift).

The 'gear' effect reports the rocking and lever angles and ratio, the swing, equal eccentric arcs
against unequal swings, and the opening/closing symmetry about the eccentric's dead centre (why
Schenker's 2R/M asymmetry is out of reach); with [gear.target] the fitted contour against the
written one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..core.reader import Table
from ..lift.registry import closed_form_names
from ..lift.validity import cam_fault, entered_error
from ..mechanics.gear_contact import GearContact
from ..mechanics.kinematics import lash_crossings
from ..mechanics.moving_mass import rigid_mass
from ..mechanics.tribology import rolling_roller_motion
from ..result import EffectOutput
from .base import Gear
from .common import (SENSES, LeverContact, eccentric_keys, lever_keys, make_eccentric, make_valve_drive, section,
                     spec_of, valve_keys)
from .jet import Jet
from .linkage import side_sign
from .rocking import RockingContour, build_rocking_gear, check_one_turn, fit_target, swing_increments, target_report

TWO_PI = 2.0 * math.pi


def rocking_cam_keys(t: Table) -> dict:
    t.reject_unknown(("dwell_radius", "rise", "lift_start", "flank", "law", "opens"))
    out = {
        "dwell_radius": t.quantity("dwell_radius", "length", positive=True),
        "rise": t.quantity("rise", "length", positive=True),
        "lift_start": t.quantity("lift_start", "angle", nonnegative=True),
        "flank": t.quantity("flank", "angle", positive=True),
        "law": t.string("law", "cycloidal", choices=closed_form_names()),
        "opens": t.string("opens", "ccw", choices=SENSES),
    }
    check_one_turn(out["lift_start"], out["flank"], t.file)
    return out


TARGET_USES = ("given", "fitted")


def target_keys(t: Table) -> dict:
    t.reject_unknown(("lift", "open_angle", "max_pressure_angle", "use"))
    out = {
        "lift": t.quantity("lift", "length", positive=True),  # the valve's own lift, after the lash
        "open_angle": t.quantity("open_angle", "angle", positive=True),  # shaft angle, valve off its seat
        "max_pressure_angle": t.quantity("max_pressure_angle", "angle", positive=True)
        if t.has("max_pressure_angle") else None,
        "use": t.string("use", "given", choices=TARGET_USES),
    }
    if out["open_angle"] >= 2.0 * math.pi:
        raise t.error("open_angle", "must be less than 360 deg (the valve must close once per revolution)")
    if out["max_pressure_angle"] is not None and out["max_pressure_angle"] >= 0.5 * math.pi:
        raise t.error("max_pressure_angle", "must be less than 90 deg")
    return out


@dataclass(frozen=True)
class RockingLift:
    gear: Any
    marks: tuple[float, ...]

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        return self.gear.lift_jet(theta.reshape(-1)).c.reshape((4,) + theta.shape)

    def breakpoints(self) -> np.ndarray:
        return np.array(sorted(self.marks))


def make_rocking_gear(spec, source, lift_start=None, rise=None):
    """The rocking-cam gear of a spec, with the contour as written or with its flank start and
    rise replaced (the fitted contour of [gear.target])."""
    file = spec.file
    follower = section(source, "follower")
    drive = make_eccentric(spec.part("eccentric"), file)
    rc, lever = spec.part("rocking_cam"), spec.part("lever")
    r = follower.roller_radius
    contour = RockingContour(dwell_radius=rc["dwell_radius"] + r, rise=rc["rise"] if rise is None else rise,
                             lift_start=rc["lift_start"] if lift_start is None else lift_start,
                             flank=rc["flank"], law=rc["law"], sense=1 if rc["opens"] == "ccw" else -1)
    cam_pivot = drive.pivot

    def make_valve(psi0):
        rx = lever["pivot"][0] + lever["arm"] * math.cos(psi0)
        ry = lever["pivot"][1] + lever["arm"] * math.sin(psi0)
        climb = (rx - cam_pivot[0]) * -math.sin(psi0) + (ry - cam_pivot[1]) * math.cos(psi0)
        return make_valve_drive(spec.part("valve"), pivot=lever["pivot"], lever_arm=lever["arm"], rest=psi0,
                                lifting=float(np.sign(climb)), file=file)

    gear = build_rocking_gear(drive=drive, cam_pivot=cam_pivot, contour=contour, roller_radius=r,
                              lever_pivot=lever["pivot"], lever_arm=lever["arm"],
                              roller_branch=side_sign(lever["roller_side"]), make_valve=make_valve, file=file)
    check_rocking_contour(gear)
    return gear


def rocking_target(spec, source):
    """(given gear, ContourFit, fitted gear) for a rocking-cam spec with [gear.target]: the flank
    start and rise that give the wanted valve lift (after the scene's lash) and open angle. The
    fitted gear passes the same checks as a written contour; its failures name gear.target."""
    target = spec.part("target")
    valve = section(source, "valve")
    lash = valve.lash if valve is not None else 0.0
    given = make_rocking_gear(spec, source)
    fit = fit_target(given, target["lift"], target["open_angle"], lash)
    try:
        fitted = make_rocking_gear(spec, source, lift_start=fit.lift_start, rise=fit.rise)
    except InputError as exc:
        raise InputError(spec.file, "gear.target", f"the fitted contour (lift_start "
                         f"{math.degrees(fit.lift_start):.4g} deg, rise {fit.rise * 1e3:.4g} mm) fails: {exc.reason}; "
                         "for this target lower gear.target.lift, lengthen gear.target.open_angle or give a longer "
                         "gear.rocking_cam.flank") from None
    return given, fit, fitted


def check_rocking_contour(gear, n: int = 721) -> None:
    """The checks every cam passes (explorer.lift.validity), on the rocking cam as written or as
    fitted: its valve-referred lift over the shaft's turn (finite, in range), the pressure angle at
    the roller, and undercut -- a convex stretch of the flank's pitch curve sharper than the roller."""
    c = gear.contour
    w = np.linspace(c.lift_start, c.lift_start + c.flank, n)
    curvature = c.pitch_curvature(c.reference - c.sense * w)
    with np.errstate(divide="ignore"):
        radius = 1.0 / curvature
    theta = np.linspace(0.0, TWO_PI, 721)
    lift = gear.lift_jet(theta).c  # the roller keeps the cam all round (else the gear raises)
    fault = cam_fault(theta, lift, pressure_angle=gear.contact_details(theta)["pressure_angle"], pitch_radius=radius,
                      roller_radius=gear.roller_radius, curvature_angle=w, where="shaft angle {}",
                      curvature_where="flank angle {}")
    if fault is not None:
        raise entered_error(fault, gear.file)


def symmetry_report(scene, lift) -> dict:
    """Opening and closing about the eccentric's dead centre: half-durations, the linkage's
    prediction of their difference (mirror images about the line O -> rod pin), and the largest
    decelerations p1 (opening) and p2 (closing), with Schenker's 2R/M for comparison."""
    gear = lift.gear
    lash = scene.valve.lash if scene.valve else 0.0
    ups, downs = lash_crossings(lift, 1.0, lash)
    out: dict = {}
    if ups.size != 1 or downs.size != 1:
        return out
    w = scene.drive.omega
    td = gear.dead_centre
    open_half = float(np.mod(td - ups[0], TWO_PI))
    close_half = float(np.mod(downs[0] - td, TWO_PI))
    chi_open = float(gear.drive.angle(np.array([ups[0]]))[0])
    chi_dead = float(gear.drive.angle(np.array([td]))[0])
    predicted = 2.0 * float(np.angle(np.exp(1j * (gear.rod_pin_angle(np.array([chi_open]))[0]
                                                    - gear.rod_pin_angle(np.array([chi_dead]))[0]))))
    u = np.linspace(0.0, max(open_half, close_half), 2001)
    p_open = w**2 * lift.derivatives(np.mod(td - u[u <= open_half], TWO_PI))[2]
    p_close = w**2 * lift.derivatives(np.mod(td + u[u <= close_half], TWO_PI))[2]
    p1, p2 = float(p_open.min()), float(p_close.min())
    out.update(
        opening_half_deg=math.degrees(open_half),
        closing_half_deg=math.degrees(close_half),
        timing_asymmetry_deg=math.degrees(close_half - open_half),
        timing_asymmetry_from_linkage_deg=math.degrees(predicted),
        peak_deceleration_opening_m_s2=p1,
        peak_deceleration_closing_m_s2=p2,
        deceleration_difference_m_s2=p2 - p1,
    )
    if scene.valve is not None:
        # M: the rigid train's mass at the valve (the forces effect's, mechanics.moving_mass)
        out["schenker_2R_over_M_m_s2"] = 2.0 * scene.loads.friction / rigid_mass(scene).total
    return out


class RockingCam(LeverContact, Gear):
    type = "rocking-cam"
    description = "eccentric-driven rocking cam on a roller lever (seed 004)"
    parts = MappingProxyType({"eccentric": eccentric_keys, "rocking_cam": rocking_cam_keys, "lever": lever_keys,
                              "valve": valve_keys, "target": target_keys})
    optional_parts = frozenset({"target"})
    linkage_ratio = True
    makes_lift = True
    contact_roller = True
    fits_target = True
    columns = MappingProxyType({"gear": ("rocking_angle_deg", "rocking_swing_deg", "lever_angle_deg", "lever_ratio")})

    def check(self, spec, fields) -> None:
        super().check(spec, fields)
        if fields["follower"].roller_radius <= 0.0:
            raise InputError(fields.get("source", "<memory>"), "follower.roller_radius",
                             f"the {self.type} gear needs a roller (roller_radius > 0)")

    def parse(self, table, fields):
        spec = super().parse(table, fields)
        if "target" in spec.parts and spec.part("target")["use"] == "given":
            rocking_target(spec, fields)  # a target out of reach fails here, not later in the 'gear' effect
        return spec

    def make(self, spec, source):
        """The gear with the contour as written, or as fitted to [gear.target] (use = "fitted")."""
        if "target" in spec.parts and spec.part("target")["use"] == "fitted":
            return rocking_target(spec, source)[2]
        return make_rocking_gear(spec, source)

    def lift_reads(self, scene) -> tuple[str, ...]:
        """None of the sweep keys for a contour as written (its geometry alone makes the lift); the
        lash for one fitted to [gear.target] (the fit is to the valve's lift after the lash:
        rocking_target)."""
        spec = scene.gear
        if "target" in spec.parts and spec.part("target")["use"] == "fitted":
            return ("valve.lash",)
        return ()

    def build_lift(self, scene) -> RockingLift:
        gear = self.make(spec_of(self, scene), scene)
        return RockingLift(gear, tuple(gear.flank_angles()))

    def report(self, ctx) -> EffectOutput:
        lift = ctx.lift if hasattr(ctx.lift, "gear") else self.build_lift(ctx.scene)
        gear = lift.gear
        d = gear.contact_details(ctx.theta)
        w = gear.contour.sense * (d["rocking_angle"] - gear.closed_end)
        columns = {
            "rocking_angle_deg": np.degrees(d["rocking_angle"]),
            "rocking_swing_deg": np.degrees(w),
            "lever_angle_deg": np.degrees(d["lever_angle"]),
            "lever_ratio": d["ratio"],
        }
        sym = symmetry_report(ctx.scene, lift)
        closed_dc = [c for c in gear.drive.dead_centres() if abs(np.angle(np.exp(1j * (c - gear.dead_centre)))) > 1e-9][0]
        start = gear.dead_centre - float(np.mod(gear.dead_centre - closed_dc, TWO_PI))
        _, increments = swing_increments(gear, start, gear.dead_centre, 12)
        chis = gear.drive.angle(np.array([closed_dc, gear.dead_centre]))
        summary = {
            "swing_deg": float(np.degrees(abs(chis[1] - chis[0]))),
            "eccentric_dead_centre_deg": math.degrees(gear.dead_centre),
            "eccentric_closed_dead_centre_deg": math.degrees(closed_dc),
            "flank_angles_deg": [math.degrees(a) for a in lift.breakpoints()],
            # seed 004: 12 equal eccentric arcs from the closed to the open dead centre give unequal swings
            "swing_per_equal_eccentric_arc_deg": [float(np.degrees(abs(x))) for x in increments],
            "min_lever_ratio": float(d["ratio"].min()),
            "max_lever_ratio": float(d["ratio"].max()),
            "symmetry": sym,
        }
        warnings = []
        if "target" in ctx.scene.gear.parts:
            # [gear.target]: the fitted flank next to the written one; which of the two is simulated
            # is `use` (RockingCam.make), so `gear` here is the fitted one when use = "fitted"
            spec = ctx.scene.gear
            given, fit, fitted = rocking_target(spec, ctx.scene)
            lash = ctx.scene.valve.lash if ctx.scene.valve is not None else 0.0
            summary["target"], warnings = target_report(given, fit, fitted, spec.part("target"), spec.part("rocking_cam"),
                                                        lash, ctx.theta)
        return EffectOutput(columns=columns, summary=summary, warnings=tuple(warnings))

    def fit(self, scene, theta) -> tuple[dict, list[str]]:
        """`explorer fit`: the flank (lift_start, rise) that gives [gear.target]'s valve lift and open
        angle, next to the written one (target_report)."""
        spec = spec_of(self, scene)
        given, fit, fitted = rocking_target(spec, scene)
        lash = scene.valve.lash if scene.valve is not None else 0.0
        return target_report(given, fit, fitted, spec.part("target"), spec.part("rocking_cam"), lash, theta)


    def lifter_ratio(self, scene, lift, theta):
        """No follower the trade's lobe figures are quoted at: the valve's own lift ([lift])."""
        return "valve", np.ones(np.shape(np.asarray(theta, dtype=float)))

    def cam_contact(self, scene, lift, theta) -> GearContact:
        """The roller rolls without slipping on the rocking cam (rolling_roller_motion), the pitch
        curve traced in the frame of the rocking body, about its pivot; the lever swings."""
        gear = lift.gear
        geometry = gear.contact_geometry(theta)
        phi, _ = gear.contact_angle(theta)  # the contact's body angle on the pitch curve, jets in theta
        rho = gear.contour.radius(Jet.variable(phi.c[0]))  # pitch radius about the pivot, jets in phi
        speed = np.hypot(rho.c[0], rho.c[1]) * np.abs(phi.c[1])  # |dP/dtheta| in the rocking body's frame
        pitch_radius = np.asarray(geometry.contour_radius, dtype=float) + gear.roller_radius
        motion = rolling_roller_motion(speed, pitch_radius, gear.roller_radius)
        return GearContact(geometry, motion, oscillating=True, pitch_radius=pitch_radius)

GEAR = RockingCam()
