"""The live rerun stream (`explorer serve --rerun / --rerun-save`): to a file, to a gRPC server on
127.0.0.1 read by a real rerun process, labelled recordings, and no hang at exit.

Values are compared bit for bit with the Result that was logged (float64 both ways)."""

from __future__ import annotations

import argparse
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from explorer import load_scene
from explorer.effects.pipeline import simulate
from explorer.core.errors import InputError
from explorer.view.rerun.recording import rerun_executable, series_layout
from explorer.view.rerun.live import LiveStream, add_live_arguments, open_live_stream
from explorer.view.rerun.read import read_blueprint_views, read_rrd
from explorer.core.processes import spawn, stop_group
from conftest import process_timeout

ROOT = Path(__file__).resolve().parent.parent
CYCLOIDAL = ROOT / "assets" / "scenes" / "cycloidal_demo.toml"


def result_at(rpm: float, steps: int = 360):
    return simulate(load_scene(CYCLOIDAL, [f"drive.rpm={rpm}", f"solver.steps_per_revolution={steps}",
                                           'effects=["kinematics", "lash"]']))


def assert_same_series(run, result) -> None:
    series = run.series
    for s in series_layout(result.columns):
        assert np.array_equal(series[s.path]["value"], s.values(result.columns)), s.column


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def args(**kw) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_live_arguments(parser)
    ns = parser.parse_args([])
    for key, value in kw.items():
        setattr(ns, key, value)
    return ns


def test_disabled_stream_does_nothing(tmp_path):
    stream = open_live_stream(args())
    assert not stream.enabled
    stream.log(result_at(600), "ignored")
    assert stream.flush(1.0)
    stream.close()
    assert list(tmp_path.iterdir()) == []


def test_bad_arguments_are_input_errors(tmp_path):
    with pytest.raises(InputError, match=".rrd"):
        open_live_stream(args(rerun_save=str(tmp_path / "x.csv")))
    with pytest.raises(InputError, match="does not exist"):
        open_live_stream(args(rerun_save=str(tmp_path / "no" / "x.rrd")))
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        with pytest.raises(InputError, match="in use"):
            open_live_stream(args(rerun=True, rerun_port=busy.getsockname()[1]))
    assert list(tmp_path.iterdir()) == []


def test_each_change_is_a_new_labelled_recording_in_the_file(tmp_path):
    out = tmp_path / "live.rrd"
    first, second = result_at(600), result_at(1200)
    with open_live_stream(args(rerun_save=str(out))) as stream:
        stream.log(first, "cycloidal_demo.toml")
        assert stream.flush(60)
        stream.log(second, "cycloidal_demo.toml  drive.rpm=1200")
        assert stream.flush(60)
        assert not out.exists()  # written whole at close, never half
    assert stream.errors == []
    runs = {r.name: r for r in read_rrd(out)}
    assert set(runs) == {"#1 cycloidal_demo.toml", "#2 cycloidal_demo.toml  drive.rpm=1200"}
    assert_same_series(runs["#1 cycloidal_demo.toml"], first)
    assert_same_series(runs["#2 cycloidal_demo.toml  drive.rpm=1200"], second)
    assert "/parts/cam" in runs["#1 cycloidal_demo.toml"].temporal  # the 3D motion too
    assert read_blueprint_views(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["live.rrd"]  # pieces cleaned up


def test_newest_result_wins_while_one_is_written(tmp_path):
    out = tmp_path / "live.rrd"
    results = [result_at(rpm) for rpm in (600, 700, 800, 900, 1000)]
    stream = LiveStream(save_path=out, parts=False)
    for i, r in enumerate(results):
        stream.log(r, f"run {i}")
    stream.close()
    names = [r.name for r in read_rrd(out)]
    # the last one is always written; the ones in between may have been replaced
    assert "#5 run 4" in names and 1 <= len(names) <= 5
    assert stream.labels[-1] == "#5 run 4"
    with pytest.raises(RuntimeError):
        stream.log(results[0], "after close")


@pytest.mark.filterwarnings("ignore:RRD file has no footer")  # rerun --save streams without one
def test_grpc_server_on_localhost_reaches_a_rerun_viewer(tmp_path):
    """A real rerun process connects to our server and saves what it receives."""
    port, viewer_port = free_port(), free_port()
    received = tmp_path / "received.rrd"
    result = result_at(900)
    stream = open_live_stream(args(rerun=True, rerun_port=port))
    receiver = None
    try:
        assert stream.url == f"rerun+http://127.0.0.1:{port}/proxy"
        listening = [c for c in psutil.Process().net_connections(kind="inet")
                     if c.status == psutil.CONN_LISTEN and c.laddr.port == port]
        assert [c.laddr.ip for c in listening] == ["127.0.0.1"]  # not every interface
        stream.log(result, "live run")
        assert stream.flush(60)
        receiver = spawn(
            [*rerun_executable(), "--save", str(received), "--bind", "127.0.0.1", "--port", str(viewer_port),
             stream.url],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        # the server keeps what was logged before the viewer came: wait until it has all arrived
        deadline, names = time.monotonic() + process_timeout(0.5), []
        while time.monotonic() < deadline:
            time.sleep(0.5)
            if received.exists() and received.stat().st_size > 100_000:
                break
        time.sleep(1.0)
        receiver.send_signal(signal.SIGINT)  # rerun finishes the file on Ctrl-C
        receiver.wait(timeout=process_timeout(0.5))
        runs = {r.name: r for r in read_rrd(received)}
        assert "#1 live run" in runs
        assert_same_series(runs["#1 live run"], result)
        # the server's own stream is the session's index, one line per recording
        index = runs["explorer live session"].temporal["/session"]["TextLog:text"]
        assert list(index) == ["#1 live run | 900 rpm | 2 events"]
    finally:
        if receiver is not None:
            stop_group(receiver, grace=1.0)
        started = time.monotonic()
        stream.close()
        assert time.monotonic() - started < process_timeout(0.5)


EXIT_SCRIPT = textwrap.dedent("""
    import argparse, sys
    from explorer import load_scene
    from explorer.effects.pipeline import simulate
    from explorer.view.rerun.live import open_live_stream
    ns = argparse.Namespace(rerun=True, rerun_save=sys.argv[2] if len(sys.argv) > 2 else None,
                            rerun_port=int(sys.argv[1]))
    stream = open_live_stream(ns)
    stream.log(simulate(load_scene(sys.argv[3] if len(sys.argv) > 3 else {scene!r})), "exit test")
    print("logged", flush=True)
    # no close(): the atexit hook must finish the stream and let the process end
""")


@pytest.mark.parametrize("save", [False, True])
def test_process_exits_without_close_and_without_hanging(tmp_path, save):
    out = tmp_path / "exit.rrd"
    cmd = [sys.executable, "-c", EXIT_SCRIPT.format(scene=str(CYCLOIDAL)), str(free_port())]
    if save:
        cmd.append(str(out))
    started = time.monotonic()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=process_timeout())
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "logged" in proc.stdout
    assert time.monotonic() - started < process_timeout(0.75)
    if save:  # the atexit close merged the file
        assert [r.name for r in read_rrd(out)] == ["#1 exit test"]


def test_failed_merge_keeps_every_recording_and_says_where(tmp_path, monkeypatch, capsys):
    import explorer.view.rerun.recording as recording

    def broken_merge(pieces, target):
        raise RuntimeError("disk full")

    monkeypatch.setattr(recording, "merge_rrd", broken_merge)
    out = tmp_path / "live.rrd"
    stream = LiveStream(save_path=out, parts=False)
    first, second = result_at(600), result_at(700)
    stream.log(first, "a")
    assert stream.flush(60)
    stream.log(second, "b")
    stream.close()
    assert not out.exists()
    assert "could not write" in capsys.readouterr().err and stream.errors
    (pieces_dir,) = [p for p in tmp_path.iterdir() if p.name.endswith(".parts")]
    runs = [read_rrd(p)[0] for p in sorted(pieces_dir.glob("*.rrd"))]
    assert [r.name for r in runs] == ["#1 a", "#2 b"]
    assert_same_series(runs[0], first)
    assert_same_series(runs[1], second)


# -- the design checks, added when the browser has computed them ---------------------------------

FLOAT = ROOT / "assets" / "scenes" / "valve_float_demo.toml"
# the float demo over a range of speeds: five rules fail, three draw limits (tests/test_checks_view.py)
FLOAT_RANGE = ("drive.operating_range=[1000, 4000]", "drive.rpm=2000")


def check_entities(run) -> dict:
    """What the checks put in a recording: the markers' entity and every limit line."""
    return {path: cols for path, cols in run.temporal.items() if path == "/events/checks" or "/limit_" in path}


def assert_same_entities(got: dict, want: dict) -> None:
    assert sorted(got) == sorted(want)
    for path, cols in want.items():
        assert sorted(got[path]) == sorted(cols), path
        for name, values in cols.items():
            assert list(got[path][name]) == list(values), (path, name)


def test_checks_join_their_results_recording_as_explorer_record_writes_them(tmp_path):
    """`serve --rerun`/`--rerun-save`: the checks the browser computes after a result go into that
    result's recording (its id: one recording, its name kept), with the very markers and limit
    lines `explorer record --checks` writes for the scene; checks sent twice, or of a result never
    recorded, add nothing."""
    from conftest import run_cli
    from explorer.checks.viewer import evaluate

    recorded = tmp_path / "record.rrd"
    proc = run_cli("record", FLOAT, *sum((["--set", o] for o in FLOAT_RANGE), []), "--checks", "--no-parts",
                   "-o", recorded)
    assert proc.returncode == 0, proc.stderr
    want = check_entities(read_rrd(recorded)[0])
    # 6 FAIL markers (hertz_stress and dynamic_hertz_stress among them), 6 limit lines
    assert len(want["/events/checks"]["TextLog:text"]) == 6 and len(want) == 7, sorted(want)

    scene = load_scene(FLOAT, list(FLOAT_RANGE))
    first, second, never = simulate(scene), simulate(scene), result_at(600)
    checks = evaluate(scene)
    out = tmp_path / "live.rrd"
    with LiveStream(save_path=out, parts=False) as stream:
        stream.log(first, "float")
        assert stream.flush(60)
        stream.log_checks(first, checks)  # written: added to its recording
        assert stream.flush(60)
        stream.log_checks(first, checks)  # again (a fresh compute child checks the same result): nothing
        stream.log_checks(never, checks)  # a result that was never recorded: nothing
        stream.log(second, "float again")
        stream.log_checks(second, checks)  # still waiting, or being written: either way its own
        assert stream.flush(60)
    assert stream.errors == []
    runs = {r.name: r for r in read_rrd(out)}
    assert sorted(runs) == ["#1 float", "#2 float again"]  # the checks made no recording of their own
    for run, result in ((runs["#1 float"], first), (runs["#2 float again"], second)):
        assert_same_series(run, result)
        assert_same_entities(check_entities(run), want)
    # the layout shows the limit lines of the tabs that name their series one by one (the file holds
    # a blueprint per layout sent; the last one sent, and every one after the checks, lists them)
    stress = [v.get("contents", []) for v in read_blueprint_views(out) if v.get("name") == "stress"]
    assert stress and all("/stress/hertz/limit_hertz_stress_fail" in contents for contents in stress), stress


@pytest.mark.filterwarnings("ignore:RRD file has no footer")  # rerun --save streams without one
def test_checks_reach_a_rerun_viewer_in_the_results_recording(tmp_path):
    """Over gRPC (`serve --rerun`): the checks sent after the recording arrive in it, one marker at
    the worst's cam angle, the limit beside the velocity, and a line in the session's index."""
    from explorer.view.verdicts import CheckLine, CheckSummary, Threshold

    port, viewer_port = free_port(), free_port()
    received = tmp_path / "received.rrd"
    result = result_at(900)
    line = CheckLine("seating_velocity", "Seating velocity", "fail", -2.0, "2 m/s", 900.0, 123.25,
                     limit="fail 1 m/s", thresholds=(Threshold("valve_velocity_m_s", (-1.0,), "fail"),))
    checks = CheckSummary("cycloidal", "900 rpm", (line,))
    stream = open_live_stream(args(rerun=True, rerun_port=port))
    receiver = None
    try:
        stream.log(result, "live run")
        assert stream.flush(60)
        stream.log_checks(result, checks)
        assert stream.flush(60)
        receiver = spawn(
            [*rerun_executable(), "--save", str(received), "--bind", "127.0.0.1", "--port", str(viewer_port),
             stream.url],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + process_timeout(0.5)
        while time.monotonic() < deadline:
            time.sleep(0.5)
            if received.exists() and received.stat().st_size > 20_000:
                break
        time.sleep(1.0)
        receiver.send_signal(signal.SIGINT)
        receiver.wait(timeout=process_timeout(0.5))
        runs = {r.name: r for r in read_rrd(received)}
        run = runs["#1 live run"]
        assert_same_series(run, result)
        marks = run.temporal["/events/checks"]
        assert list(marks["TextLog:level"]) == ["ERROR"] and "Seating velocity" in marks["TextLog:text"][0]
        assert list(marks["cam_angle_0.01deg"]) == [12325]
        assert list(run.series["/valve/velocity/limit_seating_velocity_fail"]["value"]) == [-1.0, -1.0]
        index = list(runs["explorer live session"].temporal["/session"]["TextLog:text"])
        assert index == ["#1 live run | 900 rpm | 2 events", "#1 live run | checks FAIL: 1 fail, 0 warn"]
    finally:
        if receiver is not None:
            stop_group(receiver, grace=1.0)
        stream.close()


def test_serve_rerun_save_adds_the_checks_the_browser_computed(tmp_path):
    """`explorer serve --rerun-save` end to end: the browser's compute child checks the first
    result after showing it, and the checks join that result's recording in the saved file
    (the serve command's wiring: ComputeWorker.on_checked -> LiveStream.log_checks)."""
    from conftest import run_cli
    from test_viewer import _kill, _start_serve, _wait_for

    recorded = tmp_path / "record.rrd"
    proc = run_cli("record", FLOAT, *sum((["--set", o] for o in FLOAT_RANGE), []), "--checks", "--no-parts",
                   "-o", recorded)
    assert proc.returncode == 0, proc.stderr
    want = check_entities(read_rrd(recorded)[0])
    target = tmp_path / "live.rrd"
    proc, _, _ = _start_serve(FLOAT, *sum((["--set", o] for o in FLOAT_RANGE), []), "--shared", "--rerun-save", target)
    try:
        # a piece for the recording, then one for its checks (after the compiled solver is ready)
        assert _wait_for(lambda: len(list(tmp_path.glob(".live.rrd.*.parts/*.rrd"))) >= 2, process_timeout())
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=process_timeout(0.5))
        assert proc.returncode == 0, err
        (run,) = read_rrd(target)
        assert run.name.startswith("#1 valve_float_demo.toml")
        assert_same_entities(check_entities(run), want)
    finally:
        _kill(proc)
