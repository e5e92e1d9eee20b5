"""Trip gear: latch pick-up, release, free closing against friction, air and oil dashpots.

Oracles: closed forms of the free closing (constant force: t = sqrt(2h/p); with a spring: a
cosine; with an upward start: apex then fall, friction changing sign), Trinks' rule (seed 003)
reproduced by the closing model, the oil cushion's closed form v^2(y) under constant force, the
energy balance of a sealed air cushion (polytropic work in closed form), mass conservation of a
leaking cushion, and the eccentric latch's pick-up velocity omega sqrt(s_o (2e - s_o)).
Tolerances: the ODE runs at rtol 1e-11, so 1e-8 relative is a safe bound for closed forms.
"""

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

from explorer.errors import InputError
from explorer.gears.dashpot import AirDashpot, OilDashpot, cylinder_area, oil_seating_velocity
from explorer.gears.trip import ClosingModel, compare_buffers, simulate_closing
from explorer.kinematics import lash_crossings
from explorer.lift import build_lift
from explorer.scene import load_scene
from explorer.springs import TRINKS_G, trinks_closing_force

SCENE = Path(__file__).resolve().parent.parent / "assets" / "scenes" / "trip_gear_dashpot.toml"
M = 3.0


def test_free_closing_from_rest_under_constant_force():
    model = ClosingModel(mass=M, preload=300.0, rate=0.0, closing=29.4, friction=20.0)
    h = 0.02
    sol = simulate_closing(model, h, 0.0, 1.0)
    p = (300.0 + 29.4 - 20.0) / M
    assert sol.seat_time == pytest.approx(math.sqrt(2 * h / p), rel=1e-10)
    assert sol.seat_velocity == pytest.approx(-math.sqrt(2 * h * p), rel=1e-10)


def test_upward_start_apex_then_fall_with_friction_changing_sign():
    """Released while still rising: decelerates with (F + R)/M to the apex, falls with (F - R)/M."""
    model = ClosingModel(mass=M, preload=200.0, rate=0.0, closing=29.4, friction=30.0)
    h, v0 = 0.015, 0.4
    sol = simulate_closing(model, h, v0, 1.0)
    up, down = (229.4 + 30.0) / M, (229.4 - 30.0) / M
    t_apex = v0 / up
    apex = h + v0**2 / (2 * up)
    assert sol.apex == pytest.approx(apex, rel=1e-10)
    assert [e["kind"] for e in sol.events] == ["apex", "seat"]
    assert sol.events[0]["t"] == pytest.approx(t_apex, rel=1e-10)
    assert sol.seat_time == pytest.approx(t_apex + math.sqrt(2 * apex / down), rel=1e-10)


def test_closing_with_spring_rate_is_a_cosine():
    """M s'' = -(F0 + k s): s = -F0/k + (h + F0/k) cos(wn t), seat where s = 0."""
    k, f0 = 20_000.0, 300.0 + 29.4 - 20.0
    model = ClosingModel(mass=M, preload=300.0, rate=k, closing=29.4, friction=20.0)
    h = 0.02
    sol = simulate_closing(model, h, 0.0, 1.0)
    wn = math.sqrt(k / M)
    t_seat = math.acos((f0 / k) / (h + f0 / k)) / wn
    assert sol.seat_time == pytest.approx(t_seat, rel=1e-10)
    assert sol.seat_velocity == pytest.approx(-(h + f0 / k) * wn * math.sin(wn * t_seat), rel=1e-9)


def test_trinks_rule_reproduced_by_the_closing_model():
    """Seed 003: P_f = (p/g - 1) G_v + W_s closes the valve over h in time t from rest (p = 2h/t^2).
    The spring force from the rule, with the valve weight G_v = M g and the friction W_s, makes the
    model close in exactly t."""
    h, t = 0.025, 0.04
    weight = M * TRINKS_G
    force = trinks_closing_force(h, t, weight, 25.0)
    model = ClosingModel(mass=M, preload=force, rate=0.0, closing=weight, friction=25.0)
    sol = simulate_closing(model, h, 0.0, 1.0)
    assert sol.seat_time == pytest.approx(t, rel=1e-10)


def test_hang_when_friction_exceeds_the_closing_force():
    sol = simulate_closing(ClosingModel(mass=M, preload=10.0, rate=0.0, closing=5.0, friction=20.0), 0.01, 0.0, 0.5)
    assert sol.hang and not sol.seated


def test_oil_cushion_matches_its_closed_form():
    """Constant net force F (no spring rate): v^2(y) = F/c + (v_in^2 - F/c) exp(-2 c y / M)."""
    oil = OilDashpot(area=cylinder_area(0.03), stroke=0.006, orifice_area=cylinder_area(0.004))
    model = ClosingModel(mass=M, preload=300.0, rate=0.0, closing=29.4, friction=20.0, buffer=oil)
    h = 0.02
    sol = simulate_closing(model, h, 0.0, 1.0)
    net = 300.0 + 29.4 - 20.0
    v_in = math.sqrt(2 * (h - oil.stroke) * net / M)
    want = oil_seating_velocity(M, net, oil.coefficient, v_in, oil.stroke)
    assert abs(sol.seat_velocity) == pytest.approx(want, rel=1e-8)
    entry = [e for e in sol.events if e["kind"] == "dashpot-entry"][0]
    assert entry["s"] == pytest.approx(oil.stroke, abs=1e-15)
    assert abs(entry["v"]) == pytest.approx(v_in, rel=1e-10)


def test_sealed_air_cushion_conserves_energy():
    """No leak, no friction, no spring rate: 1/2 M v_seat^2 = 1/2 M v_in^2 + F y - W_air(y), with
    the polytropic work in closed form."""
    air = AirDashpot(area=cylinder_area(0.05), stroke=0.006, clearance=0.002, orifice_area=0.0)
    model = ClosingModel(mass=M, preload=300.0, rate=0.0, closing=29.4, friction=0.0, buffer=air)
    h = 0.02
    sol = simulate_closing(model, h, 0.0, 1.0)
    net = 329.4
    energy = 0.5 * M * 0.0 + net * h - air.sealed_work(air.stroke)
    assert sol.seated
    assert 0.5 * M * sol.seat_velocity**2 == pytest.approx(energy, rel=1e-8)


def test_sealed_air_cushion_throws_the_valve_back_where_the_energy_runs_out():
    """A stiffer pocket stops the valve short of the seat: at the turning point the work of the
    air equals the energy brought in, F (h - s) = W_air(stroke - s); then it rebounds."""
    air = AirDashpot(area=cylinder_area(0.09), stroke=0.006, clearance=0.001, orifice_area=0.0)
    model = ClosingModel(mass=M, preload=300.0, rate=0.0, closing=29.4, friction=0.0, buffer=air)
    h = 0.02
    sol = simulate_closing(model, h, 0.0, 0.05)
    first = [e for e in sol.events if e["kind"] == "rebound"][0]
    turn = brentq(lambda s: 329.4 * (h - s) - air.sealed_work(air.stroke - s), 1e-9, air.stroke - 1e-9)
    assert first["s"] == pytest.approx(turn, rel=1e-8)
    assert not sol.seated  # sealed and frictionless: it bounces for ever


def test_leaking_air_cushion_conserves_mass():
    """Gas in the pocket at the seat plus what left through the orifice equals the air trapped at
    the entry (the outflow integrated independently along the dense solution)."""
    air = AirDashpot(area=cylinder_area(0.07), stroke=0.006, clearance=0.001, orifice_area=cylinder_area(0.002))
    model = ClosingModel(mass=M, preload=300.0, rate=5000.0, closing=29.4, friction=20.0, buffer=air)
    sol = simulate_closing(model, 0.02, 0.2, 1.0)
    segs = [seg for seg in sol.segments if seg.engaged]
    assert len(segs) == 1
    seg = segs[0]
    m0 = air.ambient_density * air.volume(air.stroke)
    out, _ = quad(lambda t: air.mass_outflow(seg.sol(t)[2]), seg.t0, seg.t1, epsabs=1e-16, epsrel=1e-11, limit=200)
    rho_end = seg.sol(seg.t1)[2]
    m_end = rho_end * air.volume(0.0)
    assert m_end + out == pytest.approx(m0, rel=1e-8)


def test_buffers_compared_by_seating_velocity_and_closing_time():
    """The same valve closed with no buffer, an air and an oil dashpot (the scene's). Both buffers
    slow the seating several-fold; the air cushion keeps the closing short (it acts late and
    hard), the oil one spreads its braking over the stroke and closes later; the oil buffer cannot
    throw the valve back, an air cushion with a small leak can."""
    scene = load_scene(SCENE)
    from explorer.effects import simulate

    result = simulate(scene)
    rows = {r["buffer"]: r for r in result.summary["gear"]["buffer_comparison"]}
    none, air, oil = rows["none"], rows["air"], rows["oil"]
    assert air["seating_velocity_m_s"] < 0.3 * none["seating_velocity_m_s"]
    assert oil["seating_velocity_m_s"] < 0.3 * none["seating_velocity_m_s"]
    assert none["closing_time_s"] < air["closing_time_s"] < oil["closing_time_s"]
    assert air["rebounds"] == 0 and oil["rebounds"] == 0
    # a tighter leak on the same air cushion: it throws the valve back, oil never does
    tight = replace(
        AirDashpot(area=cylinder_area(0.075), stroke=0.006, clearance=0.001, orifice_area=cylinder_area(0.0015)))
    lift = build_lift(scene)
    model = lift.closing.model
    s0 = float(lift.latch.derivatives(np.array([lift.trip_angle]))[0, 0] - lift.overtravel)
    v0 = float(scene.omega * lift.latch.derivatives(np.array([lift.trip_angle]))[1, 0])
    table = compare_buffers(model, {"tight-air": tight}, s0, v0, 1.0)
    assert table[0]["rebounds"] >= 1


def test_trip_lift_pick_up_release_and_seat():
    """Through the pipeline: the latch (an eccentric, harmonic 180/180 of height 2e) picks the
    valve up after the over-travel s_o with v = w sqrt(s_o (2e - s_o)); at the trip the lift is
    continuous in value and slope; the seat is found with the closing model's velocity."""
    scene = load_scene(SCENE)
    lift = build_lift(scene)
    w = scene.omega
    e, so = 0.015, scene.valve.lash
    ups, downs = lash_crossings(lift, 1.0, so)
    assert w * lift.derivatives(ups)[1][0] == pytest.approx(w * math.sqrt(so * (2 * e - so)), rel=1e-12)
    assert w * lift.derivatives(downs)[1][0] == pytest.approx(lift.closing.seat_velocity, rel=1e-9)
    trip = lift.trip_angle
    before, after = lift.derivatives(np.array([trip - 1e-9]))[:, 0], lift.derivatives(np.array([trip]))[:, 0]
    assert after[0] == pytest.approx(before[0] + 1e-9 * before[1], abs=1e-15)
    assert after[1] == pytest.approx(before[1], rel=1e-7)
    # valve shut after the seat: the virtual continuation stays below the over-travel
    th = np.linspace(downs[0] + 1e-9, downs[0] + 1.0, 500)
    assert np.all(lift.derivatives(th)[0] < so)
    # after the release: the second and third derivatives (equation of motion at the interpolated
    # state, and its time derivative) against Richardson differences of the first and second
    for fraction in (0.3, 0.95):  # free fall, then inside the air cushion
        th = np.array([trip + fraction * (downs[0] - trip)])
        h = 1e-4
        for k in (1, 2):
            d = lambda step: (lift.derivatives(th + step)[k] - lift.derivatives(th - step)[k]) / (2 * step)
            rich = (4 * d(h / 2) - d(h)) / 3
            assert lift.derivatives(th)[k + 1][0] == pytest.approx(rich[0], rel=1e-5)


def test_summary_has_latch_impact_and_trinks():
    from explorer.effects import simulate

    result = simulate(load_scene(SCENE))
    g = result.summary["gear"]
    assert g["latch_pickup_velocity_m_s"] == pytest.approx(result.summary["impact_velocity_opening_m_s"], rel=1e-12)
    assert g["latch_pickup_impulse_N_s"] == pytest.approx(M * g["latch_pickup_velocity_m_s"], rel=1e-12)
    t = g["trinks"]
    assert t["required_spring_force_N"] == pytest.approx(
        (2 * t["lift_m"] / t["closing_time_s"] ** 2 / TRINKS_G - 1) * t["valve_weight_N"] + 20.0, rel=1e-12)
    assert g["seating_velocity_m_s"] == pytest.approx(result.summary["impact_velocity_closing_m_s"], rel=1e-9)
    kinds = [e["kind"] for e in result.summary["events"]]
    assert kinds.index("lash-take-up") < kinds.index("trip") < kinds.index("dashpot-entry") < kinds.index("seat")


BAD = [
    ({"gear.trip.angle": '"340 deg"'}, "gear.trip.angle"),  # the latch has already set the valve down
    ({"gear.trip.angle": '"20 deg"'}, "gear.trip.angle"),  # before the pick-up
    ({"spring.preload": '"5 N"', "loads.closing.valve_weight": '"1 N"'}, "spring.preload"),  # hangs open
    ({"effects": '["kinematics", "forces"]'}, "effects"),
    ({"effects": '["kinematics", "elastic"]', "linkage.stiffness": '"1e6 N/m"'}, "effects"),
    ({"valve.lash": '"0 mm"'}, "valve.lash"),
    ({"gear.air_dashpot.stroke": '"40 mm"'}, "gear.air_dashpot.stroke"),
    ({"gear.oil_dashpot.orifice_diameter": '"40 mm"'}, "gear.oil_dashpot.orifice_diameter"),
    ({"drive.rpm": "3000"}, "gear.trip.angle"),  # the valve cannot close before the next stroke
]


@pytest.mark.parametrize("overrides, key", BAD, ids=[f"{b[1]}-{i}" for i, b in enumerate(BAD)])
def test_bad_input_names_the_part(overrides, key):
    with pytest.raises(InputError) as info:
        load_scene(SCENE, [f"{k}={v}" for k, v in overrides.items()])
    assert info.value.key == key


def test_buffer_without_its_section():
    import tomllib

    from explorer.scene import scene_from_dict

    data = tomllib.loads(SCENE.read_text())
    del data["gear"]["air_dashpot"]
    with pytest.raises(InputError) as info:
        scene_from_dict(data, "x.toml")
    assert info.value.key == "gear.trip.buffer"
