"""The sweep's kernels compiled ahead of time (explorer/core/aot.py, issue #27.3): `make` builds
them (tests run after it: `make test`), they give the same floats as numba's JIT kernels, a
sweep that uses them loads no numba, and a module built from other sources is never used.

Oracle: numba's JIT kernels (the fallback path), which tests/test_sweep_kernel.py holds to
`simulate`. Tolerance: none -- the same LLVM IR from the same source for the same CPU, without
fast-math (so no reassociation or fused multiply-add), must give the same bits: np.array_equal
with equal_nan, NaN positions included.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import SCENES
from explorer.core import aot
from explorer.dynamics import exact_kernel
from explorer.mechanics import sweep_loops
from explorer.scene.scene import load_scene
from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns
from test_sweep_kernel import KEYS, _random_values


@pytest.fixture
def modules(monkeypatch):
    """The two ahead-of-time modules, which must exist and be current (make builds them)."""
    monkeypatch.delenv(aot.ENV, raising=False)
    elastic = aot.load(exact_kernel.AOT_MODULE, exact_kernel.aot_sources())
    rigid = aot.load(sweep_loops.AOT_MODULE, list(sweep_loops.SOURCES))
    assert elastic is not None and rigid is not None, "run `make .venv/.kernel-compiled` (it builds them)"
    return elastic, rigid


def _tables(monkeypatch, base, keys, values, elastic, rigid):
    """compute_chunk's table with the ahead-of-time kernels and with numba's."""
    from explorer.dynamics.kernel_figures import revolutions
    from explorer.mechanics.sweep_kernels import peak_torques, piece_minima, zoom_minima

    out = []
    for batch, loops in ((elastic.revolutions, (rigid.piece_minima, rigid.peak_torques, rigid.zoom_minima)),
                         (revolutions, (piece_minima, peak_torques, zoom_minima))):
        monkeypatch.setattr(exact_kernel, "batch_function", lambda batch=batch: batch)
        monkeypatch.setattr(sweep_loops, "kernels", lambda loops=loops: loops)
        shared = _Shared()
        assert engine_for(base, shared).name == "compiled"
        out.append(compute_chunk(base, keys, values, result_columns(base), shared))
    return out


@pytest.mark.parametrize("scene_file, seed, runs, rpm, k_max", [
    ("elastic_float.toml", 1, 150, (1500.0, 6000.0), 1e11),
    ("elastic_float.toml", 2, 150, (300.0, 9000.0), 1e9),
    ("valve_float_demo.toml", 3, 150, (1500.0, 6000.0), 1e11),
    ("valve_float_demo.toml", 4, 150, (300.0, 9000.0), 1e9),
])
def test_aot_rows_equal_jit_rows_bit_for_bit(monkeypatch, modules, scene_file, seed, runs, rpm, k_max):
    """600 seeded random runs (speed, stiffness up to 1e11 N/m, masses, preload, lash, damping,
    restitution, friction: test_sweep_kernel's) on both float scenes with all their effects: every
    column of every row the same bits, the failed runs the same runs."""
    base = load_scene(SCENES / scene_file)
    values = _random_values(np.random.default_rng(seed), runs, rpm, k_max)
    got, expected = _tables(monkeypatch, base, KEYS, values, *modules)
    assert np.array_equal(got, expected, equal_nan=True)
    names = result_columns(base)
    assert np.isnan(got).any() and (got[:, names.index("separations")] > 0).any()  # (the runs reach both)


def test_aot_speed_sweep_equals_jit_bit_for_bit(monkeypatch, modules):
    """A 400-speed sweep of the float demo (the rigid figures' loops over all speeds at once) from
    a standstill to far beyond the float speed."""
    base = load_scene(SCENES / "valve_float_demo.toml")
    values = np.linspace(100.0, 14000.0, 400)[:, None]
    got, expected = _tables(monkeypatch, base, ("drive.rpm",), values, *modules)
    assert np.array_equal(got, expected, equal_nan=True)


def test_aot_rigid_loops_equal_jit_on_nan_inf_and_ties(modules):
    """The rigid loops on test_sweep_kernel's awkward inputs (NaN, inf, equal values)."""
    from explorer.mechanics.sweep_kernels import peak_torques, piece_minima, zoom_minima

    rigid = modules[1]
    rng = np.random.default_rng(27)
    for _ in range(20):
        a, g = rng.normal(size=400), rng.normal(size=400)
        a[rng.integers(0, 400, 3)] = np.nan
        a[300:310], g[300:310] = a[300], g[300]
        push, pull = rng.uniform(0.5, 2.0, 400), rng.uniform(0.5, 2.0, 400)
        push[rng.integers(0, 400)] = np.inf
        w2 = rng.uniform(0.0, 3.0, 50)
        lows = np.array([0, 10, 200, 300, 390], dtype=np.intp)
        highs = np.array([10, 200, 300, 390, 400], dtype=np.intp)
        for x, y in zip(rigid.piece_minima(w2, a, g, lows, highs), piece_minima(w2, a, g, lows, highs)):
            assert np.array_equal(x, y, equal_nan=True)
        for floor in (0.0, -np.inf):
            assert np.array_equal(rigid.peak_torques(w2, a, g, push, pull, floor),
                                  peak_torques(w2, a, g, push, pull, floor), equal_nan=True)
        # the zoom's round (closed and open samples, NaN, inf)
        lift_at, accel_at = rng.uniform(0.0, 2e-3, (8, 33)), rng.normal(0.0, 0.02, (8, 33))
        lift_at[rng.integers(0, 8), rng.integers(0, 33)] = np.nan
        accel_at[rng.integers(0, 8), rng.integers(0, 33)] = np.inf
        w2z, direction = rng.uniform(1e3, 4e5, 8), rng.choice([-1.0, 0.0, 1.0], 8)
        constants = (1.0, 2.5e-4, 0.1, 220.0, 3e4, 10.0, 15.0)
        for x, y in zip(rigid.zoom_minima(lift_at, accel_at, w2z, direction, *constants),
                        zoom_minima(lift_at, accel_at, w2z, direction, *constants)):
            assert np.array_equal(x, y)


SWEEP = ("import sys, explorer; explorer.sweep(sys.argv[1], vary={'drive.rpm': '2000:5000:10'}, workers=1); "
         "print('numba' in sys.modules)")


@pytest.mark.parametrize("setting, loads_numba", [("1", "False"), ("0", "True")])
def test_a_sweep_with_the_aot_modules_loads_no_numba(modules, setting, loads_numba):
    """A fresh process's 10-speed sweep of the float demo (elastic and rigid figures) imports no
    numba while the modules are current; EXPLORER_AOT=0 takes numba's path."""
    env = {**os.environ, aot.ENV: setting}
    out = subprocess.run([sys.executable, "-c", SWEEP, str(SCENES / "valve_float_demo.toml")], capture_output=True,
                         text=True, check=True, env=env)
    assert out.stdout.strip().splitlines()[-1] == loads_numba


def test_a_module_built_from_other_sources_is_not_used(monkeypatch, tmp_path, modules):
    """The digest baked into the module must equal the current sources': one byte changed in any
    source (a copy here), a source missing, another CPU, or no module at all -- None, and the caller compiles."""
    sources = exact_kernel.aot_sources()
    assert aot.load(exact_kernel.AOT_MODULE, sources) is not None
    for i in (0, len(sources) - 1):
        changed = list(sources)
        changed[i] = tmp_path / sources[i].name
        changed[i].write_bytes(sources[i].read_bytes() + b"\n")
        assert aot.load(exact_kernel.AOT_MODULE, changed) is None
    assert aot.load(exact_kernel.AOT_MODULE, [*sources[:-1], tmp_path / "missing.py"]) is None
    assert aot.load("explorer.dynamics._no_such_module", sources) is None
    monkeypatch.setattr(aot, "_cpu", lambda: b"another CPU")  # (built for the host CPU, as numba's JIT)
    assert aot.load(exact_kernel.AOT_MODULE, sources) is None
    monkeypatch.undo()
    monkeypatch.setenv(aot.ENV, "0")
    assert aot.load(exact_kernel.AOT_MODULE, sources) is None


def test_aot_solver_equals_jit_bit_for_bit(modules):
    """The `exact-compiled` solver's compiled call (kernel_phase.solve_nodes) from the AOT module
    and from numba, on the float scenes and on 40 seeded random models of elastic_float
    (test_sweep_kernel's: stiff, chattering, with friction, some from a thrown start): every node
    record, event and count the same bits."""
    from explorer.dynamics.kernel_phase import solve_nodes
    from explorer.dynamics.model import Drive, LinkageModel
    from explorer.effects.lift import build_lift
    from explorer.studies.bench import model_and_drive
    from explorer.studies.sweep_spec import scene_for
    from test_sweep_kernel import KEYS as RUN_KEYS

    elastic = modules[0]
    cases = []
    for name in ("valve_float_demo.toml", "elastic_float.toml"):
        model, drive = model_and_drive(load_scene(SCENES / name))
        cases.append((model, drive, 3600, None))
    scene = load_scene(SCENES / "elastic_float.toml")
    lift = build_lift(scene)
    for q, row in enumerate(_random_values(np.random.default_rng(11), 40, (1500.0, 6000.0), 1e10)):
        sc = scene_for(scene, RUN_KEYS, row)
        start = (2e-4, 0.5) if q % 4 == 0 else None
        cases.append((LinkageModel.from_scene(sc), Drive(lift, sc.follower.ratio, sc.drive.omega), 1200, start))
    for model, drive, n, start in cases:
        t = np.arange(n + 1) * (2.0 * np.pi / n) / drive.omega
        got, expected = (exact_kernel._solve(model, drive, t, start, 1e-12, 100_000, kernel)
                         for kernel in (elastic.solve_nodes, solve_nodes))
        for column in ("s", "v", "a", "linkage_force", "phase"):
            assert np.array_equal(getattr(got, column), getattr(expected, column))
        assert got.events == expected.events


SIMULATE = ("import sys, explorer; explorer.simulate(explorer.load_scene(sys.argv[1], "
            "['effects=[\"elastic\"]', 'solver.method=\"exact-compiled\"'])); print('numba' in sys.modules)")


@pytest.mark.parametrize("setting, loads_numba", [("1", "False"), ("0", "True")])
def test_simulate_with_exact_compiled_loads_no_numba_with_the_aot_module(modules, setting, loads_numba):
    """A fresh process's `simulate` of the float demo with [solver] method = "exact-compiled" runs
    the AOT module's solve_nodes and imports no numba while it is current; EXPLORER_AOT=0: numba's."""
    env = {**os.environ, aot.ENV: setting}
    out = subprocess.run([sys.executable, "-c", SIMULATE, str(SCENES / "valve_float_demo.toml")], capture_output=True,
                         text=True, check=True, env=env)
    assert out.stdout.strip().splitlines()[-1] == loads_numba
