"""The sweep's batch engine against `simulate` (issue #14.3): on 240 random runs of the float
scenes and Schenker's gear -- speeds, stiffnesses up to 1e11 N/m, masses, preloads, lash
(zero included), damping, restitution up to 0.9 (chatter) -- every row equals the row read
from `simulate` on the same values, the valve lift equals simulate's within 1e-12 m and the
event sequences are identical (kinds and instants).

The oracle is `simulate` itself: the engine shares the lift, the float speed, the smooth
pieces and the lash take-up across runs and skips what no row needs; it must not change a
number. These tests hold the "shared" engine (the elastic effect itself, the registry's exact
solver), so the comparison is exact; the compiled engine, which takes these scenes by default,
is held to simulate in tests/test_sweep_kernel.py.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import SCENES
from explorer.effects.pipeline import simulate
from explorer.core.errors import InputError
from explorer.scene.scene import load_scene
from explorer.effects.pipeline import figures
from explorer.studies.sweep_engine import ENGINES, _Shared, compute_chunk, result_columns, row_figures
from explorer.studies.sweep_spec import scene_for

KEYS = ("drive.rpm", "linkage.stiffness", "valve.mass", "spring.preload", "valve.lash", "linkage.damping",
        "seat.restitution")
LIFT_TOL_M = 1e-12
# the engine that runs the elastic effect itself (the compiled one, which takes these scenes by
# default, is tests/test_sweep_kernel.py's)
SHARED = next(engine for engine in ENGINES if engine.name == "shared")


def _random_values(rng, n, rpm, k_max):
    """n runs: log-uniform stiffness up to k_max (a tenth of the runs at k_max itself), a fifth of
    the runs with zero lash, a third with restitution 0.9 (chatter), a third undamped."""
    v = np.empty((n, len(KEYS)))
    v[:, 0] = rng.uniform(*rpm, n)
    v[:, 1] = np.exp(rng.uniform(math.log(1e6), math.log(k_max), n))
    v[: n // 10, 1] = k_max
    v[:, 2] = rng.uniform(0.08, 0.2, n)
    v[:, 3] = rng.uniform(120.0, 320.0, n)
    v[:, 4] = rng.uniform(0.0, 4e-4, n)
    v[rng.random(n) < 0.2, 4] = 0.0
    v[:, 5] = rng.uniform(0.0, 20.0, n)
    v[rng.random(n) < 1 / 3, 5] = 0.0
    v[:, 6] = rng.choice([0.0, 0.3, 0.9], n)
    return v


CASES = [
    # scene, overrides, runs, speeds, largest stiffness
    ("elastic_float.toml", [], 100, (2000.0, 6000.0), 1e11),
    ("valve_float_demo.toml", ['effects=["elastic"]'], 60, (1500.0, 6000.0), 1e11),
    ("valve_float_demo.toml", ["solver.steps_per_revolution=1440"], 50, (2500.0, 6000.0), 1e9),
]


def _elastic_events(events):
    return [(e["kind"], float(e["time_s"]), e.get("velocity_m_s")) for e in events if e.get("effect") == "elastic"]


@pytest.mark.parametrize("scene_file, overrides, runs, rpm, k_max", CASES)
def test_engine_rows_lift_and_events_equal_simulate(scene_file, overrides, runs, rpm, k_max):
    base = load_scene(SCENES / scene_file, overrides)
    names = result_columns(base)
    values = _random_values(np.random.default_rng(len(overrides) * 100 + runs), runs, rpm, k_max)
    # masses below the mass of the scene's [valve] oscillating part are fine: the float scenes have none
    shared = _Shared()
    table = compute_chunk(base, KEYS, values, names, shared, engine=SHARED)
    chatter = stiff = zero_lash = separated = 0
    for i, row_values in enumerate(values):
        scene = scene_for(base, KEYS, row_values)
        try:
            result = simulate(scene)
        except (InputError, RuntimeError):
            assert table[i, names.index("run_failed")] == 1.0, i
            continue
        run = figures(scene, shared)  # the engine's run: the pipeline's figures-only run
        # the motion: lift within 1e-12 m, the same events in the same order at the same instants
        lift = np.asarray(run.columns["valve_lift_m"])
        assert np.max(np.abs(lift - result.columns["valve_lift_m"])) <= LIFT_TOL_M, i
        assert _elastic_events(run.events) == _elastic_events(result.events), i
        # the row: every figure as read from simulate's result
        expected = row_figures(names, result)
        got = dict(zip(names, table[i]))
        assert got["run_failed"] == 0.0
        for name, value in expected.items():
            assert got[name] == value or (math.isnan(got[name]) and math.isnan(value)), (i, name, got[name], value)
        chatter += scene.seat.restitution == 0.9 and expected["seat_impacts"] > 1
        stiff += scene.linkage.stiffness == 1e11 if k_max == 1e11 else 0
        zero_lash += scene.valve.lash == 0.0
        separated += expected["separations"] > 0
    # the hard cases are in the draw, not only planned
    assert zero_lash > 0 and separated > 0
    if scene_file == "elastic_float.toml":
        assert chatter > 0 and stiff > 0


def test_a_failing_run_is_marked_and_the_others_are_kept():
    base = load_scene(SCENES / "elastic_float.toml")
    names = result_columns(base)
    # 1 rpm with a 1e11 N/m linkage needs more solver steps than the budget: simulate refuses it
    values = np.array([[1.0, 1e11], [4000.0, 3e6]])
    with pytest.raises(InputError):
        simulate(scene_for(base, KEYS[:2], values[0]))
    table = compute_chunk(base, KEYS[:2], values, names, engine=SHARED)
    fail = names.index("run_failed")
    assert table[0, fail] == 1.0 and np.isnan(table[0, :fail]).all()
    assert table[1, fail] == 0.0 and np.isfinite(table[1, names.index("peak_linkage_force_N")])


def test_gear_scenes_take_the_simulate_path_and_agree():
    base = load_scene(SCENES / "pivoted_roller_lever.toml", ["solver.steps_per_revolution=720"])
    names = result_columns(base)
    values = np.array([[200.0], [260.0]])
    table = compute_chunk(base, ("drive.rpm",), values, names)
    for i, r in enumerate(values):
        result = simulate(scene_for(base, ("drive.rpm",), r))
        expected = row_figures(names, result)
        for name, value in expected.items():
            got = table[i, names.index(name)]
            assert got == value or (math.isnan(got) and math.isnan(value)), name


def test_shared_caches_stay_bounded_in_a_tolerance_study():
    """Memory grows with runs x columns, not with the distinct values drawn: a lash drawn anew
    every run must not keep a float-speed and pieces entry per run."""
    from explorer.studies.sweep_engine import CACHE_ENTRIES

    base = load_scene(SCENES / "valve_float_demo.toml", ['effects=["forces"]', "solver.steps_per_revolution=720"])
    names = result_columns(base)
    lash = np.random.default_rng(5).uniform(2e-4, 3e-4, CACHE_ENTRIES + 8)[:, None]
    shared = _Shared()
    table = compute_chunk(base, ("valve.lash",), lash, names, shared)
    assert len(shared.of("forces pieces")) <= CACHE_ENTRIES and len(shared.of("forces jumps")) <= CACHE_ENTRIES
    # and an evicted entry, made again, gives the same figures (the cache holds pure results)
    again = compute_chunk(base, ("valve.lash",), lash[:2], names, shared)
    assert np.array_equal(again, table[:2])


@pytest.mark.parametrize("scene_file, engine", [
    ("pivoted_roller_lever.toml", "shared"), ("rocking_cam.toml", "shared"), ("rolling_lever.toml", "shared"),
    ("trip_gear_dashpot.toml", "simulate"),  # its lift is the valve's closing: it reads the speed, the train
])
def test_a_gear_lift_that_reads_no_run_value_is_built_once_and_rows_equal_simulate(scene_file, engine):
    """The lever gears' lifts depend on their geometry alone (Gear.lift_reads):
    the engine builds the lift once and shares it (with the lash take-up) across runs; every figure
    of every row still equals simulate's to the bit, with the speed, lash, preload and stiffness
    varied together. The trip gear keeps the simulate path."""
    from explorer.studies.sweep_engine import engine_for

    base = load_scene(SCENES / scene_file, ["solver.steps_per_revolution=720"])
    assert engine_for(base, _Shared()).name == engine
    assert (base.gear_plugin.lift_reads(base) == ()) == (engine == "shared")
    names = result_columns(base)
    keys = ("drive.rpm", "valve.lash", "spring.preload", "linkage.stiffness")
    v0 = np.array([base.drive.rpm, base.valve.lash, base.spring.preload, base.linkage.stiffness])
    values = v0 * np.array([[0.8, 1.0, 1.0, 1.0], [1.3, 1.2, 0.9, 2.0], [1.1, 0.7, 1.1, 0.5]])
    shared = _Shared()
    table = compute_chunk(base, keys, values, names, shared)
    for i, r in enumerate(values):
        result = simulate(scene_for(base, keys, r))
        expected = row_figures(names, result)
        for name, value in expected.items():
            got = table[i, names.index(name)]
            assert got == value or (math.isnan(got) and math.isnan(value)), (i, name, got, value)
    assert (shared.lift is not None) == (engine == "shared")  # built once, kept for the next chunk


def test_a_rocking_cam_fitted_to_its_target_reads_the_lash():
    """gear.target use = "fitted" fits the contour to the valve's lift after the lash: its lift reads
    valve.lash, so a sweep cannot share it (the simulate path)."""
    from explorer.studies.sweep_engine import engine_for

    base = load_scene(SCENES / "rocking_cam.toml", ['gear.target.use="fitted"'])
    assert base.gear_plugin.lift_reads(base) == ("valve.lash",)
    assert engine_for(base, _Shared()).name == "simulate"
