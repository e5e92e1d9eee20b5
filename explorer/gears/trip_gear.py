"""The trip gear (seed 003, Corliss-type): a latch lifts the valve and releases it at the trip
angle; the valve then closes by itself under its spring, loads and friction, cushioned by an air
or oil dashpot (explorer.gears.trip: the closing; explorer.gears.dashpot: the buffers;
explorer.gears.trip_latched: the latched phase in the effects forces, contact and elastic).

[gear.trip] angle, buffer ("none" | "air" | "oil"), valve_weight, closing_time, latch_friction (mu
    of the latch face on the catch, 0...1, default 0.15), latch_width and latch_depth (the latch
    face's bearing area; depth = its engagement, the distance the trip pulls it out)
[gear.air_dashpot] diameter, stroke, clearance, orifice_diameter, discharge_coefficient,
    polytropic_exponent, ambient_pressure, ambient_temperature, inlet ("check-valve", default: the
    pocket refills through a non-return valve and never pulls on the valve | "orifice": air returns
    through the orifice, an expanding pocket sucks)
[gear.oil_dashpot] diameter, stroke, orifice_diameter, discharge_coefficient, oil_density (kg/m^3)
[lift] is the latch's valve-referred lift law (a closed form), valve.lash its over-travel before it
catches the valve; [valve] and [spring] are needed (the closing). No [contact] section: the latch
has no cam and roller.

The 'gear' effect reports the latch lift, the buffer's force and pressure, the closing (apex,
cushion, seat), the latch's pick-up impact, Trinks' closing-force rule and the same valve closed
by each buffer.
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from ..core.errors import InputError
from ..core.ranges import AMBIENT_TEMPERATURE, OIL_DENSITY
from ..core.reader import Table
from ..lift.curves import law_lift
from ..lift.registry import closed_form_names, law_spec
from ..mechanics.forces import TrainLoads
from ..mechanics.kinematics import lash_crossings
from ..mechanics.springs import TRINKS_G, trinks_closing_force
from ..result import EffectOutput, Event
from .base import Gear
from .common import section, spec_of
from .dashpot import INLETS, AirDashpot, OilDashpot, cylinder_area
from .trip import ClosingModel, build_trip_lift, compare_buffers, peak_buffer_force
from .trip_latched import (carried_pieces, latch_force, latch_force_extremes, trip_contact_effect, trip_elastic_effect,
                           trip_forces_effect)

TWO_PI = 2.0 * math.pi
BUFFERS = ("none", "air", "oil")


# Latch face on the spindle's catch: hardened steel on hardened steel, oiled (boundary
# lubrication, mu about 0.1 to 0.2); the release starts from rest, so the upper half of that range.
LATCH_FRICTION = 0.15


def trip_keys(t: Table) -> dict:
    t.reject_unknown(("angle", "buffer", "valve_weight", "closing_time", "latch_friction", "latch_width",
                      "latch_depth"))
    angle = t.quantity("angle", "angle")
    if not 0.0 <= angle < 2.0 * math.pi:
        raise t.error("angle", "must lie in [0 deg, 360 deg)")
    if t.has("latch_width") != t.has("latch_depth"):
        missing = "latch_depth" if t.has("latch_width") else "latch_width"
        raise t.error(missing, "the latch's bearing area needs both latch_width and latch_depth")
    return {
        "angle": angle,
        "buffer": t.string("buffer", "none", choices=BUFFERS),
        "valve_weight": t.quantity("valve_weight", "force", positive=True) if t.has("valve_weight") else None,
        "closing_time": t.quantity("closing_time", "time", positive=True) if t.has("closing_time") else None,
        "latch_friction": t.number("latch_friction", LATCH_FRICTION, minimum=0.0, maximum=1.0),
        "latch_width": t.quantity("latch_width", "length", positive=True) if t.has("latch_width") else None,
        "latch_depth": t.quantity("latch_depth", "length", positive=True) if t.has("latch_depth") else None,
    }


def air_dashpot_keys(t: Table) -> dict:
    t.reject_unknown(("diameter", "stroke", "clearance", "orifice_diameter", "discharge_coefficient",
                      "polytropic_exponent", "ambient_pressure", "ambient_temperature", "inlet"))
    out = {
        "diameter": t.quantity("diameter", "length", positive=True),
        "stroke": t.quantity("stroke", "length", positive=True),
        "clearance": t.quantity("clearance", "length", positive=True),
        "orifice_diameter": t.quantity("orifice_diameter", "length", 0.0, nonnegative=True),
        "discharge_coefficient": t.number("discharge_coefficient", 0.62, minimum=0.0, maximum=1.0, open_minimum=True),
        "polytropic_exponent": t.number("polytropic_exponent", 1.4, minimum=1.0, maximum=1.67),
        "ambient_pressure": t.quantity("ambient_pressure", "pressure", 101_325.0, positive=True),
        "ambient_temperature": t.number("ambient_temperature", 293.15, minimum=AMBIENT_TEMPERATURE[0],
                                        maximum=AMBIENT_TEMPERATURE[1]),
        "inlet": t.string("inlet", "check-valve", choices=INLETS),
    }
    if out["orifice_diameter"] >= out["diameter"]:  # the flow area would exceed the bore: p - p0 / 0
        raise t.error("orifice_diameter", "the orifice must be smaller than the dashpot piston")
    return out


def oil_dashpot_keys(t: Table) -> dict:
    t.reject_unknown(("diameter", "stroke", "orifice_diameter", "discharge_coefficient", "oil_density"))
    out = {
        "diameter": t.quantity("diameter", "length", positive=True),
        "stroke": t.quantity("stroke", "length", positive=True),
        "orifice_diameter": t.quantity("orifice_diameter", "length", positive=True),
        "discharge_coefficient": t.number("discharge_coefficient", 0.62, minimum=0.0, maximum=1.0, open_minimum=True),
        "oil_density": t.number("oil_density", 880.0, minimum=OIL_DENSITY[0], maximum=OIL_DENSITY[1]),
    }
    if out["orifice_diameter"] >= out["diameter"]:
        raise t.error("orifice_diameter", "the orifice must be smaller than the dashpot piston")
    return out


def make_buffer(spec, which: str):
    if which == "none":
        return None
    part = spec.part(f"{which}_dashpot")
    if which == "air":
        return AirDashpot(area=cylinder_area(part["diameter"]), stroke=part["stroke"], clearance=part["clearance"],
                          orifice_area=cylinder_area(part["orifice_diameter"]), discharge=part["discharge_coefficient"],
                          exponent=part["polytropic_exponent"], ambient_pressure=part["ambient_pressure"],
                          ambient_temperature=part["ambient_temperature"], inlet=part["inlet"])
    return OilDashpot(area=cylinder_area(part["diameter"]), stroke=part["stroke"],
                      orifice_area=cylinder_area(part["orifice_diameter"]), discharge=part["discharge_coefficient"],
                      density=part["oil_density"])


def closing_model(spec, source, buffer=None):
    valve, spring, loads = section(source, "valve"), section(source, "spring"), section(source, "loads")
    return ClosingModel(mass=valve.mass, preload=spring.preload, rate=spring.rate, closing=loads.closing_total,
                        friction=loads.friction, buffer=buffer)


def make_trip_lift(spec, source):
    trip = spec.part("trip")
    valve = section(source, "valve")
    omega = section(source, "drive").omega
    model = closing_model(spec, source, make_buffer(spec, trip["buffer"]))
    return build_trip_lift(law_lift(section(source, "lift")), valve.lash, trip["angle"], omega, model, spec.file)


class TripGear(Gear):
    type = "trip"
    description = "latch lifts the valve and releases it at the trip angle; dashpot-cushioned closing (seed 003)"
    parts = MappingProxyType({"trip": trip_keys, "air_dashpot": air_dashpot_keys, "oil_dashpot": oil_dashpot_keys})
    optional_parts = frozenset({"air_dashpot", "oil_dashpot"})
    rejected = MappingProxyType({
        "contact": "the trip gear has no cam and roller: its latch keys are latch_friction, latch_width and "
                   "latch_depth in [gear.trip]",
    })
    linkage_ratio = True
    effects = MappingProxyType({
        "forces": trip_forces_effect,  # the latch drives only from the pick-up to the trip
        "contact": trip_contact_effect,  # a latch on the spindle, no cam surface
        "elastic": trip_elastic_effect,  # latch drives until the trip, then the valve closes freely
    })
    columns = MappingProxyType({
        "forces": ("latch_buffer_force_N", "camshaft_torque_Nm"),
        "contact": ("latch_release_friction_N", "latch_bearing_pressure_Pa"),
        "gear": ("latch_lift_m", "buffer_force_N", "buffer_gauge_pressure_Pa", "latch_force_N"),
    })

    def law_refusal(self, law) -> str:
        return f"the trip gear's latch follows one of the laws: {', '.join(closed_form_names())}"

    def check(self, spec, fields) -> None:
        super().check(spec, fields)  # the ratio; a law that is no closed form
        file, lift = spec.file, fields["lift"]
        if law_spec(lift.law).gear_made:
            raise InputError(file, "lift.law", f"the {self.type} gear needs a lift law (the valve-referred latch motion)")
        if fields.get("valve") is None or fields.get("spring") is None:
            raise InputError(file, "valve" if fields.get("valve") is None else "spring",
                             "missing section: the trip gear's closing needs [valve] mass and [spring]")
        if fields["valve"].lash <= 0.0:
            raise InputError(file, "valve.lash", "the trip gear needs the latch's over-travel as valve.lash (> 0)")
        buffer = spec.part("trip")["buffer"]
        if buffer != "none" and f"{buffer}_dashpot" not in spec.parts:
            raise InputError(file, "gear.trip.buffer", f"buffer = \"{buffer}\" needs [gear.{buffer}_dashpot]")
        for name in ("air_dashpot", "oil_dashpot"):
            if name in spec.parts and spec.part(name)["stroke"] >= lift.height - fields["valve"].lash:
                raise InputError(file, f"gear.{name}.stroke", "the cushion stroke must be shorter than the valve lift")

    def make(self, spec, source):
        """The trip lift (latch, buffer, closing); InputError when it cannot be built."""
        return make_trip_lift(spec, source)

    def build_lift(self, scene):
        return self.make(spec_of(self, scene), scene)

    def lift_reads(self, scene) -> None:
        """Its lift is the valve's free closing after the trip: it reads the speed, the masses, the
        spring, the loads and the lash -- any sweep key."""
        return None

    def lifter_ratio(self, scene, lift, theta):
        """No follower the trade's lobe figures are quoted at: the valve's own lift ([lift])."""
        return "valve", np.ones(np.shape(np.asarray(theta, dtype=float)))

    def report(self, ctx) -> EffectOutput:
        """Latch lift and force, buffer, the closing, the pick-up impact, Trinks' rule, the buffers compared."""
        lift = ctx.lift if hasattr(ctx.lift, "closing") else self.build_lift(ctx.scene)
        scene, spec = ctx.scene, ctx.scene.gear
        trip = spec.part("trip")
        omega = ctx.omega
        columns = lift.columns(ctx.theta)
        sol = lift.closing
        # while the latch carries the valve it transmits the rigid-train force (the forces effect's, one function)
        loads = TrainLoads.from_scene(scene)
        latch = latch_force(lift, ctx.theta, loads, omega)
        columns["latch_force_N"] = latch["force"]
        n_grid = max(4096, scene.solver.steps_per_revolution)
        extremes = latch_force_extremes(lift, loads, omega, carried_pieces(lift, n_grid), n_grid)
        s_trip = float(lift.latch.derivatives(np.array([lift.trip_angle]))[0, 0] - lift.overtravel)
        v_trip = float(omega * lift.latch.derivatives(np.array([lift.trip_angle]))[1, 0])
        ups, _ = lash_crossings(lift.latch, 1.0, lift.overtravel)
        v_pick = float(omega * lift.latch.derivatives(ups)[1, 0]) if ups.size else 0.0
        mass = scene.valve.mass
        events = [Event("trip", lift.trip_angle / omega, math.degrees(lift.trip_angle),
                        {"lift_m": s_trip, "velocity_m_s": v_trip})]
        for e in sol.events:
            if e["kind"] == "seat":
                continue
            th = lift.theta_of(lift.phi_trip + omega * e["t"])
            events.append(Event(e["kind"], th / omega, math.degrees(th), {"lift_m": float(e["s"])}))
        if lift.latched is not None:  # the buffer opening, closing or venting while the latch carries the valve
            for e in lift.latched.events:
                th = lift.theta_of(e["phi"])
                events.append(Event(e["kind"], th / omega, math.degrees(th), {"latched": True}))
        buffers = {"none": None}
        densities = {}
        for name in ("air", "oil"):
            if f"{name}_dashpot" in spec.parts:
                buffers[name] = make_buffer(spec, name)
                if name == "air":  # the pocket as the latched phase leaves it at the trip
                    densities[name] = lift.density_at_trip(buffers[name])
        t_max = (TWO_PI - lift.phi_trip) / omega
        table = compare_buffers(closing_model(spec, scene), buffers, s_trip, v_trip, t_max, densities, scene.source)
        summary = {
            "trip_angle_deg": math.degrees(lift.trip_angle),
            "lift_at_trip_m": s_trip,
            "velocity_at_trip_m_s": v_trip,
            "apex_lift_m": sol.apex,
            "closing_time_s": sol.seat_time,
            "seating_velocity_m_s": abs(sol.seat_velocity),
            "seat_cam_angle_deg": math.degrees(lift.theta_of(lift.phi_seat)),
            "buffer": trip["buffer"],
            "max_buffer_force_N": peak_buffer_force(sol),
            # refined on the analytic law (the forces effect's, one function)
            "max_latch_force_N": extremes["max"],
            "min_latch_force_N": extremes["min"],
            "rebounds": sum(1 for e in sol.events if e["kind"] == "rebound"),
            # the latch meets the resting valve with its own velocity after the over-travel (Schenker)
            "latch_overtravel_m": lift.overtravel,
            "latch_pickup_velocity_m_s": v_pick,
            "latch_pickup_impulse_N_s": mass * v_pick,
            "latch_pickup_energy_J": 0.5 * mass * v_pick**2,
            "buffer_comparison": table,
        }
        # Trinks' closing-force rule (seed 003) for the lift at the trip and a wanted closing time
        weight = trip["valve_weight"] if trip["valve_weight"] is not None else mass * TRINKS_G
        t_wanted = trip["closing_time"] if trip["closing_time"] is not None else sol.seat_time
        if s_trip > 0.0:
            summary["trinks"] = {
                "closing_time_s": t_wanted,
                "lift_m": s_trip,
                "valve_weight_N": weight,
                "required_spring_force_N": trinks_closing_force(s_trip, t_wanted, weight, scene.loads.friction),
                "spring_force_at_trip_N": scene.spring.preload + scene.spring.rate * s_trip,
            }
        warnings = []
        if trip["closing_time"] is not None and sol.seat_time > trip["closing_time"]:
            warnings.append(f"the tripped valve takes {sol.seat_time * 1e3:.4g} ms to close, more than the wanted "
                            f"{trip['closing_time'] * 1e3:.4g} ms")
        return EffectOutput(columns=columns, summary=summary, events=tuple(events), warnings=tuple(warnings))


GEAR = TripGear()
