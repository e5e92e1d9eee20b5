"""Scene section [gear]: the geometry of the seeds' other valve gears, validated at load time.

follower.type selects the gear; [gear] holds its parts as sub-tables (lengths with units, points
as [x, y] pairs relative to the cam/eccentric shaft centre, angles counter-clockwise from +x):

pivoted-roller   roller lever on a rotating cam; [lift] is the valve-referred lift law (lash
                 included); follower.base_radius and roller_radius size the cam and roller.
                 [gear.lever] pivot, arm, roller_side      [gear.valve] (see below)
rocking-cam      eccentric-driven rocking cam on a roller lever; [lift] law = "gear".
                 [gear.eccentric] radius, phase, rod, lever_pivot, lever_arm, pin_side
                 [gear.rocking_cam] dwell_radius, rise, lift_start, flank, law, opens
                 [gear.lever] (pivot, arm, roller_side seen from the pivot towards the cam pivot)
                 [gear.valve]; follower.roller_radius
                 [gear.target] (optional) lift, open_angle, max_pressure_angle, use = "given" |
                     "fitted": the flank (lift_start, rise) that gives the wanted valve lift and
                     open angle; reported by the 'gear' effect and `explorer fit`, simulated
                     only with use = "fitted"
rolling-lever    eccentric rolling lever ("Waelzhebel"); [lift] law = "gear".
                 [gear.eccentric] (the rolling lever is the eccentric's lever)
                 [gear.rolling_lever] valve_lever_pivot, contact_radius, growth, contact_swing,
                     opens, lever_stiffness, rod_stiffness (optional; with either, the elastic
                     effect's stiffness is theirs referred to the valve, k(t), in series with
                     [linkage] stiffness, and needs a solver.method that takes k(t):
                     explorer/dynamics/solvers.py, varying_stiffness)
                 [gear.valve] type = "rocker" on the valve lever (angle from the direction
                     valve-lever pivot -> rolling-lever pivot)
trip             latch lifts the valve, releases it at the trip angle; [lift] is the latch's
                 valve-referred lift law, valve.lash its over-travel before it catches the valve.
                 [gear.trip] angle, buffer ("none" | "air" | "oil"), valve_weight, closing_time,
                     latch_friction (mu of the latch face on the catch, 0...1, default 0.15), latch_width and
                     latch_depth (the latch face's bearing area; depth = its engagement, the
                     distance the trip pulls it out); forces, contact and elastic analyse the
                     latched phase (explorer.effects.trip)
                 [gear.air_dashpot] diameter, stroke, clearance, orifice_diameter,
                     discharge_coefficient, polytropic_exponent, ambient_pressure, ambient_temperature,
                     inlet ("check-valve", default: the pocket refills through a non-return valve
                     and never pulls on the valve | "orifice": air returns through the orifice, an
                     expanding pocket sucks; explorer.gears.dashpot)
                 [gear.oil_dashpot] diameter, stroke, orifice_diameter, discharge_coefficient,
                     oil_density (kg/m^3, plain number)

[gear.valve]  type = "rocker" (valve pin on the lever: arm, angle from the roller arm) or
              "rod-and-lever" (Schenker's Fig. 3: rod from the roller axle to pin d of the valve
              lever d-e-f: rod, lever_pivot, arm_in, arm_out, bend, pin_side); axis = direction
              in which the valve opens (default: the way the pin moves when the roller lifts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Mapping

from ..core.errors import InputError, echo
from ..lift.laws import LAWS
from ..core.ranges import AMBIENT_TEMPERATURE, OIL_DENSITY
from ..core.reader import Table
from . import GEAR_TYPES

SIDES = ("left", "right")
SENSES = ("ccw", "cw")
BUFFERS = ("none", "air", "oil")


@dataclass(frozen=True)
class GearSpec:
    type: str
    parts: Mapping[str, Mapping[str, Any]]  # sub-table -> {key: SI value}
    file: str = "<memory>"

    def part(self, name: str) -> Mapping[str, Any]:
        return self.parts.get(name, MappingProxyType({}))


def _point(t: Table, name: str, default=...) -> tuple[float, float]:
    raw = t.raw(name, default)
    if raw is default and default is not ...:
        return default
    if not isinstance(raw, list) or len(raw) != 2:
        raise t.error(name, 'expected a point [x, y], such as ["-120 mm", "70 mm"]')
    from ..core.ranges import check_range
    from ..core.units import to_si

    return tuple(
        check_range(to_si(v, "length", file=t.file, key=f"{t.key(name)}[{i}]"), "length", file=t.file,
                    key=f"{t.key(name)}[{i}]", shown=v)
        for i, v in enumerate(raw)
    )


def _required_table(t: Table, name: str, gear_type: str) -> Table:
    sub = t.table(name, required=False)
    if sub is None:
        raise InputError(t.file, t.key(name), f"missing section: follower.type '{gear_type}' needs [{t.key(name)}]")
    return sub


# A pivot closer than this to the shaft centre makes the lever's geometry degenerate (no
# triangle to close): refused at load with the key, not found as a division by zero later.
MIN_PIVOT_DISTANCE = 1e-4  # m


def _pivot(t: Table, name: str) -> tuple[float, float]:
    point = _point(t, name)
    if math.hypot(*point) < MIN_PIVOT_DISTANCE:
        raise t.error(name, f"must be at least {MIN_PIVOT_DISTANCE * 1e3:g} mm from the shaft centre, got {t.raw(name)!r}")
    return point


def _lever(t: Table) -> dict:
    t.reject_unknown(("pivot", "arm", "roller_side"))
    return {
        "pivot": _pivot(t, "pivot"),
        "arm": t.quantity("arm", "length", positive=True),
        "roller_side": t.string("roller_side", "left", choices=SIDES),
    }


def _valve(t: Table, rolling: bool = False) -> dict:
    kind = t.string("type", "rocker", choices=("rocker",) if rolling else ("rocker", "rod-and-lever"))
    common = ("type", "axis")
    out: dict[str, Any] = {"type": kind}
    if kind == "rocker":
        t.reject_unknown(common + ("arm", "angle"))
        out["arm"] = t.quantity("arm", "length", positive=True)
        out["angle"] = t.quantity("angle", "angle", math.pi)
    else:
        t.reject_unknown(common + ("rod", "lever_pivot", "arm_in", "arm_out", "bend", "pin_side"))
        out["rod"] = t.quantity("rod", "length", positive=True)
        out["lever_pivot"] = _point(t, "lever_pivot")
        out["arm_in"] = t.quantity("arm_in", "length", positive=True)
        out["arm_out"] = t.quantity("arm_out", "length", positive=True)
        out["bend"] = t.quantity("bend", "angle", math.pi)
        out["pin_side"] = t.string("pin_side", "left", choices=SIDES)
    out["axis"] = t.quantity("axis", "angle") if t.has("axis") else None
    return out


def _eccentric(t: Table) -> dict:
    t.reject_unknown(("radius", "phase", "rod", "lever_pivot", "lever_arm", "pin_side"))
    return {
        "radius": t.quantity("radius", "length", positive=True),
        "phase": t.quantity("phase", "angle", 0.0),
        "rod": t.quantity("rod", "length", positive=True),
        "lever_pivot": _pivot(t, "lever_pivot"),
        "lever_arm": t.quantity("lever_arm", "length", positive=True),
        "pin_side": t.string("pin_side", "left", choices=SIDES),
    }


def _rocking_cam(t: Table) -> dict:
    t.reject_unknown(("dwell_radius", "rise", "lift_start", "flank", "law", "opens"))
    out = {
        "dwell_radius": t.quantity("dwell_radius", "length", positive=True),
        "rise": t.quantity("rise", "length", positive=True),
        "lift_start": t.quantity("lift_start", "angle", nonnegative=True),
        "flank": t.quantity("flank", "angle", positive=True),
        "law": t.string("law", "cycloidal", choices=tuple(LAWS)),
        "opens": t.string("opens", "ccw", choices=SENSES),
    }
    from .rocking import check_one_turn

    check_one_turn(out["lift_start"], out["flank"], t.file)
    return out


TARGET_USES = ("given", "fitted")


def _target(t: Table) -> dict:
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


def _rolling_lever(t: Table) -> dict:
    t.reject_unknown(("valve_lever_pivot", "contact_radius", "growth", "contact_swing", "opens",
                      "lever_stiffness", "rod_stiffness"))
    return {
        "valve_lever_pivot": _point(t, "valve_lever_pivot"),
        "contact_radius": t.quantity("contact_radius", "length", positive=True),
        "growth": t.quantity("growth", "length", 0.0),  # m per rad of rolling swing
        "contact_swing": t.quantity("contact_swing", "angle", nonnegative=True),
        "opens": t.string("opens", "ccw", choices=SENSES),
        "lever_stiffness": t.quantity("lever_stiffness", "torque", positive=True) if t.has("lever_stiffness") else None,
        "rod_stiffness": t.quantity("rod_stiffness", "stiffness", positive=True) if t.has("rod_stiffness") else None,
    }


# Latch face on the spindle's catch: hardened steel on hardened steel, oiled (boundary
# lubrication, mu about 0.1 to 0.2); the release starts from rest, so the upper half of that range.
LATCH_FRICTION = 0.15


def _trip(t: Table) -> dict:
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


def _air(t: Table) -> dict:
    from .dashpot import INLETS

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


def _oil(t: Table) -> dict:
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


PARTS = {
    "pivoted-roller": {"lever": _lever, "valve": _valve},
    "rocking-cam": {"eccentric": _eccentric, "rocking_cam": _rocking_cam, "lever": _lever, "valve": _valve,
                    "target": _target},
    "rolling-lever": {"eccentric": _eccentric, "rolling_lever": _rolling_lever,
                      "valve": lambda t: _valve(t, rolling=True)},
    "trip": {"trip": _trip, "air_dashpot": _air, "oil_dashpot": _oil},
}
OPTIONAL_PARTS = {"air_dashpot", "oil_dashpot", "target"}


def parse_gear_section(table: Table | None, fields: dict) -> GearSpec | None:
    """[gear] -> GearSpec, and the gear itself built once, so that bad geometry (links that cannot
    close, a lever through the cam, an eccentric rod too short) fails at load time."""
    file = fields.get("source", "<memory>")
    follower = fields["follower"]
    if follower.type not in GEAR_TYPES:
        if table is not None:
            raise InputError(file, "gear", f"[gear] describes the gears {', '.join(GEAR_TYPES)}; follower.type is "
                             f"{echo(follower.type)}")
        return None
    if table is None:
        raise InputError(file, "gear", f"missing section: follower.type '{follower.type}' needs [gear]")
    kind = follower.type
    table.reject_unknown(tuple(PARTS[kind]))
    parts: dict[str, Mapping[str, Any]] = {}
    for name, parser in PARTS[kind].items():
        sub = table.table(name, required=False)
        if sub is None:
            if name in OPTIONAL_PARTS:
                continue
            raise InputError(file, f"gear.{name}", f"missing section: follower.type '{kind}' needs [gear.{name}]")
        parts[name] = MappingProxyType(parser(sub))
    spec = GearSpec(type=kind, parts=MappingProxyType(parts), file=file)
    _check_scene(spec, fields)
    from .build import make_gear

    make_gear(spec, fields)  # builds and checks the geometry over the whole cycle
    if "target" in spec.parts and spec.part("target")["use"] == "given":
        from .build import rocking_target

        rocking_target(spec, fields)  # a target out of reach fails here, not later in the 'gear' effect
    return spec


def _check_scene(spec: GearSpec, fields: dict) -> None:
    file, kind = spec.file, spec.type
    follower, lift, effects = fields["follower"], fields["lift"], fields["effects"]
    if follower.ratio != 1.0:
        raise InputError(file, "follower.ratio", f"the {kind} gear's linkage sets the valve ratio; leave follower.ratio = 1")
    if kind in ("rocking-cam", "rolling-lever") and lift.law != "gear":
        raise InputError(file, "lift.law", f"the {kind} gear makes its own lift: set lift.law = \"gear\"")
    if kind in ("pivoted-roller", "trip") and lift.law == "gear":
        raise InputError(file, "lift.law", f"the {kind} gear needs a lift law (the valve-referred "
                         f"{'lift' if kind == 'pivoted-roller' else 'latch motion'})")
    if kind == "pivoted-roller" and lift.law == "contour":
        raise InputError(file, "lift.law", "a pivoted roller lever synthesises its cam from a lift law, not from [cam]")
    if kind == "pivoted-roller" and lift.law not in LAWS:
        # its cam is synthesised through the closed-form law's jets (gears/pivoted.py)
        raise InputError(file, "lift.law", f"a pivoted roller lever synthesises its cam from one of the laws "
                         f"{', '.join(LAWS)}, not from law \"{lift.law}\"")
    if kind in ("pivoted-roller", "rocking-cam") and follower.roller_radius <= 0.0:
        raise InputError(file, "follower.roller_radius", f"the {kind} gear needs a roller (roller_radius > 0)")
    if kind == "rolling-lever" and "elastic" in effects:
        rl = spec.part("rolling_lever")
        from ..dynamics.solvers import varying_stiffness

        varying = varying_stiffness()
        if (rl["lever_stiffness"] is not None or rl["rod_stiffness"] is not None) \
                and fields["solver"].method not in varying:
            raise InputError(file, "solver.method", f"method \"{fields['solver'].method}\" needs a constant linkage "
                             "stiffness, but the rolling lever's (lever_stiffness, rod_stiffness) changes with its ratio "
                             "along the lift: use method = " + " or ".join(f'"{m}"' for m in varying))
    if kind == "trip":
        if lift.law not in LAWS:
            raise InputError(file, "lift.law", f"the trip gear's latch follows one of the laws: {', '.join(LAWS)}")
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
