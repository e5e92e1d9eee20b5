"""Rigid kinematics: follower and valve motion from the lift curve; lash take-up and seating.

The valve moves only once the follower has taken up the lash: s = max(0, ratio L - lash).
At the take-up and seating instants the rigid theory gives the valve a finite velocity in zero
time (Schenker's v1, v2), i.e. an impact; the lash effect finds those instants by root-finding
on the analytic lift, not on the sampled grid.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .result import EffectOutput


def kinematics_effect(ctx) -> EffectOutput:
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
        "max_valve_velocity_m_s": float(valve["valve_velocity_m_s"].max()),
        "min_valve_velocity_m_s": float(valve["valve_velocity_m_s"].min()),
        "max_valve_accel_m_s2": float(valve["valve_accel_m_s2"].max()),
        "min_valve_accel_m_s2": float(valve["valve_accel_m_s2"].min()),
        "max_abs_valve_jerk_m_s3": float(np.abs(valve["valve_jerk_m_s3"]).max()),
        "valve_open_angle_deg": float(360.0 * np.count_nonzero(is_open) / is_open.size),
    }
    if scene.follower.type == "translating-roller":
        # pressure angle and radii of curvature (closed forms); raises InputError on undercut
        from .geometry.contour import geometry_columns

        geo_columns, geo_summary = geometry_columns(scene, ctx.theta, d)
        columns.update(geo_columns)
        summary.update(geo_summary)
    # laws that check themselves (table fit, acceleration closure) carry a report and warnings
    summary.update(getattr(ctx.lift, "report", None) or {})
    warnings = tuple(getattr(ctx.lift, "warnings", None) or ())
    return EffectOutput(columns=columns, summary=summary, warnings=warnings)


def lash_crossings(lift, ratio: float, lash: float, n_grid: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """Cam angles (rad) where ratio*L crosses `lash` upwards (take-up) and downwards (seating).

    Brackets come from a grid refined at the curve's breakpoints and at the lift's local maxima
    between closed grid points (a brief opening narrower than a grid cell would hide there); each
    root is polished with Brent's method on the analytic curve to machine precision.
    """
    grid = np.linspace(0.0, 2.0 * math.pi, n_grid + 1)
    grid = np.unique(np.concatenate([grid, np.asarray(lift.breakpoints(), dtype=float)]))
    d = lift.derivatives(grid)
    g = ratio * d[0] - lash

    def f(th: float) -> float:
        return float(ratio * lift.derivatives(np.array([th]))[0, 0] - lash)

    def slope(th: float) -> float:
        return float(lift.derivatives(np.array([th]))[1, 0])

    hidden = np.nonzero((d[1][:-1] > 0.0) & (d[1][1:] < 0.0) & (g[:-1] <= 0.0) & (g[1:] <= 0.0))[0]
    if hidden.size:
        peaks = [brentq(slope, grid[i], grid[i + 1], xtol=1e-15, maxiter=200) for i in hidden]
        grid = np.unique(np.concatenate([grid, peaks]))
        g = ratio * lift.derivatives(grid)[0] - lash

    # The valve is open where ratio*L - lash > 0 (the kinematics' own test), so only changes of
    # that state count: a lift that just touches the lash (g = 0 at a point, or on a whole dwell)
    # never opens the valve and gives no take-up or seating.
    is_open = g > 0.0
    ups, downs = [], []
    for i in np.nonzero(is_open[:-1] != is_open[1:])[0]:
        a, b = grid[i], grid[i + 1]
        if g[i] == 0.0 or g[i + 1] == 0.0:
            root = a if g[i] == 0.0 else b
        else:
            root = brentq(f, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
        (ups if is_open[i + 1] else downs).append(math.fmod(root, 2.0 * math.pi))
    return np.unique(ups), np.unique(downs)


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
        events.append({"kind": "lash-take-up", "time_s": th / w, "cam_angle_deg": math.degrees(th), "velocity_m_s": float(v)})
    for th, v in zip(downs, v_down):
        events.append({"kind": "seat", "time_s": th / w, "cam_angle_deg": math.degrees(th), "velocity_m_s": float(v)})
    # Speeds (>= 0) with which the follower meets the valve and the valve meets its seat.
    summary.update(
        impact_velocity_opening_m_s=float(np.max(np.abs(v_up))),
        impact_velocity_closing_m_s=float(np.max(np.abs(v_down))) if v_down.size else 0.0,
        lash_take_up_angles_deg=[math.degrees(a) for a in ups],
        seating_angles_deg=[math.degrees(a) for a in downs],
    )
    return EffectOutput(summary=summary, events=tuple(events), warnings=tuple(warnings))
