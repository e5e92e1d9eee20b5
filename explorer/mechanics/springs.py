"""Valve springs: Schenker's worked example (1902, section 4), the spring advisor, the historic rules.

Schenker's balance at the largest deceleration of each phase (constant loads, p < 0 decelerates
the opening valve):
    lift phase:     F1 + R + sum D = |p1| M      (friction helps the spring to stop the valve)
    closing phase:  F2 - R + sum D = |p2| M      (friction now opposes the spring)
The spring is best used when F1 = F2, i.e. p2 - p1 = 2R/M: the opening side should decelerate
more than the closing side by 2R/M. An intake valve has the steam on its stem opposing the
spring, which only changes the sign of that load in sum D; the optimum is the same.

Units: the functions of the worked example take any consistent set (the tests use Schenker's
kgf and kgf*s^2/m); everything that takes a scene works in SI.

Seed 003 (section 96): preload at closed valve in kgf about bore_mm/15 for high-pressure and
bore_mm/17 to bore_mm/22 for low-pressure cylinders; P_max = 1.2 to 2 P_min. Trinks' trip-gear
closing force P_f = (p/g - 1) G_v + W_s with p = 2h/t^2.

The optional scene section [spring_design] (parsed here) asks the forces effect for advice:
    target_rpm      speed to design for (default: drive.rpm)
    safety_margin   contact force to keep everywhere (default 0)
    cylinder_bore   bore of the engine cylinder, for seed 003's preload rule
    cylinder        "high-pressure" (default) or "low-pressure"
    trip_closing_time  closing time after release, for Trinks' trip-gear closing force
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import InputError, echo
from ..core.roots import root_in
from .forces import TWO_PI, RPM_PER_RAD_S, TrainLoads
from ..core.units import KGF
from ..lift.curves import LawLift
from ..lift.registry import normalised

TRINKS_G = 9.81  # m/s^2, the g of Trinks' formula as printed in seed 003

# --- Schenker's worked example (any consistent units) -------------------------------------------


def required_spring_forces(mass: float, friction: float, p_opening: float, p_closing: float,
                           closing_loads: float) -> tuple[float, float]:
    """(F1, F2): spring force needed at the largest deceleration of the lift phase (p_opening < 0)
    and of the closing phase (p_closing < 0), with Coulomb friction R and constant closing loads."""
    _check_nonnegative(friction, "friction")
    _check_positive(mass, "mass")
    f1 = -p_opening * mass - friction - closing_loads
    f2 = -p_closing * mass + friction - closing_loads
    return f1, f2


def reversed_spring_forces(mass: float, friction: float, p_opening: float, p_closing: float,
                           closing_loads: float) -> tuple[float, float]:
    """(F2', F1'): the cam run the other way round, so the closing curve becomes the lift curve.
    Returns the force needed where the larger deceleration now sits on the lift side (F2') and
    the other (F1'), in Schenker's naming."""
    f2r, f1r = required_spring_forces(mass, friction, p_closing, p_opening, closing_loads)
    return f2r, f1r


def wasted_spring_force(f_a: float, f_b: float) -> float:
    """Spring force present on one side beyond what that side needs (Schenker's 'schädlicher Druck')."""
    return abs(f_a - f_b)


def optimum_deceleration_difference(friction: float, mass: float) -> float:
    """Schenker's optimum p2 - p1 = 2R/M: then F1 = F2 and no spring force is wasted."""
    _check_nonnegative(friction, "friction")
    _check_positive(mass, "mass")
    return 2.0 * friction / mass


def _check_positive(value: float, key: str) -> None:
    if not (math.isfinite(value) and value > 0.0):
        raise InputError("<arguments>", key, f"must be greater than zero, got {echo(value)}")


def _check_nonnegative(value: float, key: str) -> None:
    if not (math.isfinite(value) and value >= 0.0):
        raise InputError("<arguments>", key, f"must not be negative, got {echo(value)}")


# --- seed 003: historic rules -------------------------------------------------------------------

CYLINDERS = ("high-pressure", "low-pressure")
_PRELOAD_DIVISORS = {"high-pressure": (15.0, 15.0), "low-pressure": (22.0, 17.0)}


def historic_preload(bore: float, cylinder: str = "high-pressure") -> tuple[float, float]:
    """(low, high) preload P_min in N from the cylinder bore in m: bore_mm/15 kgf for high-pressure,
    bore_mm/22 to bore_mm/17 kgf for low-pressure cylinders (seed 003)."""
    _check_positive(bore, "cylinder_bore")
    if cylinder not in _PRELOAD_DIVISORS:
        raise InputError("<arguments>", "cylinder", f"unknown value {echo(cylinder)}; choose one of: {', '.join(CYLINDERS)}")
    bore_mm = bore * 1e3
    lo_div, hi_div = _PRELOAD_DIVISORS[cylinder]
    return bore_mm / lo_div * KGF, bore_mm / hi_div * KGF


def historic_max_spring_force(preload: float) -> tuple[float, float]:
    """(low, high) spring force at full lift: 1.2 to 2 times the preload (seed 003)."""
    return 1.2 * preload, 2.0 * preload


def trinks_closing_force(lift: float, closing_time: float, valve_weight: float, friction: float,
                         g: float = TRINKS_G) -> float:
    """Trinks' spring force for a trip gear's valve after release (seed 003):
    P_f = (p/g - 1) G_v + W_s with p = 2h/t^2 (constant acceleration over the closing time).
    Forces in any one unit (kgf or N); g must be the gravity that turned the mass into G_v."""
    _check_positive(lift, "lift")
    _check_positive(closing_time, "closing_time")
    _check_positive(valve_weight, "valve_weight")
    _check_nonnegative(friction, "friction")
    p = 2.0 * lift / closing_time**2
    return (p / g - 1.0) * valve_weight + friction


# --- scene section [spring_design] --------------------------------------------------------------


@dataclass(frozen=True)
class SpringDesign:
    target_rpm: float | None = None  # rev/min; None: the scene's speed
    safety_margin: float = 0.0  # N
    cylinder_bore: float | None = None  # m
    cylinder: str = "high-pressure"
    trip_closing_time: float | None = None  # s


def parse_spring_design_section(table, fields) -> SpringDesign | None:
    if table is None:
        return None
    table.reject_unknown(("target_rpm", "safety_margin", "cylinder_bore", "cylinder", "trip_closing_time"))
    target = table.quantity("target_rpm", "speed", positive=True) * RPM_PER_RAD_S if table.has("target_rpm") else None
    return SpringDesign(
        target_rpm=target,
        safety_margin=table.quantity("safety_margin", "force", 0.0, nonnegative=True),
        cylinder_bore=table.quantity("cylinder_bore", "length", positive=True) if table.has("cylinder_bore") else None,
        cylinder=table.string("cylinder", "high-pressure", choices=CYLINDERS),
        trip_closing_time=table.quantity("trip_closing_time", "time", positive=True) if table.has("trip_closing_time") else None,
    )


# --- lift-curve transformations for the comparisons ---------------------------------------------


@dataclass(frozen=True)
class ReversedLift:
    """The same cam turned the other way round: L_rev(theta) = L(-theta)."""

    lift: Any

    def derivatives(self, theta) -> np.ndarray:
        d = np.array(self.lift.derivatives(np.mod(-np.asarray(theta, dtype=float), TWO_PI)), dtype=float)
        d[1] *= -1.0
        d[3] *= -1.0
        return d

    def breakpoints(self) -> np.ndarray:
        return np.unique(np.mod(-np.asarray(self.lift.breakpoints(), dtype=float), TWO_PI))


# --- the spring advisor -------------------------------------------------------------------------


@dataclass(frozen=True)
class SpringAdvice:
    rpm: float
    safety_margin: float  # N
    preload: float  # N, smallest spring: preload ...
    rate: float  # N/m, ... and rate
    max_spring_force: float  # N, preload + rate * largest valve lift
    mean_spring_force: float  # N, preload + rate * largest valve lift / 2
    preload_for_current_rate: float  # N, smallest preload keeping the scene's rate
    constant_force: float  # N, the zero-rate limit: smallest possible largest spring force
    objective: str
    min_contact_force: float  # N, with the advised spring at the target speed (>= safety_margin)
    opening_required: float | None  # N, Schenker's F1 at the target speed
    closing_required: float | None  # N, Schenker's F2

    def as_dict(self) -> dict:
        return {
            "rpm": self.rpm,
            "safety_margin_N": self.safety_margin,
            "preload_N": self.preload,
            "rate_N_m": self.rate,
            "max_spring_force_N": self.max_spring_force,
            "mean_spring_force_N": self.mean_spring_force,
            "preload_for_current_rate_N": self.preload_for_current_rate,
            "constant_force_N": self.constant_force,
            "objective": self.objective,
            "min_contact_force_N": self.min_contact_force,
            "opening_required_spring_force_N": self.opening_required,
            "closing_required_spring_force_N": self.closing_required,
            "wasted_spring_force_N": (abs(self.closing_required - self.opening_required)
                                      if self.opening_required is not None and self.closing_required is not None else None),
        }


OBJECTIVES = ("mean", "peak")


def _upper_hull(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points that matter to a line P0 + k x with k >= 0 lying above all of (x, y): the rising
    staircase (each point higher than every point at smaller x), then its upper convex hull
    (monotone chain). The LP needs only these rows."""
    order = np.lexsort((-y, x))  # by x, the highest first among equal x
    # a point with a lower or equal y than some point at smaller or equal x is implied by it
    # (P0 + k x_i >= P0 + k x_j for k >= 0): keep the rising staircase only (vectorised)
    ys = y[order]
    previous_max = np.concatenate([[-np.inf], np.maximum.accumulate(ys)[:-1]])
    order = order[ys > previous_max]
    hull: list[int] = []
    for i in order:
        while len(hull) >= 2:
            o, a = hull[-2], hull[-1]
            cross = (x[a] - x[o]) * (y[i] - y[o]) - (y[a] - y[o]) * (x[i] - x[o])
            if cross >= 0.0:  # a lies on or below the chord o-i: not on the upper hull
                hull.pop()
            else:
                break
        hull.append(int(i))
    idx = np.asarray(hull, dtype=int)
    return x[idx], y[idx]


# The split's angles are a rise and a return as a scene would write them: the scene loader's
# smallest (explorer.scene.scene.MIN_EVENT_ANGLE, 0.1 deg; equal by a test)
SPLIT_MIN_ANGLE = math.radians(0.1)


@dataclass(frozen=True)
class BalancedSplit:
    """Schenker's balanced rise and return (rad), or None with the reason no valid split exists."""

    angles: tuple[float, float] | None
    reason: str = ""


def balanced_split(lift, loads: TrainLoads, omega: float, ratio: float) -> BalancedSplit | None:
    """For a law-based event (LawLift): the rise and return angles, same total, that satisfy
    Schenker's optimum |p1| - |p2| = 2R/M (F1 = F2). Peak decelerations of a law scale as 1/beta^2:
    |p1| = ratio w^2 h c_r / beta_r^2 with c_r = -min f_rise'', |p2| = ratio w^2 h c_d / beta_d^2
    with c_d = max f_return''. None when the lift is not a law-based event.

    phi(beta_r) = c_r / beta_r^2 - c_d / (total - beta_r)^2 - target decreases strictly from +inf
    to -inf on (0, total), so its root is unique; it is a valid split when both angles are at
    least SPLIT_MIN_ANGLE, i.e. when phi changes sign between those ends -- the proven bracket.
    Else (a crawl, where friction outweighs any deceleration the event can have) the reason says
    which side the balance would need and how short it would be."""
    if not isinstance(lift, LawLift) or omega <= 0.0:
        return None
    c_r = -_law_extreme(normalised(lift.rise_law), -1.0)
    c_d = _law_extreme(normalised(lift.return_law), 1.0)
    if c_r <= 0.0 or c_d <= 0.0:
        return None
    total = lift.rise + lift.ret
    target = 2.0 * loads.friction / (loads.mass * ratio * omega**2 * lift.height)

    def phi(beta_r: float) -> float:  # decreasing from +inf to -inf on (0, total)
        return c_r / beta_r**2 - c_d / (total - beta_r) ** 2 - target

    lo, hi = SPLIT_MIN_ANGLE, total - SPLIT_MIN_ANGLE
    f_lo, f_hi = (phi(lo), phi(hi)) if hi > lo else (-math.inf, -math.inf)
    if not (f_lo >= 0.0 >= f_hi) or not math.isfinite(target):
        side, sign = ("rise", f_lo) if not f_lo >= 0.0 else ("return", f_hi)
        rpm = omega * 60.0 / (2.0 * math.pi)
        return BalancedSplit(None, f"no split of the {math.degrees(total):.6g} deg event balances the sides at "
                             f"{rpm:.6g} rpm: |p1| - |p2| = 2R/M would need a {side} shorter than "
                             f"{math.degrees(SPLIT_MIN_ANGLE):g} deg (friction outweighs the inertia at this speed)")
    beta_r = root_in(phi, lo, hi, fa=f_lo, fb=f_hi, xtol=1e-15, maxiter=300)
    return BalancedSplit((beta_r, total - beta_r))


def _law_extreme(f, sign: float) -> float:
    """max (sign = 1) or min (sign = -1) of a normalised law's f'' on [0, 1]: grid, then Brent."""
    from scipy.optimize import minimize_scalar

    u = np.linspace(0.0, 1.0, 2001)
    values = -sign * f(u)[2]
    j = int(np.argmin(values))
    lo, hi = u[max(j - 1, 0)], u[min(j + 1, u.size - 1)]
    res = minimize_scalar(lambda x: float(-sign * f(np.array([x]))[2, 0]), bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-12})
    return sign * -min(float(res.fun), float(values[j]))


