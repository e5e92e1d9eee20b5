"""Schenker 1902, section 3 (Fig. 4): impacts at lift-off and the elastic linkage (SEEDS.md 3).

The gear of the paper in its own units (kgf, technical mass units TME = kgf s^2/m): M = 2.9,
M1 = 2.6, W0 = 260 + 90 + 35 = 385 kgf taken constant (spring preload, steam, other
resistances), k = 1 800 000 kgf/m, lash 0.6 mm, 20.6 mm of roller travel over a 160 deg flank
at 240 rpm. The paper's cam (Fig. 2) is drawn, not given by formulas; here its flank is an
analytic harmonic rise and return of the same size, so the checks are the paper's relations,
which hold for any flank:
  - the valve lifts when the linkage is compressed by S0 = W/k = 385/1 800 000 = 0.000214 m;
  - while separated it decelerates with W/M = 385/2.9 = 133 m/s^2;
  - the back-pressure on the camshaft is W + p M1 (= 385 + 292 * 2.6 = 1145 kgf at p = 292);
  - the lift is a chain of oscillations whose nodes lie on the (S - W/k) curve;
  - more elasticity gives larger oscillations and smaller forces.
"""

import math

import numpy as np
import pytest

from explorer.dynamics.model import PHASE_CODES
from explorer.effects.pipeline import simulate
from explorer.scene.scene import load_scene, loads_scene
from explorer.scene.builtin import scenes_dir

G = 9.80665  # kgf -> N, TME -> kg

SCENE = """
name = "Schenker 1902 Fig. 4, analytic flank"
effects = ["elastic"]
[drive]
rpm = 240
[lift]
law = "harmonic"
height = "20.6 mm"
start = "20 deg"
rise = "80 deg"
return = "80 deg"
[follower]
base_radius = "120 mm"
roller_radius = "40 mm"
[valve]
mass = "2.9 TME"
oscillating_mass = "2.6 TME"
lash = "0.6 mm"
[spring]
preload = "260 kgf"
rate = 0
[loads.closing]
steam_on_stem_and_valve = "90 kgf"
other_resistances = "35 kgf"
[linkage]
stiffness = "1800000 kgf/m"
"""

W_KGF, M_TME, M1_TME, K_KGF_M = 385.0, 2.9, 2.6, 1.8e6


@pytest.fixture(scope="module")
def result():
    return simulate(loads_scene(SCENE))


def test_the_valve_lifts_when_the_linkage_is_compressed_by_S0(result):
    S0 = W_KGF / K_KGF_M
    assert round(S0, 6) == 0.000214  # the paper's number
    assert result.summary["lift_off_compression_m"] == pytest.approx(S0, rel=1e-12)
    lift_off = next(e for e in result.events if e["kind"] == "lift-off")
    take_up = next(e for e in result.events if e["kind"] == "lash-take-up")
    scene = result.scene
    lift = scene_lift(scene)
    S = lift.derivatives(np.array([math.radians(lift_off["cam_angle_deg"])]))[0, 0]
    # k (S - lash) = W at the lift-off instant, to the precision of the event location
    assert S - scene.valve.lash == pytest.approx(S0, rel=1e-9)
    assert take_up["time_s"] < lift_off["time_s"]  # first the lash closes, then the linkage is compressed


def scene_lift(scene):
    from explorer.effects.lift import build_lift

    return build_lift(scene)


def test_free_flight_decelerates_with_W_over_M(result):
    c = result.columns
    flight = c["valve_phase"] == PHASE_CODES["flight"]
    assert flight.sum() > 10  # the flank throws the valve off the linkage (and catches it again)
    decel = -c["valve_accel_m_s2"][flight]
    np.testing.assert_allclose(decel, W_KGF / M_TME, rtol=1e-12)  # g cancels: kgf / TME = m/s^2
    assert round(W_KGF / M_TME) == 133
    kinds = [e["kind"] for e in result.events if e["effect"] == "elastic"]
    assert kinds.count("separation") == kinds.count("re-contact") >= 3


def test_back_pressure_is_W_plus_p_M1(result):
    c = result.columns
    moving = c["valve_phase"] == PHASE_CODES["contact"]
    p = c["valve_accel_m_s2"][moving]
    back = c["camshaft_back_pressure_N"][moving] / G  # kgf
    np.testing.assert_allclose(back, W_KGF + p * M1_TME, rtol=1e-9)
    assert W_KGF + 292.0 * M1_TME == pytest.approx(1145.0, abs=1.0)  # the paper: 1145 kg
    assert result.summary["peak_camshaft_back_pressure_N"] / G == pytest.approx(W_KGF + p.max() * M1_TME, rel=1e-9)


def test_the_lift_oscillates_about_the_S_minus_W_over_k_curve(result):
    # in contact M1 p = k (S - lash - s) - W = -k * deviation: the acceleration vanishes exactly
    # where the lift crosses the (S - W/k) curve, i.e. the oscillation's nodes lie on it
    c = result.columns
    moving = c["valve_phase"] == PHASE_CODES["contact"]
    dev = c["deviation_from_drive_m"][moving]
    p = c["valve_accel_m_s2"][moving]
    np.testing.assert_allclose(M1_TME * p, -K_KGF_M * dev, rtol=1e-8, atol=1e-6)
    lifting = c["valve_lift_m"] > 0.0
    crossings = np.count_nonzero(np.diff(np.sign(c["deviation_from_drive_m"][lifting])) != 0)
    assert crossings >= 8  # a chain of oscillations, not one swing
    assert 1e-4 < result.summary["max_deviation_m"] < 1e-3  # the paper's scale: 0.37 mm


def test_more_elasticity_gives_larger_oscillations_and_smaller_forces():
    deviation, force = [], []
    for factor in (0.25, 0.5, 1.0, 2.0, 4.0):
        scene = loads_scene(SCENE, overrides=[f'linkage.stiffness="{K_KGF_M * factor} kgf/m"'])
        summary = simulate(scene).summary
        deviation.append(summary["max_deviation_m"])
        force.append(summary["peak_linkage_force_N"])
    assert np.all(np.diff(deviation) < 0.0)  # stiffer: smaller oscillation
    assert np.all(np.diff(force) > 0.0)  # stiffer: larger forces
    assert deviation[0] > 4 * deviation[-1] and force[-1] > 1.5 * force[0]


FIG2 = scenes_dir() / "schenker1902_fig2.toml"


@pytest.mark.skipif(not FIG2.exists(), reason="the Fig. 2 cam scene is built by the geometry work")
def test_the_fig2_cam_with_the_elastic_linkage():
    base = load_scene(FIG2)
    effects = [e for e in base.effects if e != "elastic"] + ["elastic"]
    scene = load_scene(FIG2, overrides=[f"effects={effects!r}".replace("'", '"')])
    result = simulate(scene)
    s = result.report()
    W = scene.spring.preload + scene.loads.closing_total + scene.loads.friction
    assert s["lift_off_compression_m"] == pytest.approx(W / scene.linkage.stiffness, rel=1e-12)
    kinds = [e["kind"] for e in s["events"] if e.get("effect") == "elastic"]
    assert kinds[0] == "lift-off" and kinds[-1] == "seat"
    assert np.all(np.isfinite(result.columns["valve_lift_m"]))
    assert not [w for w in s["warnings"] if "not come back to rest" in w]
