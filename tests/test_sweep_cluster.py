"""Scale-out of a sweep (issue #14.4): every local core, and a Dask distributed cluster. The
tables must equal the serial one bit for bit; a worker killed in the middle of a sweep loses
and duplicates no row; no process outlives a test (conftest checks)."""

from __future__ import annotations

import os
import signal

import numpy as np
import pytest

from conftest import SCENES
from explorer.scene.scene import load_scene
from explorer.studies.sweep_run import dumps_scene, loads_scene_bytes, plan_from, run_plan

# a short revolution keeps the runs quick; the float scene still separates and seats
SCENE = load_scene(SCENES / "valve_float_demo.toml", ["solver.steps_per_revolution=720"])
VARY = {"drive.rpm": "2500:5500:24"}


def _same(a, b) -> None:
    assert list(a.columns) == list(b.columns)
    for name in a.columns:
        x, y = np.asarray(a.columns[name]), np.asarray(b.columns[name])
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert np.array_equal(np.ascontiguousarray(x).view(np.uint8), np.ascontiguousarray(y).view(np.uint8)), name  # bit for bit, NaN included


@pytest.fixture(scope="module")
def serial():
    plan = plan_from(SCENE, VARY)
    return plan, run_plan(SCENE, plan, workers=1)


def test_the_scene_travels_to_workers_unchanged():
    again = loads_scene_bytes(dumps_scene(SCENE))
    assert again == SCENE  # frozen dataclasses: equal field by field, read-only mappings restored
    assert type(again.loads.closing) is type(SCENE.loads.closing)


def test_local_processes_equal_serial(serial):
    plan, table = serial
    assert table.complete and len(table) == plan.runs
    assert np.count_nonzero(np.asarray(table.columns["separations"]) > 0) > 0  # the runs do separate
    _same(run_plan(SCENE, plan, workers=2, chunk=3), table)


@pytest.fixture
def cluster():
    """Two worker processes (each with a nanny that restarts it) and a scheduler on 127.0.0.1,
    per test: closed within the test, so the process check sees them end."""
    distributed = pytest.importorskip("distributed")
    import multiprocessing.resource_tracker as tracker

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0", silence_logs=50) as c:
        yield c
    # the workers were started by multiprocessing's spawn, which also started its resource
    # tracker; it would live until this process exits
    stop = getattr(tracker._resource_tracker, "_stop", None)
    if stop is not None:
        stop()


def test_dask_cluster_equals_serial(serial, cluster):
    plan, table = serial
    _same(run_plan(SCENE, plan, scheduler=cluster.scheduler_address, chunk=4), table)


def test_a_worker_killed_mid_sweep_loses_and_duplicates_no_row(serial, cluster):
    from distributed import Client

    plan, table = serial
    with Client(cluster.scheduler_address, set_as_default=False) as client:
        pids = client.run(os.getpid)  # worker address -> process id
    killed = []

    def progress(done, total, seconds):
        if not killed:  # after the first chunk: one worker dies with its tasks
            pid = next(iter(pids.values()))
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    result = run_plan(SCENE, plan, scheduler=cluster.scheduler_address, chunk=2, progress=progress)
    assert killed and result.complete
    runs = np.asarray(result.columns["run"])
    assert runs.tolist() == list(range(plan.runs))  # each run once, in order
    _same(result, table)


@pytest.mark.parametrize("address, message", [
    ("nonsense:::", "expected tcp://HOST:PORT"),
    ("tcp://127.0.0.1:99999", "expected tcp://HOST:PORT"),
    ("tcp://127.0.0.1:9", "cannot connect to the Dask scheduler"),  # nothing listens on the discard port
])
def test_a_bad_scheduler_is_one_line_and_nothing_written(tmp_path, address, message):
    from conftest import run_cli

    pytest.importorskip("distributed")
    r = run_cli("sweep", SCENES / "elastic_float.toml", "--vary", "drive.rpm=3000:4000:3", "-o", tmp_path / "t.csv",
                "--scheduler", address)
    assert r.returncode == 2 and message in r.stderr, r.stderr
    assert r.stderr.count("\n") == 1 and list(tmp_path.iterdir()) == []


def test_the_command_runs_on_the_cluster(serial, cluster, tmp_path):
    from conftest import run_cli
    from explorer.studies.sweep_table import read_table

    plan, table = serial
    out = tmp_path / "s.parquet"
    r = run_cli("sweep", SCENES / "valve_float_demo.toml", "--set", "solver.steps_per_revolution=720",
                "--vary", f"drive.rpm={VARY['drive.rpm']}", "-o", out, "--scheduler", cluster.scheduler_address)
    assert r.returncode == 0, r.stderr
    _same(read_table(out), table)
