"""Many recordings in one process: threads and memory stay flat (explorer.view.rerun.worker), and
--sweep has a cap that is checked before any work.

rerun-sdk keeps every RecordingStream made from Python, with its threads, until the process exits
(4 threads and ~1.6 MB per recording were measured here before the helper process). The tests
count the process's threads in /proc and its resident memory after a warm-up, then again after
many recordings; both must stay within a small bound that the old leak exceeds many times over.
"""

from __future__ import annotations

import os

import psutil
import pytest

from explorer import cli, load_scene
from explorer.effects.pipeline import simulate
from explorer.view.rerun.recording import Run, write_recordings
from explorer.view.rerun.read import read_rrd
from conftest import SCENES

DEMO = SCENES / "cycloidal_demo.toml"
# 300 each keeps the suite short (~40 s for both); EXPLORER_LEAK_RUNS=1000 runs the count.
RECORDINGS = int(os.environ.get("EXPLORER_LEAK_RUNS", 300))
LIVE_CHANGES = RECORDINGS
THREAD_SLACK = 2  # e.g. a pytest or interpreter helper thread coming or going
RSS_SLACK_MB = 40.0  # the old leak: ~1.6 MB per recording, ~400 MB over 250


def threads() -> int:
    return len(os.listdir("/proc/self/task"))


def rss_mb() -> float:
    return psutil.Process().memory_info().rss / 2**20


def recordings_in(path) -> int:
    """How many recordings the file holds (their stores only; read_rrd would decode every chunk)."""
    from rerun.chunk import RrdReader

    return len(list(RrdReader(str(path)).recordings()))


@pytest.fixture(scope="module")
def small_result():
    return simulate(load_scene(DEMO, ["solver.steps_per_revolution=36"]))


def test_threads_and_memory_stay_flat_over_many_recordings(tmp_path, small_result):
    samples = {}

    def runs():
        for i in range(RECORDINGS):
            if i in (50, RECORDINGS - 1):  # after the warm-up (imports, the helper's first start), and at the end
                samples[i] = (threads(), rss_mb())
            yield Run(f"run {i}", small_result)

    out = tmp_path / "many.rrd"
    write_recordings(out, runs())
    (t0, m0), (t1, m1) = samples[50], samples[RECORDINGS - 1]
    assert t1 <= t0 + THREAD_SLACK, f"threads {t0} -> {t1} over {RECORDINGS - 50} recordings"
    assert m1 <= m0 + RSS_SLACK_MB, f"resident memory {m0:.0f} -> {m1:.0f} MB"
    assert recordings_in(out) == RECORDINGS + 1  # and the overlay of them all


def test_threads_and_memory_stay_flat_over_many_live_changes(tmp_path, small_result):
    from explorer.view.rerun.live import LiveStream

    stream = LiveStream(save_path=tmp_path / "live.rrd", parts=False)
    try:
        samples = {}
        for i in range(LIVE_CHANGES):
            if i in (50, LIVE_CHANGES - 1):
                samples[i] = (threads(), rss_mb())
            stream.log(small_result, f"change {i}")
            assert stream.flush(timeout=120)  # every change written, none replaced by a newer one
    finally:
        stream.close()
    (t0, m0), (t1, m1) = samples[50], samples[LIVE_CHANGES - 1]
    assert t1 <= t0 + THREAD_SLACK, f"threads {t0} -> {t1} over {LIVE_CHANGES - 50} changes"
    assert m1 <= m0 + RSS_SLACK_MB, f"resident memory {m0:.0f} -> {m1:.0f} MB"
    assert stream.errors == [] and len(stream.labels) == LIVE_CHANGES
    assert recordings_in(tmp_path / "live.rrd") == LIVE_CHANGES


def test_the_helper_is_replaced_before_its_leftovers_grow(tmp_path, small_result):
    """What rerun leaks accumulates in the helper, which is replaced every `recycle_after` jobs."""
    from explorer.view.rerun.recording import recording_paths
    from explorer.view.rerun.worker import RecordingWorker, portable_run

    worker = RecordingWorker(recycle_after=5)
    pids, counts = [], []
    try:
        for i in range(12):
            job = {"kind": "record", "sinks": [("file", str(tmp_path / f"{i}.rrd"))],
                   "run": portable_run(Run(f"r{i}", small_result)),
                   "layout": (recording_paths(small_result), None), "default_blueprint": True}
            worker.run(job)
            if worker._proc is not None:
                pids.append(worker._proc.pid)
                counts.append(psutil.Process(worker._proc.pid).num_threads())
    finally:
        worker.close()
    assert len(set(pids)) == 3  # jobs 1-4, 6-9, 11-12 (the 5th and 10th end their helper)
    assert max(counts) <= min(counts) + 4 * 5  # rerun's 4 threads per recording, never more than 5 recordings' worth
    assert all(len(read_rrd(tmp_path / f"{i}.rrd")) == 1 for i in range(12))


def test_a_failing_job_is_reported_and_the_helper_goes_on(tmp_path, small_result):
    from explorer.view.rerun.worker import RecordingWorker, portable_run

    worker = RecordingWorker()
    try:
        bad = {"kind": "record", "sinks": [("file", str(tmp_path / "missing" / "x.rrd"))],
               "run": portable_run(Run("r", small_result)), "layout": None}
        with pytest.raises(RuntimeError):
            worker.run({**bad, "run": None})
        good = {**bad, "sinks": [("file", str(tmp_path / "ok.rrd"))]}
        worker.run(good)
    finally:
        worker.close()
    assert len(read_rrd(tmp_path / "ok.rrd")) == 1


# ---------------------------------------------------------------------------------------------
# the --sweep cap


@pytest.mark.parametrize("sweeps, scenes, count", [
    ([",".join(str(100 + i) for i in range(1001))], 1, 1001),
    (["drive.rpm=" + ",".join(str(100 + i) for i in range(50)),
      "valve.lash=" + ",".join(f'"{0.1 + i / 1000} mm"' for i in range(50)),
      "linkage.stiffness=" + ",".join(str(1e6 + i) for i in range(50))], 1, 125000),
    (["drive.rpm=" + ",".join(str(100 + i) for i in range(501))], 2, 1002),
])
def test_sweep_over_the_cap_is_refused_before_any_work(tmp_path, capsys, monkeypatch, sweeps, scenes, count):
    import explorer.scene.scene

    from explorer.cli.record import MAX_RUNS

    sweeps = [s if "=" in s else "drive.rpm=" + s for s in sweeps]
    monkeypatch.setattr(explorer.scene.scene, "load_scene", lambda *a, **k: pytest.fail("a scene was loaded"))
    args = ["record", *[str(DEMO)] * scenes, "-o", str(tmp_path / "run.rrd")]
    for s in sweeps:
        args += ["--sweep", s]
    assert cli.main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("error: --sweep: ")
    assert f"{count} recordings; at most {MAX_RUNS} per file" in err
    assert list(tmp_path.iterdir()) == []


def test_sweep_at_the_cap_is_planned(monkeypatch):
    from explorer.cli.record import MAX_RUNS, plan_runs

    plans = plan_runs([str(DEMO)], ["solver.steps_per_revolution=36"],
                      ["drive.rpm=" + ",".join(str(100 + i) for i in range(MAX_RUNS))])
    assert len(plans) == MAX_RUNS


def test_swept_extents_in_blocks_equal_the_whole():
    """The parts' sweep box is computed in blocks of rotations (a million steps took 15 GB at
    once); blocks change nothing, to the bit."""
    import numpy as np

    from explorer.view import drawing

    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 2.0 * np.pi, 500, endpoint=False)
    vertices = np.column_stack([np.cos(t), rng.normal(size=t.size), 0.5 * np.sin(t)])
    half = rng.uniform(0.0, np.pi, 20_011)
    wxyz = np.column_stack([np.cos(half), np.zeros_like(half), np.sin(half), np.zeros_like(half)])
    hull = drawing._hull_2d(vertices[:, [0, 2]])
    assert len(wxyz) > 2_000_000 // len(hull)  # several blocks
    q = wxyz / np.linalg.norm(wxyz, axis=1, keepdims=True)  # as _swept_extents does
    angle = 2.0 * np.arctan2(q[:, 2], q[:, 0])
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    x = c * hull[None, :, 0] + s * hull[None, :, 1]
    z = -s * hull[None, :, 0] + c * hull[None, :, 1]
    lo, hi = drawing._swept_extents(vertices, wxyz)
    assert np.array_equal(lo[:, 0], x.min(axis=1)) and np.array_equal(hi[:, 0], x.max(axis=1))
    assert np.array_equal(lo[:, 2], z.min(axis=1)) and np.array_equal(hi[:, 2], z.max(axis=1))
