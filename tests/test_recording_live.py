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
