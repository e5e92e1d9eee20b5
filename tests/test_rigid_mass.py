"""The rigid forces' one mass at the valve (explorer/mechanics/moving_mass.py, Gear.moving_parts):
valve.mass, every part of a [[linkage.elements]] train referred to the valve (m / r^2, J / a^2),
a third of the spring where the scene models it as masses, and a gear's own parts.

Oracles:
- the float (jump) speed of a rigid train, w^2 = min over the open, decelerating lift of
  (F0 + k s + D) / (-M q L''), scanned here on the closed-form polynomial laws (their L'' written
  out below, not the program's) with the mass M summed by hand from the scene's numbers; the
  scan's grid of 10^6 steps over the rise puts its minimum within ~1e-12 relative of the true
  one (a smooth minimum: error ~ f'' du^2), so 1e-9 relative is far above both sides' rounding
  and far below the mass errors this guards against (20-60 %);
- the energy of a rigid lever train, T = 1/2 M v^2 (Thomson, Theory of Vibration with
  Applications, 5th ed., sect. 2.4, p. 24: masses joined by levers are one mass at a point), and
  of a spring moving quasi-statically, m_s / 3 (ibid., Example 2.4-1, Rayleigh's value): the
  spring chain's own lumping (masses m_s/(N+1), half of one at the retainer, moving along its
  quasi-static shape) gives m_s (1/3 + 1/(6 (N+1)^2)) in closed form, tending to the third;
- bit-identity where valve.mass already is the whole mass (the classic scenes: `==`).
"""

from __future__ import annotations

import dataclasses
import math
from types import MappingProxyType

import numpy as np
import pytest

from explorer import load_scene, loads_scene, simulate, sweep
from explorer.checks.case import Case, Draws
from explorer.dynamics.chain import ChainModel
from explorer.effects.lift import build_lift
from explorer.gears.base import Gear
from explorer.gears.registry import register_gear
from explorer.mechanics.forces import TrainLoads
from explorer.mechanics.moving_mass import ReferredMass, rigid_mass

from conftest import SCENES

RPM = 60.0 / (2.0 * math.pi)
RIGID = ("kinematics", "lash", "forces")


# --- the oracle: a closed-form float scan ---------------------------------------------------------


def law_345(u):
    """3-4-5 polynomial rise: s / h and d2s/du2 / h."""
    return 10 * u**3 - 15 * u**4 + 6 * u**5, 60 * u - 180 * u**2 + 120 * u**3


def law_4567(u):
    """4-5-6-7 polynomial rise: s / h and d2s/du2 / h."""
    return 35 * u**4 - 84 * u**5 + 70 * u**6 - 20 * u**7, 420 * u**2 - 1680 * u**3 + 2100 * u**4 - 840 * u**5


def rise(law, height, rise_deg, ratio, lash, n=1_000_001):
    """(valve travel, > 0 open; valve acceleration per w^2) on n samples of the rise. The return
    is the rise mirrored (the same law and angle) and without friction its loads are the same,
    so the rise holds the minima below."""
    s, a = law(np.linspace(0.0, 1.0, n))
    return ratio * height * s - lash, ratio * height * a / math.radians(rise_deg) ** 2


def float_scan(law, height, rise_deg, ratio, lash, mass, preload, rate, closing):
    """The rigid float speed (rpm): w^2 = min over open, decelerating samples of G / (-M p/w^2)."""
    valve, accel = rise(law, height, rise_deg, ratio, lash)
    static = preload + rate * np.maximum(valve, 0.0) + closing
    take = (valve > 0.0) & (accel < 0.0)
    return math.sqrt(np.min(static[take] / -(mass * accel[take]))) * RPM


def least_force_scan(law, height, rise_deg, ratio, lash, mass, preload, rate, closing, rpm):
    """The least rigid contact force (N) while the valve is open, at `rpm`."""
    valve, accel = rise(law, height, rise_deg, ratio, lash)
    force = mass * accel * (rpm / RPM) ** 2 + preload + rate * valve + closing
    return float(np.min(force[valve > 0.0]))


# the three scenes' numbers, as their files give them (SI), and their masses summed by hand
PUSHROD = dict(law=law_4567, height=6.4e-3, rise_deg=80.0, ratio=1.5, lash=0.10e-3, preload=420.0, rate=50e3,
               closing=15.0)
PUSHROD_MASS = 0.075 + 0.070 / 1.5**2 + 0.055 / 1.5**2 + 1.0e-4 / 0.042**2  # valve, lifter, pushrod, rocker J/a^2
FINGER = dict(law=law_345, height=5.4e-3, rise_deg=75.0, ratio=1.7, lash=0.0, preload=250.0, rate=40e3, closing=0.0)
FINGER_MASS = 0.05 + 0.35e-4 / 0.040**2  # valve, finger J/a^2 (the adjuster's plunger holds the pivot: no share)
SPRING_MASS = 7850.0 * math.pi**2 * 4.0e-3**2 * 24e-3 * 6 / 4  # rho pi^2 d^2 D n / 4 = 44.6 g
SURGE = dict(law=law_345, height=9.25e-3, rise_deg=75.0, ratio=1.0, lash=0.25e-3, preload=220.0, rate=30.6e3,
             closing=15.0)
SURGE_MASS = 0.08 + SPRING_MASS / 3.0  # valve and retainer, a third of the spring (it is 8 masses in the scene)

CASES = {
    "pushrod_train": (PUSHROD, PUSHROD_MASS, 0.075),
    "finger_hla_pumpup": (FINGER, FINGER_MASS, 0.05),
    "spring_surge": (SURGE, SURGE_MASS, 0.08),
}


def rigid_summary(name, **replace):
    scene = load_scene(SCENES / f"{name}.toml")
    scene = dataclasses.replace(scene, effects=RIGID, **replace)
    return scene, simulate(scene).summary


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_float_speed_of_a_train_is_the_closed_form_scans_with_every_part_at_the_valve(name):
    numbers, mass, valve_only = CASES[name]
    scene, s = rigid_summary(name)
    assert s["rigid_mass_kg"] == pytest.approx(mass, rel=1e-14)
    assert s["jump_speed_rpm"] == pytest.approx(float_scan(mass=mass, **numbers), rel=1e-9)
    # the valve's mass alone (what the forces used to take) gives a far higher speed: 20-60 % off
    assert float_scan(mass=valve_only, **numbers) > 1.08 * s["jump_speed_rpm"]
    assert s["min_contact_force_N"] == pytest.approx(
        least_force_scan(mass=mass, rpm=scene.drive.rpm, **numbers), rel=1e-9)
    assert s["valve_floats"] is (scene.drive.rpm >= s["jump_speed_rpm"])


def test_the_figures_of_the_three_trains():
    """The numbers the fix changes, as the docs quote them (jump speeds, rpm)."""
    figures = {name: rigid_summary(name)[1]["jump_speed_rpm"] for name in CASES}
    assert figures == pytest.approx({"pushrod_train": 3363.68, "finger_hla_pumpup": 4919.75,
                                     "spring_surge": 3885.91}, abs=0.01)


def test_a_train_floats_above_its_whole_mass_speed_and_the_warning_says_so():
    _, s = rigid_summary("pushrod_train")
    scene, fast = rigid_summary("pushrod_train", drive=dataclasses.replace(load_scene(
        SCENES / "pushrod_train.toml").drive, rpm=3500.0))
    assert fast["valve_floats"] and fast["min_contact_force_N"] < 0.0
    warning = [w for w in simulate(scene).warnings if w.startswith("valve float")]
    assert warning and f"{s['jump_speed_rpm']:.6g} rpm" in warning[0]


def test_the_summary_names_each_share():
    _, s = rigid_summary("pushrod_train")
    parts = s["rigid_mass_parts_kg"]
    assert list(parts) == ["valve", "lifter", "pushrod", "rocker"]
    assert parts["lifter"] == pytest.approx(0.070 / 2.25, rel=1e-15)
    assert parts["pushrod"] == pytest.approx(0.055 / 2.25, rel=1e-15)
    assert parts["rocker"] == pytest.approx(1.0e-4 / 0.042**2, rel=1e-15)
    assert math.fsum(parts.values()) == pytest.approx(s["rigid_mass_kg"], rel=1e-15)
    _, s = rigid_summary("spring_surge")
    assert s["rigid_mass_parts_kg"] == pytest.approx({"valve": 0.08, "spring": SPRING_MASS / 3.0}, rel=1e-12)


@pytest.mark.parametrize("name", ["valve_float_demo", "schenker1902_fig2", "pushrod_rocker", "finger_follower",
                                  "elastic_float", "bucket_tappet", "trip_gear_dashpot"])
def test_a_single_mass_scene_keeps_valve_mass_bit_for_bit(name):
    scene = load_scene(SCENES / f"{name}.toml")
    rigid = rigid_mass(scene)
    assert rigid.parts == () and rigid.total == scene.valve.mass  # the same float, not close to it
    assert TrainLoads.from_scene(scene).mass == scene.valve.mass
    assert rigid.of_valve(np.array([0.1, 0.2])).tolist() == [0.1, 0.2]


@pytest.mark.parametrize("n", [1, 8, 64, 512])
def test_the_spring_chains_quasi_static_mass_tends_to_the_third(n):
    """T = 1/2 sum m_j (r_j v)^2 over the chain's masses moving along its quasi-static shape
    r_j = 1 - j/(N+1) (chain.py): m_s (1/3 + 1/(6 (N+1)^2)) beyond the valve, in closed form
    (sum of k^2 for k < N+1), so the continuous spring's third is the chain's limit, at second order."""
    m_s, m_v = 0.0446, 0.08
    chain = ChainModel(valve_mass=m_v, spring_mass=m_s, elements=n, spring_rate=30e3, preload=200.0,
                       stiffness=1e7, seat_stiffness=1e8)
    shape = 1.0 - np.arange(n + 1) / (n + 1)
    share = math.fsum(chain.masses * shape**2) - m_v
    assert share == pytest.approx(m_s * (1.0 / 3.0 + 1.0 / (6.0 * (n + 1) ** 2)), rel=1e-12)
    assert abs(share / m_s - 1.0 / 3.0) <= 1.0 / (6.0 * (n + 1) ** 2) * (1 + 1e-9)


# --- every consumer of the rigid forces takes the same mass ---------------------------------------


def test_the_sweeps_rigid_figures_take_the_whole_mass_and_each_draws_valve_mass():
    scene = dataclasses.replace(load_scene(SCENES / "pushrod_train.toml"), effects=RIGID)
    speeds = [2000.0, 3000.0, 3500.0]
    table = sweep(scene, vary={"drive.rpm": speeds}, workers=1).columns
    jump = simulate(scene).summary["jump_speed_rpm"]
    assert np.all(table["float_speed_rpm"] == jump)
    for rpm, f_min in zip(speeds, table["min_contact_force_N"]):
        assert f_min == pytest.approx(least_force_scan(mass=PUSHROD_MASS, rpm=rpm, **PUSHROD), rel=1e-9)
    # a sweep of valve.mass: each run's valve and the train's other parts
    table = sweep(scene, vary={"valve.mass": [0.05, 0.1]}, workers=1).columns
    for m, rpm in zip((0.05, 0.1), table["float_speed_rpm"]):
        assert rpm == pytest.approx(float_scan(mass=PUSHROD_MASS - 0.075 + m, **PUSHROD), rel=1e-9)


def test_the_design_rules_forces_take_the_whole_mass_for_the_nominal_design_and_each_draw():
    """explorer.checks.case.Case.force_parts (what the rigid rules read: float margin without a
    linkage, contact stress, film parameter): A = M q L'' with M the forces effect's, bit for bit
    for the nominal design; a draw of valve.mass adds the same parts."""
    scene = load_scene(SCENES / "pushrod_train.toml")
    loads = TrainLoads.from_scene(scene)
    case = Case(scene, [2000.0])
    a_coef, _, _ = case.force_parts()
    d2 = build_lift(scene).derivatives(case.theta)[2]
    assert np.array_equal(a_coef[0], loads.mass * (scene.follower.ratio * d2))
    drawn = Case(scene, [2000.0], Draws(("valve.mass",), np.array([[0.075], [0.1]])))
    a_coef, _, _ = drawn.force_parts()
    assert np.array_equal(a_coef[0], loads.mass * (scene.follower.ratio * d2))
    others = PUSHROD_MASS - 0.075
    np.testing.assert_allclose(a_coef[1], (0.1 + others) * scene.follower.ratio * d2, rtol=1e-14, atol=0.0)


# --- a plug-in gear declares parts of its own -----------------------------------------------------


def arm_keys(t) -> dict:
    t.reject_unknown(("inertia", "arm"))
    return {"inertia": t.quantity("inertia", "inertia", positive=True), "arm": t.quantity("arm", "length", positive=True)}


class ToyArmGear(Gear):
    """A roller on an arm that turns with the valve: the arm's inertia J about its pivot, its arm a
    to the valve: J / a^2 at the valve (the follower's lift is the [lift] law's, ratio follower.ratio)."""

    type = "toy-arm"
    description = "a follower on a swinging arm with its own inertia (the rigid-mass tests' toy)"
    parts = MappingProxyType({"arm": arm_keys})

    def moving_parts(self, scene):
        arm = scene.gear.part("arm")
        return super().moving_parts(scene) + (ReferredMass("toy_arm", arm["inertia"] / arm["arm"] ** 2),)


class ToyBareGear(ToyArmGear):
    """The same gear, its arm's inertia not declared: the hook's default (valve.mass alone here)."""

    type = "toy-bare"

    def moving_parts(self, scene):
        return Gear.moving_parts(self, scene)


TOY = """
name = "toy arm"
effects = ["kinematics", "lash", "forces"]
[drive]
rpm = 3000
[lift]
law = "polynomial-345"
height = "8 mm"
start = "30 deg"
rise = "80 deg"
dwell = "10 deg"
[follower]
type = "{type}"
base_radius = "20 mm"
ratio = 1.4
[valve]
mass = "0.06 kg"
lash = "0.15 mm"
[spring]
preload = "300 N"
rate = "35 N/mm"
[loads.closing]
gas = "10 N"
[gear.arm]
inertia = "0.5 kg*cm**2"
arm = "35 mm"
{extra}
"""
TOY_NUMBERS = dict(law=law_345, height=8e-3, rise_deg=80.0, ratio=1.4, lash=0.15e-3, preload=300.0, rate=35e3,
                   closing=10.0)
TOY_ELEMENT = """
[linkage]
stiffness = "100 N/um"
[[linkage.elements]]
name = "tappet"
mass = "40 g"
stiffness = "100 N/um"
[seat]
stiffness = "200 N/um"
"""


@pytest.fixture
def toy_gears():
    with register_gear(ToyArmGear()), register_gear(ToyBareGear()):
        yield


def test_a_plug_in_gears_own_parts_count_in_the_rigid_forces(toy_gears, tmp_path):
    path = str(tmp_path / "toy.toml")
    arm = 0.5e-4 / 0.035**2
    for gear, extra, mass in (("toy-arm", "", 0.06 + arm), ("toy-bare", "", 0.06),
                              ("toy-arm", TOY_ELEMENT, 0.06 + 0.040 / 1.4**2 + arm)):
        scene = loads_scene(TOY.format(type=gear, extra=extra), path)
        s = simulate(scene).summary
        assert s["rigid_mass_kg"] == pytest.approx(mass, rel=1e-14)
        assert s["jump_speed_rpm"] == pytest.approx(float_scan(mass=mass, **TOY_NUMBERS), rel=1e-9)
        if gear == "toy-arm":
            assert list(s["rigid_mass_parts_kg"])[-1] == "toy_arm"
        # the sweep engine asks the same hook
        table = sweep(scene, vary={"drive.rpm": [2500.0, 3000.0]}, workers=1).columns
        assert np.all(table["float_speed_rpm"] == s["jump_speed_rpm"])


def test_min_spring_margin_is_over_the_open_valve():
    """The summary's min_spring_margin_N is the spring's least reserve against the inertia while the
    valve is open (audit: rocking_cam gave 439 N, the seated valve's preload plus loads, against
    455.7 N open); a valve that never opens has none."""
    import numpy as np

    from explorer.effects.pipeline import simulate
    from explorer.scene.scene import load_scene

    r = simulate(load_scene("assets/scenes/rocking_cam.toml"))
    c = r.columns
    is_open = np.asarray(c["rigid_valve_lift_m"]) > 0.0
    assert r.summary["min_spring_margin_N"] == float(c["spring_margin_N"][is_open].min())
    assert r.summary["min_spring_margin_N"] > float(c["spring_margin_N"][~is_open].min())
    shut = simulate(load_scene("assets/scenes/cycloidal_demo.toml", ['valve.lash="20 mm"']))
    assert shut.summary["min_spring_margin_N"] is None
