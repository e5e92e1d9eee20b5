"""separated_angle_deg and the trip gear's float keys are the solver's events', not the output
samples' (audit of docs/reference/summary.md: the figure was 360 x the share of separated samples,
so it moved by up to a sample with steps_per_revolution, and the trip gear wrote no float keys).

Oracles: (1) the exact solvers place each event independently of the output grid (their event
angles agree to ~1e-10 deg between 3600 and 36000 steps here), so an event-based figure agrees
between the two resolutions to 1e-9 deg, where the sample count differs by up to 0.12 deg;
(2) the sum of each flight's angle straight from the event list, walked here on its own."""

import dataclasses
import math

import numpy as np
import pytest

from conftest import SCENES
from explorer.effects.pipeline import simulate
from explorer.effects.elastic_events import separated_angle_deg
from explorer.scene.scene import load_scene


def run(name: str, steps: int):
    sc = load_scene(SCENES / f"{name}.toml")
    return simulate(dataclasses.replace(sc, solver=dataclasses.replace(sc.solver, steps_per_revolution=steps)))


def flights_deg(events, stop_deg: float = math.inf) -> float:
    """Each separation's flight: to the next re-contact or seat impact (or stop_deg), summed; the
    events in time order, none of the flights crossing the revolution's end (checked)."""
    total, start = 0.0, None
    for e in events:
        if e.cam_angle_deg >= stop_deg:
            break
        if e.kind == "separation" and start is None:
            start = e.cam_angle_deg
        elif e.kind in ("re-contact", "seat") and start is not None:
            total += e.cam_angle_deg - start
            start = None
    assert start is None or stop_deg < math.inf
    return total + (stop_deg - start if start is not None else 0.0)


@pytest.mark.parametrize("name", ["valve_float_demo", "elastic_float", "spring_surge"])
def test_separated_angle_does_not_move_with_the_output_step(name):
    coarse, fine = run(name, 3600), run(name, 36000)
    a, b = coarse.summary["separated_angle_deg"], fine.summary["separated_angle_deg"]
    assert a == pytest.approx(b, abs=1e-9)
    # the sample count it replaced: off by up to a sample (0.1 deg) at 3600 steps
    c = coarse.columns
    counted = 360.0 * np.mean((c["valve_lift_m"] > 0.0) & (c["valve_in_contact"] < 0.5))
    assert abs(counted - a) > 1e-3 and abs(counted - a) < 2 * 0.1 * (1 + sum(e.effect == "elastic" for e in coarse.events))


def test_separated_angle_is_the_flights_between_the_events():
    # the massless linkage without a bounce (restitution 0): separation to re-contact or landing
    r = run("valve_float_demo", 3600)
    events = [e for e in r.events if e.effect == "elastic"]
    assert [e.kind for e in events].count("separation") == 3
    assert r.summary["separated_angle_deg"] == pytest.approx(flights_deg(events), abs=1e-9)


def test_trip_gear_separated_angle_and_float_are_the_latched_phase_flights():
    """The trip gear's valve is free by design after the trip: only its flights off the latch
    before the trip count, both in separated_angle_deg and in the float keys."""
    for steps in (3600, 36000):
        r = run("trip_gear_dashpot", steps)
        s = r.summary
        events = [e for e in r.events if e.effect == "elastic"]
        trip = next(e.cam_angle_deg for e in events if e.kind == "release")
        latched = [e for e in events if e.cam_angle_deg < trip]
        seps = [e for e in latched if e.kind == "separation"]
        assert len(seps) == 3  # the pick-up's vibration throws the valve off the latch three times
        assert s["separated_angle_deg"] == pytest.approx(flights_deg(latched, trip), abs=1e-9)
        assert s["float_separations"] == len(seps)
        assert s["first_separation_deg"] == seps[0].cam_angle_deg
        # the same flights in time: each from its separation to the next re-contact (event times)
        times = [e.time_s for e in latched if e.kind in ("separation", "re-contact")]
        assert s["float_flight_time_s"] == pytest.approx(sum(np.diff(times)[::2]), rel=1e-9)
        assert s["elastic_trip"]["separations_before_trip"] == len(seps)


def test_a_stretch_shorter_than_the_step_takes_its_events_state():
    # a flight between two samples: no sample sees it, the events do
    t = np.arange(10) * 0.1
    sep = np.zeros(10, bool)
    got = separated_angle_deg(t, sep, [(0.42, "separation"), (0.43, "re-contact")], 1.0)
    assert got == pytest.approx(360.0 * 0.01, abs=1e-12)
    # a flight through the revolution's end (from the previous revolution): the wrap-round stretch
    sep = (t > 0.85) | (t < 0.15)
    got = separated_angle_deg(t, sep, [(0.12, "re-contact"), (0.87, "separation")], 1.0)
    assert got == pytest.approx(360.0 * 0.25, abs=1e-12)


def test_trip_float_walk_by_hand():
    """latched_float on made-up events (cam angles, pick-up at 0 deg, trip at 100 deg, w = 1 rad/s
    so a flight's time is its angle in rad): a flight still off the latch at the trip ends there;
    a separation after a seat impact is the rebound's, until the latch lifts the valve again."""
    from explorer.gears.trip_latched import latched_float

    def ev(kind, deg):
        return {"kind": kind, "time_s": math.radians(deg), "cam_angle_deg": deg}

    trip = math.radians(100.0)
    events = [ev("lift-off", 10.0), ev("separation", 20.0), ev("re-contact", 25.0), ev("seat", 40.0),
              ev("separation", 45.0), ev("lift-off", 50.0), ev("separation", 90.0), ev("release", 100.0),
              ev("seat", 120.0)]
    got = latched_float(events, lambda th: th, trip, 1.0)
    assert got["float_separations"] == 2 and got["first_separation_deg"] == 20.0
    assert got["float_flight_time_s"] == pytest.approx(math.radians(5.0 + 10.0), rel=1e-14)
    assert latched_float([ev("lift-off", 10.0)], lambda th: th, trip, 1.0) == {
        "first_separation_deg": None, "float_separations": 0, "float_flight_time_s": 0.0}
