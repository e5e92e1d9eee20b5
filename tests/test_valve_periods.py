"""The valve's open and seated periods (effects/elastic_events.valve_periods and the compiled
kernel_figures._valve_periods): float is a separation while the valve is open (from the rigid
opening to its first seat impact), its flight time runs from each such separation to the next
re-contact or seat impact (event to event), the largest bounce is the highest lift from a seat
impact to the next rigid opening. The bounce against the closed form of a free rebound, the
flight against the closed form of the free flight and against a count of the output samples, the
walk's rules on hand-made revolutions, the float rule on the pushrod train, and the audit's
scenes."""

from __future__ import annotations

import math

import numpy as np
import pytest

import explorer
from explorer import load_scene
from explorer.effects.elastic_events import elastic_row, valve_periods
from explorer.result import Event
from explorer.studies.sweep_spec import scene_for

ELASTIC_FLOAT = "assets/scenes/elastic_float.toml"
PUSHROD_TRAIN = "assets/scenes/pushrod_train.toml"


@pytest.mark.parametrize("rpm, restitution", [(4200.0, 0.3), (5000.0, 0.3), (4200.0, 0.6)])
def test_largest_bounce_is_the_free_rebound_height(rpm, restitution):
    """A valve that floats over the closing flank lands on its seat after the rigid closing, on the
    base circle, where the linkage (lash open) cannot touch it: it rebounds at v_r = -e v_impact and
    flies under its spring only, the preload W0 (closing load included) and friction R against
    it on the way up and the rate k growing with lift, so M v_r^2 / 2 = (W0 + R) s + k s^2 / 2:
    s_max = (sqrt((W0 + R)^2 + k M v_r^2) - (W0 + R)) / k. The later rebounds are lower (e < 1), so
    the largest bounce is this one. On the output grid (step dt) its apex is missed by at most half
    a step: s_max - (W0 + R + k s_max) / M * dt^2 / 8 <= figure <= s_max (1e-12 m: the exact
    solver's rounding; the bound itself is ~1e-11 m here, so the figure is the apex to 1e-8)."""
    scene = scene_for(load_scene(ELASTIC_FLOAT), ["drive.rpm", "seat.restitution"], [rpm, restitution])
    result = explorer.simulate(scene)
    seats = [e for e in result.events if e.effect == "elastic" and e.kind == "seat"]
    rigid_closing = result.summary["seating_angles_deg"][0]
    assert seats[0].cam_angle_deg > rigid_closing + 1.0  # lands on the base circle: a free rebound
    W0R = scene.spring.preload + scene.loads.closing_total + scene.loads.friction
    k, M = scene.spring.rate, scene.valve.mass
    v_r = -restitution * float(seats[0]["velocity_m_s"])
    s_max = (math.sqrt(W0R**2 + k * M * v_r**2) - W0R) / k
    dt = 2.0 * math.pi / scene.drive.omega / scene.solver.steps_per_revolution
    sampling = (W0R + k * s_max) / M * dt**2 / 8.0
    figure = elastic_row(result)["largest_bounce_m"]
    assert s_max - sampling - 1e-12 <= figure <= s_max + 1e-12
    assert s_max > 1e-4  # (a rebound of a tenth of a millimetre or more: the test is not about zero)
    # the compiled sweep path: the same figure
    swept = explorer.sweep(scene, vary={"drive.rpm": [rpm]}, workers=1).columns["largest_bounce_m"][0]
    assert swept == pytest.approx(figure, abs=1e-12)


def _events(*items):
    return [Event(kind, t, 30.0 * t) for kind, t in items]


def _periods(t, s, rigid, events):
    """valve_periods (a revolution of t.size time units) with a rigid lift of 1 where `rigid` is
    open, rising on the first half of each opening (velocity +1) and falling on the rest (-1)."""
    velocity = np.zeros(t.size)
    for run in np.split(np.flatnonzero(rigid), np.flatnonzero(np.diff(np.flatnonzero(rigid)) > 1) + 1):
        velocity[run[: (run.size + 1) // 2]] = 1.0
        velocity[run[(run.size + 1) // 2:]] = -1.0
    return valve_periods(t, s, rigid.astype(float), velocity, events, float(t.size))


def _walk(t, s, rigid, events):
    """(floats, largest bounce) of _periods."""
    p = _periods(t, s, rigid, events)
    return p.floats, p.bounce


def test_walk_rules_on_a_hand_made_revolution():
    """12 samples at t = 0..11 (one revolution of 12): the rules of valve_periods one by one."""
    t = np.arange(12.0)
    s = np.array([0.0, 0.0, 1.0, 5.0, 4.0, 0.0, 0.3, 0.9, 0.2, 0.0, 0.0, 0.0])
    rigid = np.array([0, 0, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0], bool)  # opens at sample 2, closes after 5
    # float during the lift, a seat at 4.5 (before the rigid closing), a separation after it (the
    # rebound): the bounce is the highest sample after the impact up to the next opening (0.9)
    ev = _events(("separation", 3.2), ("seat", 4.5), ("separation", 4.7), ("seat", 8.5))
    floats, bounce = _walk(t, s, rigid, ev)
    assert [e.time_s for e in floats] == [3.2] and bounce == 0.9
    # no seat impact: every separation is float (the valve never landed), no bounce
    floats, bounce = _walk(t, s, rigid, _events(("separation", 3.2), ("separation", 7.5)))
    assert len(floats) == 2 and bounce == 0.0
    # the window wraps round the revolution to the next opening (sample 2): a lift at sample 0 or
    # 1 after a late seat impact is bounce, and the opening's own lift is not
    s2 = s.copy()
    s2[1] = 1.5
    floats, bounce = _walk(t, s2, rigid, _events(("seat", 9.5)))
    assert floats == [] and bounce == 1.5
    # a seat impact in the grid step before the end of the revolution belongs to sample 0
    floats, bounce = _walk(t, s2, rigid, _events(("seat", 11.5)))
    assert bounce == 1.5
    # two openings a revolution: each opening has its own open and seated periods
    s3 = np.array([0.0, 0.0, 3.0, 0.5, 0.0, 0.2, 0.0, 0.0, 2.0, 0.7, 0.0, 0.4])
    rigid3 = np.array([0, 0, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0], bool)
    ev3 = _events(("separation", 2.5), ("seat", 3.5), ("separation", 5.5), ("separation", 8.2), ("seat", 9.5))
    floats, bounce = _walk(t, s3, rigid3, ev3)
    assert [e.time_s for e in floats] == [2.5, 8.2] and bounce == 0.4  # samples 4-7 and 10-1 (not 8's 2.0)
    # a valve still bouncing when the cam opens it again is open from that opening: its landings
    # while the rigid valve rises end no open period, and what the cam then lifts is no bounce; a
    # landing on the closing side (sample 4 falls) does
    floats, bounce = _walk(t, s, rigid, _events(("seat", 1.5), ("seat", 2.5), ("separation", 3.0)))
    assert bounce == 0.0 and [e.time_s for e in floats] == [3.0]
    floats, bounce = _walk(t, s, rigid, _events(("seat", 2.5), ("seat", 3.5), ("separation", 4.2)))
    assert bounce == 4.0 and floats == []


def test_flight_rules_on_a_hand_made_revolution():
    """12 samples at t = 0..11 (a revolution of 12 time units), the rigid valve open on samples
    2-5: each float separation flies to the next re-contact or seat impact, by the events' exact
    instants (not the samples between them)."""
    t = np.arange(12.0)
    s = np.array([0.0, 0.0, 1.0, 5.0, 4.0, 0.0, 0.3, 0.9, 0.2, 0.0, 0.0, 0.0])
    rigid = np.array([0, 0, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0], bool)
    # two float flights (to a re-contact, to the landing); the rebound's own flight after the seat
    # impact (4.7 to 4.9) is the bounce's, not the float's: 0.7 + 0.4
    p = _periods(t, s, rigid, _events(("separation", 3.2), ("re-contact", 3.9), ("separation", 4.1), ("seat", 4.5),
                                      ("separation", 4.7), ("re-contact", 4.9)))
    assert len(p.floats) == 2 and p.flight_s == pytest.approx(1.1, abs=1e-15)
    # two separations in one sample and both flights shorter than a sample: 0.1 + 0.2, no sample
    # between (a count of samples would say 0)
    p = _periods(t, s, rigid, _events(("separation", 3.2), ("re-contact", 3.3), ("separation", 3.5),
                                      ("re-contact", 3.7)))
    assert p.flight_s == pytest.approx(0.3, abs=1e-15)
    # a valve that never lands flies round the revolution's end: the flight from 10.5 ends at the
    # re-contact at 1.5 of the next revolution (the walk goes round once more for it): 3
    p = _periods(t, s, rigid, _events(("re-contact", 1.5), ("separation", 10.5)))
    assert p.flight_s == pytest.approx(3.0, abs=1e-15) and len(p.floats) == 1
    # nothing ends it in the revolution: to the walk's end, the first opening (t = 2): 12 - 3.2 + 2
    p = _periods(t, s, rigid, _events(("separation", 3.2)))
    assert p.flight_s == pytest.approx(10.8, abs=1e-15)
    # a second separation while flying (no re-contact between: the train's cam contact reports
    # each) starts no second flight: 3.2 to 4.0
    p = _periods(t, s, rigid, _events(("separation", 3.2), ("separation", 3.5), ("re-contact", 4.0)))
    assert p.flight_s == pytest.approx(0.8, abs=1e-15) and len(p.floats) == 2
    # no float: no flight, whatever the bounce does
    p = _periods(t, s, rigid, _events(("seat", 4.5), ("separation", 4.7), ("re-contact", 6.0)))
    assert p.flight_s == 0.0 and p.floats == []


def _free_flights(scene, result):
    """The float's flights of a run with an undamped linkage and no friction, in closed form from
    each float separation's instant t_s and velocity v0 (the events'): off the linkage the valve
    obeys M s'' = -(W0 + k s) (dynamics/model.py, W0 the preload and closing loads, k the spring
    rate), so s(tau) = -W0/k + (s0 + W0/k) cos(w tau) + v0/w sin(w tau), w = sqrt(k/M), from
    s0 = ratio L(omega t_s) - lash (the undamped linkage lets go at zero compression). It lands
    at the first root of s = 0, tau = (phi + acos((W0/k) / R)) / w with R cos(w tau - phi) the
    oscillating part; the cam catches it first where ratio L(omega (t_s + tau)) - lash rises
    through s(tau) (a sign change on 20 001 points before the landing, then Brent to 1e-16 s).
    Returns [(tau, "re-contact" or "seat")] of each float separation (before the first seat
    impact)."""
    from scipy.optimize import brentq

    from explorer.effects.lift import build_lift

    lift, omega, ratio = build_lift(scene), scene.drive.omega, scene.follower.ratio
    W0, k = scene.spring.preload + scene.loads.closing_total, scene.spring.rate
    M, lash = scene.valve.mass, scene.valve.lash
    w = math.sqrt(k / M)
    elastic = [e for e in result.events if e.effect == "elastic"]
    landed = min(e.time_s for e in elastic if e.kind == "seat")
    flights = []
    for e in elastic:
        if e.kind != "separation" or e.time_s > landed:
            continue
        t_s, v0 = float(e.time_s), float(e["velocity_m_s"])
        a, b = ratio * lift.derivatives(np.array([omega * t_s]))[0][0] - lash + W0 / k, v0 / w

        def gap(tau):
            tau = np.atleast_1d(tau)
            cam = ratio * lift.derivatives(omega * (t_s + tau))[0] - lash
            return cam - (-W0 / k + a * np.cos(w * tau) + b * np.sin(w * tau))

        seat = (math.atan2(b, a) + math.acos(W0 / k / math.hypot(a, b))) / w
        taus = np.linspace(1e-9, seat, 20001)
        g = gap(taus)
        up = np.flatnonzero((g[:-1] < 0.0) & (g[1:] >= 0.0))
        if up.size:
            flights.append((brentq(lambda x: gap(x)[0], taus[up[0]], taus[up[0] + 1], xtol=1e-16, rtol=1e-15),
                            "re-contact"))
        else:
            flights.append((seat, "seat"))
    return flights


@pytest.mark.parametrize("rpm, ends", [(4000.0, ("re-contact",) * 3), (5000.0, ("seat",))])
def test_flight_time_is_the_free_flights_closed_form(rpm, ends):
    """The elastic float scene without linkage damping and friction: at 4000 rpm three float
    flights each end with the cam catching the valve, at 5000 rpm the one flight ends on the seat
    (thrown over the closing flank). flight_time_s is the sum of the closed-form flights (_free_flights)
    in simulate and in the compiled sweep. Tolerance 1e-12 s: the exact solver finds its events to
    rounding (1e-18 s here), the compiled path's instants agree with simulate's to TIME_TOL_S
    (tests/test_sweep_kernel.py), far inside the 4 us output step."""
    base = load_scene(ELASTIC_FLOAT, ['linkage.damping="0 N*s/m"', 'loads.friction="0 N"'])
    scene = scene_for(base, ["drive.rpm"], [rpm])
    result = explorer.simulate(scene)
    flights = _free_flights(scene, result)
    assert tuple(kind for _, kind in flights) == ends
    row = elastic_row(result)
    closed = sum(tau for tau, _ in flights)
    assert row["separations"] == len(flights)
    assert row["flight_time_s"] == pytest.approx(closed, abs=1e-12)
    swept = explorer.sweep(base, vary={"drive.rpm": [rpm]}, workers=1).columns["flight_time_s"][0]
    assert swept == pytest.approx(closed, abs=1e-12)


def test_flight_time_against_the_count_of_output_samples():
    """The elastic float scene (4000 rpm, damped linkage, friction): the output samples off the
    linkage with the valve open, from the rigid opening to the first seat impact, times the step
    estimate the float's flight time to one step per flight (each flight's ends fall between two
    samples). And the audit's finger follower at 3300 rpm: no float, so no flight -- its 11
    samples off the linkage (5.56e-5 s, the figure before) are the bounce's, after the seat
    impact."""
    result = explorer.simulate(load_scene(ELASTIC_FLOAT))
    row = elastic_row(result)
    c = result.columns
    t, s, off = (np.asarray(c[name]) for name in ("time_s", "valve_lift_m", "valve_in_contact"))
    rigid = np.asarray(c["rigid_valve_lift_m"]) > 0.0
    opening = t[np.flatnonzero(rigid & ~np.roll(rigid, 1))[0]]
    landed = min(e.time_s for e in result.events if e.effect == "elastic" and e.kind == "seat")
    step = t[1] - t[0]
    count = np.count_nonzero((off < 0.5) & (s > 0.0) & (t >= opening) & (t < landed))
    assert row["separations"] == 3 and row["flight_time_s"] > 10 * step
    assert abs(row["flight_time_s"] - count * step) <= row["separations"] * step
    finger = explorer.simulate(scene_for(load_scene("assets/scenes/finger_follower.toml"), ["drive.rpm"], [3300.0]))
    off = np.asarray(finger.columns["valve_in_contact"]) < 0.5
    assert np.count_nonzero(off & (np.asarray(finger.columns["valve_lift_m"]) > 0.0)) == 11
    assert elastic_row(finger)["flight_time_s"] == 0.0 and elastic_row(finger)["separations"] == 0


def test_a_separation_after_the_seat_impact_is_not_float():
    """The elastic float scene's valve lands at 177.8 deg while the closing ramp still pushes (the
    rigid valve seats at 178.7 deg), rebounds with the linkage and leaves it at 178.1 deg: that
    separation is the bounce's, not float (the three on the flanks are)."""
    result = explorer.simulate(load_scene(ELASTIC_FLOAT))
    elastic = [e for e in result.events if e.effect == "elastic"]
    seat = next(e for e in elastic if e.kind == "seat")
    after = [e for e in elastic if e.kind == "separation" and e.time_s > seat.time_s]
    assert seat.cam_angle_deg < result.summary["seating_angles_deg"][0] and len(after) == 1
    row = elastic_row(result)
    before = [e for e in elastic if e.kind == "separation" and e.time_s < seat.time_s]
    assert row["separations"] == len(before) == 3
    assert row["first_separation_deg"] == before[0].cam_angle_deg
    swept = explorer.sweep(load_scene(ELASTIC_FLOAT), vary={"drive.rpm": [4000.0]}, workers=1).columns
    assert swept["separations"][0] == 3 and swept["first_separation_deg"][0] == pytest.approx(
        before[0].cam_angle_deg, abs=1e-9)


def _judge(path, name, rpm):
    return explorer.check(load_scene(path), rpm=rpm, only=(name,), workers=1).result(name)


def test_pushrod_train_floats_at_the_nose_not_on_the_base_circle():
    """At 500 and 1000 rpm the train's lifter bounces on the base circle inside the lash after the
    valve has seated (a cam separation at 186.4 deg; the rigid valve seats at 186.5): no float. Its
    nose separation begins near 2480 rpm at 87 deg."""
    slow = _judge(PUSHROD_TRAIN, "float_margin", "500,1000")
    assert slow.verdict == "pass"
    fast = _judge(PUSHROD_TRAIN, "float_margin", "1000,2000,3000")
    assert fast.verdict == "fail" and 2400.0 < fast.speed_rpm < 2600.0
    assert 80.0 < float(fast.cam_angle_deg) < 95.0


# the audit's scenes: largest_bounce_m (and float counts) at their own speeds, each bounce equal to
# the valve's highest lift in the CSV after the first seat impact (before the next opening, which
# the revolution does not reach again after 0 deg in these scenes). The elastic seat letting go
# where its force falls to 0 (not at s = 0, its damper pulling) raised spring_surge's from
# 158.82 um and pushrod_train's from 8.400 um (docs/theory/spring-chain.md)
AUDIT = {
    "spring_surge": (1.600324122676291e-04, 14, 2),
    "elastic_float": (1.0875441457495925e-03, 10, 3),
    "pushrod_train": (8.523676813506128e-06, 5, 0),
}


@pytest.mark.parametrize("name", sorted(AUDIT))
def test_audit_scenes_bounce_and_float(name):
    height, impacts, floats = AUDIT[name]
    result = explorer.simulate(load_scene(f"assets/scenes/{name}.toml"))
    row = elastic_row(result)
    t, s = np.asarray(result.columns["time_s"]), np.asarray(result.columns["valve_lift_m"])
    first = min(e.time_s for e in result.events if e.effect == "elastic" and e.kind == "seat")
    assert row["largest_bounce_m"] == s[t > first].max()
    assert row["largest_bounce_m"] == pytest.approx(height, rel=1e-9)
    assert (row["seat_impacts"], row["separations"]) == (impacts, floats)


def test_seat_bounce_rule_sees_the_spring_surge_bounces():
    """spring_surge bounces 0.16 mm after its first seat impact (13 more impacts): the rule fails it
    (it passed with 0 before the bounce's window reached past the rebound's own lift-off)."""
    r = _judge("assets/scenes/spring_surge.toml", "seat_bounce", None)
    assert r.verdict == "fail" and r.value == 13
