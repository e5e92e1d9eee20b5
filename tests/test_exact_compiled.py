"""The solver table's `exact-compiled` (explorer.dynamics.exact_kernel.solve, issue #27.8): the
exact solver's grid, closed forms, events and output with the stepping and the event search in one
compiled call, as a scene's [solver] method.

Oracles and tolerances:
- the Python exact solver (dynamics/exact.py) on the same model and times: the same grid and
  output code, node states carried step by step instead of by the modal closed form over a
  window, so they differ by rounding only (~1e-16 relative per step): phases and event kinds
  identical, lift within 1e-12 m and event instants within 1e-12 s (tests/test_sweep_kernel.py's
  tolerances; measured 3e-16 and 1e-15 m on the float scenes, 1e-13 m on a 1e9 N/m linkage
  chattering with restitution 0.9, where rounding is amplified from bounce to bounce);
- closed forms (tests/dynamics_cases.py): the friction apex (stick for good, or fall), the
  stopping drive (oscillation, separation, flight, re-contact), within 1e-15 m and 1e-15 s
  (measured 2e-17 and 6e-17 m);
- the Zeno tail of the seat chatter: the accumulation instant 2 v e / (A (1 - e)) of the
  geometric series to 1e-12 relative, the valve at rest after it;
- scipy DOP853 at rtol 1e-12, atol 1e-15 (the bench's reference): within 1e-12 m, the reference's
  own accuracy at that tolerance (measured 7e-14 m, as the Python exact solver's);
- bad input: a stiffness k(t), unsorted or non-finite times, refused in one line (a ValueError;
  at scene load an InputError naming solver.method).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import SCENES
from dynamics_cases import flight_case, friction_apex, stopping_drive
from explorer.core.errors import InputError
from explorer.dynamics.model import PHASE_CODES
from explorer.dynamics.solvers import solve
from explorer.effects.pipeline import simulate
from explorer.scene.scene import load_scene
from explorer.studies.bench import model_and_drive
from test_dynamics_varying import _manufactured

LIFT_TOL_M = 1e-12
TIME_TOL_S = 1e-12
FLOATS = ("valve_float_demo.toml", "elastic_float.toml")


def _revolution(scene_file: str, *overrides: str):
    scene = load_scene(SCENES / scene_file, list(overrides))
    model, drive = model_and_drive(scene)
    n = scene.solver.steps_per_revolution
    return model, drive, np.arange(n) * (2.0 * math.pi / drive.omega / n)


def _agree(got, ref, lift_tol: float = LIFT_TOL_M, time_tol: float = TIME_TOL_S) -> None:
    """got (exact-compiled) as ref (exact): phases and event kinds identical, lift and instants
    within the tolerances, Zeno accumulation instants where ref has them."""
    assert np.array_equal(got.phase, ref.phase)
    assert [e["kind"] for e in got.events] == [e["kind"] for e in ref.events]
    assert np.abs(got.s - ref.s).max() <= lift_tol
    for a, b in zip(got.events, ref.events):
        assert abs(a["time_s"] - b["time_s"]) <= time_tol
        assert ("zeno_accumulation_s" in a) == ("zeno_accumulation_s" in b)
        if "zeno_accumulation_s" in b:
            assert abs(a["zeno_accumulation_s"] - b["zeno_accumulation_s"]) <= time_tol
    assert got.stats["method"] == "exact-compiled"


@pytest.mark.parametrize("scene_file", FLOATS)
@pytest.mark.parametrize("overrides", [(), ('linkage.stiffness="1e9 N/m"', "seat.restitution=0.9"),
                                       ('linkage.stiffness="1e10 N/m"', "seat.restitution=0.9"),
                                       ("loads.friction=150", "seat.restitution=0.6", "drive.rpm=3000")])
def test_float_scenes_as_the_python_exact_solver(scene_file, overrides):
    """The float scenes as shipped, on stiff linkages chattering on the seat (restitution 0.9),
    and with Coulomb friction strong enough to hold the valve (stuck phases)."""
    model, drive, t = _revolution(scene_file, *overrides)
    ref = solve(model, drive, t, method="exact")
    got = solve(model, drive, t, method="exact-compiled")
    _agree(got, ref)
    assert {"separation", "seat"} <= {e["kind"] for e in ref.events}


def test_friction_sticks_and_falls_as_the_closed_form():
    """Thrown up from the seat against the preload W and friction mu = 50 N: at the apex it sticks
    for good when W <= mu, else it falls with deceleration (W - mu)/M (dynamics_cases.friction_apex)."""
    for preload in (30.0, 80.0):
        case = friction_apex(preload)
        # (the apex between nodes: on a node, where the velocity is zero to rounding, the node's
        # phase may be flight in one and stuck in the other, v = 6e-17 m/s against 0)
        t = np.linspace(0.0, 3.0 * case.t_top, 3000)
        ref = solve(case.model, case.drive, t, method="exact", initial_state=case.start)
        got = solve(case.model, case.drive, t, method="exact-compiled", initial_state=case.start)
        _agree(got, ref)
        after = t > case.t_top
        truth = np.full(after.sum(), case.top) if case.sticks else case.fall(t[after])
        assert np.abs(got.s[after] - truth).max() <= 1e-15
        assert (got.phase[after] == PHASE_CODES["stuck"]).any() == case.sticks


def test_stopping_drive_separates_and_lands_as_the_closed_form():
    """A drive that stops dead from 1 m/s: the valve oscillates, separates where k x = 0, flies a
    parabola and touches again (dynamics_cases.stopping_drive); starts moving (initial_state)."""
    case = stopping_drive()
    got = solve(case.model, case.drive, case.t, method="exact-compiled", initial_state=case.start)
    _agree(got, solve(case.model, case.drive, case.t, method="exact", initial_state=case.start))
    osc = (case.t > case.t1) & (case.t < case.t_sep)
    fly = (case.t > case.t_sep) & (case.t < case.t_re)
    assert np.abs(got.s[osc] - case.oscillation(case.t[osc])).max() <= 1e-15
    assert np.abs(got.s[fly] - case.flight(case.t[fly])).max() <= 1e-15
    assert [e["kind"] for e in got.events] == ["separation", "re-contact"]
    assert got.events[0]["time_s"] == pytest.approx(case.t_sep, abs=1e-15)
    assert got.events[1]["time_s"] == pytest.approx(case.t_re, abs=1e-15)


@pytest.mark.parametrize("friction", [150.0, 300.0])
@pytest.mark.parametrize("start", [(0.0, 0.0), (1e-4, 0.0), (3e-4, 0.0), (0.0, 0.3), (2e-4, -0.3), (5e-4, 0.2)])
def test_initial_states_as_the_python_exact_solver(start, friction):
    """initial_state (s, v) at the first output time: seated, released from above the seat (falling
    against 150 N of friction, or held by 300 N against the 235 N preload: stuck), thrown up or
    down, in the phase phases.phase_of_state gives both solvers."""
    model, drive, t = _revolution("elastic_float.toml", f"loads.friction={friction}", "seat.restitution=0.6")
    ref = solve(model, drive, t, method="exact", initial_state=start)
    got = solve(model, drive, t, method="exact-compiled", initial_state=start)
    _agree(got, ref)
    assert got.phase[0] == ref.phase[0]
    if friction == 300.0 and start[0] > 0.0 and start[1] == 0.0:
        assert got.phase[0] == PHASE_CODES["stuck"]


@pytest.mark.parametrize("e", [0.5, 0.8, 0.95])
def test_chatter_zeno_tail_as_the_series(e):
    """Thrown up from 1 mm at 2 m/s, restitution e: bounces whose heights fall geometrically, the
    rest summed in closed form; the accumulation instant is the series' t_land + 2 e |v| / (g (1 - e))
    and the valve rests on its seat after it, as in the Python exact solver."""
    model, drive, start, g, t_land = flight_case()
    model = replace(model, restitution=e)
    v_land = start[1] - g * t_land
    t_acc = t_land + 2.0 * (-e * v_land) / (g * (1.0 - e))
    t = np.linspace(0.0, 1.3 * t_acc, 6001)
    ref = solve(model, drive, t, method="exact", initial_state=start)
    got = solve(model, drive, t, method="exact-compiled", initial_state=start)
    _agree(got, ref)
    zeno = [ev["zeno_accumulation_s"] for ev in got.events if "zeno_accumulation_s" in ev]
    assert len(zeno) == 1 and zeno[0] == pytest.approx(t_acc, rel=1e-12)
    rest = t > t_acc
    assert np.all(got.s[rest] == 0.0) and np.all(got.v[rest] == 0.0)


@pytest.mark.parametrize("scene_file", FLOATS)
def test_float_scenes_against_the_scipy_reference(scene_file):
    model, drive, t = _revolution(scene_file)
    ref = solve(model, drive, t, method="scipy", rtol=1e-12, atol=1e-15)
    got = solve(model, drive, t, method="exact-compiled")
    assert np.abs(got.s - ref.s).max() <= 1e-12
    assert [e["kind"] for e in got.events] == [e["kind"] for e in ref.events]
    for a, b in zip(got.events, ref.events):
        assert abs(a["time_s"] - b["time_s"]) <= 1e-9  # (scipy's own event location)


def test_repeated_and_single_output_times_as_the_python_solver():
    """Sorted times with repeats (and a single instant) are the Python solver's: each repeated
    time gets its node's values (exact_output.output_nodes, shared)."""
    model, drive, t = _revolution("valve_float_demo.toml")
    t = np.sort(np.concatenate([t, t[::7]]))
    _agree(solve(model, drive, t, method="exact-compiled"), solve(model, drive, t, method="exact"))
    one = solve(model, drive, t[:1], method="exact-compiled")
    assert one.s.tolist() == [0.0] and one.phase.tolist() == [PHASE_CODES["seated"]]


def test_a_scene_may_name_it_and_simulate_runs_it():
    """[solver] method = "exact-compiled": the elastic effect runs it and reports it; its columns
    as the exact solver's within the lift tolerance (the linkage force within k times it)."""
    exact = simulate(load_scene(SCENES / "valve_float_demo.toml", ['effects=["elastic"]']))
    compiled = simulate(load_scene(SCENES / "valve_float_demo.toml",
                                   ['effects=["elastic"]', 'solver.method="exact-compiled"']))
    assert compiled.summary["elastic_method"] == "exact-compiled"
    assert exact.summary["elastic_method"] == "exact"
    k = compiled.scene.linkage.stiffness
    assert np.abs(compiled.columns["valve_lift_m"] - exact.columns["valve_lift_m"]).max() <= LIFT_TOL_M
    force = [c for c in exact.columns if c.startswith("linkage_force")][0]
    assert np.abs(compiled.columns[force] - exact.columns[force]).max() <= k * LIFT_TOL_M
    assert [e.kind for e in compiled.events] == [e.kind for e in exact.events]


def test_a_varying_stiffness_is_refused_in_one_line():
    model, drive, t, _ = _manufactured()
    with pytest.raises(ValueError, match="'exact-compiled' needs a constant linkage stiffness") as err:
        solve(model, drive, t, method="exact-compiled")
    assert "\n" not in str(err.value)
    with pytest.raises(InputError) as err:
        load_scene(SCENES / "rolling_lever.toml", ['solver.method="exact-compiled"'])
    assert "solver.method" in str(err.value) and "exact-compiled" in str(err.value) and "\n" not in str(err.value)


_TIME = st.one_of(st.floats(0.0, 0.01), st.sampled_from([math.nan, math.inf, -math.inf, -0.0]))


@settings(max_examples=60, deadline=None)
@given(st.lists(_TIME, min_size=0, max_size=12))
def test_bad_output_times_are_refused_as_the_python_solver_refuses_them(times):
    """Lists of times within the flight case's 10 ms, some NaN or infinite, in any order: the
    compiled solver refuses exactly those the Python solver refuses (empty, unsorted, not finite),
    with the same one-line ValueError, and solves the others alike."""
    model, drive, start, g, t_land = flight_case()
    outcome = []
    for method in ("exact", "exact-compiled"):
        try:
            outcome.append(solve(model, drive, np.array(times, dtype=float), method=method).phase.tolist())
        except ValueError as err:
            assert "\n" not in str(err)
            outcome.append(str(err))
    assert outcome[0] == outcome[1]


def test_a_sweep_of_a_scene_naming_it_runs_the_compiled_batch_as_exact():
    """Its batch module is the exact solver's (solvers.py: batch_entry): a speed sweep of a scene
    with exact-compiled takes the compiled path and gives the rows of the same scene with exact,
    bit for bit (one kernel, one model)."""
    from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns

    rows = []
    for method in ("exact", "exact-compiled"):
        base = load_scene(SCENES / "elastic_float.toml", [f'solver.method="{method}"'])
        shared = _Shared()
        assert engine_for(base, shared).name == "compiled"
        rows.append(compute_chunk(base, ("drive.rpm",), np.linspace(1500.0, 6000.0, 40)[:, None], result_columns(base),
                                  shared))
    assert np.array_equal(rows[0], rows[1], equal_nan=True)
