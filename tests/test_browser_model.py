"""What the browser explorer computes for the page, without a viewer: one float speed whichever
effects are ticked (issue #28.5), the spring advice off the path to the plots (#27.1), the
fields' reading of what was typed (#28.1, #28.2)."""

from __future__ import annotations

import math
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import SCENES, process_timeout
from explorer.core.units import parse_quantity, to_si
from explorer.effects.lift import build_lift
from explorer.effects.pipeline import simulate
from explorer.scene.scene import load_scene
from explorer.view.browser import model
from explorer.view.browser import speedsweep as ss
from explorer.view.browser.parameters import PARAMETERS, NotYet, field_value

DEMO = SCENES / "cycloidal_demo.toml"
FLOAT = SCENES / "valve_float_demo.toml"


def _jump(path, *overrides):
    """The oracle: the forces effect's own float (jump) speed, from a run with it ticked."""
    scene = load_scene(path, [*overrides, 'effects=["forces"]'])
    return simulate(scene).summary["jump_speed_rpm"]


@pytest.mark.parametrize("path, rpm", [(DEMO, 6000.0), (DEMO, 2000.0), (SCENES / "elastic_float.toml", 4000.0),
                                       (SCENES / "trip_gear_dashpot.toml", 100.0)])
def test_one_float_speed_whichever_effects_are_ticked(path, rpm):
    """#28.5: on cycloidal_demo at 6000 rpm the page said "Warnings (0)" (forces not ticked)
    while its own speed sweep said the float speed is 2900 rpm. Now the read-out, its warning and
    the sweep's marker all carry the forces effect's float speed (the trip gear's is its latch's
    throw-off speed, not the generic rigid train's), whichever effects are ticked; one warning."""
    expected = _jump(path, f"drive.rpm={rpm}")
    trip = path.name.startswith("trip")
    for effects in ('effects=["kinematics"]', 'effects=["kinematics", "lash", "elastic"]', None):
        overrides = (f"drive.rpm={rpm}",) + ((effects,) if effects else ())
        prepared = model.prepare(model.Request(str(path), overrides))
        assert prepared.float_rpm == expected, effects
        if not trip:  # (the trip gear's own warnings speak of its latch throwing the valve off)
            warned = [line for line in prepared.readout.splitlines() if line.startswith("- ⚠ valve float")]
            assert len(warned) == (1 if rpm >= expected else 0), (effects, warned)
        sweep = ss.start_sweep(prepared.scene, prepared.lift, 1, None, prepared.result, prepared.float_rpm)
        assert isinstance(sweep, ss.NoSweep) == trip
        if not trip:
            assert sweep.float_rpm == expected
            # and computed by the sweep itself, the same number
            assert ss.start_sweep(prepared.scene, prepared.lift, 1, None, prepared.result).float_rpm == expected


def test_the_float_speed_of_a_speed_change_is_the_previous_one():
    """It does not depend on the speed: a speed change reuses it (no second run of 'forces')."""
    first = model.prepare(model.Request(str(DEMO), ('effects=["kinematics"]',)))
    calls = []
    original = model.rigid_float_rpm
    model.rigid_float_rpm = lambda *a, **k: calls.append(1) or original(*a, **k)
    try:
        second = model.prepare(model.Request(str(DEMO), ('effects=["kinematics"]', "drive.rpm=6000")), first)
    finally:
        model.rigid_float_rpm = original
    assert calls == [] and second.float_rpm == first.float_rpm == _jump(DEMO)


def test_the_spring_advice_is_off_the_path_to_the_plots_and_cached_by_what_it_depends_on(monkeypatch):
    """#27.1: the spring advisor was 73 % of simulate on the float demo, on every speed change.
    The result shown first has the plots and figures without it; the advice follows
    (advice_readout, in the compute child once idle) and is the advisor's own block (oracle:
    simulate with it in the pipeline). With a target_rpm of its own it does not depend on the
    speed: a speed change reuses it."""
    prepared = model.prepare(model.Request(str(FLOAT)))
    assert prepared.advice_pending and "Spring advice:** computing" in prepared.readout
    assert "spring_design" not in prepared.result.summary
    full = simulate(load_scene(FLOAT))
    cache: dict = {}
    readout = model.advice_readout(prepared, cache)
    expected = model.readout_markdown(full, prepared.label, prepared.float_rpm)
    advice = [line for line in readout.splitlines() if line.startswith("- ") and "preload" in line]
    assert advice and advice == [line for line in expected.splitlines() if line.startswith("- ") and "preload" in line]
    assert "computing" not in readout

    from explorer.effects import spring_design

    calls = []
    original = spring_design.spring_design_summary
    monkeypatch.setattr(spring_design, "spring_design_summary", lambda *a: calls.append(1) or original(*a))
    targeted = ('spring_design.target_rpm="4000 rpm"',)
    a = model.prepare(model.Request(str(FLOAT), targeted))
    b = model.prepare(model.Request(str(FLOAT), (*targeted, "drive.rpm=3000")), a)
    cache = {}
    model.advice_readout(a, cache)
    model.advice_readout(b, cache)
    assert len(calls) == 1  # the speed changed, the advice's target did not
    c = model.prepare(model.Request(str(FLOAT), ("drive.rpm=3000",)))
    d = model.prepare(model.Request(str(FLOAT), ("drive.rpm=3100",)), c)
    model.advice_readout(c, cache)
    model.advice_readout(d, cache)
    assert len(calls) == 3  # no target: the advice is for the scene's speed, each its own


def test_the_compute_worker_hands_the_advice_on_after_the_result():
    from explorer.view.browser.compute import ComputeWorker

    got = []
    worker = ComputeWorker(on_ready=lambda p: got.append(("ready", p.request.serial)),
                           on_error=lambda r, m: got.append(("error", m)),
                           on_advice=lambda serial, readout: got.append(("advice", serial, readout))).start()
    try:
        worker.submit(model.Request(str(FLOAT), serial=1))
        deadline = time.monotonic() + process_timeout()
        while not worker.sweep_idle() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert worker.sweep_idle()
    finally:
        worker.stop()
    assert [g[0] for g in got] == ["ready", "advice"] and got[1][1] == 1
    assert "**Spring advice** for 4000 rpm" in got[1][2]


@pytest.mark.parametrize("key, text, complete", [
    ("valve.lash", "7 ", None),  # a number waiting for its unit: not yet anything (#28.1)
    ("valve.lash", "7 k", "error"),
    ("valve.lash", "7 kg", "error"),  # not a length
    ("valve.lash", "7", "7 mm"),  # a bare number means the label's unit (#28.2)
    ("valve.lash", "0.6 mm", "0.6 mm"),
    ("linkage.stiffness", "3000", "3000 N/mm"),
    ("linkage.stiffness", "3000 N", "error"),  # a force, not a stiffness
    ("linkage.stiffness", "3000 N/", "error"),
    ("linkage.stiffness", "2.5e6 N/m", "2.5e6 N/m"),
    ("spring.preload", "40 kgf", "40 kgf"),
    ("spring.rate", "", None),
])
def test_a_field_applies_only_a_complete_quantity_of_its_dimension(key, text, complete):
    p = PARAMETERS[key]
    if complete is None or complete == "error":
        with pytest.raises(NotYet) as why:
            field_value(p, text)
        assert why.value.typing == (complete is None)
        return
    assert field_value(p, text) == complete
    # and the scene reader takes it as that quantity: the field's unit, not SI
    scene = load_scene(DEMO, [model.override(key, complete)])
    section, name = key.split(".")
    got = getattr(getattr(scene, section), name)
    number = float(complete.split()[0])
    factor = {"mm": 1e-3, "N/mm": 1e3, "N/m": 1.0, "kgf": 9.80665, "N": 1.0}[complete.split()[1]]
    assert got == pytest.approx(number * factor, rel=1e-12)


def test_the_readout_of_a_scene_that_floats_says_so_once():
    prepared = model.prepare(model.Request(str(DEMO), ("drive.rpm=6000",)))
    assert "forces" in prepared.scene.effects  # the demo opens with forces now (#28.10)
    warnings = [line for line in prepared.readout.splitlines() if line.startswith("- ⚠ valve float")]
    assert len(warnings) == 1 and f"{prepared.float_rpm:.6g}" in warnings[0]
    assert math.isfinite(prepared.float_rpm) and prepared.float_rpm < 6000


def test_cycloidal_demo_opens_with_what_the_readme_shows():
    """#28.10: the README's scene example (the cycloidal demo) lists effects kinematics, lash,
    forces, contact and elastic; the file opened with kinematics and lash only."""
    scene = load_scene(DEMO)
    assert set(scene.effects) == {"kinematics", "lash", "forces", "contact", "elastic"}
    result = simulate(scene, lift=build_lift(scene))
    assert {"contact_force_N", "linkage_force_N", "hertz_stress_Pa"} <= set(result.columns)
    assert result.summary["elastic_event_counts"].get("separation", 0) > 0  # just above its float speed


TEXT = st.one_of(
    st.text(max_size=120),
    st.builds(lambda n, sp, u: f"{n}{sp}{u}", st.floats(allow_nan=True, allow_infinity=True).map(repr),
              st.sampled_from(["", " ", "  "]),
              st.sampled_from(["", "mm", "m", "kg", "N", "N/mm", "N/m", "kgf", "in", "deg", "mm/", "**2", "N*s/m", "µm"])),
)


@settings(max_examples=300, deadline=None)
@given(key=st.sampled_from(["valve.lash", "linkage.stiffness", "spring.preload", "spring.rate"]), text=TEXT,
       final=st.booleans())
def test_any_text_is_a_value_of_the_fields_dimension_or_not_yet(key, text, final):
    """Whatever a page sends into a quantity field: a complete quantity of the field's dimension
    (with its unit, which the scene reader takes as that dimension), or NotYet with the reason;
    never another exception (the server reads it, not the time-limited compute process)."""
    p = PARAMETERS[key]
    try:
        value = field_value(p, text, final=final)
    except NotYet as why:
        assert str(why)
        return
    assert isinstance(value, str) and parse_quantity(value, file="test", key=key)[1]  # a number and its unit
    assert math.isfinite(to_si(value, p.dimension, file="test", key=key))
