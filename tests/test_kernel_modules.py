"""The compiled exact solver's modules (explorer/dynamics/kernel_*.py, issue #23): a batch's runs
share buffers without leaking one run into the next, and numba's cache is discarded when any
source the compiled code depends on changes (kernel_stamp)."""

from __future__ import annotations

import math

import numpy as np

from conftest import SCENES
from explorer.dynamics import exact_kernel, kernel_stamp
from explorer.effects.elastic_batch import _residual_reference
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene
from explorer.studies.sweep_engine import _Shared


def test_a_batch_equals_its_runs_one_by_one():
    """run_batch (one set of buffers for all runs, runs that fail among them) gives every run the
    figures run_revolution gives it alone (fresh buffers), to the bit: a run writes every node it
    reads, whatever the run before it left there."""
    scene = load_scene(SCENES / "elastic_float.toml")
    lift = build_lift(scene)
    grid = exact_kernel.revolution_grid(lift, 1.0, 3600)
    ref, dwell, S_dwell = _residual_reference(_Shared(), lift, 1.0, scene.valve.lash, 3600)
    rng = np.random.default_rng(5)
    runs = []
    for _ in range(40):
        omega = rng.uniform(1500.0, 6000.0) * 2 * math.pi / 60
        M = rng.uniform(0.08, 0.2)
        preload = rng.uniform(120.0, 320.0)
        runs.append([omega, M, rng.uniform(0.5, 1.0) * M, rng.uniform(1e6, 1e8), rng.choice([0.0, 8.0]),
                     rng.choice([0.0, 2.5e-4]), preload, 3e4, rng.choice([0.0, 10.0]), rng.choice([0.0, 0.3, 0.9]),
                     preload, 0.0])
    runs = np.array(runs)
    figs, status = exact_kernel.run_batch(grid, 1.0, runs, ref, dwell, S_dwell)
    assert (status == exact_kernel.OK).sum() > 30
    for r, p in enumerate(runs):
        if status[r] != exact_kernel.OK:
            continue
        from explorer.dynamics.model import LinkageModel

        model = LinkageModel(mass=p[1], oscillating_mass=p[2], stiffness=p[3], damping=p[4], lash=p[5], preload=p[6],
                             spring_rate=p[7], friction=p[8], restitution=p[9])
        alone, _, _ = exact_kernel.run_revolution(grid, p[0], model, 1.0, p[11], ref, dwell, S_dwell)
        np.testing.assert_array_equal(figs[r], alone)


def test_a_changed_source_discards_the_kernels_cache(tmp_path, monkeypatch):
    """kernel_stamp: the cache files of the kernel's modules go when a source's digest changes
    (others stay), and stay while it does not."""
    sources = tmp_path / "src"
    cache = sources / "__pycache__"
    cache.mkdir(parents=True)
    for name in kernel_stamp.SOURCES:
        (sources / name).write_text(f"# {name}\n")
    monkeypatch.setattr(kernel_stamp, "HERE", sources)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    kept = cache / "chain_kernels.advance-75.py311.nbi"

    def plant():
        paths = [cache / "kernel_phase.run_nodes-10.py311.nbi", cache / "kernel_phase.run_nodes-10.py311.1.nbc",
                 cache / "free_vibration.free_amplitude-28.py311.nbi", kept]
        for path in paths:
            path.write_text("x")
        return paths[:3]

    planted = plant()
    assert kernel_stamp.refresh()  # no stamp yet: discarded, stamp written
    assert not any(p.exists() for p in planted) and kept.exists()
    planted = plant()
    assert not kernel_stamp.refresh() and all(p.exists() for p in planted)  # unchanged sources: kept
    (sources / "exact_events.py").write_text("ZERO_START = 2e-11\n")  # a constant the kernel reads
    assert kernel_stamp.refresh() and not any(p.exists() for p in planted) and kept.exists()
