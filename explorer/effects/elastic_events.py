"""The elastic solvers' events as the summary lists them (the massless linkage and the spring chain)."""

from __future__ import annotations

import math


def revolution_events(solver_events, kinds, t_start: float, period: float, omega: float) -> list[dict]:
    """The solver's events of the reported revolution (from t_start), in time order, as the
    summary lists them: time within the revolution, cam angle, and the impact speed where known."""
    events = []
    for ev in solver_events:
        if ev["kind"] not in kinds or ev["time_s"] >= t_start + period:
            continue
        t_ev = math.fmod(ev["time_s"], period)
        item = {"kind": ev["kind"], "time_s": t_ev, "cam_angle_deg": math.degrees(omega * t_ev) % 360.0}
        if "velocity_m_s" in ev:
            item["velocity_m_s"] = float(ev["velocity_m_s"])
        events.append(item)
    events.sort(key=lambda e: e["time_s"])
    return events


def valve_motion_summary(s, v, a, events: list[dict], kinds) -> dict:
    """The elastic valve's extremes over the revolution and how many events of each kind."""
    return {
        "elastic_max_valve_lift_m": float(s.max()),
        "elastic_max_valve_velocity_m_s": float(v.max()),
        "elastic_min_valve_velocity_m_s": float(v.min()),
        "elastic_max_valve_accel_m_s2": float(a.max()),
        "elastic_min_valve_accel_m_s2": float(a.min()),
        "elastic_event_counts": {kind: sum(e["kind"] == kind for e in events) for kind in kinds},
    }
