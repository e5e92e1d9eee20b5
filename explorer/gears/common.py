"""What several gears share: the [gear] sub-tables of levers, valve drives and eccentrics (their key
parsers), the valve drive and eccentric built from them, and the contact geometry of a lever gear.

Point keys are [x, y] pairs relative to the cam (or eccentric) shaft centre, angles
counter-clockwise from +x (see each gear's module for its sub-tables):

[gear.lever]      pivot, arm, roller_side
[gear.valve]      type = "rocker" (valve pin on the lever: arm, angle from the roller arm) or
                  "rod-and-lever" (Schenker's Fig. 3: rod from the roller axle to pin d of the valve
                  lever d-e-f: rod, lever_pivot, arm_in, arm_out, bend, pin_side); axis = direction in
                  which the valve opens (default: the way the pin moves when the roller lifts).
[gear.eccentric]  radius, phase, rod, lever_pivot, lever_arm, pin_side
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..core.ranges import check_range
from ..core.reader import Table
from ..core.units import to_si
from .jet import Jet
from .linkage import EccentricDrive, RockerDrive, RodLeverDrive, side_sign

SIDES = ("left", "right")
SENSES = ("ccw", "cw")


def point_key(t: Table, name: str, default=...) -> tuple[float, float]:
    raw = t.raw(name, default)
    if raw is default and default is not ...:
        return default
    if not isinstance(raw, list) or len(raw) != 2:
        raise t.error(name, 'expected a point [x, y], such as ["-120 mm", "70 mm"]')
    return tuple(
        check_range(to_si(v, "length", file=t.file, key=f"{t.key(name)}[{i}]"), "length", file=t.file,
                    key=f"{t.key(name)}[{i}]", shown=v)
        for i, v in enumerate(raw)
    )


# A pivot closer than this to the shaft centre makes the lever's geometry degenerate (no
# triangle to close): refused at load with the key, not found as a division by zero later.
MIN_PIVOT_DISTANCE = 1e-4  # m


def pivot_key(t: Table, name: str) -> tuple[float, float]:
    point = point_key(t, name)
    if math.hypot(*point) < MIN_PIVOT_DISTANCE:
        raise t.error(name, f"must be at least {MIN_PIVOT_DISTANCE * 1e3:g} mm from the shaft centre, got {t.raw(name)!r}")
    return point


def lever_keys(t: Table) -> dict:
    t.reject_unknown(("pivot", "arm", "roller_side"))
    return {
        "pivot": pivot_key(t, "pivot"),
        "arm": t.quantity("arm", "length", positive=True),
        "roller_side": t.string("roller_side", "left", choices=SIDES),
    }


def valve_keys(t: Table, rolling: bool = False) -> dict:
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
        out["lever_pivot"] = point_key(t, "lever_pivot")
        out["arm_in"] = t.quantity("arm_in", "length", positive=True)
        out["arm_out"] = t.quantity("arm_out", "length", positive=True)
        out["bend"] = t.quantity("bend", "angle", math.pi)
        out["pin_side"] = t.string("pin_side", "left", choices=SIDES)
    out["axis"] = t.quantity("axis", "angle") if t.has("axis") else None
    return out


def eccentric_keys(t: Table) -> dict:
    t.reject_unknown(("radius", "phase", "rod", "lever_pivot", "lever_arm", "pin_side"))
    return {
        "radius": t.quantity("radius", "length", positive=True),
        "phase": t.quantity("phase", "angle", 0.0),
        "rod": t.quantity("rod", "length", positive=True),
        "lever_pivot": pivot_key(t, "lever_pivot"),
        "lever_arm": t.quantity("lever_arm", "length", positive=True),
        "pin_side": t.string("pin_side", "left", choices=SIDES),
    }


def section(source, name):
    """Section `name` of a Scene, or of the partial scene fields while the scene is being read."""
    return source.get(name) if isinstance(source, dict) else getattr(source, name)


def make_valve_drive(part, *, pivot, lever_arm, rest, lifting, file):
    """Valve drive on a lever (pivot, rest angle); `lifting` = +1/-1 is the direction of the
    lever angle that opens the valve. Default axis: the valve pin's direction of motion then."""
    if part["type"] == "rocker":
        probe = RockerDrive(pivot=pivot, arm=part["arm"], angle=part["angle"], axis=0.0, rest=rest, file=file)
        pin_dir = rest + part["angle"] + math.pi / 2.0  # d f / d psi direction
        dx, dy = lifting * math.cos(pin_dir), lifting * math.sin(pin_dir)
    else:
        probe = RodLeverDrive(lever_pivot=pivot, lever_arm=lever_arm, rod=part["rod"], valve_pivot=part["lever_pivot"],
                              arm_in=part["arm_in"], arm_out=part["arm_out"], bend=part["bend"], axis=0.0,
                              branch=side_sign(part["pin_side"]), rest=rest, file=file)
        beta = probe.valve_lever_angle(Jet.variable(np.array([rest])))
        ang = beta.c[0][0] + part["bend"] + math.pi / 2.0
        rate = beta.c[1][0] * lifting
        dx, dy = rate * math.cos(ang), rate * math.sin(ang)
    axis = part["axis"] if part["axis"] is not None else math.atan2(dy, dx)
    speed = math.hypot(dx, dy)
    along = (dx * math.cos(axis) + dy * math.sin(axis)) / max(speed, 1e-300)
    if part["axis"] is not None and along <= 0.0:
        raise InputError(file, "gear.valve.axis", "the valve would close as the lever lifts; reverse the axis (add 180 deg)")
    if along < 1e-3:
        raise InputError(file, "gear.valve.angle" if part["type"] == "rocker" else "gear.valve.bend",
                         "the valve pin moves across the valve axis at rest (dead point)")
    if part["type"] == "rocker":
        return RockerDrive(pivot=pivot, arm=part["arm"], angle=part["angle"], axis=axis, rest=rest, file=file)
    return RodLeverDrive(lever_pivot=pivot, lever_arm=lever_arm, rod=part["rod"], valve_pivot=part["lever_pivot"],
                         arm_in=part["arm_in"], arm_out=part["arm_out"], bend=part["bend"], axis=axis,
                         branch=side_sign(part["pin_side"]), rest=rest, file=file)


def make_eccentric(part, file) -> EccentricDrive:
    drive = EccentricDrive(radius=part["radius"], phase=part["phase"], rod=part["rod"], pivot=part["lever_pivot"],
                           arm=part["lever_arm"], branch=side_sign(part["pin_side"]), file=file, key="gear.eccentric")
    drive.check()
    return drive



def spec_of(gear, scene):
    """The scene's [gear] spec, or InputError when it has none (a lift built for a scene that was
    changed after loading)."""
    spec = scene.gear
    if spec is None:
        raise InputError(scene.source, "gear", f"missing section: follower.type '{gear.type}' needs [gear]")
    return spec


class LeverContact:
    """Mixin of the gears whose lift curve carries its geometry (`.gear`) with contact statics
    (`contact_geometry(theta)`: explorer.mechanics.contact.ContactModel)."""

    def contact_geometry(self, ctx):
        lift = ctx.lift if hasattr(ctx.lift, "gear") else self.build_lift(ctx.scene)
        return lift.gear.contact_geometry(ctx.theta)
