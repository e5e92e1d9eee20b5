"""The seeds' worked numbers (SEEDS.md), computed through the project's own functions: scene
parsing with technical units, the drive's time scale, lash root finding and the exact integration
of an acceleration law. Tolerances follow the paper's printed digits (three significant figures
unless it prints more)."""

from __future__ import annotations

import math

import pytest

from explorer import loads_scene, simulate
from explorer.effects.lift import build_lift
from explorer.core.units import KGF, to_si


def si(value, dimension):
    return to_si(value, dimension, file="seed", key="k")


def schenker_scene(lash="0.6 mm", effects='["kinematics", "lash"]'):
    """Fig. 2 proportions with a harmonic flank: 20.6 mm cam lift over 160 deg at 240 rpm."""
    return loads_scene(f"""
effects = {effects}
[drive]
rpm = "240 rpm"
[lift]
law = "harmonic"
height = "20.6 mm"
start = "100 deg"
rise = "80 deg"
return = "80 deg"
[valve]
mass = "2.9 kgf*s**2/m"
lash = "{lash}"
""")


def test_event_duration_t_prime():
    """t' = 60 * 160 / (240 * 360) = 0.111 s: 160 deg between the flank tangent points at 240 rpm."""
    scene = schenker_scene()
    t_prime = (scene.lift.rise + scene.lift.dwell + scene.lift.ret) / scene.omega
    assert t_prime == pytest.approx(60 * 160 / (240 * 360), rel=1e-14)
    assert round(t_prime, 3) == 0.111


def test_t_prime_splits_into_take_up_open_and_run_off():
    """t' = t1' (roller takes up the lash) + t (valve open) + t2' (roller runs off the lash); with
    a harmonic flank the lash instants have the closed form u = acos(1 - 2 s'/h) / pi."""
    scene = schenker_scene()
    s = simulate(scene).summary
    w = scene.omega
    start = math.radians(100)
    up, seat = math.radians(s["lash_take_up_angles_deg"][0]), math.radians(s["seating_angles_deg"][0])
    t1, t, t2 = (up - start) / w, (seat - up) / w, (start + math.radians(160) - seat) / w
    assert t1 + t + t2 == pytest.approx(0.1111111111111111, rel=1e-12)
    u = math.acos(1 - 2 * 0.6 / 20.6) / math.pi
    assert t1 == pytest.approx(u * math.radians(80) / w, rel=1e-9)
    assert t2 == pytest.approx(t1, rel=1e-9)
    # the rigid theory's finite meeting velocity v1 (an impact) at take-up
    v1 = w * 0.0206 * math.pi / (2 * math.radians(80)) * math.sin(math.pi * u)
    assert s["impact_velocity_opening_m_s"] == pytest.approx(v1, rel=1e-9)


def test_tangent_construction_v_and_p():
    """Schenker: ds = 0.0215 m over dt = 0.031 s gives v = 0.694 m/s; a tangent over 0.0385 s then
    gives p = 0.694 / 0.0385 = 18.03 m/s^2. As an acceleration law at 240 rpm (1440 deg/s):
    p = 18.03 m/s^2 for 0.0385 s, coast 0.031 s, -p for 0.077 s, coast, +p for 0.0385 s (a closed
    event). Its exact integration must give v = 0.694 m/s after the first phase and a lift gain
    of 0.0215 m over the coast."""
    deg_per_s = 240 * 360 / 60
    t1, t2, p = 0.0385, 0.031, 18.03
    a1, a2 = t1 * deg_per_s, t2 * deg_per_s
    marks = [0.0, a1, a1 + a2, 3 * a1 + a2, 3 * a1 + 2 * a2, 4 * a1 + 2 * a2]
    values = [p, 0.0, -p, 0.0, p, 0.0]
    points = ", ".join(f"[{m!r}, {v!r}]" for m, v in zip(marks, values))
    scene = loads_scene(f"""
[drive]
rpm = 240
[lift]
law = "acceleration"
interpolation = "step"
points = [{points}]
""")
    lift = build_lift(scene)
    w = scene.omega
    d_end_accel = lift.derivatives([math.radians(a1)])
    v = w * d_end_accel[1][0]
    assert v == pytest.approx(0.694, abs=5e-4)  # 18.03 * 0.0385 = 0.69416
    v0 = w * lift.derivatives([0.0])[1][0]
    assert (v - v0) / t1 == pytest.approx(0.694 / 0.0385, rel=1e-3)  # the tangent's slope: 18.03
    gain = lift.derivatives([math.radians(a1 + a2)])[0][0] - lift.derivatives([math.radians(a1)])[0][0]
    assert gain == pytest.approx(0.0215, abs=5e-5)  # 0.69416 * 0.031 = 0.021519
    assert gain / t2 == pytest.approx(0.0215 / 0.031, rel=2e-3)  # ds/dt = v on the straight flank
    closure = lift.closure_check()
    assert abs(closure.end_velocity) < 1e-15 and abs(closure.end_lift) < 1e-15


def test_kgf_and_technical_mass_unit_in_fig4():
    """Fig. 4: M = 2.9 and M1 = 2.6 (kgf s^2/m), W0 = 260 + 90 + 35 = 385 kg, k = 1 800 000 kg/m:
    S0 = W/k = 0.000214 m, 1 mm of compression = 1800 kg, separated deceleration W/M = 133 m/s^2,
    largest back-pressure W + p M1 = 385 + 292 * 2.6 = 1145 kg."""
    text = """
effects = ["kinematics"]
[drive]
rpm = 240
[lift]
law = "harmonic"
height = "20.6 mm"
rise = "80 deg"
[valve]
mass = "2.9 kgf*s**2/m"
oscillating_mass = "2.6 TME"
[spring]
preload = "260 kgf"
[loads.closing]
steam_on_stem_and_valve = "90 kgf"
other_resistances = "35 kgf"
[linkage]
stiffness = "1800000 kgf/m"
"""
    scene = loads_scene(text)
    w0 = scene.spring.preload + scene.loads.closing_total  # N
    assert w0 / KGF == pytest.approx(385.0, rel=1e-14)
    assert w0 / scene.linkage.stiffness == pytest.approx(0.000214, abs=5e-7)
    assert scene.linkage.stiffness * 0.001 / KGF == pytest.approx(1800.0, rel=1e-14)
    assert w0 / scene.valve.mass == pytest.approx(133.0, abs=0.5)  # 132.76, unit-system free
    back_pressure = (w0 + 292.0 * scene.valve.oscillating_mass) / KGF
    assert back_pressure == pytest.approx(1145.0, rel=1e-3)  # 1144.2; the paper rounds up


def test_steam_on_stem_from_technical_atmospheres():
    """Ds = 4 at x 9 cm^2 = 36 kg."""
    force = si("4 at", "pressure") * si("9 cm**2", "area")
    assert force / KGF == pytest.approx(36.0, rel=1e-14)
    assert si("36 kgf", "force") == pytest.approx(force, rel=1e-14)
