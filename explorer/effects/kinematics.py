"""Effects `kinematics` and `lash`: the rigid motion of follower and valve over one revolution,
and where the lash is taken up and the valve seats (explorer.mechanics.kinematics holds the physics)."""

from __future__ import annotations

import math

import numpy as np

from ..core.memo import remember
from ..mechanics.kinematics import accel_jumps, lash_crossings, open_angle, valve_extremes
from ..result import EffectOutput, Event


def kinematics_effect(ctx) -> EffectOutput:
    return _kinematics(ctx, exact=True)


def kinematics_figures(ctx, cache) -> EffectOutput:
    """The kinematics effect's figures-only form (sweeps, the design checks' elastic revolutions):
    its columns and the gear's, without the exact peaks and open angle of its summary, which no
    sweep row and no later effect reads (on a gear whose lift is implicit, a rocking cam, their
    root searches are most of a revolution's cost)."""
    return _kinematics(ctx, exact=False)


def _kinematics(ctx, exact: bool) -> EffectOutput:
    scene, w = ctx.scene, ctx.omega
    d = ctx.lift.derivatives(ctx.theta)
    ratio, lash = scene.follower.ratio, scene.valve.lash if scene.valve else 0.0
    follower = {
        "follower_lift_m": d[0],
        "follower_velocity_m_s": w * d[1],
        "follower_accel_m_s2": w**2 * d[2],
        "follower_jerk_m_s3": w**3 * d[3],
    }
    x = ratio * d[0] - lash
    is_open = x > 0.0
    valve = {
        "valve_lift_m": np.where(is_open, x, 0.0),
        "valve_velocity_m_s": np.where(is_open, ratio * w * d[1], 0.0),
        "valve_accel_m_s2": np.where(is_open, ratio * w**2 * d[2], 0.0),
        "valve_jerk_m_s3": np.where(is_open, ratio * w**3 * d[3], 0.0),
    }
    columns = {**follower, **valve}
    # the rigid motion stays available under its own name when a later effect refines valve_*
    columns.update({f"rigid_{k}": v for k, v in valve.items()})
    summary = {
        "max_follower_lift_m": float(d[0].max()),
        "max_valve_lift_m": float(valve["valve_lift_m"].max()),
    }
    if exact:
        # the peaks of velocity and acceleration exact (between samples, one-sided at a jump), as is
        # the open angle (from the take-up and seating angles); the jerk's sampled (no fourth derivative)
        ups, downs = lash_crossings(ctx.lift, ratio, lash)
        ends = np.concatenate([ups, downs])
        peaks = valve_extremes(ctx.lift, ctx.theta, d, ratio, lash, {0: 1.0, 1: ratio * w, 2: ratio * w**2}, ends)
        (v_max, v_min), (a_max, a_min) = peaks[1], peaks[2]
        # the lift's peak exact too (a spline's nose overshoots its station between samples): the
        # extremes are taken over the open valve, where the lift's peak is whenever the valve opens;
        # a valve that never opens leaves the sampled peak
        lift_top = max(peaks[0][0], summary["max_follower_lift_m"])
        summary.update({
            "max_follower_lift_m": lift_top,
            "max_valve_lift_m": max(ratio * lift_top - lash, 0.0),
        })
        summary.update({
            "max_valve_velocity_m_s": v_max,
            "min_valve_velocity_m_s": v_min,
            "max_valve_accel_m_s2": a_max,
            "min_valve_accel_m_s2": a_min,
            "max_abs_valve_jerk_m_s3": float(np.abs(valve["valve_jerk_m_s3"]).max()),
            "valve_open_angle_deg": math.degrees(open_angle(ups, downs, bool(is_open.all()))),
            # where the cam's acceleration jumps (the jerk unbounded there), one-sided limits
            "valve_accel_jumps": [
                {"cam_angle_deg": math.degrees(x), "before_m_s2": before, "after_m_s2": after}
                for x, before, after in accel_jumps(ctx.lift, ratio, lash, ratio * w**2, max(abs(a_max), abs(a_min)))],
        })
    # the gear's own figures (a translating roller's pressure angle and radii of curvature; InputError
    # when its cam fails the validity checks of every cam, explorer.lift.validity)
    gear_columns, gear_summary = ctx.gear.kinematics(ctx, d)
    columns.update(gear_columns)
    summary.update(gear_summary)
    # laws that check themselves (table fit, acceleration closure) carry a report and warnings
    summary.update(getattr(ctx.lift, "report", None) or {})
    warnings = tuple(getattr(ctx.lift, "warnings", None) or ())
    return EffectOutput(columns=columns, summary=summary, warnings=warnings)


def lash_effect(ctx) -> EffectOutput:
    scene, w = ctx.scene, ctx.omega
    ratio = scene.follower.ratio
    lash = scene.valve.lash if scene.valve else 0.0
    ups, downs = lash_crossings(ctx.lift, ratio, lash)
    events, warnings = [], []
    summary: dict = {"lash_m": lash, "lash_take_up_angles_deg": [], "seating_angles_deg": []}
    if ups.size == 0:
        warnings.append("valve never opens: ratio * lift does not exceed the lash")
        summary.update(impact_velocity_opening_m_s=0.0, impact_velocity_closing_m_s=0.0)
        return EffectOutput(summary=summary, warnings=tuple(warnings))
    v_up = ratio * w * ctx.lift.derivatives(ups)[1]
    v_down = ratio * w * ctx.lift.derivatives(downs)[1] if downs.size else np.zeros(0)
    for th, v in zip(ups, v_up):
        events.append(Event("lash-take-up", th / w, math.degrees(th), {"velocity_m_s": float(v)}))
    for th, v in zip(downs, v_down):
        events.append(Event("seat", th / w, math.degrees(th), {"velocity_m_s": float(v)}))
    # Speeds (>= 0) with which the follower meets the valve and the valve meets its seat.
    summary.update(
        impact_velocity_opening_m_s=float(np.max(np.abs(v_up))),
        impact_velocity_closing_m_s=float(np.max(np.abs(v_down))) if v_down.size else 0.0,
        lash_take_up_angles_deg=[math.degrees(a) for a in ups],
        seating_angles_deg=[math.degrees(a) for a in downs],
    )
    return EffectOutput(summary=summary, events=tuple(events), warnings=tuple(warnings))


def lash_figures(ctx, cache) -> EffectOutput:
    """The lash effect's figures for sweeps: the take-up events only (what a row's lift-off delay
    reads), their angles kept per lever ratio and lash across the runs."""
    ratio = ctx.scene.follower.ratio
    lash = ctx.scene.valve.lash if ctx.scene.valve else 0.0
    ups = remember(cache.of("lash"), (ratio, lash), lambda: lash_crossings(ctx.lift, ratio, lash)[0])
    w = ctx.omega
    return EffectOutput(events=tuple(Event("lash-take-up", th / w, math.degrees(th)) for th in ups))
