"""What the elastic effects (the massless linkage and the spring chain) report alike: the events as
the summary lists them, the valve's motion figures and columns, the run put back in output order."""

from __future__ import annotations

import math

import numpy as np

from ..result import Event


def output_order(n: int, i0: int):
    """(rotate, back) for a run that started at output sample i0: rotate(values) puts its first n
    values in output order (floats); back[i] is the output index of run sample i."""
    back = (np.arange(n) + i0) % n  # output index of each run sample

    def rotate(values) -> np.ndarray:
        out = np.empty(n)
        out[back] = np.asarray(values, dtype=float)[:n]
        return out

    return rotate, back


def revolution_events(solver_events, kinds, t_start: float, period: float, omega: float) -> list[Event]:
    """The solver's events of the reported revolution (from t_start), in time order, as the
    result lists them: time within the revolution, cam angle, and the impact speed where known."""
    events = []
    for ev in solver_events:
        if ev["kind"] not in kinds or ev["time_s"] >= t_start + period:
            continue
        t_ev = math.fmod(ev["time_s"], period)
        values = {"velocity_m_s": float(ev["velocity_m_s"])} if "velocity_m_s" in ev else {}
        events.append(Event(ev["kind"], t_ev, math.degrees(omega * t_ev) % 360.0, values))
    events.sort(key=lambda e: e.time_s)
    return events


def valve_motion_summary(s, v, a, events: list[Event], kinds) -> dict:
    """The elastic valve's extremes over the revolution and how many events of each kind."""
    return {
        "elastic_max_valve_lift_m": float(s.max()),
        "elastic_max_valve_velocity_m_s": float(v.max()),
        "elastic_min_valve_velocity_m_s": float(v.min()),
        "elastic_max_valve_accel_m_s2": float(a.max()),
        "elastic_min_valve_accel_m_s2": float(a.min()),
        "elastic_event_counts": {kind: sum(e.kind == kind for e in events) for kind in kinds},
    }


def linkage_outputs(s, v, a, jerk, force, back_pressure, deviation, contact, separated, events, kinds):
    """(summary entries, columns) of the valve's motion and the linkage's force over the output
    samples, as both elastic effects report them."""
    summary = {
        "max_deviation_m": float(np.abs(deviation).max()),
        "peak_linkage_force_N": float(force.max()),
        "peak_camshaft_back_pressure_N": float(back_pressure.max()),
        "separated_angle_deg": float(360.0 * np.count_nonzero(separated) / s.size),
        **valve_motion_summary(s, v, a, events, kinds),
    }
    columns = {
        "valve_lift_m": s,
        "valve_velocity_m_s": v,
        "valve_accel_m_s2": a,
        "valve_jerk_m_s3": jerk,
        "linkage_force_N": force,
        "camshaft_back_pressure_N": back_pressure,
        "deviation_from_drive_m": deviation,
        "valve_in_contact": contact.astype(float),
    }
    return summary, columns


def elastic_row(result) -> dict[str, float]:
    """A sweep row's elastic figures from a run (its summary, events in time order and columns; the
    lash effect's take-up events give the lift-off delay)."""
    summary, events = result.summary, result.events
    elastic = [e for e in events if e.effect == "elastic"]
    period = float(summary["revolution_time_s"])
    seps = [e for e in elastic if e.kind == "separation"]
    seats = [e for e in elastic if e.kind == "seat"]
    lift_offs = [float(e.time_s) for e in elastic if e.kind == "lift-off"]
    ups = [float(e.time_s) for e in events if e.kind == "lash-take-up"]
    row = {
        "first_separation_deg": float(seps[0].cam_angle_deg) if seps else math.nan,
        "separations": float(len(seps)),
        "flight_time_s": float(summary["separated_angle_deg"]) / 360.0 * period,
        "max_deviation_m": float(summary["max_deviation_m"]),
        "peak_linkage_force_N": float(summary["peak_linkage_force_N"]),
        "peak_camshaft_back_pressure_N": float(summary["peak_camshaft_back_pressure_N"]),
        "lift_off_delay_s": (min(math.fmod(t - ups[0] + period, period) for t in lift_offs)
                             if ups and lift_offs else math.nan),
        "seating_velocity_m_s": min(float(e["velocity_m_s"]) for e in seats) if seats else math.nan,
        "seat_impacts": float(len(seats)),
        "largest_bounce_m": _largest_bounce(elastic, seats, result.columns),
    }
    for name in ("residual_deviation_m", "residual_amplitude_m"):  # the elastic effect's (effects/residual.py)
        value = summary.get(name)
        row[name] = math.nan if value is None else float(value)
    return row


def _largest_bounce(elastic, seats, columns) -> float:
    """Highest valve lift on the output grid after a seat impact, before the next elastic event."""
    if not seats:
        return 0.0
    t, s = np.asarray(columns["time_s"]), np.asarray(columns["valve_lift_m"])
    times = [float(e.time_s) for e in elastic]
    best = 0.0
    for ev in seats:
        t0 = float(ev.time_s)
        later = [x for x in times if x > t0]
        t1 = min(later) if later else float(t[-1]) + 1.0
        inside = (t > t0) & (t < t1)
        if inside.any():
            best = max(best, float(s[inside].max()))
    return best
