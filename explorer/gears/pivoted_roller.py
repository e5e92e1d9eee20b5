"""The pivoted roller lever (seed 004; Schenker's Fig. 3): a roller on a lever about a fixed pivot,
on a cam synthesised from the valve-referred lift law; the lever drives the valve through a rocker
arm or Fig. 3's rod and valve lever (explorer.gears.pivoted: geometry, synthesis and analysis).

[gear.lever]  pivot, arm, roller_side        [gear.valve]  (explorer.gears.common)
[lift] is the valve-referred lift law (lash included), a closed form: the cam is synthesised
through the law's jets. follower.base_radius and roller_radius size the cam and the roller.

The 'gear' effect reports the lever angle and ratio, the cam's size and seed 004's
instant-centre check of the lever's velocity; the contact statics are the lever's
(PivotedRollerGear.contact_geometry).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..lift.curves import law_lift
from ..lift.registry import closed_form_names, law_spec
from ..mechanics.gear_contact import GearContact
from ..mechanics.tribology import rolling_roller_motion
from ..result import EffectOutput
from .base import Gear
from .common import LeverContact, lever_keys, make_valve_drive, section, spec_of, valve_keys
from .linkage import side_sign
from .pivoted import PivotedRollerGear


@dataclass(frozen=True)
class PivotedLift:
    """The valve-referred lift of a pivoted roller lever, remembering its gear."""

    gear: Any

    def derivatives(self, theta) -> np.ndarray:
        return self.gear.lift.derivatives(theta)

    def breakpoints(self) -> np.ndarray:
        return np.asarray(self.gear.lift.breakpoints())


class PivotedRoller(LeverContact, Gear):
    type = "pivoted-roller"
    description = "roller lever about a fixed pivot on a rotating cam synthesised from the lift law (seed 004)"
    parts = MappingProxyType({"lever": lever_keys, "valve": valve_keys})
    linkage_ratio = True
    contact_roller = True
    columns = MappingProxyType({"gear": ("lever_angle_deg", "lever_ratio")})

    def law_refusal(self, law) -> str:
        if law.from_contour:
            return "a pivoted roller lever synthesises its cam from a lift law, not from [cam]"
        return (f"a pivoted roller lever synthesises its cam from one of the laws {', '.join(closed_form_names())}, "
                f"not from law \"{law.name}\"")

    def check(self, spec, fields) -> None:
        super().check(spec, fields)  # the ratio; a law that is no closed form
        file, follower = fields.get("source", "<memory>"), fields["follower"]
        if law_spec(fields["lift"].law).gear_made:
            raise InputError(file, "lift.law", f"the {self.type} gear needs a lift law (the valve-referred lift)")
        if follower.roller_radius <= 0.0:
            raise InputError(file, "follower.roller_radius", f"the {self.type} gear needs a roller (roller_radius > 0)")

    def make(self, spec, source) -> PivotedRollerGear:
        """The lever and its synthesised cam; InputError on bad geometry."""
        file = spec.file
        follower = section(source, "follower")
        lever = spec.part("lever")
        branch = side_sign(lever["roller_side"])
        psi0 = PivotedRollerGear.rest_angle_for(follower.base_radius, follower.roller_radius, lever["pivot"],
                                                lever["arm"], branch, file)
        rx, ry = lever["pivot"][0] + lever["arm"] * math.cos(psi0), lever["pivot"][1] + lever["arm"] * math.sin(psi0)
        lifting = float(np.sign(rx * -math.sin(psi0) + ry * math.cos(psi0)))
        drive = make_valve_drive(spec.part("valve"), pivot=lever["pivot"], lever_arm=lever["arm"], rest=psi0,
                                 lifting=lifting, file=file)
        gear = PivotedRollerGear(lift=law_lift(section(source, "lift")), base_radius=follower.base_radius,
                                 roller_radius=follower.roller_radius, pivot=lever["pivot"], arm=lever["arm"],
                                 branch=branch, drive=drive, file=file)
        gear.check()
        return gear

    def build_lift(self, scene) -> PivotedLift:
        return PivotedLift(self.make(spec_of(self, scene), scene))

    def report(self, ctx) -> EffectOutput:
        """Lever angle and ratio, the cam's size, seed 004's instant-centre check."""
        lift = ctx.lift if hasattr(ctx.lift, "gear") else self.build_lift(ctx.scene)
        gear = lift.gear
        g = gear.geometry(ctx.theta)
        ic = PivotedRollerGear.instant_centre_rate(gear.pivot, g.roller_centre, g.normal_ground)
        columns = {
            "lever_angle_deg": np.degrees(g.lever_angle),
            "lever_ratio": g.ratio,
        }
        convex = g.contour_radius[g.contour_radius > 0.0]
        summary = {
            "rest_lever_angle_deg": math.degrees(gear.rest_angle),
            "lever_swing_deg": float(np.degrees(g.lever_angle.max() - g.lever_angle.min())),
            "min_lever_ratio": float(g.ratio.min()),
            "max_lever_ratio": float(g.ratio.max()),
            "cam_max_radius_m": float(np.max(np.hypot(g.contour[:, 0], g.contour[:, 1]))),
            "min_convex_contour_radius_m": float(convex.min()) if convex.size else None,
            # seed 004's velocity construction against the analytic chain rule: a built-in self-check
            "instant_centre_check_rad": float(np.max(np.abs(ic - g.lever_rate))),
        }
        return EffectOutput(columns=columns, summary=summary)


    def lifter_ratio(self, scene, lift, theta):
        """The lever's ratio |ds/dpsi| / a, the valve's travel per travel of the roller centre (the
        [lift] being the valve's)."""
        return "roller centre", np.asarray(lift.gear.geometry(np.asarray(theta, dtype=float)).ratio, dtype=float)

    def cam_contact(self, scene, lift, theta) -> GearContact:
        """The roller rolls without slipping on the cam (rolling_roller_motion), its centre's path
        traced in the camshaft's frame; the lever swings (oscillating)."""
        gear = lift.gear
        geometry = gear.contact_geometry(theta)
        px, py = gear.pitch(theta)  # the roller centre in the cam frame, jets in theta
        speed = np.hypot(px.c[1], py.c[1])
        pitch_radius = np.asarray(geometry.contour_radius, dtype=float) + gear.roller_radius
        motion = rolling_roller_motion(speed, pitch_radius, gear.roller_radius)
        return GearContact(geometry, motion, oscillating=True, pitch_radius=pitch_radius)

GEAR = PivotedRoller()
