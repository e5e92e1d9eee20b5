"""The validity checks every cam passes, whether the user entered it or the program computed it.

A cam is entered as a closed-form law, a contour, stations or a rocking cam's flank; it is
computed by a polydyne design, a spline solve, a table's smoothing, an acceleration law's
integration, `explorer fit` / [gear.target] use = "fitted" and `explorer design`. Whatever made
it, the same function decides whether it is a cam at all (docs/reference/validity.md):

1. finite: the lift and its first three derivatives per radian are finite numbers;
2. lift range: the lift stays on or above the base circle (at most `dip` below it: a measured
   table's gauge noise, an integrated law's closure residual; otherwise 1 nm, the smallest length
   the program takes, for rounding) and at most MAX_LIFT (1 m: no valve gear lifts more; beyond it
   a unit or a design is wrong);
3. pressure angle: below 90 deg, so that the contact normal has a component along the
   follower's path (at 90 deg the cam cannot push it at all; self-locking with friction, below 90
   deg, is the contact effect's warning, the same for every cam);
4. curvature: no undercut -- no convex stretch of the pitch curve is as sharp as the roller
   (radius <= roller radius: the envelope folds into a cusp and the cam cannot be made).

`cam_fault` runs them in that order on samples and returns the first fault (CamFault) or None.
An entered cam is refused with the fault's own advice (`entered_error`); a computed cam's maker
says what made it impossible and what to change (`computed_error`), e.g. a polydyne's linkage
stiffness for its design speed. Both are one InputError line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ..core.errors import InputError
from ..core.ranges import RANGES
from .contours.translating import find_undercut, pitch_geometry
from .curves import grid_with

TWO_PI = 2.0 * math.pi
MAX_LIFT = 1.0  # m: no valve gear lifts more; a bigger lift means a wrong unit or an impossible design
ROUNDING_DIP = RANGES["length"][0]  # 1 nm: below the base circle by less is rounding, not a dip
MAX_PRESSURE_ANGLE = 0.5 * math.pi  # rad, exclusive
SAMPLES = 7200  # cam angles per revolution for a lift curve (plus its breakpoints)
# angles inside each stretch between two breakpoints besides the revolution's grid: a short event
# (a 0.1 deg rise falls between two of the 7200) is checked as finely as a long one, so the verdict
# depends on the law alone, never on a run's sample grid (docs/reference/validity.md)
SEGMENT_SAMPLES = 256
CHECKS = ("finite", "lift range", "pressure angle", "undercut")


@dataclass(frozen=True)
class CamFault:
    """The first check a cam fails: which (one of CHECKS), where, what is wrong (text, with
    numbers), and for a cam entered as it is what to change and which key to name; the maker of a
    computed cam replaces those two with what made the cam and what to change there."""

    check: str
    angle: float  # rad, where (a cam angle; the flank angle for a rocking cam's curvature)
    text: str
    advice: str  # what to change when the cam was entered as it is
    key: str  # the scene key to name when the cam was entered as it is


def cam_fault(angle, lift_jet, *, pressure_angle=None, pitch_radius=None, roller_radius: float = 0.0,
              dip: float = 0.0, curvature_angle=None, where: str = "cam angle {}",
              curvature_where: str | None = None) -> CamFault | None:
    """The first failed check (module doc) of a cam sampled at `angle` (rad): lift_jet (k, N) holds
    the lift (row 0, m) and any derivatives per radian; pressure_angle (rad) at the same samples;
    pitch_radius (m, signed: > 0 convex) at `curvature_angle` (default: the same samples); dip (m)
    how far below the base circle the lift may go besides rounding; where: how a sample's place is
    named, "{}" standing for its angle in degrees (curvature_where: at curvature_angle)."""
    angle = np.asarray(angle, dtype=float).reshape(-1)
    jet = np.asarray(lift_jet, dtype=float).reshape(-1, angle.size)
    bad = ~np.all(np.isfinite(jet), axis=0)
    if pressure_angle is not None:
        bad |= ~np.isfinite(np.asarray(pressure_angle, dtype=float).reshape(-1))
    if np.any(bad):
        i = int(np.argmax(bad))
        return CamFault("finite", float(angle[i]), f"the lift or its slope, curvature or jerk is not a finite number "
                        f"at {_at(where, angle[i])}", "check the units and the values that shape the lift", "lift")
    lift = jet[0]
    floor = -(ROUNDING_DIP + max(float(dip), 0.0))
    if np.any(lift < floor):
        i = int(np.argmin(lift))
        return CamFault("lift range", float(angle[i]), f"the lift dips below the base circle by {_mm(-lift[i])} at "
                        f"{_at(where, angle[i])} (at most {_mm(-floor)})",
                        "the base circle is the cam's smallest radius: the lift is measured from it", "lift")
    if np.any(lift > MAX_LIFT):
        i = int(np.argmax(lift))
        return CamFault("lift range", float(angle[i]), f"the lift reaches {lift[i]:.4g} m at {_at(where, angle[i])}, "
                        f"more than {MAX_LIFT:g} m (no valve gear lifts more)", "check the units", "lift")
    if pressure_angle is not None:
        phi = np.abs(np.asarray(pressure_angle, dtype=float).reshape(-1))
        if np.any(phi >= MAX_PRESSURE_ANGLE):
            i = int(np.argmax(phi))
            return CamFault("pressure angle", float(angle[i]), f"the pressure angle reaches {math.degrees(phi[i]):.4g} deg "
                            f"at {_at(where, angle[i])} (at {math.degrees(MAX_PRESSURE_ANGLE):g} deg the cam cannot "
                            "push the follower)", "lower the lift or lengthen the event", "lift")
    if pitch_radius is not None:
        rho = np.asarray(pitch_radius, dtype=float).reshape(-1)
        at = angle if curvature_angle is None else np.asarray(curvature_angle, dtype=float).reshape(-1)
        i = find_undercut(rho, roller_radius)
        if i is not None:
            return CamFault("undercut", float(at[i]), f"undercut: roller radius {roller_radius * 1e3:.4g} mm exceeds the "
                            f"convex pitch-curve radius {rho[i] * 1e3:.4g} mm at {_at(curvature_where or where, at[i])}",
                            "(reduce the roller, enlarge the base circle or lengthen the event)",
                            "follower.roller_radius")
    return None


def translating_fault(theta, d, follower, dip: float = 0.0) -> CamFault | None:
    """cam_fault of a translating-roller cam from its lift derivatives d (4, N) at cam angles theta:
    pressure angle and pitch-curve radius in closed form (explorer.lift.contours.translating)."""
    phi, rho = pitch_geometry(d, follower.base_radius, follower.roller_radius, follower.offset)
    return cam_fault(theta, d, pressure_angle=phi, pitch_radius=rho, roller_radius=follower.roller_radius, dip=dip)


def sample_angles(lift, n: int = SAMPLES, per_segment: int = SEGMENT_SAMPLES) -> np.ndarray:
    """n cam angles over the revolution plus the lift's breakpoints (where a derivative may jump)
    plus per_segment equally spaced angles inside each stretch between consecutive breakpoints
    (however short: a 0.1 deg rise gets as many as a 100 deg one)."""
    grid = np.arange(int(n)) * (TWO_PI / int(n))
    marks = np.unique(np.mod(np.asarray(lift.breakpoints(), dtype=float).reshape(-1), TWO_PI))
    parts = [marks]
    if marks.size and per_segment > 0:
        ends = np.append(marks, marks[0] + TWO_PI)
        t = np.arange(1, int(per_segment) + 1) / (int(per_segment) + 1.0)
        parts.append(np.mod((ends[:-1, None] + np.diff(ends)[:, None] * t).reshape(-1), TWO_PI))
    # np.unique(np.concatenate([grid, *parts])), the same floats: the few points merged into the
    # sorted grid rather than all sorted again (grid_with; a third of geometry_extremes' time was sorts)
    return grid_with(grid, np.concatenate(parts))


def lift_fault(lift, follower, dip: float | None = None, n: int = SAMPLES) -> CamFault | None:
    """cam_fault of a lift curve (explorer.lift.curves.LiftCurve) over one revolution: the whole
    check for a cam that is the envelope of the follower's roller on a straight path
    (follower.roller_envelope, which its gear declares: the translating roller); the finite and
    lift-range checks for a gear's follower lift (the gear checks its own geometry through
    cam_fault). dip: default the lift's own
    `dip_allowance` (a measured table's noise), else 0."""
    if dip is None:
        dip = float(getattr(lift, "dip_allowance", 0.0))
    theta = sample_angles(lift, n)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        d = lift.derivatives(theta)
        if follower is not None and follower.roller_envelope:
            return translating_fault(theta, d, follower, dip)
        return cam_fault(theta, d, dip=dip)


def entered_error(fault: CamFault, file: str, key: str | None = None) -> InputError:
    """The one line for a cam entered as it is: the fault and its own advice."""
    return InputError(file, key or fault.key, f"{fault.text} {fault.advice}" if fault.advice.startswith("(")
                      else f"{fault.text}; {fault.advice}")


def computed_error(fault: CamFault, file: str, key: str, what: str, remedy: str | Mapping[str, str]) -> InputError:
    """The one line for a computed cam: `what` made it (and so made it impossible), the fault, and
    `remedy`, what to change (or per check: {check: remedy}, "" for the others)."""
    if not isinstance(remedy, str):
        remedy = remedy.get(fault.check) or remedy.get("", "") or fault.advice.strip("()")
    return InputError(file, key, f"{what} is not a valid cam: {fault.text}; {remedy}")


def check_computed(lift, follower, file: str, key: str, what: str, remedy: str | Mapping[str, str],
                   dip: float | None = None, n: int = SAMPLES) -> None:
    """InputError (computed_error) when the lift curve a program step made fails lift_fault."""
    fault = lift_fault(lift, follower, dip, n)
    if fault is not None:
        raise computed_error(fault, file, key, what, remedy)


def _at(where: str, angle: float) -> str:
    return where.format(_deg(angle))


def _deg(angle: float) -> str:
    return f"{math.degrees(float(angle)) % 360.0:.3f} deg"


def _mm(length: float) -> str:
    return f"{float(length) * 1e3:.4g} mm"
