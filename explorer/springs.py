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
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from .errors import InputError
from .forces import (
    TWO_PI,
    piece_direction,
    sample_pieces,
    RPM_PER_RAD_S,
    TrainLoads,
    min_contact_force,
    side_extremes,
    smooth_pieces,
)
from .units import G0, KGF

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
        raise InputError("<arguments>", key, f"must be greater than zero, got {value!r}")


def _check_nonnegative(value: float, key: str) -> None:
    if not (math.isfinite(value) and value >= 0.0):
        raise InputError("<arguments>", key, f"must not be negative, got {value!r}")


# --- seed 003: historic rules -------------------------------------------------------------------

CYLINDERS = ("high-pressure", "low-pressure")
_PRELOAD_DIVISORS = {"high-pressure": (15.0, 15.0), "low-pressure": (22.0, 17.0)}


def historic_preload(bore: float, cylinder: str = "high-pressure") -> tuple[float, float]:
    """(low, high) preload P_min in N from the cylinder bore in m: bore_mm/15 kgf for high-pressure,
    bore_mm/22 to bore_mm/17 kgf for low-pressure cylinders (seed 003)."""
    _check_positive(bore, "cylinder_bore")
    if cylinder not in _PRELOAD_DIVISORS:
        raise InputError("<arguments>", "cylinder", f"unknown value {cylinder!r}; choose one of: {', '.join(CYLINDERS)}")
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


def advise_spring(scene, rpm: float | None = None, safety_margin: float = 0.0, lift=None,
                  ratio_range: tuple[float, float] | None = None, n_grid: int | None = None,
                  objective: str = "mean") -> SpringAdvice:
    """Smallest spring that keeps the rigid contact force >= safety_margin at `rpm` (default: the scene's).

    A linear program in (preload P0, rate k) subject to P0 + k s(theta) >= required(theta) + margin
    on every open sample, P0 >= margin - sum D (the seat must hold the valve shut), P0, k >= 0.
    Objective "mean" (default): the spring force averaged over the valve stroke, P0 + k s_max/2,
    which makes the spring line touch the required-force curve near mid-stroke; "peak": the largest
    spring force P0 + k s_max, whose optimum is always the zero-rate spring (reported anyway as
    `constant_force`). Ties go to the softest spring. `ratio_range` (e.g. (1.2, 2.0), seed 003)
    bounds P_max/P_min as well. The result is checked on the analytic lift (refined minimum) and
    the preload raised by any deficit the sampling missed.
    """
    from scipy.optimize import linprog

    from .lift import build_lift

    if scene.valve is None or scene.spring is None:
        TrainLoads.from_scene(scene)  # raises the one-line InputError for the missing section
    if not (math.isfinite(safety_margin) and safety_margin >= 0.0):
        raise InputError(scene.source, "spring_design.safety_margin", f"must not be negative, got {safety_margin!r}")
    if rpm is not None and not (math.isfinite(rpm) and rpm > 0.0):
        raise InputError(scene.source, "spring_design.target_rpm", f"must be greater than zero, got {rpm!r}")
    lift = lift if lift is not None else build_lift(scene)
    loads = TrainLoads.from_scene(scene)
    ratio, lash = scene.follower.ratio, scene.valve.lash
    rpm = scene.drive.rpm if rpm is None else rpm
    omega = rpm / RPM_PER_RAD_S
    n = n_grid or max(4096, scene.solver.steps_per_revolution)
    if objective not in OBJECTIVES:
        raise InputError(scene.source, "objective", f"unknown value {objective!r}; choose one of: {', '.join(OBJECTIVES)}")
    pieces = smooth_pieces(lift, ratio, lash, n)
    # samples of the open stretches, ends just inside (one-sided limits at breakpoints and seating)
    theta, direction, _, _ = sample_pieces(pieces, None, n)

    def requirement(th, dirn):
        d = lift.derivatives(np.mod(th, TWO_PI))
        lift_s = np.maximum(ratio * d[0] - lash, 0.0)
        return lift_s, -(loads.mass * ratio * omega**2 * d[2] + loads.friction * dirn + loads.closing)

    s, required = requirement(theta, direction)
    s_max = float(s.max()) if s.size else 0.0
    seat_need = safety_margin - loads.closing
    weight = 0.5 * s_max if objective == "mean" else s_max
    row_s, row_need = list(s), list(required + safety_margin)
    fixed_a, fixed_b = [], []
    if seat_need > 0.0:  # the seat must hold the valve shut
        fixed_a.append([-1.0, 0.0])
        fixed_b.append(-seat_need)
    if ratio_range is not None:
        lo, hi = ratio_range
        fixed_a += [[lo - 1.0, -s_max], [1.0 - hi, s_max]]  # lo P0 <= P0 + k s_max <= hi P0
        fixed_b += [0.0, 0.0]

    def solve() -> tuple[float, float]:
        rs, rn = _upper_hull(np.asarray(row_s), np.asarray(row_need))
        keep = rn > 0.0  # rows with a non-positive need hold for any P0, k >= 0
        a_ub = np.vstack([np.column_stack([-np.ones(int(keep.sum())), -rs[keep]]), np.reshape(fixed_a, (-1, 2))])
        b_ub = np.concatenate([-rn[keep], np.asarray(fixed_b, dtype=float)])
        if a_ub.shape[0] == 0:
            return 0.0, 0.0
        bounds = [(0, None), (0, None)]
        first = linprog([1.0, weight], A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
        if first.status != 0:
            raise InputError(scene.source, "spring_design", f"no spring satisfies the constraints ({first.message})")
        # among the optimal springs, the softest
        cap_a = np.vstack([a_ub, [[1.0, weight]]])
        cap_b = np.append(b_ub, first.fun * (1.0 + 1e-10) + 1e-10)
        second = linprog([0.0, 1.0], A_ub=cap_a, b_ub=cap_b, bounds=bounds, method="highs")
        return tuple((second.x if second.status == 0 else first.x).tolist())

    if s_max <= 0.0:  # valve never opens: only the seat matters
        preload, rate = max(0.0, seat_need), 0.0
    else:
        # cutting planes: add the exact (refined) worst angle of each candidate until none is short
        tolerance = 1e-9 * max(1.0, float(np.max(np.abs(required))))
        for _ in range(12):
            preload, rate = solve()
            f_min, th = min_contact_force(lift, loads.with_spring(preload, rate), omega, ratio, lash, pieces, n)
            if not (math.isfinite(f_min) and f_min < safety_margin - tolerance):
                break
            s_new, req_new = requirement(np.array([th]), piece_direction(pieces, th))
            row_s.append(float(s_new[0]))
            row_need.append(float(req_new[0]) + safety_margin)
    advised = loads.with_spring(preload, rate)
    f_min, _ = min_contact_force(lift, advised, omega, ratio, lash, pieces, n)
    if math.isfinite(f_min) and f_min < safety_margin:  # last resort: the deficit the planes left
        preload += (safety_margin - f_min) * (1.0 + 1e-12) + 1e-12
        advised = loads.with_spring(preload, rate)
        f_min, _ = min_contact_force(lift, advised, omega, ratio, lash, pieces, n)
    # keeping a given rate, the preload follows in closed form: P0 = max(required + margin - k s)
    def preload_for_rate(k: float) -> float:
        p0 = max(0.0, seat_need, float(np.max(required + safety_margin - k * s, initial=-np.inf)))
        f_k, _ = min_contact_force(lift, loads.with_spring(p0, k), omega, ratio, lash, pieces, n)
        if math.isfinite(f_k) and f_k < safety_margin:
            p0 += (safety_margin - f_k) * (1.0 + 1e-12) + 1e-12
        return p0

    p_current = preload_for_rate(loads.rate)
    sides = side_extremes(lift, loads, omega, ratio, lash, pieces, n)
    return SpringAdvice(
        rpm=rpm,
        safety_margin=safety_margin,
        preload=preload,
        rate=rate,
        max_spring_force=preload + rate * s_max,
        mean_spring_force=preload + 0.5 * rate * s_max,
        preload_for_current_rate=p_current,
        constant_force=preload_for_rate(0.0),
        objective=objective,
        min_contact_force=f_min if math.isfinite(f_min) else math.inf,
        opening_required=sides["opening"]["required_spring_force_N"],
        closing_required=sides["closing"]["required_spring_force_N"],
    )


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


def balanced_split(lift, loads: TrainLoads, omega: float, ratio: float) -> tuple[float, float] | None:
    """For a law-based event (LawLift): the rise and return angles, same total, that satisfy
    Schenker's optimum |p1| - |p2| = 2R/M (F1 = F2). Peak decelerations of a law scale as 1/beta^2:
    |p1| = ratio w^2 h c_r / beta_r^2 with c_r = -min f_rise'', |p2| = ratio w^2 h c_d / beta_d^2
    with c_d = max f_return''. None when the lift is not a law-based event."""
    from scipy.optimize import brentq

    from .laws import law
    from .lift import LawLift

    if not isinstance(lift, LawLift) or omega <= 0.0:
        return None
    c_r = -_law_extreme(law(lift.rise_law), -1.0)
    c_d = _law_extreme(law(lift.return_law), 1.0)
    if c_r <= 0.0 or c_d <= 0.0:
        return None
    total = lift.rise + lift.ret
    target = 2.0 * loads.friction / (loads.mass * ratio * omega**2 * lift.height)

    def phi(beta_r: float) -> float:  # decreasing from +inf to -inf on (0, total)
        return c_r / beta_r**2 - c_d / (total - beta_r) ** 2 - target

    beta_r = brentq(phi, total * 1e-6, total * (1 - 1e-6), xtol=1e-15, maxiter=300)
    return beta_r, total - beta_r


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


def compare_events(scene, rpm: float | None = None, safety_margin: float = 0.0, lift=None) -> dict:
    """Does reversing the event, or making it asymmetric by Schenker's 2R/M rule, save spring force?

    Each variant is judged two ways: Schenker's constant-force measure max(F1, F2) (the spring force
    needed at the worse side) and the advisor's smallest spring (its largest force P0 + k s_max)."""
    from .lift import LawLift, build_lift

    lift = lift if lift is not None else build_lift(scene)
    loads = TrainLoads.from_scene(scene)
    rpm = scene.drive.rpm if rpm is None else rpm
    omega = rpm / RPM_PER_RAD_S

    def judge(variant_lift) -> dict:
        advice = advise_spring(scene, rpm, safety_margin, lift=variant_lift)
        out = advice.as_dict()
        f1, f2 = advice.opening_required, advice.closing_required
        out["needed_spring_force_N"] = max(f1, f2) if f1 is not None and f2 is not None else None
        return out

    current = judge(lift)
    reverse = judge(ReversedLift(lift))
    result: dict = {
        "rpm": rpm,
        "optimum_deceleration_difference_m_s2": 2.0 * loads.friction / loads.mass,
        "current": current,
        "reversed": reverse,
        "reversing_saves_N": _difference(current["needed_spring_force_N"], reverse["needed_spring_force_N"]),
        "reversing_saves_max_spring_force_N": current["max_spring_force_N"] - reverse["max_spring_force_N"],
        "asymmetric": None,
        "asymmetric_saves_N": None,
        "asymmetric_saves_max_spring_force_N": None,
    }
    split = balanced_split(lift, loads, omega, scene.follower.ratio)
    if split is not None:
        balanced = replace(lift, rise=split[0], ret=split[1])
        assert isinstance(balanced, LawLift)
        asym = judge(balanced)
        asym["rise_deg"] = math.degrees(split[0])
        asym["return_deg"] = math.degrees(split[1])
        result["asymmetric"] = asym
        result["asymmetric_saves_N"] = _difference(current["needed_spring_force_N"], asym["needed_spring_force_N"])
        result["asymmetric_saves_max_spring_force_N"] = current["max_spring_force_N"] - asym["max_spring_force_N"]
    return result


def _difference(a, b):
    return a - b if a is not None and b is not None else None


def spring_design_summary(scene, lift) -> tuple[dict, list[str]]:
    """The [spring_design] block of the forces summary: advice, comparisons, historic rules, Trinks."""
    design: SpringDesign = scene.spring_design
    warnings: list[str] = []
    rpm = design.target_rpm or scene.drive.rpm
    comparison = compare_events(scene, rpm, design.safety_margin, lift=lift)
    out: dict = {"advice": comparison["current"], "event_comparison": comparison}
    if design.cylinder_bore is not None:
        lo, hi = historic_preload(design.cylinder_bore, design.cylinder)
        computed = comparison["current"]["preload_for_current_rate_N"]
        out["historic"] = {
            "cylinder_bore_m": design.cylinder_bore,
            "cylinder": design.cylinder,
            "preload_N": [lo, hi],
            "preload_kgf": [lo / KGF, hi / KGF],
            "max_spring_force_N": [1.2 * lo, 2.0 * hi],
            "computed_preload_N": computed,
            "scene_preload_N": scene.spring.preload,
            "scene_max_to_min_ratio": ((scene.spring.preload + scene.spring.rate * _max_valve_lift(scene, lift))
                                       / scene.spring.preload if scene.spring.preload > 0 else None),
        }
        with_ratio = advise_spring(scene, rpm, design.safety_margin, lift=lift, ratio_range=(1.2, 2.0))
        out["historic"]["advice_with_historic_ratio"] = with_ratio.as_dict()
        out["historic"]["computed_exceeds_rule"] = bool(computed > hi)
    if design.trip_closing_time is not None:
        h = _max_valve_lift(scene, lift)
        weight = scene.valve.mass * G0
        if h > 0.0:
            p_f = trinks_closing_force(h, design.trip_closing_time, weight, scene.loads.friction, g=G0)
            out["trinks"] = {
                "closing_time_s": design.trip_closing_time,
                "lift_m": h,
                "valve_weight_N": weight,
                "acceleration_m_s2": 2.0 * h / design.trip_closing_time**2,
                "closing_force_N": p_f,
            }
    return out, warnings


def _max_valve_lift(scene, lift) -> float:
    n = max(4096, scene.solver.steps_per_revolution)
    d = lift.derivatives(np.arange(n) * (TWO_PI / n))
    return float(max(0.0, (scene.follower.ratio * d[0] - scene.valve.lash).max()))
