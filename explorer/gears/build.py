"""From a validated [gear] spec to gear objects and their valve-referred lift curves.

`make_gear(spec, source)` works on the partial scene fields while the scene is being read (so
that bad geometry fails at load time) and on a finished Scene (when the pipeline builds the
lift curve, possibly after `with_changes`). `build_gear_lift(scene)` is the lift builder of
the gears' entries in explorer.gears.registry, which lift.build_lift consults.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import InputError
from .jet import Jet
from .linkage import EccentricDrive, RockerDrive, RodLeverDrive, side_sign

TWO_PI = 2.0 * math.pi


def _get(source, name):
    return source.get(name) if isinstance(source, dict) else getattr(source, name)


def law_lift(lift_spec):
    from ..lift.curves import LawLift

    return LawLift(height=lift_spec.height, start=lift_spec.start, rise=lift_spec.rise, dwell=lift_spec.dwell,
                   ret=lift_spec.ret, rise_law=lift_spec.law, return_law=lift_spec.return_law or lift_spec.law)


# --------------------------------------------------------------------------------------------
# valve drives
# --------------------------------------------------------------------------------------------


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


# --------------------------------------------------------------------------------------------
# lift curves that remember their gear
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class PivotedLift:
    gear: Any

    def derivatives(self, theta) -> np.ndarray:
        return self.gear.lift.derivatives(theta)

    def breakpoints(self) -> np.ndarray:
        return np.asarray(self.gear.lift.breakpoints())


@dataclass(frozen=True)
class RockingLift:
    gear: Any
    marks: tuple[float, ...]

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        return self.gear.lift_jet(theta.reshape(-1)).c.reshape((4,) + theta.shape)

    def breakpoints(self) -> np.ndarray:
        return np.array(sorted(self.marks))


# --------------------------------------------------------------------------------------------


def make_gear(spec, source):
    """The gear object (and for the trip gear its lift) for a spec; raises InputError on bad geometry."""
    file = spec.file
    follower = _get(source, "follower")
    kind = spec.type
    if kind == "pivoted-roller":
        from .pivoted import PivotedRollerGear

        lever = spec.part("lever")
        branch = side_sign(lever["roller_side"])
        psi0 = PivotedRollerGear.rest_angle_for(follower.base_radius, follower.roller_radius, lever["pivot"],
                                                lever["arm"], branch, file)
        rx, ry = lever["pivot"][0] + lever["arm"] * math.cos(psi0), lever["pivot"][1] + lever["arm"] * math.sin(psi0)
        lifting = float(np.sign(rx * -math.sin(psi0) + ry * math.cos(psi0)))
        drive = make_valve_drive(spec.part("valve"), pivot=lever["pivot"], lever_arm=lever["arm"], rest=psi0,
                                 lifting=lifting, file=file)
        gear = PivotedRollerGear(lift=law_lift(_get(source, "lift")), base_radius=follower.base_radius,
                                 roller_radius=follower.roller_radius, pivot=lever["pivot"], arm=lever["arm"],
                                 branch=branch, drive=drive, file=file)
        gear.check()
        return gear
    if kind == "rocking-cam":
        if "target" in spec.parts and spec.part("target")["use"] == "fitted":
            return rocking_target(spec, source)[2]
        return make_rocking_gear(spec, source)
    if kind == "rolling-lever":
        from .rolling import RollingLaw, RollingLeverGear

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
    if kind == "trip":
        return make_trip_lift(spec, source)
    raise ValueError(kind)


def make_rocking_gear(spec, source, lift_start=None, rise=None):
    """The rocking-cam gear of a spec, with the contour as written or with its flank start and
    rise replaced (the fitted contour of [gear.target])."""
    from .rocking import RockingContour, build_rocking_gear

    file = spec.file
    follower = _get(source, "follower")
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
    from .rocking import fit_target

    target = spec.part("target")
    valve = _get(source, "valve")
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
    from ..lift.validity import cam_fault, entered_error

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


def make_buffer(spec, which: str):
    from .dashpot import AirDashpot, OilDashpot, cylinder_area

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
    from .trip import ClosingModel

    valve, spring, loads = _get(source, "valve"), _get(source, "spring"), _get(source, "loads")
    return ClosingModel(mass=valve.mass, preload=spring.preload, rate=spring.rate, closing=loads.closing_total,
                        friction=loads.friction, buffer=buffer)


def make_trip_lift(spec, source):
    from .trip import build_trip_lift

    trip = spec.part("trip")
    valve = _get(source, "valve")
    omega = _get(source, "drive").omega
    model = closing_model(spec, source, make_buffer(spec, trip["buffer"]))
    return build_trip_lift(law_lift(_get(source, "lift")), valve.lash, trip["angle"], omega, model, spec.file)


def gear_lift_reads(scene) -> tuple[str, ...] | None:
    """The sweep keys (explorer.studies.sweep_spec.SWEEP_KEYS) whose values build_gear_lift reads
    for this scene (the registry's lift_reads): none for the lever gears, whose geometry alone
    makes the lift; the lash for a rocking cam fitted to [gear.target] (the fit is to the valve's
    lift after the lash: rocking_target); None for the trip gear, whose lift is the valve's free
    closing after the trip (the speed, the masses, the spring, the loads, the lash)."""
    spec = scene.gear
    if spec is None or spec.type == "trip":
        return None
    if spec.type == "rocking-cam" and "target" in spec.parts and spec.part("target")["use"] == "fitted":
        return ("valve.lash",)
    return ()


def build_gear_lift(scene):
    """The valve-referred lift curve of a gear scene (called by lift.build_lift)."""
    spec = scene.gear
    if spec is None:
        raise InputError(scene.source, "gear", f"missing section: follower.type '{scene.follower.type}' needs [gear]")
    gear = make_gear(spec, scene)
    if spec.type == "pivoted-roller":
        return PivotedLift(gear)
    if spec.type == "rocking-cam":
        return RockingLift(gear, tuple(gear.flank_angles()))
    if spec.type == "rolling-lever":
        from .rolling import RollingLeverLift

        marks = gear.contact_angles()
        if marks.size != 2:
            raise InputError(scene.source, "gear.rolling_lever.contact_swing", "the levers must meet once per revolution")
        return RollingLeverLift(gear, tuple(marks))
    return gear  # trip: the lift itself
