"""The valve train of parts in scenes (issue #25): [[linkage.elements]] and [hla], the elastic
effect's train variant, the built-in scenes, bad input, and sweeps through the shared engine
(each row equal to simulate's, bit for bit)."""

from __future__ import annotations

import json
import math
import re
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from explorer import load_scene, loads_scene, simulate
from explorer.core.errors import InputError
from explorer.dynamics.train import TrainModel
from explorer.scene.builtin import scenes_dir
from explorer.scene.train_section import HLA_KEYS, HLA_NUMBERS
from explorer.effects.registry import effect_spec
from explorer.studies.sweep_engine import ENGINES, _Shared, compute_chunk, result_columns, row_figures
from explorer.studies.sweep_spec import scene_for

PUSHROD = scenes_dir() / "pushrod_train.toml"
FINGER = scenes_dir() / "finger_hla_pumpup.toml"
SHARED = next(engine for engine in ENGINES if engine.name == "shared")
# the elastic effect's adjuster figures, a row's with [hla] (its table line's section_figures)
HLA_COLUMNS = next(extra.figures for extra in effect_spec("elastic").section_figures if extra.section == "hla")


def _text(extra: str = "", linkage: str = 'stiffness = "120 N/um"\ndamping = "40 N*s/m"', seat: str = "",
          follower_ratio: float = 1.5) -> str:
    return f"""
effects = ["elastic"]
[drive]
rpm = 2000
[lift]
law = "polynomial-4567"
height = "6 mm"
rise = "80 deg"
[follower]
ratio = {follower_ratio}
[valve]
mass = "0.07 kg"
lash = "0.1 mm"
[spring]
preload = "400 N"
rate = "50 N/mm"
[linkage]
{linkage}
[seat]
{seat or 'stiffness = "250 N/um"'}
{extra}
"""


ELEMENT = '[[linkage.elements]]\nname = "lifter"\nmass = "60 g"\nstiffness = "150 N/um"\ndamping = "200 N*s/m"\n'


def test_elements_are_referred_to_the_valve():
    scene = loads_scene(_text(ELEMENT + '[[linkage.elements]]\nname = "rocker"\ninertia = "1 kg*cm**2"\narm = "40 mm"\n'
                                        'stiffness = "60 N/um"\nlash = "0.05 mm"\ncontact = "bonded"\n'))
    lifter, rocker = scene.linkage.elements
    assert lifter.ratio == rocker.ratio == 1.5  # follower.ratio by default
    tr = TrainModel.from_scene(scene)
    assert [p.mass for p in tr.parts] == pytest.approx([0.06 / 1.5**2, 1e-4 / 0.04**2], rel=1e-15)
    cam, cup, valve = tr.joints
    assert cam.stiffness == pytest.approx(150e6 / 2.25) and cam.damping == pytest.approx(200.0 / 2.25)
    assert cup.stiffness == pytest.approx(60e6 / 2.25) and cup.lash == pytest.approx(0.05e-3 * 1.5)
    assert not cup.one_sided and valve.one_sided
    assert valve.stiffness == 120e6 and valve.lash == pytest.approx(0.1e-3)


def test_pushrod_scene_reports_each_part_and_contact():
    r = simulate(load_scene(PUSHROD))
    for name in ("lifter", "pushrod", "rocker"):
        for col in ("displacement_m", "velocity_m_s", "accel_m_s2"):
            assert np.all(np.isfinite(r.columns[f"part_{name}_{col}"]))
    for name in ("cam", "pushrod", "rocker", "valve"):
        f = r.columns[f"contact_{name}_force_N"]
        assert np.all(f >= 0.0) or name == "pushrod"  # the bonded seat can pull
        assert set(np.unique(r.columns[f"contact_{name}_closed"])) <= {0.0, 1.0}
    # the lifter follows the cam's lift (its own travel) within the joints' deflection
    lift = r.columns["rigid_valve_lift_m"] if "rigid_valve_lift_m" in r.columns else None
    s = r.summary
    assert len(s["train_natural_frequencies_Hz"]) == 4 and s["train_natural_frequencies_Hz"][0] > 500.0
    assert r.warnings == ()
    # the cam contact's force along the lifter is the camshaft's back pressure
    np.testing.assert_allclose(r.columns["contact_cam_force_N"], r.columns["camshaft_back_pressure_N"], rtol=1e-12)
    del lift


def test_each_contact_force_is_plotted_in_the_browser_and_recorded():
    # issue #25 item 3 (the plots): the browser draws every joint's force, cam to valve, in a plot
    # of its own (the generic Forces plot keeps its five curves); the recording puts each under
    # /forces (the rerun rule for N columns)
    from explorer.view.browser import model
    from explorer.view.rerun.recording import entity_path

    r = simulate(load_scene(PUSHROD))
    plots = {p.title: p for p in model.build_plots(r)}
    contacts = plots["Contact forces"]
    assert [label for label, _, _ in contacts.series] == ["cam", "pushrod", "rocker", "valve"]
    for label, values, _ in contacts.series:  # the decimated curve keeps each column's extremes
        col = r.columns[f"contact_{label}_force_N"]
        assert np.nanmax(values) == np.max(col) and np.nanmin(values) == np.min(col)
    assert not any(label.startswith("contact ") and label != "contact force" for label, _, _ in plots["Forces"].series)
    assert entity_path("contact_rocker_force_N") == "/forces/contact_rocker"
    # a scene without parts has no such plot
    plain = simulate(load_scene(scenes_dir() / "spring_surge.toml"))
    assert "Contact forces" not in [p.title for p in model.build_plots(plain)]


def test_finger_scene_pumps_up():
    r = simulate(load_scene(FINGER))
    hla = r.summary["hla"]
    assert hla["pump_up"] and hla["pump_up_valve_lift_m"] > 1e-5
    assert not hla["per_revolution"][-1]["seated"]
    assert any(e["kind"] == "pump-up" for e in r.events)
    assert any(w.startswith("pump-up") for w in r.warnings)
    for col in ("hla_plunger_travel_m", "hla_chamber_pressure_Pa", "hla_check_valve_open"):
        assert np.all(np.isfinite(r.columns[col]))
    assert hla["check_valve_openings"] > 0
    # the adjuster's conductances in the JSON (12 digits: 1e-11 rel), by hand from the TOML: the
    # leak-down gap's Poiseuille pi d c^3 / (12 mu L), d 12 mm, c 6 um, mu 10 mPa s, L 8 mm; the
    # check valve's orifice secant C_d A_o sqrt(2 / (rho dp_ref)), 0.7, 1 mm, 850 kg/m^3, 0.5 bar
    printed = json.loads(r.json_text())["hla"]
    assert printed["leak_conductance_m3_s_Pa"] == pytest.approx(
        math.pi * 12e-3 * (6e-6) ** 3 / (12 * 0.01 * 8e-3), rel=1e-11)
    assert printed["refill_conductance_m3_s_Pa"] == pytest.approx(
        0.7 * math.pi * (1e-3) ** 2 / 4 * math.sqrt(2 / (850 * 0.5e5)), rel=1e-11)
    assert printed["leak_conductance_m3_s_Pa"] == pytest.approx(8.4823e-15, rel=1e-4)
    assert printed["refill_conductance_m3_s_Pa"] == pytest.approx(1.19264e-10, rel=1e-5)
    # the running modes (test_finger_train_modes_are_the_running_trains_hand_assembled) as cam
    # orders at 4800 rpm: f / 80 Hz
    f = _finger_hand_frequencies()
    assert r.summary["train_natural_frequencies_Hz"] == pytest.approx(f, rel=1e-11)
    orders = r.summary["train_modes_cam_orders"]
    assert [m["cam_order"] for m in orders] == pytest.approx(f / 80.0, rel=1e-11)
    assert [sorted(m["exciting_accel_m_s2"]) for m in orders] == [
        sorted({str(math.floor(x)), str(math.ceil(x))}) for x in f / 80.0]


def _finger_hand_frequencies(stop_stiffness: float = 0.0, pr: float = 5.7e6) -> np.ndarray:
    """finger_hla_pumpup's running modes assembled by hand from its TOML (valve-referred, DOFs
    [valve s, finger q, plunger p]): the roller on the cam k_0 = 100 N/um / 1.7^2 compressed by
    S - q - g p (g = 0.7, the lever: the plunger going in lowers the finger's pivot), the pad
    k_1 = 150 N/um by q - s, the valve spring 40 N/mm on s (off its seat), the plunger spring
    5 N/mm and the shut chamber's oil column A^2 beta_e / V on p (beta_e the secant of 2 % air,
    isothermal, from 3 bar to the scene's reference_pressure pr, 5.7 MPa gauge, oil 1.5 GPa); the
    finger 0.35 kg cm^2 / (40 mm)^2."""
    from scipy.linalg import eigh

    atm, X, ps = 101_325.0, 0.02, 0.3e6
    beta_e = (pr - ps) / ((1 - X) * (pr - ps) / 1.5e9 + X * (1 - (ps + atm) / (pr + atm)))
    oil = (math.pi * 0.012**2 / 4) ** 2 * beta_e / 200e-9
    k0, k1, kv, kp, g = 100e6 / 1.7**2, 150e6, 40e3, 5e3, 0.7
    K = np.array([[k1 + kv, -k1, 0.0],
                  [-k1, k0 + k1, k0 * g],
                  [0.0, k0 * g, k0 * g * g + kp + oil + stop_stiffness]])
    M = np.diag([0.05, 0.35e-4 / 0.04**2, 0.012])
    return np.sqrt(eigh(K, M, eigvals_only=True)) / (2 * math.pi)


def test_a_secant_modulus_far_from_the_chambers_peak_warns():
    # the linear chamber runs on the aerated oil's secant to hla.reference_pressure; the summary
    # gives the secant to the chamber's peak as well, by the chord (hand: (p - p_s) over the oil's
    # (1 - X)(p - p_s)/beta_l plus the air's X (1 - p_s,abs/p_abs), isothermal; 1e-12 rel), and
    # the run warns when the two are more than 50 % apart. The scene sets 5.7 MPa, near its peak:
    # no warning; the default 10 MPa: the secant 380 MPa against 243 MPa at the 5.69 MPa peak, +56 %
    atm, X, ps = 101_325.0, 0.02, 0.3e6

    def secant(p):
        return (p - ps) / ((1 - X) * (p - ps) / 1.5e9 + X * (1 - (ps + atm) / (p + atm)))

    for pr, warned in ((None, False), (10e6, True)):
        r = simulate(load_scene(FINGER, [] if pr is None else [f'hla.reference_pressure="{pr / 1e6:g} MPa"']))
        hla = r.summary["hla"]
        peak = hla["chamber_pressure_max_Pa"]
        assert hla["secant_modulus_at_peak_Pa"] == pytest.approx(secant(peak), rel=1e-12)
        assert hla["effective_bulk_modulus_Pa"] == pytest.approx(secant(pr or 5.7e6), rel=1e-12)
        lines = [w for w in r.warnings if w.startswith("the oil's modulus")]
        assert bool(lines) is warned
        if warned:
            assert peak == pytest.approx(5.687e6, rel=1e-3)
            assert "10 MPa (380 MPa)" in lines[0] and "5.69 MPa, where the secant is 243 MPa (+56 %)" in lines[0]
        else:
            assert abs(hla["effective_bulk_modulus_Pa"] / hla["secant_modulus_at_peak_Pa"] - 1.0) < 0.05
    # oil without air has one modulus at every pressure: no secant to the peak, no warning
    r = simulate(load_scene(FINGER, ["hla.aeration=0.0"]))
    assert "secant_modulus_at_peak_Pa" not in r.summary["hla"]
    assert not any(w.startswith("the oil's modulus") for w in r.warnings)


def test_finger_train_modes_are_the_running_trains_hand_assembled():
    # the audit's finding: the modes closed the plunger's retaining stop (1e8 N/m), 1 mm away in
    # running, and came out 3116 / 15958 / 17987 Hz. The running train has the load path closed
    # and the stop open: the hand eigenproblem above. Tolerance 1e-12 rel: two dense
    # eigensolvers on a 3x3 pair whose stiffness spread is ~50 (round-off ~1e-15)
    scene = load_scene(FINGER)
    tr = TrainModel.from_scene(scene)
    f = tr.natural_frequencies(tr.running_key())
    hand = _finger_hand_frequencies()
    np.testing.assert_allclose(f, hand, rtol=1e-12)
    # the auditor's printed hand figures, for the secant to the default 10 MPa (0.1 Hz: 5e-5 rel)
    ten = replace(tr, hla=replace(tr.hla, reference_pressure=10e6))
    np.testing.assert_allclose(ten.natural_frequencies(ten.running_key()), [2528.4, 9277.5, 16863.4], rtol=5e-5)
    np.testing.assert_allclose(ten.natural_frequencies(ten.running_key()), _finger_hand_frequencies(pr=10e6),
                               rtol=1e-12)
    # the stop's travel does not enter the running modes: without hla.travel the same, bit for bit
    text = FINGER.read_text()
    assert text.count("\ntravel = ") == 1
    no_stop = TrainModel.from_scene(loads_scene(re.sub(r"\ntravel = [^\n]*", "", text)))
    assert no_stop.hla.travel is None and len(no_stop.all_joints) == len(tr.all_joints) - 1
    assert np.array_equal(no_stop.natural_frequencies(no_stop.running_key()), f)
    # a plunger that rests on its stop (a travel below its rest: pressed on it by its spring and
    # the supply) has the stop in its modes: the hand matrix with the stop's 1e8 N/m on p, the
    # audit's 3116 Hz
    on_stop = replace(tr, hla=replace(tr.hla, travel=-1e-5))
    assert on_stop.running_key()[0] == (True, True, True)
    stiff = _finger_hand_frequencies(1e8)
    np.testing.assert_allclose(on_stop.natural_frequencies(on_stop.running_key()), stiff, rtol=1e-12)
    np.testing.assert_allclose(_finger_hand_frequencies(1e8, pr=10e6)[0], 3116.14, rtol=5e-6)  # with 10 MPa's secant


def test_finger_scene_below_its_float_speed_seats_every_revolution():
    r = simulate(load_scene(FINGER, overrides=["drive.rpm=3000", "hla.revolutions=3"]))
    hla = r.summary["hla"]
    assert not hla["pump_up"] and hla["pump_up_valve_lift_m"] == 0.0
    assert all(rev["seated"] for rev in hla["per_revolution"])
    assert not any(e["kind"] == "pump-up" for e in r.events)
    # the adjuster leaks down under the lift's load: its plunger sinks over each revolution
    assert abs(hla["plunger_travel_per_revolution_m"]) < 5e-5


def test_scene_without_elements_is_todays_model():
    # the linkage's explicit default (contact one-sided) changes nothing: the same model, the same numbers
    base = simulate(load_scene(scenes_dir() / "spring_surge.toml"))
    same = simulate(load_scene(scenes_dir() / "spring_surge.toml", overrides=['linkage.contact="one-sided"']))
    for name, values in base.columns.items():
        assert np.array_equal(values, same.columns[name]), name


@pytest.mark.parametrize("extra, linkage, seat, key", [
    (ELEMENT.replace('mass = "60 g"', 'mass = "60 g"\ninertia = "1 kg*cm**2"\narm = "4 cm"'), None, None,
     "linkage.elements[0].mass"),
    (ELEMENT + 'contact = "bonded"\n', None, None, "linkage.elements[0].contact"),
    (ELEMENT.replace('"lifter"', '"valve"'), None, None, "linkage.elements[0].name"),
    (ELEMENT.replace('"lifter"', '"Lifter 1"'), None, None, "linkage.elements[0].name"),
    (ELEMENT + ELEMENT, None, None, "linkage.elements[1].name"),
    (ELEMENT + 'colour = "red"\n', None, None, "linkage.elements[0].colour"),
    (ELEMENT.replace('stiffness = "150 N/um"', 'stiffness = "150 kg"'), None, None, "linkage.elements[0].stiffness"),
    (ELEMENT, None, "restitution = 0.3", "seat.stiffness"),
    ("", 'stiffness = "120 N/um"\ncontact = "bonded"', None, "linkage.contact"),
    ("", 'stiffness = "120 N/um"\ncontact = "glued"', None, "linkage.contact"),
    ('[hla]\nplunger_mass = "12 g"', None, None, "hla.plunger_diameter"),
])
def test_train_input_errors_name_the_key(extra, linkage, seat, key):
    text = _text(extra, linkage or 'stiffness = "120 N/um"\ndamping = "40 N*s/m"', seat or "")
    with pytest.raises(InputError) as err:
        loads_scene(text, "train.toml")
    assert err.value.key == key, str(err.value)
    assert "\n" not in str(err.value)


HLA = """[hla]
plunger_mass = "12 g"
plunger_diameter = "12 mm"
clearance = "6 um"
leak_length = "8 mm"
viscosity = "10 mPa*s"
chamber_volume = "200 mm**3"
supply_pressure = "3 bar"
spring_rate = "5 N/mm"
"""


@pytest.mark.parametrize("extra, ratio, key", [
    (HLA, 1.5, "hla"),  # no elements: nothing to pivot
    (ELEMENT + HLA, 1.0, "hla.lever"),  # a ratio of 1 has no default lever
    (ELEMENT + HLA + 'reference_pressure = "2 bar"\n', 1.5, "hla.reference_pressure"),
    (ELEMENT + HLA + 'clearance_x = "1 um"\n', 1.5, "hla.clearance_x"),
    (ELEMENT + HLA.replace('clearance = "6 um"', 'clearance = "7 mm"'), 1.5, "hla.clearance"),
    (ELEMENT + HLA + 'aeration = 1.5\n', 1.5, "hla.aeration"),
    (ELEMENT + HLA + 'revolutions = 0\n', 1.5, "hla.revolutions"),
    (ELEMENT + HLA.replace('viscosity = "10 mPa*s"', 'viscosity = "10 mm"'), 1.5, "hla.viscosity"),
])
def test_hla_input_errors_name_the_key(extra, ratio, key):
    with pytest.raises(InputError) as err:
        loads_scene(_text(extra, follower_ratio=ratio), "train.toml")
    assert err.value.key == key, str(err.value)


_values = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), st.floats(allow_nan=True),
                    st.text(max_size=12), st.lists(st.integers(), max_size=2))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(key=st.sampled_from(["name", "mass", "inertia", "arm", "ratio", "stiffness", "damping", "lash", "contact"]),
       value=_values)
def test_any_bad_element_value_is_one_input_error(key, value):
    # a valid element with one value replaced by anything: it loads, or fails with one InputError
    import tomllib

    data = tomllib.loads(_text(ELEMENT))
    element = data["linkage"]["elements"][0]
    if value is None:
        element.pop(key, None)
    else:
        element[key] = value
    from explorer.scene.scene import scene_from_dict

    try:
        scene_from_dict(data, "train.toml")
    except InputError as err:
        assert "\n" not in str(err)


_quantities = st.sampled_from(["-3 bar", "0 bar", "1e30 Pa", "nan Pa", "inf mm", "12 kg", "5", "abc", "1e-30 m",
                                "0 mm**3", "-1 mPa*s", "2 N/um"])


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(key=st.sampled_from([*HLA_KEYS, *HLA_NUMBERS, "lever", "revolutions"]), value=st.one_of(_values, _quantities))
def test_any_bad_hla_value_is_one_input_error(key, value):
    # a valid [hla] with one value replaced by anything (removed where None): it loads with a
    # finite adjuster, or fails with one InputError naming an [hla] key, in one line
    import tomllib

    from explorer.scene.scene import scene_from_dict

    data = tomllib.loads(_text(ELEMENT + HLA))
    if value is None:
        data["hla"].pop(key, None)
    else:
        data["hla"][key] = value
    try:
        scene = scene_from_dict(data, "train.toml")
    except InputError as err:
        assert "\n" not in str(err) and err.key.startswith("hla"), str(err)
        return
    hla = scene.hla.hla
    assert all(math.isfinite(v) for v in vars(hla).values() if isinstance(v, float)), hla


def test_sweep_rows_equal_simulate_bit_for_bit():
    # the shared engine (the elastic effect itself) on the finger scene over speed: each row is
    # simulate's own, the pump-up column where the adjuster holds the valve open
    base = load_scene(FINGER, overrides=["hla.revolutions=2", "solver.steps_per_revolution=720"])
    names = result_columns(base)
    assert set(HLA_COLUMNS) <= set(names)
    # a scene without [hla] has none of them (its table stays as before: the golden sweeps)
    assert not set(HLA_COLUMNS) & set(result_columns(load_scene(PUSHROD)))
    keys = ("drive.rpm",)
    values = np.array([[3000.0], [5200.0]])
    table = compute_chunk(base, keys, values, names, _Shared(), engine=SHARED)
    for row, vals in zip(table, values):
        r = simulate(scene_for(base, keys, vals))
        want = row_figures(set(names), r)
        got = dict(zip(names, row))
        for name in want:
            assert (got[name] == want[name]) or (math.isnan(got[name]) and math.isnan(want[name])), name
    assert table[0][names.index("pump_up_valve_lift_m")] == 0.0
    assert table[1][names.index("pump_up_valve_lift_m")] > 0.0
