"""The eccentric rolling lever (Schenker's "Waelzhebel"): the eccentric's lever rolls on the valve
lever, whose rolling contact point moves out as the lever swings, so the ratio grows along the lift
(explorer.gears.rolling: the rolling law, the geometry, the levers' stiffness referred to the valve).

[gear.eccentric] (the rolling lever is the eccentric's lever; explorer.gears.common)
[gear.rolling_lever] valve_lever_pivot, contact_radius, growth, contact_swing, opens,
    lever_stiffness, rod_stiffness (optional; with either, the elastic effect's stiffness is theirs
    referred to the valve, k(t), in series with [linkage] stiffness, and needs a solver.method that
    takes k(t): explorer/dynamics/solvers.py, varying_stiffness)
[gear.valve] type = "rocker" on the valve lever (angle from the direction valve-lever pivot ->
    rolling-lever pivot); [lift] law = "gear" (the gear makes its lift).

The 'gear' effect reports the lever angles, the rolling ratio, the pick-up and release and the
valve-referred stiffness; the contact statics are the rolling faces' (RollingLeverGear).
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from ..core.errors import InputError
from ..core.reader import Table
from ..dynamics.solvers import varying_stiffness
from ..mechanics.gear_contact import GearContact
from ..mechanics.tribology import SurfaceMotion
from ..result import EffectOutput, Event
from .base import Gear
from .common import (SENSES, LeverContact, eccentric_keys, make_eccentric, make_valve_drive, point_key, spec_of,
                     valve_keys)
from .rolling import RollingLaw, RollingLeverGear, RollingLeverLift


def rolling_lever_keys(t: Table) -> dict:
    t.reject_unknown(("valve_lever_pivot", "contact_radius", "growth", "contact_swing", "opens",
                      "lever_stiffness", "rod_stiffness"))
    return {
        "valve_lever_pivot": point_key(t, "valve_lever_pivot"),
        "contact_radius": t.quantity("contact_radius", "length", positive=True),
        "growth": t.quantity("growth", "length", 0.0),  # m per rad of rolling swing
        "contact_swing": t.quantity("contact_swing", "angle", nonnegative=True),
        "opens": t.string("opens", "ccw", choices=SENSES),
        "lever_stiffness": t.quantity("lever_stiffness", "torque", positive=True) if t.has("lever_stiffness") else None,
        "rod_stiffness": t.quantity("rod_stiffness", "stiffness", positive=True) if t.has("rod_stiffness") else None,
    }


def rolling_valve_keys(t: Table) -> dict:
    return valve_keys(t, rolling=True)


class RollingLever(LeverContact, Gear):
    type = "rolling-lever"
    description = "eccentric-driven rolling lever (Waelzhebel): the ratio grows along the lift"
    parts = MappingProxyType({"eccentric": eccentric_keys, "rolling_lever": rolling_lever_keys,
                              "valve": rolling_valve_keys})
    linkage_ratio = True
    makes_lift = True
    columns = MappingProxyType({"gear": ("rolling_lever_angle_deg", "valve_lever_angle_deg", "rolling_ratio",
                                         "rolling_contact_radius_m", "valve_referred_stiffness_N_m")})

    def check(self, spec, fields) -> None:
        super().check(spec, fields)
        if "elastic" in fields["effects"]:
            rl = spec.part("rolling_lever")
            varying = varying_stiffness()
            if (rl["lever_stiffness"] is not None or rl["rod_stiffness"] is not None) \
                    and fields["solver"].method not in varying:
                raise InputError(spec.file, "solver.method", f"method \"{fields['solver'].method}\" needs a constant "
                                 "linkage stiffness, but the rolling lever's (lever_stiffness, rod_stiffness) changes with "
                                 "its ratio along the lift: use method = " + " or ".join(f'"{m}"' for m in varying))

    def make(self, spec, source) -> RollingLeverGear:
        file = spec.file
        drive = make_eccentric(spec.part("eccentric"), file)
        rl = spec.part("rolling_lever")
        ax, ay = drive.pivot
        bx, by = rl["valve_lever_pivot"]
        distance = math.hypot(bx - ax, by - ay)
        if distance <= rl["contact_radius"]:
            raise InputError(file, "gear.rolling_lever.contact_radius", "the contact point must lie between the two pivots")
        sense = 1 if rl["opens"] == "ccw" else -1
        chis = [float(drive.angle(np.array([c]))[0]) for c in drive.dead_centres()]
        closed = min(chis) if sense > 0 else max(chis)
        rest = math.atan2(ay - by, ax - bx)
        valve = make_valve_drive(spec.part("valve"), pivot=(bx, by), lever_arm=distance, rest=rest, lifting=-sense,
                                 file=file)
        gear = RollingLeverGear(drive=drive, valve_pivot=(bx, by),
                                law=RollingLaw(distance, rl["contact_radius"], rl["growth"]), sense=sense,
                                closed_end=closed, contact_swing=rl["contact_swing"], rest=rest, valve=valve,
                                lever_stiffness=rl["lever_stiffness"], rod_stiffness=rl["rod_stiffness"], file=file)
        gear.check()
        return gear

    def build_lift(self, scene) -> RollingLeverLift:
        gear = self.make(spec_of(self, scene), scene)
        marks = gear.contact_angles()
        if marks.size != 2:
            raise InputError(scene.source, "gear.rolling_lever.contact_swing", "the levers must meet once per revolution")
        return RollingLeverLift(gear, tuple(marks))

    def report(self, ctx) -> EffectOutput:
        """Lever angles, rolling ratio, pick-up and release, valve-referred stiffness."""
        lift = ctx.lift if hasattr(ctx.lift, "gear") else self.build_lift(ctx.scene)
        gear = lift.gear
        theta = ctx.theta
        w = gear.rolling_swing(theta)
        beta = gear.valve_lever_angle(w)
        alpha = gear.drive.angle(theta)
        contact = (w.c[0] > 0.0)
        ratio = np.where(contact, gear.law.ratio(w.c[0]), 0.0)
        columns = {
            "rolling_lever_angle_deg": np.degrees(alpha),
            "valve_lever_angle_deg": np.degrees(np.where(contact, beta.c[0], gear.rest)),
            "rolling_ratio": ratio,
            "rolling_contact_radius_m": np.where(contact, gear.law.rho(w.c[0]), 0.0),
        }
        k = gear.stiffness(theta)
        summary: dict = {}
        warnings = []
        lift_values = lift.derivatives(theta)[0]
        i_max = int(np.argmax(lift_values))
        if "lever" in k or "rod" in k:
            total = k.get("total", k.get("lever", k.get("rod")))
            columns["valve_referred_stiffness_N_m"] = np.where(contact, total, np.nan)
            summary["valve_referred_stiffness_at_max_lift_N_m"] = float(total[i_max])
            if "lever" in k:
                summary["lever_stiffness_at_max_lift_N_m"] = float(k["lever"][i_max])
            if "rod" in k:
                summary["rod_stiffness_at_max_lift_N_m"] = float(k["rod"][i_max])
            if "lever" in k and "rod" in k:
                # Schenker: most of the elasticity sits in the rolling lever
                summary["share_of_compliance_in_lever"] = float(k["total"][i_max] / k["lever"][i_max])
            link = ctx.scene.linkage
            if link is not None:  # the elastic effect's k(t): the gear's in series with the rest of the chain
                chain = 1.0 / (1.0 / total[contact] + 1.0 / link.stiffness)
                summary["linkage_stiffness_in_contact_N_m"] = [float(chain.min()), float(chain.max())]
        marks = lift.breakpoints()
        omega = ctx.omega
        picks = []
        for m in marks:
            virtual = gear.virtual_lift(np.array([m]))
            picks.append({"cam_angle_deg": math.degrees(m), "velocity_m_s": float(omega * virtual.c[1][0]),
                          "ratio": float(gear.law.ratio(0.0))})
        events = []
        for p in picks:
            kind = "rolling-contact" if p["velocity_m_s"] > 0 else "rolling-release"
            events.append(Event(kind, math.radians(p["cam_angle_deg"]) / omega, p["cam_angle_deg"],
                                {k: v for k, v in p.items() if k != "cam_angle_deg"}))
        summary.update(
            pick_up_ratio=float(gear.law.ratio(0.0)),
            max_rolling_ratio=float(gear.law.ratio(gear.max_rolling_swing())),
            swing_deg=float(np.degrees(np.ptp(alpha))),
            rolling_swing_deg=math.degrees(gear.max_rolling_swing()),
            pick_up=picks,
            eccentric_dead_centres_deg=[math.degrees(a) for a in gear.drive.dead_centres()],
        )
        return EffectOutput(columns=columns, summary=summary, events=tuple(events), warnings=tuple(warnings))


    def lifter_ratio(self, scene, lift, theta):
        """No follower the trade's lobe figures are quoted at: the valve's own lift ([lift])."""
        return "valve", np.ones(np.shape(np.asarray(theta, dtype=float)))

    def cam_contact(self, scene, lift, theta) -> GearContact:
        """The faces roll on each other: the contact runs along face A (a spiral rho = rho_c + k w
        about its pivot) at sqrt(k^2 + rho^2) per radian of rolling swing w, both surfaces alike."""
        gear = lift.gear
        geometry = gear.contact_geometry(theta)
        swing = gear.rolling_swing(theta)  # w and dw/dtheta
        w = np.maximum(swing.c[0], 0.0)
        rho = gear.law.rho(w)
        rate = np.where(swing.c[0] > 0.0, -np.hypot(gear.law.growth, rho) * np.abs(swing.c[1]), 0.0)
        return GearContact(geometry, SurfaceMotion(rate, rate.copy()), oscillating=True, pitch_radius=None)

GEAR = RollingLever()
