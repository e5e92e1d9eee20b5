"""The compiled exact solver (explorer/dynamics/exact_kernel.py) and the sweep's compiled path
(explorer/effects/elastic_batch.py) against the registry's exact solver and `simulate` (issue #14.3).

Oracle: the Python exact solver (dynamics/exact.py) and `simulate` itself, on the same values.
The kernel solves the same step ODEs with the same closed forms and finds the same events with the
same rigorous bounds; it carries the node states step by step where exact.py uses the modal closed
form over a window, so the two differ by rounding only (~1e-16 relative per step). Tolerances:
  lift                 1e-12 m on every output sample (the issue's)
  event instants       1e-12 s, kinds and order identical
  event velocities     1e-9 relative + 1e-12 m/s (a velocity is the state's derivative at the root)
  figures              1e-9 relative; those that come from the linkage force k (S - lash - s) may
                       differ by k times the lift's tolerance; angles and times of events by the
                       instant's (omega * 1e-12 s); counts exactly.
Where these are below the problem's own conditioning they cannot be met by any other order of the
same operations: a chain of bounces on a very stiff linkage (k ~ 1e10 N/m, restitution 0.9)
amplifies rounding from event to event, and one ulp more stiffness, mass or preload moves the
Python solver's own lift by ~1e-12 m and its instants by ~3e-12 s. For such a run (detected when
the strict tolerances are missed) the tolerances become SPREAD_FACTOR times that spread -- the
largest change of simulate's (or exact.solve's) lift, instants and velocities under one-ulp
changes of those inputs, measured on the run itself -- and the test counts how many runs needed it
(a handful of the chattering stiff ones; events and phases stay identical in every run). One ulp
of one input is a noisy probe of the rounding of every step: on the 60 runs of the first test the
kernel's differences were 0.8 to 33 times it (lift, instants and velocities alike: one amplified
mode), hence the factor 50.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pytest

from conftest import SCENES
from explorer.core.errors import InputError
from explorer.dynamics import exact, exact_kernel
from explorer.dynamics.model import Drive, LinkageModel
from explorer.effects.lift import build_lift
from explorer.effects.pipeline import simulate
from explorer.scene.scene import load_scene
from explorer.studies.sweep_engine import ENGINES, _Shared, compute_chunk, engine_for, result_columns, row_figures
from explorer.effects.elastic_batch import ELASTIC, kernel_outputs
from explorer.studies.sweep_spec import scene_for

LIFT_TOL_M = 1e-12
TIME_TOL_S = 1e-12
REL = 1e-9
SPREAD_FACTOR = 50.0  # the kernel's rounding vs one ulp of one input: measured 0.8-33x (6 of 60 runs)
ULP_INPUTS = ("stiffness", "mass", "oscillating_mass", "preload")  # LinkageModel fields


@dataclass(frozen=True)
class Tolerance:
    lift: float = LIFT_TOL_M
    time: float = TIME_TOL_S
    velocity: float = 0.0  # added to REL * |v| + 1e-12


def _differences(lift_a, events_a, lift_b, events_b) -> Tolerance:
    """The largest differences of lift, event instants and event velocities (same kinds)."""
    dt = max([abs(a["time_s"] - b["time_s"]) for a, b in zip(events_a, events_b)] or [0.0])
    dv = max([abs(a.get("velocity_m_s", 0.0) - b.get("velocity_m_s", 0.0)) for a, b in zip(events_a, events_b)]
             or [0.0])
    return Tolerance(float(np.max(np.abs(np.asarray(lift_a) - np.asarray(lift_b)))), dt, dv)


def _within(d: Tolerance, tol: Tolerance, events) -> bool:
    vmax = max([abs(e.get("velocity_m_s", 0.0)) for e in events] or [0.0])
    return d.lift <= tol.lift and d.time <= tol.time and d.velocity <= REL * vmax + 1e-12 + tol.velocity


def _spread_tolerance(solve_with, reference) -> Tolerance:
    """SPREAD_FACTOR times the largest change of the reference under one ulp up or down of each of
    ULP_INPUTS (solve_with(field, value) -> (lift, events)), at least the strict tolerances."""
    worst = Tolerance(0.0, 0.0, 0.0)
    for field_name, value in reference["inputs"].items():
        for direction in (math.inf, -math.inf):
            lift, events = solve_with(field_name, float(np.nextafter(value, direction)))
            if [e["kind"] for e in events] != [e["kind"] for e in reference["events"]]:
                continue  # (a perturbation that changes the sequence says nothing about rounding)
            d = _differences(lift, events, reference["lift"], reference["events"])
            worst = Tolerance(max(worst.lift, d.lift), max(worst.time, d.time), max(worst.velocity, d.velocity))
    return Tolerance(max(LIFT_TOL_M, SPREAD_FACTOR * worst.lift), max(TIME_TOL_S, SPREAD_FACTOR * worst.time),
                     SPREAD_FACTOR * worst.velocity)

KEYS = ("drive.rpm", "linkage.stiffness", "valve.mass", "valve.oscillating_mass", "spring.preload", "valve.lash",
        "linkage.damping", "seat.restitution", "loads.friction")


def _random_values(rng, n, rpm, k_max):
    """n runs: log-uniform stiffness up to k_max (a tenth at k_max itself), a fifth with zero
    lash, a third with restitution 0.9 (chatter), a third undamped, a third without friction."""
    v = np.empty((n, len(KEYS)))
    v[:, 0] = rng.uniform(*rpm, n)
    v[:, 1] = np.exp(rng.uniform(math.log(1e6), math.log(k_max), n))
    v[: n // 10, 1] = k_max
    v[:, 2] = rng.uniform(0.08, 0.2, n)
    v[:, 3] = rng.uniform(0.5, 1.0, n) * v[:, 2]
    v[:, 4] = rng.uniform(120.0, 320.0, n)
    v[:, 5] = rng.uniform(0.0, 4e-4, n)
    v[rng.random(n) < 0.2, 5] = 0.0
    v[:, 6] = rng.uniform(0.0, 20.0, n)
    v[rng.random(n) < 1 / 3, 6] = 0.0
    v[:, 7] = rng.choice([0.0, 0.3, 0.9], n)
    v[:, 8] = rng.uniform(0.0, 40.0, n)
    v[rng.random(n) < 1 / 3, 8] = 0.0
    return v


def _same_kinds(got, expected):
    assert [e["kind"] for e in got] == [e["kind"] for e in expected]


def _check_solution(model, drive, t, got, ref) -> bool:
    """got (exact_kernel.solve) equals ref (exact.solve): phases and event kinds identical, lift,
    instants and velocities within the strict tolerances or the run's spread. True: the spread
    was needed."""
    assert np.array_equal(got.phase, ref.phase)
    _same_kinds(got.events, ref.events)
    d = _differences(got.s, got.events, ref.s, ref.events)
    if _within(d, Tolerance(), ref.events):
        return False

    def solve_with(name, value):
        alt = exact.solve(replace(model, **{name: value}), drive, t)
        return alt.s, alt.events

    tol = _spread_tolerance(solve_with, {"inputs": {f: getattr(model, f) for f in ULP_INPUTS}, "lift": ref.s,
                                         "events": ref.events})
    assert _within(d, tol, ref.events), (d, tol)
    return True


def test_kernel_solves_as_the_exact_solver_on_random_models():
    """exact_kernel.solve against exact.solve (same grid, same output code) on 60 random models
    of the float scene's drive: every output sample's lift and phase, every event."""
    scene = load_scene(SCENES / "elastic_float.toml")
    lift = build_lift(scene)
    values = _random_values(np.random.default_rng(7), 60, (1500.0, 6000.0), 1e11)
    kinds = set()
    spread = 0
    for row in values:
        sc = scene_for(scene, KEYS, row)
        model = LinkageModel.from_scene(sc)
        omega = sc.drive.omega
        t = np.arange(1201) * (2.0 * math.pi / 1200) / omega
        drive = Drive(lift, sc.follower.ratio, omega)
        ref = exact.solve(model, drive, t)
        got = exact_kernel.solve(model, drive, t)
        spread += _check_solution(model, drive, t, got, ref)
        kinds |= {e["kind"] for e in ref.events}
    assert kinds == {"lift-off", "separation", "re-contact", "seat"}
    assert spread <= 10  # the ill-conditioned runs are few (5 of these 60)


def test_kernel_sticks_and_turns_with_friction_as_the_exact_solver():
    """Strong Coulomb friction and a valve released from above its seat: stuck phases (held by
    friction) and velocity reversals, the same nodes and events as exact.solve."""
    scene = load_scene(SCENES / "elastic_float.toml")
    lift = build_lift(scene)
    stuck = 0
    for friction, rpm in ((120.0, 3000.0), (300.0, 2000.0), (60.0, 5000.0), (250.0, 4500.0)):
        sc = scene_for(scene, ("loads.friction", "drive.rpm", "seat.restitution"), (friction, rpm, 0.6))
        model = LinkageModel.from_scene(sc)
        omega = sc.drive.omega
        t = np.arange(3601) * (2.0 * math.pi / 3600) / omega
        drive = Drive(lift, 1.0, omega)
        ref = exact.solve(model, drive, t)
        got = exact_kernel.solve(model, drive, t)
        assert not _check_solution(model, drive, t, got, ref)
        stuck += int(np.count_nonzero(ref.phase == 3) > 0)
    assert stuck > 0  # the stuck phase is exercised, not only planned


def _close(name, got, value, stiffness, omega, tol: Tolerance, vmax: float, wn: float, flights: float = 0.0):
    """A figure within the run's tolerances (module docstring). The flight time is a sum of
    `flights` spans between two event instants, each within the instants' tolerance."""
    if isinstance(value, float) and math.isnan(value):
        return math.isnan(got)
    if name in ("separations", "seat_impacts"):
        return got == value
    err = REL * abs(value)
    if name in ("peak_linkage_force_N", "peak_camshaft_back_pressure_N"):
        err += stiffness * tol.lift
    elif name == "first_separation_deg":
        err += math.degrees(omega * tol.time)
    elif name == "lift_off_delay_s":
        err += tol.time
    elif name == "flight_time_s":
        err += 2.0 * flights * tol.time
    elif name in ("max_deviation_m", "largest_bounce_m", "residual_deviation_m"):
        err += tol.lift
    elif name == "residual_amplitude_m":  # hypot(e, e'/wn)
        err += tol.lift + (REL * vmax + 1e-12 + tol.velocity) / wn
    elif name == "seating_velocity_m_s":
        err += REL * vmax + 1e-12 + tol.velocity  # as the events' velocities (vmax: their largest)
    return abs(got - value) <= err


_SCENE_FIELDS = {"stiffness": "linkage.stiffness", "mass": "valve.mass", "oscillating_mass": "valve.oscillating_mass",
                 "preload": "spring.preload"}


def _scene_inputs(scene) -> dict:
    return {f: float(getattr(getattr(scene, key.split(".")[0]), key.split(".")[1]))
            for f, key in _SCENE_FIELDS.items()}


def _simulated(scene, name, value):
    """simulate's elastic lift and events with one input changed."""
    result = simulate(scene_for(scene, (_SCENE_FIELDS[name],), (value,)))
    return result.columns["valve_lift_m"], [e for e in result.events if e.get("effect") == "elastic"]


CASES = [
    # scene, overrides, runs, speeds, largest stiffness
    ("elastic_float.toml", [], 110, (2000.0, 6000.0), 1e11),
    ("valve_float_demo.toml", ['effects=["elastic"]'], 60, (1500.0, 6000.0), 1e11),
    ("valve_float_demo.toml", ["solver.steps_per_revolution=1440"], 40, (2500.0, 6000.0), 1e9),
]


@pytest.mark.parametrize("scene_file, overrides, runs, rpm, k_max", CASES)
def test_compiled_rows_equal_simulate(scene_file, overrides, runs, rpm, k_max):
    """210 random runs: each row of the compiled path equals the row read from simulate on the
    same values, with its lift and events."""
    base = load_scene(SCENES / scene_file, overrides)
    names = result_columns(base)
    shared = _Shared()
    assert engine_for(base, shared).name == "compiled"
    values = _random_values(np.random.default_rng(len(overrides) * 100 + runs), runs, rpm, k_max)
    table = compute_chunk(base, KEYS, values, names, shared)
    chatter = stiff = zero_lash = separated = split = spread = 0
    for i, row_values in enumerate(values):
        scene = scene_for(base, KEYS, row_values)
        try:
            result = simulate(scene)
        except (InputError, RuntimeError):
            assert table[i, names.index("run_failed")] == 1.0, i
            continue
        events, lift = kernel_outputs(scene, shared)
        elastic = [e for e in result.events if e.get("effect") == "elastic"]
        _same_kinds(events, elastic)
        d = _differences(lift, events, result.columns["valve_lift_m"], elastic)
        tol = Tolerance()
        if not _within(d, tol, elastic):
            tol = _spread_tolerance(lambda name, value: _simulated(scene, name, value),
                                    {"inputs": _scene_inputs(scene), "lift": result.columns["valve_lift_m"],
                                     "events": elastic})
            assert _within(d, tol, elastic), (i, d, tol)
            spread += 1
        expected = row_figures(names, result)
        got = dict(zip(names, table[i]))
        assert got["run_failed"] == 0.0
        for name, value in expected.items():
            vmax = max(abs(e.get("velocity_m_s", 0.0)) for e in elastic)
            M1 = scene.valve.oscillating_mass or scene.valve.mass
            wn = math.sqrt((scene.linkage.stiffness + scene.spring.rate) / M1)
            assert _close(name, got[name], value, scene.linkage.stiffness, scene.drive.omega, tol, vmax, wn,
                          expected["separations"]), \
                (i, name, got[name], value, tol)
        chatter += scene.seat.restitution == 0.9 and expected["seat_impacts"] > 1
        stiff += scene.linkage.stiffness == k_max
        zero_lash += scene.valve.lash == 0.0
        separated += expected["separations"] > 0
        split += len([k for k in shared.grids if len(k) == 3]) > 0
    assert zero_lash > 0 and separated > 0 and stiff > 0
    assert spread <= runs // 6  # the ill-conditioned runs are few
    if scene_file == "elastic_float.toml":
        assert chatter > 0 and split > 0


def test_scenes_outside_the_kernel_take_the_other_paths():
    """A spring chain, another solver, a gear: not the compiled path (the registry's next). A lever
    gear's lift reads no run value, so its runs share it (the shared path, Gear.shares_lift); the
    trip gear's lift and effects are its own per run (simulate)."""
    shared = _Shared()
    chain = load_scene(SCENES / "spring_surge.toml")
    assert engine_for(chain, shared).name == "shared"
    taylor = load_scene(SCENES / "elastic_float.toml", ['solver.method="taylor"'])
    assert engine_for(taylor, _Shared()).name == "shared"
    gear = load_scene(SCENES / "pivoted_roller_lever.toml")
    assert engine_for(gear, _Shared()).name == "shared"
    trip = load_scene(SCENES / "trip_gear_dashpot.toml")
    assert engine_for(trip, _Shared()).name == "simulate"
    assert [e.name for e in ENGINES] == ["compiled", "shared", "simulate"]


def test_failing_runs_are_marked_on_the_compiled_path():
    base = load_scene(SCENES / "elastic_float.toml")
    names = result_columns(base)
    values = np.array([[1.0, 1e11], [4000.0, 3e6]])  # 1 rpm at 1e11 N/m: beyond the step budget
    table = compute_chunk(base, KEYS[:2], values, names)
    fail = names.index("run_failed")
    assert table[0, fail] == 1.0 and np.isnan(table[0, :fail]).all()
    assert table[1, fail] == 0.0 and table[1, names.index("separations")] > 0
    assert set(ELASTIC) <= set(names)


def test_numba_is_imported_by_the_kernel_module_only():
    """numba (~0.3 s to import) only in the compiled exact solver's modules (dynamics/kernel_*.py,
    imported only by dynamics/exact_kernel.py, which only the sweep's compiled path and the solver
    table's exact-compiled import, and the latter loads no numba while the AOT module is current:
    tests/test_aot_kernels.py), and
    in dynamics/chain_kernels.py, which only the spring chain's exact solver imports (scenes with
    spring.elements > 0), and in mechanics/sweep_kernels.py, imported inside sweep_loops.kernels
    (the compiled sweep's rigid figures when no current ahead-of-time module of them exists), and in
    core/aot_build.py (make's ahead-of-time build): `import
    explorer`, loading and simulating a massless scene leave it out."""
    import ast
    import subprocess
    import sys
    from pathlib import Path

    package = Path(__file__).resolve().parents[1] / "explorer"
    users = set()
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(n.split(".")[0] == "numba" for n in names):
                users.add(path.relative_to(package).as_posix())
    kernel = {f"dynamics/kernel_{part}.py" for part in ("steps", "events", "grid", "phase", "figures")}
    # (core/aot_build.py: the ahead-of-time build, run by make only)
    assert users == kernel | {"dynamics/chain_kernels.py", "mechanics/sweep_kernels.py", "core/aot_build.py"}
    rigid = set()
    for path in package.rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in tree.body:  # a module-level import of it would load numba with its module
            assert not (isinstance(node, ast.ImportFrom) and (node.module or "").endswith("sweep_kernels")), path
        for fn in ast.walk(tree):
            if isinstance(fn, ast.FunctionDef):
                for node in ast.walk(fn):
                    if isinstance(node, ast.ImportFrom) and (node.module or "").endswith("sweep_kernels"):
                        rigid.add((path.relative_to(package).as_posix(), fn.name))
    # (sweep_loops.kernels: only when no current ahead-of-time module of them exists; build_aot: make's
    # ahead-of-time build)
    assert rigid == {("mechanics/sweep_loops.py", "kernels"), ("mechanics/sweep_loops.py", "build_aot")}
    importers = set()
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[-1].startswith("kernel_"):
                importers.add(path.relative_to(package).as_posix())
    assert importers <= kernel | {"dynamics/exact_kernel.py"}
    code = ("import sys, explorer; explorer.simulate(explorer.load_scene(sys.argv[1])); "
            "print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(SCENES / "elastic_float.toml")], capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "False"


def test_a_speed_sweeps_rigid_figures_at_once_equal_simulates():
    """The compiled path's chunk of a speed sweep computes the rigid figures of all its speeds at
    once (sweep_rigid.py). Oracle: `simulate` at each speed. The refined minimum contact force is
    the same floats (the batched zoom repeats min_contact_force's samples row by row), the float
    speed too; the peak camshaft torque within 1e-9 relative (the same product per sample, its
    factor formed once). Speeds from 'never floats' to far beyond the float speed."""
    from explorer.studies.sweep_engine import reference_row, speed_groups

    base = load_scene(SCENES / "valve_float_demo.toml")
    names = result_columns(base)
    rpms = np.array([150.0, 900.0, 2600.0, 3727.0, 4400.0, 8000.0, 14000.0])
    values = rpms[:, None]  # (a sweep's values are in the scene file's units: rpm)
    shared = _Shared()
    assert engine_for(base, shared).name == "compiled"
    assert [g.tolist() for g in speed_groups(("drive.rpm",), values)] == [list(range(len(rpms)))]  # one group
    got = compute_chunk(base, ("drive.rpm",), values, names, shared)
    for i, v in enumerate(values):
        expected = reference_row(scene_for(base, ("drive.rpm",), v), names)
        row = dict(zip(names, got[i]))
        assert row["min_contact_force_N"] == expected["min_contact_force_N"]
        assert row["float_speed_rpm"] == expected["float_speed_rpm"]
        assert row["max_camshaft_torque_Nm"] == pytest.approx(expected["max_camshaft_torque_Nm"], rel=1e-9)
    assert got[0, names.index("min_contact_force_N")] > 0 > got[-1, names.index("min_contact_force_N")]


def test_rigid_figures_do_not_depend_on_how_the_runs_are_chunked():
    """A map rpm x lash: runs group by lash (speed_groups); each run's rigid figures are the same
    floats whether its chunk holds its whole group, part of it, or it alone (the cluster's table
    equals the serial one bit for bit), and equal simulate's (torque to 1e-9 relative)."""
    from explorer.studies.sweep_engine import reference_row, speed_groups

    base = load_scene(SCENES / "valve_float_demo.toml")
    names = result_columns(base)
    keys = ("drive.rpm", "valve.lash")
    values = np.array([[r, lash] for lash in (0.2e-3, 0.4e-3) for r in (1500.0, 3000.0, 4500.0)])
    assert [g.tolist() for g in speed_groups(keys, values)] == [[0, 1, 2], [3, 4, 5]]
    whole = compute_chunk(base, keys, values, names)
    pieces = np.concatenate([compute_chunk(base, keys, values[i:i + 1], names) for i in range(len(values))])
    halves = np.concatenate([compute_chunk(base, keys, values[:4], names), compute_chunk(base, keys, values[4:], names)])
    np.testing.assert_array_equal(whole, pieces)
    np.testing.assert_array_equal(whole, halves)
    for i, v in enumerate(values):
        expected = reference_row(scene_for(base, keys, v), names)
        assert whole[i, names.index("min_contact_force_N")] == expected["min_contact_force_N"]
        assert whole[i, names.index("max_camshaft_torque_Nm")] == pytest.approx(expected["max_camshaft_torque_Nm"], rel=1e-9)


def test_every_sweep_key_sets_a_run_parameter_of_the_compiled_path():
    """The compiled path builds its runs' parameters from the sweep keys' values (no scene per
    run): every sweepable key has its column, and a key without one is refused, not ignored."""
    from explorer.effects.elastic_batch import KEY_PARAMETERS, BatchCache, elastic_chunk_values
    from explorer.studies.sweep_spec import SWEEP_KEYS

    assert set(KEY_PARAMETERS) == set(SWEEP_KEYS)
    base = load_scene(SCENES / "elastic_float.toml")
    with pytest.raises(ValueError, match="follower.ratio"):
        elastic_chunk_values(base, ("follower.ratio",), np.ones((1, 1)), BatchCache())


def test_rigid_kernels_equal_numpy_forms_bit_for_bit():
    """mechanics/sweep_kernels.py (issue #27.5) against the numpy forms they replace: the minimum
    of F = w^2 A + G per piece and its first index (np.minimum.reduceat, np.argmin), and the
    largest finite torque F c (contact.peak_torques' numpy form), NaN, inf and ties included."""
    from explorer.mechanics.sweep_kernels import peak_torques, piece_minima

    rng = np.random.default_rng(27)
    a, g = rng.normal(size=400), rng.normal(size=400)
    a[17], a[250] = np.nan, 0.0
    g[250] = 0.0
    a[300:310] = a[300]
    g[300:310] = g[300]  # equal values: the first one's index
    push, pull = rng.uniform(0.5, 2.0, 400), rng.uniform(0.5, 2.0, 400)
    push[5], pull[9] = np.inf, np.inf
    w2 = rng.uniform(0.0, 3.0, 50)
    lows = np.array([0, 10, 200, 300, 390], dtype=np.intp)
    highs = np.array([10, 200, 300, 390, 400], dtype=np.intp)
    values = w2[:, None] * a[None, :] + g[None, :]
    minima, where = piece_minima(w2, a, g, lows, highs)
    assert np.array_equal(minima, np.minimum.reduceat(values, lows, axis=1), equal_nan=True)
    for k in range(lows.size):
        assert np.array_equal(where[:, k], np.argmin(values[:, lows[k]:highs[k]], axis=1))
    for floor in (0.0, -np.inf):
        with np.errstate(invalid="ignore"):
            torque = values * np.where(values > 0.0, push[None, :], pull[None, :])
        expected = np.maximum(floor, np.where(np.isfinite(torque), torque, -np.inf).max(axis=1))
        assert np.array_equal(peak_torques(w2, a, g, push, pull, floor), expected)
    from explorer.effects import contact

    for is_open in (np.ones(400, bool), rng.uniform(size=400) > 0.3):
        numpy_form = contact.peak_torques(a, g, is_open, push, pull, np.sqrt(w2))
        assert np.array_equal(contact.peak_torques(a, g, is_open, push, pull, np.sqrt(w2), compiled=True), numpy_form,
                              equal_nan=True)


def test_rigid_kernels_speed_by_speed_nans_equal_numpy_forms():
    """The rigid kernels loop over the speeds inside the samples (independent lanes, vectorised);
    a NaN that only some speeds meet (w^2 = inf times A = 0), a NaN on a piece's first sample
    and one after a speed's minimum must end that speed's scan and no other's, as np.argmin and
    np.minimum.reduceat do (oracle: the numpy forms, as in the test above), through the module
    the sweep calls (sweep_loops: ahead of time when current, else numba)."""
    from explorer.mechanics.sweep_loops import peak_torques, piece_minima

    rng = np.random.default_rng(28)
    a, g = rng.normal(size=300), rng.normal(size=300)
    a[[40, 41, 150]] = 0.0  # w^2 = inf: NaN there for that speed only
    a[100] = np.nan  # a piece's first sample
    g[220] = np.nan  # late in a piece, after most speeds' minimum
    w2 = np.concatenate([rng.uniform(0.0, 3.0, 30), [np.inf, 0.0, 2.0, 2.0]])
    lows = np.array([0, 100, 120, 200], dtype=np.intp)
    highs = np.array([100, 120, 200, 300], dtype=np.intp)
    with np.errstate(invalid="ignore"):
        values = w2[:, None] * a[None, :] + g[None, :]
    minima, where = piece_minima(w2, a, g, lows, highs)
    assert np.array_equal(minima, np.minimum.reduceat(values, lows, axis=1), equal_nan=True)
    for k in range(lows.size):
        assert np.array_equal(where[:, k], np.argmin(values[:, lows[k]:highs[k]], axis=1)), k
    push, pull = rng.uniform(0.5, 2.0, 300), rng.uniform(-1.0, 2.0, 300)
    for floor in (0.0, -np.inf):
        with np.errstate(invalid="ignore"):
            torque = values * np.where(values > 0.0, push[None, :], pull[None, :])
        expected = np.maximum(floor, np.where(np.isfinite(torque), torque, -np.inf).max(axis=1))
        assert np.array_equal(peak_torques(w2, a, g, push, pull, floor), expected)


def test_zoom_minima_kernel_is_load_parts_and_argmin_floats():
    """sweep_kernels.zoom_minima (a round of the zoom: F = w^2 A + G from the lift and L'' at each
    row's samples, its first minimum) against its numpy form, forces.load_parts then
    w2 A + G, non-finite values as +inf and np.argmin: the same value and index, bit for bit, for
    samples open and closed (ratio L - lash on both sides of 0, and 0 itself), both friction signs
    and none, rows with the same samples, NaN and inf in the lift, an infinite speed (inf * 0),
    equal values (the first), a lever ratio; numba's loop and the module the sweep calls (ahead of
    time when current)."""
    from explorer.mechanics import forces, sweep_kernels, sweep_loops

    loads = forces.TrainLoads.from_scene(load_scene(SCENES / "valve_float_demo.toml"))
    rng = np.random.default_rng(29)
    lash, ratio = 2.5e-4, 1.3
    lift_at = rng.uniform(0.0, 2.0 * lash / ratio, (12, 33))
    accel_at = rng.normal(0.0, 0.02, (12, 33))
    lift_at[0, 3], accel_at[1, 5], accel_at[2, 7], lift_at[3, :] = np.nan, np.inf, 0.0, lash / ratio
    accel_at[4, 10:14] = -1.0
    lift_at[4, 10:14] = lift_at[4, 10]  # equal smallest values: the first one's index
    accel_at[5, :] = np.nan  # no finite value: +inf at index 0
    of = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 6, 6, 2, 0], dtype=np.intp)  # rows 12-15: copies
    lift_at, accel_at = lift_at[of], accel_at[of]
    w2 = rng.uniform(1e3, 4e5, of.size)
    w2[2] = np.inf  # inf * 0 = NaN at accel_at[2, 7]
    direction = np.array([1.0, -1.0, 0.0, 1.0] * 4)
    a_coef, g_part, _ = forces.load_parts((lift_at, None, accel_at), direction[:, None], loads, ratio, lash)
    with np.errstate(invalid="ignore"):
        values = w2[:, None] * a_coef + g_part
    values[~np.isfinite(values)] = math.inf
    j = np.argmin(values, axis=1)
    expected = values[np.arange(of.size), j], j
    constants = (ratio, lash, loads.mass * ratio, loads.preload, loads.rate, loads.friction, loads.closing)
    for kernel in (sweep_kernels.zoom_minima, sweep_loops.zoom_minima):
        v, where = kernel(lift_at, accel_at, w2, direction, *constants)
        assert np.array_equal(v, expected[0]) and np.array_equal(where, expected[1])
    assert expected[0][5] == math.inf and expected[1][5] == 0 and expected[1][4] == 10  # the cases were met


def test_speeds_of_is_drive_omega():
    """The rigid sweep's speeds without a scene per run are each scene's Drive.omega, bit for bit."""
    from explorer.studies.sweep_rigid import speeds_of

    scene = load_scene(SCENES / "valve_float_demo.toml")
    rpms = np.concatenate([np.linspace(1.0, 20000.0, 2001), np.geomspace(0.1, 1e5, 500)])
    assert np.array_equal(speeds_of(scene, rpms), [replace(scene.drive, rpm=float(r)).omega for r in rpms])


def test_torque_factors_do_not_depend_on_the_speed_so_chunks_share_them():
    """sweep_rigid keeps a group's torque factors across a sweep's chunks (issue #27.5): they must be
    the same floats at any speed (every built-in scene with the contact effect), and a table must
    not depend on how it was cut into chunks."""
    from types import MappingProxyType

    from explorer.effects.contact import torque_factors
    from explorer.effects.pipeline import Context, RunCache, figures
    from explorer.studies.sweep_engine import _Shared, compute_chunk, result_columns

    checked = 0
    for path in sorted(SCENES.glob("*.toml")):
        base = load_scene(path)
        if "contact" not in base.effects or base.valve is None:
            continue
        factors = []
        for rpm in (base.drive.rpm, 0.37 * base.drive.rpm, 1.9 * base.drive.rpm):
            scene = replace(base, drive=replace(base.drive, rpm=rpm))
            shared = RunCache()
            try:
                shared.lift = scene.gear_plugin.build_lift(scene)
                kin = figures(scene, shared, effects=("kinematics",))
                n = scene.solver.steps_per_revolution
                theta = np.arange(n) * (2.0 * math.pi / n)
                ctx = Context(scene, theta, kin.columns["time_s"], shared.lift, kin.columns, MappingProxyType({}))
                factors.append(torque_factors(ctx))
            except InputError:  # the trip gear: its own contact variant, not on the compiled path
                break
        else:
            for push, pull in factors[1:]:
                assert np.array_equal(push, factors[0][0], equal_nan=True), path.name
                assert np.array_equal(pull, factors[0][1], equal_nan=True), path.name
            checked += 1
    assert checked >= 3
    demo = load_scene(SCENES / "valve_float_demo.toml")
    names = result_columns(demo)
    values = np.column_stack([np.linspace(1500.0, 6000.0, 30), np.repeat([2.0e-4, 3.0e-4], 15)])
    keys = ("drive.rpm", "valve.lash")
    whole = compute_chunk(demo, keys, values, names, _Shared())
    shared = _Shared()
    parts = np.vstack([compute_chunk(demo, keys, values[i:i + 7], names, shared) for i in range(0, 30, 7)])
    assert np.array_equal(whole, parts, equal_nan=True)


@pytest.mark.parametrize("scene_file, overrides", [("valve_float_demo.toml", ()),
                                                   ("valve_float_demo.toml", ('lift.dwell="0 deg"', "valve.lash=0")),
                                                   ("cycloidal_demo.toml", ()), ("polydyne_demo.toml", ())])
def test_min_contact_forces_are_min_contact_forces_floats(scene_file, overrides):
    """forces.min_contact_forces (all speeds at once; its zoom's rows taken in the order of their
    brackets) against min_contact_force speed by speed, the oracle `simulate`'s forces effect
    calls: the same value and angle to the bit, at 300 speeds from 'never floats' to far beyond
    the float speed (several pieces near the minimum at some speeds, one at others)."""
    from explorer.mechanics.forces import TrainLoads, min_contact_force, min_contact_forces, smooth_pieces

    s = load_scene(SCENES / scene_file, list(overrides))
    lift, ratio = build_lift(s), s.follower.ratio
    lash = s.valve.lash if s.valve is not None else 0.0
    loads = TrainLoads.from_scene(s)
    pieces = smooth_pieces(lift, ratio, lash, 4096)
    omegas = np.geomspace(10.0, 2000.0, 300)
    values, angles = min_contact_forces(lift, loads, omegas, ratio, lash, pieces, 4096)
    for w, v, a in zip(omegas, values, angles):
        ev, ea = min_contact_force(lift, loads, float(w), ratio, lash, pieces, 4096)
        assert v == ev and (a == ea or math.isnan(a) and math.isnan(ea)), (w, v, ev, a, ea)


def test_take_ups_several_halvings_an_evaluation_are_one_at_a_times_floats(monkeypatch):
    """mechanics.kinematics.lash_take_ups halves each bracket BISECT_LEVELS times from one
    evaluation of the lift (the tree of midpoints, then the path the signs choose). Oracle: the
    same function one halving an evaluation (BISECT_LEVELS = 1: plain bisection): the same
    floats for any number of levels, lashes from closed to beyond the top (NaN) and the 80-halving
    bound reached mid-tree (7 does not divide 80)."""
    from explorer.mechanics import kinematics

    for scene_file in ("valve_float_demo.toml", "polydyne_demo.toml", "schenker1902_fig2.toml"):
        s = load_scene(SCENES / scene_file)
        lift, ratio = build_lift(s), s.follower.ratio
        top = ratio * float(np.max(lift.derivatives(np.linspace(0, 2 * math.pi, 7200))[0]))
        lashes = np.concatenate([np.random.default_rng(3).uniform(0.0, 1.1 * top, 40), [0.0, top, 2.5e-4]])
        monkeypatch.setattr(kinematics, "BISECT_LEVELS", 1)
        expected = kinematics.lash_take_ups(lift, ratio, lashes)
        for levels in (2, 4, 6, 7):
            monkeypatch.setattr(kinematics, "BISECT_LEVELS", levels)
            assert np.array_equal(kinematics.lash_take_ups(lift, ratio, lashes), expected, equal_nan=True), levels


@pytest.mark.parametrize("scene_file", ["valve_float_demo.toml", "cycloidal_demo.toml"])
def test_zoom_minima_rows_are_each_rows_own_floats(scene_file):
    """forces._zoom_minima (all rows at once, in the order of their brackets' starts; only the
    lift and its second derivative evaluated, lift_rows; F and each row's minimum compiled,
    sweep_kernels.zoom_minima). Oracle: _zoom_minimum row by row (min_contact_force's zoom), the
    same value and angle to the bit, for rows on one bracket at several speeds (equal speeds
    too), the same bracket with the other friction sign, and brackets of their own."""
    from explorer.mechanics import forces

    s = load_scene(SCENES / scene_file)
    lift, ratio = build_lift(s), s.follower.ratio
    lash = s.valve.lash if s.valve is not None else 0.0
    loads = forces.TrainLoads.from_scene(s)
    pieces = forces.smooth_pieces(lift, ratio, lash, 4096)
    step = 2.0 * math.pi / 4096
    open_starts = pieces.start[pieces.is_open] + 10 * step
    rng = np.random.default_rng(8)
    lo, w2, sign = [], [], []
    for start in open_starts[:3]:
        for t in (start, start + 40 * step):
            speeds = np.concatenate([rng.uniform(20.0, 900.0, 5), [300.0, 300.0]]) ** 2
            lo += [t] * (speeds.size + 1)
            w2 += speeds.tolist() + [300.0**2]
            sign += [1.0] * speeds.size + [-1.0]
    lo += rng.uniform(0.0, 2.0 * math.pi, 6).tolist()  # brackets of their own
    w2 += (rng.uniform(20.0, 900.0, 6) ** 2).tolist()
    sign += [1.0, -1.0] * 3
    lo, w2, sign = np.array(lo), np.array(w2), np.array(sign)
    hi = lo + 2.0 * step
    values, angles = forces._zoom_minima(lift, loads, w2, ratio, lash, sign, lo.copy(), hi.copy())
    for k in range(lo.size):
        def force(d, direction, w2k=w2[k]):
            a_coef, g_part, _ = forces.load_parts(d, direction, loads, ratio, lash)
            return w2k * a_coef + g_part

        ev, ea = forces._zoom_minimum(lift, force, sign[k], float(lo[k]), float(hi[k]))
        assert values[k] == ev and angles[k] == ea, (k, values[k], ev, angles[k], ea)


@pytest.mark.parametrize("scene_file, overrides", [("valve_float_demo.toml", ()),
                                                   ("valve_float_demo.toml", ('spring.preload="1 N"', 'loads.friction="50 N"')),
                                                   ("cycloidal_demo.toml", ()), ("polydyne_demo.toml", ()),
                                                   ("schenker1902_fig2.toml", ())])
def test_float_speed_from_shared_samples_is_minimise_on_pieces_floats(scene_file, overrides):
    """float_speed reads its samples' A and G from sampled_parts (made once a sweep and shared with
    min_contact_forces) instead of evaluating the lift again. Oracle: the float speed as
    minimise_on_pieces defines it (the static part G, then G / -A where A < 0, each sampled and
    zoomed on its own), the same omega and angle to the bit; a spring too weak at standstill
    (static loss) included; and min_contact_forces given the shared parts equals it without."""
    from explorer.mechanics import forces

    s = load_scene(SCENES / scene_file, list(overrides))
    lift, ratio = build_lift(s), s.follower.ratio
    lash = s.valve.lash if s.valve is not None else 0.0
    loads = forces.TrainLoads.from_scene(s)
    pieces = forces.smooth_pieces(lift, ratio, lash, 4096)
    parts = forces.sampled_parts(lift, loads, ratio, lash, pieces, 4096)

    def static(d, direction):
        return forces.load_parts(d, direction, loads, ratio, lash)[1]

    def quotient(d, direction):
        a_coef, g_part, _ = forces.load_parts(d, direction, loads, ratio, lash)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(a_coef < 0.0, g_part / -a_coef, np.inf)

    g_min, g_theta = forces.minimise_on_pieces(lift, pieces, static)
    if g_min < 0.0:
        expected = forces.FloatSpeed(0.0, g_theta, True)
    else:
        q_min, q_theta = forces.minimise_on_pieces(lift, pieces, quotient)
        expected = (forces.FloatSpeed(math.inf, math.nan, False) if not math.isfinite(q_min)
                    else forces.FloatSpeed(math.sqrt(max(q_min, 0.0)), q_theta, False))
    for got in (forces.float_speed(lift, loads, ratio, lash, pieces, 4096),
                forces.float_speed(lift, loads, ratio, lash, pieces, 4096, parts)):
        assert got.omega == expected.omega and got.static_loss == expected.static_loss
        assert got.theta == expected.theta or math.isnan(got.theta) and math.isnan(expected.theta)
    assert ("spring.preload" in str(overrides)) == expected.static_loss  # both branches are met
    omegas = np.geomspace(10.0, 2000.0, 50)
    alone = forces.min_contact_forces(lift, loads, omegas, ratio, lash, pieces, 4096)
    shared = forces.min_contact_forces(lift, loads, omegas, ratio, lash, pieces, 4096, parts)
    assert all(np.array_equal(x, y, equal_nan=True) for x, y in zip(alone, shared))


def test_velocity_zeros_exact_zeros_on_the_grid_as_the_loop_found_them():
    """forces.velocity_zeros takes the grid points where the slope is exactly 0 between opposite
    signs vectorised (a base circle is thousands of zero slopes). Oracle: the loop it replaced
    (each zero point, kept when its neighbours' signs differ, in grid order), on a slope with such
    zeros (a sign change through an exact 0 on a grid point, both ways), flat stretches of zeros
    (none kept) and a zero between equal signs (a touch, not kept); and the float demo's lift."""
    from explorer.mechanics import forces

    grid0 = np.linspace(0.0, 2.0 * math.pi, 4097)
    c1, c2, c3 = grid0[1000], grid0[2000], grid0[2500]

    class Slope:  # d1 = 0 exactly at c1 (- to +), c2 (+ to -), touching 0 at c3, flat beyond 5 rad
        def breakpoints(self):
            return np.zeros(0)

        def derivatives(self, theta):
            theta = np.asarray(theta, dtype=float)
            d1 = np.where(theta < c2, theta - c1, c2 - theta)
            d1 = np.where(theta == c2, 0.0, d1)
            d1 = np.where((theta > c2) & (theta <= c3 + 1e-9), -(theta - c3) ** 2, d1)
            d1 = np.where(theta > 5.0, 0.0, d1)
            return np.stack([np.zeros_like(theta), d1, np.zeros_like(theta), np.zeros_like(theta)])

    for lift in (Slope(), build_lift(load_scene(SCENES / "valve_float_demo.toml"))):
        grid = np.unique(np.concatenate([grid0, np.asarray(lift.breakpoints(), dtype=float)]))
        sg = np.sign(lift.derivatives(grid)[1])
        looped = [grid[i] for i in np.nonzero(sg[1:-1] == 0.0)[0] + 1 if sg[i - 1] * sg[i + 1] < 0.0]
        got = forces.velocity_zeros(lift, 4096)
        assert set(looped) <= set(got.tolist())
        brent = [r for r in got.tolist() if r not in set(looped)]
        assert np.array_equal(got, np.mod(np.asarray(brent + looped, dtype=float), 2.0 * math.pi))
        # the synthetic slope's two crossings through an exact 0 (not the touch, not the flat);
        # the float demo's slope is 0 only on flat stretches (base circle, dwell)
        assert looped == ([c1, c2] if isinstance(lift, Slope) else [])
