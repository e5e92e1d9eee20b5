"""The spring advisor and the event comparison for a scene, and the `spring_design` block of the
forces summary (explorer.mechanics.springs holds Schenker's and the historic rules)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..core.errors import InputError, echo
from ..core.units import G0, KGF
from ..lift.curves import LawLift
from ..mechanics.forces import (RPM_PER_RAD_S, TWO_PI, TrainLoads, min_contact_force, piece_direction, sample_pieces,
                                side_extremes, smooth_pieces)
from ..mechanics.springs import (OBJECTIVES, ReversedLift, SpringAdvice, SpringDesign, _upper_hull, balanced_split,
                                 historic_preload, trinks_closing_force)
from .lift import build_lift


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


    if scene.valve is None or scene.spring is None:
        TrainLoads.from_scene(scene)  # raises the one-line InputError for the missing section
    if not (math.isfinite(safety_margin) and safety_margin >= 0.0):
        raise InputError(scene.source, "spring_design.safety_margin", f"must not be negative, got {echo(safety_margin)}")
    if rpm is not None and not (math.isfinite(rpm) and rpm > 0.0):
        raise InputError(scene.source, "spring_design.target_rpm", f"must be greater than zero, got {echo(rpm)}")
    lift = lift if lift is not None else build_lift(scene)
    loads = TrainLoads.from_scene(scene)
    ratio, lash = scene.follower.ratio, scene.valve.lash
    rpm = scene.drive.rpm if rpm is None else rpm
    omega = rpm / RPM_PER_RAD_S
    n = n_grid or max(4096, scene.solver.steps_per_revolution)
    if objective not in OBJECTIVES:
        raise InputError(scene.source, "objective", f"unknown value {echo(objective)}; choose one of: {', '.join(OBJECTIVES)}")
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


def compare_events(scene, rpm: float | None = None, safety_margin: float = 0.0, lift=None) -> dict:
    """Does reversing the event, or making it asymmetric by Schenker's 2R/M rule, save spring force?

    Each variant is judged two ways: Schenker's constant-force measure max(F1, F2) (the spring force
    needed at the worse side) and the advisor's smallest spring (its largest force P0 + k s_max)."""
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
    found = balanced_split(lift, loads, omega, scene.follower.ratio)
    if found is not None and found.angles is None:
        result["asymmetric_note"] = found.reason
    if found is not None and found.angles is not None:
        split = found.angles
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
    if "asymmetric_note" in comparison:  # the speed is the input that rules the balance out
        speed_key = "spring_design.target_rpm" if design.target_rpm else "drive.rpm"
        warnings.append(f"{speed_key}: {comparison['asymmetric_note']}")
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
