"""What the elastic effects (the massless linkage and the spring chain) report alike: the events as
the summary lists them, the valve's motion figures and columns, the run put back in output order."""

from __future__ import annotations

import math
from typing import NamedTuple

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


def separated_angle_deg(time_s, separated, boundaries, period: float) -> float:
    """The cam angle (deg) over which the valve is separated (the mask `separated` on the output
    samples at time_s, ascending in [0, period)), measured between the exact instants where that
    can change: `boundaries`, times in [0, period) (the solver's events, every kind, and whatever
    else bounds the mask). Between two boundaries that are neighbours on the revolution's circle
    the state is one: a sample strictly between them says which, and the stretch counts whole; the
    stretch from the last boundary round to the first is one too (a flight that started in the
    previous revolution). So the figure is the events' and does not move with the output step.
    A stretch shorter than the step holds no sample: it takes the state the event opening it
    leaves (separation: off; re-contact: on; a seat impact followed by a landing or a re-contact:
    a rebound's flight, off), else the state before it. Without boundaries: 360 or 0, as the
    first sample."""
    t = np.asarray(time_s, dtype=float)
    sep = np.asarray(separated, dtype=bool)
    marks = sorted((float(b), kind) for b, kind in boundaries)
    if not marks:
        return 360.0 if sep.size and sep[0] else 0.0
    times = [m[0] for m in marks]
    total, state = 0.0, None
    for k, (b0, kind) in enumerate(marks):
        b1 = times[k + 1] if k + 1 < len(marks) else times[0] + period
        middle = _middle_sample(t, b0, b1, period)
        if middle is not None:
            state = bool(sep[middle])
        else:
            nxt = marks[k + 1][1] if k + 1 < len(marks) else marks[0][1]
            if kind == "separation" or (kind == "seat" and nxt in ("seat", "re-contact")):
                state = True
            elif kind == "re-contact":
                state = False
            elif state is None:  # the first stretch: what the wrap-round stretch before it holds
                state = _wrap_state(t, sep, times, period)
        if state:
            total += b1 - b0
    return float(360.0 * total / period)


def _wrap_state(t, sep, times, period: float) -> bool:
    """The state on the stretch from the last boundary round to the first (its samples), False
    when it holds none (a separated valve is seen on some sample of the revolution)."""
    middle = _middle_sample(t, times[-1], times[0] + period, period)
    return bool(sep[middle]) if middle is not None else False


def _middle_sample(t, b0: float, b1: float, period: float) -> int | None:
    """The index of the middle sample strictly between b0 and b1 (b1 past `period`: round the
    revolution's end), None if none; t ascending (a bisection: the events times log n)."""
    lo = int(np.searchsorted(t, b0, side="right"))
    if b1 <= period:
        hi = int(np.searchsorted(t, b1, side="left"))
        return lo + (hi - lo) // 2 if hi > lo else None
    tail, head = t.size - lo, int(np.searchsorted(t, b1 - period, side="left"))
    if tail + head == 0:
        return None
    m = (tail + head) // 2
    return lo + m if m < tail else m - tail


def linkage_outputs(s, v, a, jerk, force, back_pressure, deviation, contact, separated, events, kinds, time_s,
                    period: float):
    """(summary entries, columns) of the valve's motion and the linkage's force over the output
    samples (at time_s, within the revolution of `period` s), as both elastic effects report them."""
    summary = {
        "max_deviation_m": float(np.abs(deviation).max()),
        "peak_linkage_force_N": float(force.max()),
        "peak_camshaft_back_pressure_N": float(back_pressure.max()),
        "separated_angle_deg": separated_angle_deg(time_s, separated, [(e.time_s, e.kind) for e in events], period),
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


def not_at_rest(on_seat_at_end: bool, start_deg: float) -> list[str]:
    """The warning of a run whose valve is not back on its seat one revolution after it started
    there (the run begins at rest on the seat at the drive's lowest point): what it shows is one
    revolution of a motion that has not closed on itself, not the periodic motion."""
    if on_seat_at_end:
        return []
    return ["the valve has not come back to rest on its seat one revolution after the start angle "
            f"({start_deg:.3f} deg): the motion shown is not periodic"]


FLOAT_KINDS = ("separation", "re-contact", "seat")  # the events valve_periods walks


def float_report(ctx, lift, events: list[Event], period: float) -> tuple[dict, list[str]]:
    """(summary entries, warnings) of the elastic valve's float in the reported revolution: the
    separations while it is open, as the sweep counts them (valve_periods on the rigid valve's
    columns), the first one's cam angle and the float's flight time; a warning when it floats, which
    says whether the rigid train would keep contact at this speed (the forces effect's float speed:
    below it, the float is the train's vibration, not the inertia over the nose)."""
    periods = valve_periods(ctx.time, lift, ctx.columns["rigid_valve_lift_m"], ctx.columns["rigid_valve_velocity_m_s"],
                            [e for e in events if e.kind in FLOAT_KINDS], period)
    floats = periods.floats
    summary = {
        "first_separation_deg": float(floats[0].cam_angle_deg) if floats else None,
        "float_separations": len(floats),
        "float_flight_time_s": periods.flight_s,
    }
    warnings = []
    if floats:
        text = (f"elastic float: contact with the cam is lost {len(floats)} time(s) while the valve is open, first "
                f"at {floats[0].cam_angle_deg:.1f} deg, {1e3 * periods.flight_s:.3g} ms in flight")
        jump = ctx.summary.get("jump_speed_rpm")
        if jump is not None and ctx.scene.drive.rpm < jump:
            text += (f"; below the rigid train's float speed ({jump:.0f} rpm): the train's vibration throws it off, "
                     "not the inertia over the nose")
        warnings.append(text)
    return summary, warnings


def elastic_row(result) -> dict[str, float]:
    """A sweep row's elastic figures from a run (its summary, events in time order and columns; the
    lash effect's take-up events give the lift-off delay). The separations counted are the valve's
    float, those while it is open (valve_periods); the flight time (from each of them to the valve's
    re-contact or landing, event to event) and the largest bounce are valve_periods' too."""
    summary, events = result.summary, result.events
    elastic = [e for e in events if e.effect == "elastic"]
    period = float(summary["revolution_time_s"])
    seats = [e for e in elastic if e.kind == "seat"]
    lift_offs = [float(e.time_s) for e in elastic if e.kind == "lift-off"]
    ups = [float(e.time_s) for e in events if e.kind == "lash-take-up"]
    columns = result.columns
    periods = valve_periods(columns["time_s"], columns["valve_lift_m"], columns["rigid_valve_lift_m"],
                            columns["rigid_valve_velocity_m_s"],
                            [e for e in elastic if e.kind in ("separation", "re-contact", "seat")], period)
    floats = periods.floats
    row = {
        "first_separation_deg": float(floats[0].cam_angle_deg) if floats else math.nan,
        "separations": float(len(floats)),
        "flight_time_s": periods.flight_s,
        "max_deviation_m": float(summary["max_deviation_m"]),
        "peak_linkage_force_N": float(summary["peak_linkage_force_N"]),
        "peak_camshaft_back_pressure_N": float(summary["peak_camshaft_back_pressure_N"]),
        "lift_off_delay_s": (min(math.fmod(t - ups[0] + period, period) for t in lift_offs)
                             if ups and lift_offs else math.nan),
        "seating_velocity_m_s": min(float(e["velocity_m_s"]) for e in seats) if seats else math.nan,
        "seat_impacts": float(len(seats)),
        "largest_bounce_m": periods.bounce,
    }
    for name in ("residual_deviation_m", "residual_amplitude_m"):  # the elastic effect's (effects/residual.py)
        value = summary.get(name)
        row[name] = math.nan if value is None else float(value)
    return row


class ValvePeriods(NamedTuple):
    """What valve_periods finds in a revolution."""

    floats: list  # the separations while the valve is open (its float), in time order
    bounce: float  # m, the largest bounce
    flight_s: float  # s, the time the valve flies off the linkage in its float


def valve_periods(time_s, lift, rigid_lift, rigid_velocity, events, period: float) -> ValvePeriods:
    """(the separations while the valve is open: its float, in time order; the largest bounce; the
    float's flight time) of a revolution of `period` s on its output grid (time_s, the valve's lift,
    the rigid valve's lift and velocity: open where its lift is > 0, the kinematics' test ratio L >
    lash) from its events in time order (kinds "separation", "re-contact" and "seat"; others are
    ignored). The compiled path computes the same: dynamics/kernel_figures.py, _valve_periods.

    The revolution is walked once, periodically, from the rigid valve's first opening on the grid
    (the lash take-up: the first sample where it is open after one where it is closed; column 0
    when it never opens or never closes), each event at the first sample after it (an event within
    the grid step before an opening counts as after it). The valve is *open* from each opening to
    its first seat impact after it: a separation there is float. From that impact to the next
    opening it is *seated*: the highest lift on those samples (strictly after the impact) is its
    bounce -- what the valve does after it has landed, before the cam opens it again, the flight
    of every rebound and the Zeno tail's summed chatter included; 0 without a seat impact (a valve
    that never seats floats; its separations say so). A seat impact before the rigid closing point
    (the linkage's compression seats the elastic valve while the closing ramp still has a few um
    of rigid lift, W/k) starts the seated period there: what follows on the ramp's end is bounce,
    the ramp lifting the valve again by at most what it has left. A separation after the seat
    impact (the rebound leaving the linkage, a lifter bouncing on the base circle inside the lash)
    is not float. The same for every model: the walk reads no lift-off (the massless linkage's is
    the cam lifting a resting valve, the spring chain's and the train's each crossing of the seat
    upwards, every rebound too), and a separation is any contact's (the train's joints: its
    lifter leaving the cam included). A valve still bouncing when the cam opens it again is open
    from that opening: a seat impact while the rigid valve is open and rising (at the sample after
    it) ends no open period, and what the cam then lifts is no bounce.

    Flight: each float separation's flight lasts from its instant to the next re-contact or seat
    impact (the valve back on the linkage, or landed: its open period ends there), from the exact
    event times (t_end - t_sep, plus the period where the end is in the next revolution: the walk
    goes round once more for it); with neither in the revolution (a valve still flying when the run
    ends) to the walk's end, the first opening's sample. A separation while the valve is already
    flying starts no second flight. The flights of the bounce (after the seat impact) are not in it:
    the bounce's figures are the largest bounce and the seat impacts."""
    t = np.asarray(time_s, dtype=float)
    s = np.asarray(lift, dtype=float)
    rigid_open = np.asarray(rigid_lift, dtype=float) > 0.0
    rising = rigid_open & (np.asarray(rigid_velocity, dtype=float) > 0.0)
    n = t.size
    opens = rigid_open & ~np.roll(rigid_open, 1)
    ups = np.flatnonzero(opens)
    start = int(ups[0]) if ups.size else 0
    # walk positions (samples from `start`) of the openings and of the sample after each event
    walk_opens = np.roll(opens, -start)
    at = (np.searchsorted(t, [float(e.time_s) for e in events], side="right") % n - start) % n
    order = np.argsort(at, kind="stable")  # (events of one sample keep their time order)
    walk_s = np.roll(s, -start)
    walk_rising = np.roll(rising, -start)
    breaks = sorted({0, *np.flatnonzero(walk_opens).tolist(), *at.tolist()}) + [n]
    floats, best, seated, q = [], 0.0, False, 0
    flight, flying = 0.0, None  # flying: the time of the float separation the valve flies from
    for b, end in zip(breaks[:-1], breaks[1:]):  # the state holds from a break to the next
        if walk_opens[b]:
            seated = False
        while q < order.size and at[order[q]] == b:
            e = events[order[q]]
            q += 1
            if e.kind in ("seat", "re-contact") and flying is not None:
                flight += _elapsed(flying, float(e.time_s), period)
                flying = None
            if e.kind == "seat":
                seated = seated or not walk_rising[b]
            elif e.kind == "separation" and not seated:
                floats.append(e)
                if flying is None:
                    flying = float(e.time_s)
        if seated:
            best = max(best, float(walk_s[b:end].max()))
    if flying is not None:  # round once more to the end of the flight, or to the walk's end
        ends = [float(events[i].time_s) for i in order if events[i].kind in ("seat", "re-contact")]
        flight += _elapsed(flying, ends[0] if ends else float(t[start]), period)
    floats.sort(key=lambda e: e.time_s)
    return ValvePeriods(floats, best, flight)


def _elapsed(t0: float, t1: float, period: float) -> float:
    """The time from t0 to t1 (both within the revolution), t1 in the next revolution when before
    t0 (kernel_figures._elapsed: the same operations)."""
    d = t1 - t0
    return d + period if d < 0.0 else d
