"""`explorer view`: rerun's web viewer for a recording, bound to 127.0.0.1 only, stopped by Ctrl-C."""

from __future__ import annotations

import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import psutil
import pytest

from conftest import process_timeout, started, still_running
from explorer.cli import main

ROOT = Path(__file__).resolve().parent.parent
CYCLOIDAL = ROOT / "assets" / "scenes" / "cycloidal_demo.toml"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def listening(proc: psutil.Process) -> dict[int, set[str]]:
    """port -> addresses that the process or its children listen on."""
    out: dict[int, set[str]] = {}
    for p in [proc, *proc.children(recursive=True)]:
        try:
            for c in p.net_connections(kind="inet"):
                if c.status == psutil.CONN_LISTEN:
                    out.setdefault(c.laddr.port, set()).add(c.laddr.ip)
        except psutil.NoSuchProcess:
            pass
    return out


@pytest.fixture(scope="module")
def recording(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("view") / "run.rrd"
    assert main(["record", str(CYCLOIDAL), "--set", "solver.steps_per_revolution=360", "-o", str(out)]) == 0
    return out


def _view(*args, env=None):
    return started([sys.executable, "-m", "explorer", "view", *args], cwd=ROOT, stdout=subprocess.PIPE,
                   stderr=subprocess.PIPE, text=True, env=env)


def _first_line(proc) -> str:
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in proc.stdout], daemon=True).start()
    try:
        return lines.get(timeout=process_timeout())
    except queue.Empty:
        raise AssertionError(f"explorer view printed nothing; stderr: {proc.stderr.read() if proc.poll() is not None else ''}")


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_view_serves_on_localhost_and_stops_on_ctrl_c(recording, stop):
    web, grpc = free_port(), free_port()
    with _view(str(recording), "--port", str(web), "--grpc-port", str(grpc)) as proc:
        line = _first_line(proc)
        assert line.startswith("rerun web viewer: http://127.0.0.1:")
        url = line.split()[3]
        assert url.startswith(f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy")
        ports = listening(psutil.Process(proc.pid))
        assert ports.get(web) == {"127.0.0.1"} and ports.get(grpc) == {"127.0.0.1"}, ports
        with urllib.request.urlopen(f"http://127.0.0.1:{web}/", timeout=process_timeout(0.25)) as page:
            assert page.status == 200 and b"<html" in page.read(4096).lower()
        children = psutil.Process(proc.pid).children(recursive=True)
        # the rerun server, and the guard that ends its group should we die; no browser of its own
        assert [c.name() for c in children if c.name() == "rerun"] == ["rerun"], [c.cmdline() for c in children]
        assert not [c for c in children if "chrom" in c.name()]
        proc.send_signal(stop)
        assert proc.wait(timeout=process_timeout(0.5)) == 0
        gone, alive = psutil.wait_procs(children, timeout=process_timeout(0.25))
        assert not alive


# A stand-in for the rerun CLI that is as hard to stop as a program can be: it ignores SIGINT and
# SIGTERM, serves the web port it is given, and starts a helper of its own (in its group).
STUBBORN_VIEWER = """#!{python}
import os, signal, socket, subprocess, sys, time
signal.signal(signal.SIGINT, signal.SIG_IGN)
signal.signal(signal.SIGTERM, signal.SIG_IGN)
port = int(sys.argv[sys.argv.index("--web-viewer-port") + 1])
server = socket.socket()
server.bind(("127.0.0.1", port))
server.listen()
helper = subprocess.Popen(["sleep", "1000"])
with open({pids!r} + ".tmp", "w") as handle:
    handle.write(f"{{os.getpid()}} {{helper.pid}}")
os.replace({pids!r} + ".tmp", {pids!r})  # whole or absent: the test polls for it
while True:
    time.sleep(1)
"""


def _stub_pids(pids) -> tuple[int, int]:
    """The stub's and its helper's pids. The explorer reports the viewer's address as soon as the
    stub serves its port, which on a loaded machine can be before the stub has started its helper
    and written this file: wait for it (bounded by the suite's process timeout)."""
    deadline = time.monotonic() + process_timeout(0.25)
    while not pids.exists():
        assert time.monotonic() < deadline, "the stub viewer never wrote its pids"
        time.sleep(0.02)
    viewer, helper = map(int, pids.read_text().split())
    return viewer, helper


def _stubborn(tmp_path):
    pids = tmp_path / "pids"
    script = tmp_path / "rerun"
    script.write_text(STUBBORN_VIEWER.format(python=sys.executable, pids=str(pids)))
    script.chmod(0o755)
    return {**os.environ, "RERUN_CLI_PATH": str(script)}, pids


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_view_ends_a_viewer_that_ignores_signals_and_everything_it_started(recording, tmp_path, stop):
    """The escalation (SIGINT, SIGTERM to the whole group, then SIGKILL) ends even a viewer that
    ignores both signals, and the helper it started: the command exits and nothing is left."""
    env, pids = _stubborn(tmp_path)
    with _view(str(recording), "--port", "0", "--grpc-port", "0", env=env) as proc:
        assert _first_line(proc).startswith("rerun web viewer: http://127.0.0.1:")
        viewer, helper = _stub_pids(pids)
        proc.send_signal(stop)
        assert proc.wait(timeout=process_timeout(0.5)) == 0
        assert still_running([viewer, helper], process_timeout(0.25)) == []


def test_a_killed_view_takes_its_viewer_and_its_helpers_along(recording, tmp_path):
    """`kill -9` of the explorer leaves it no chance to clean up: the viewer dies by its
    parent-death signal, and the guard kills the viewer's group, its helper included."""
    env, pids = _stubborn(tmp_path)
    with _view(str(recording), "--port", "0", "--grpc-port", "0", env=env) as proc:
        assert _first_line(proc).startswith("rerun web viewer: http://127.0.0.1:")
        viewer, helper = _stub_pids(pids)
        proc.kill()
        proc.wait(timeout=process_timeout(0.25))
        assert still_running([viewer, helper], process_timeout(0.25)) == []


def test_a_second_ctrl_c_ends_view_at_once(recording, tmp_path):
    env, pids = _stubborn(tmp_path)
    with _view(str(recording), "--port", "0", "--grpc-port", "0", env=env) as proc:
        assert _first_line(proc).startswith("rerun web viewer: http://127.0.0.1:")
        viewer, helper = _stub_pids(pids)
        proc.send_signal(signal.SIGINT)
        time.sleep(0.3)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=process_timeout(0.5)) in (0, 1)
        assert still_running([viewer, helper], process_timeout(0.25)) == []


def test_view_bad_input(tmp_path, capsys, recording):
    not_rrd = tmp_path / "notes.rrd"
    not_rrd.write_text("hello")
    cases = [
        ([str(tmp_path / "missing.rrd")], "file not found"),
        ([str(not_rrd)], "not a rerun recording"),
        ([str(tmp_path)], "directory"),
        ([str(recording), "--port", "70000"], "from 1 to 65535, or 0"),
    ]
    for args, needle in cases:
        assert main(["view", *args]) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: ") and err.count("\n") == 1 and needle in err, err
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        assert main(["view", str(recording), "--port", str(busy.getsockname()[1])]) == 2
        assert "in use" in capsys.readouterr().err


def test_view_without_a_rerun_cli_is_one_line(tmp_path, capsys, recording, monkeypatch):
    """No rerun executable (a broken install) or one that cannot start: one line, no traceback."""
    import explorer.view.rerun.recording as recording_module

    def missing():
        raise RuntimeError("the rerun command-line tool was not found")

    with monkeypatch.context() as m:
        m.setattr(recording_module, "rerun_executable", missing)
        assert main(["view", str(recording), "--port", "0", "--grpc-port", "0"]) == 1
        assert capsys.readouterr().err == "error: the rerun command-line tool was not found\n"
    monkeypatch.setenv("RERUN_CLI_PATH", str(tmp_path / "no-such-rerun"))
    assert main(["view", str(recording), "--port", "0", "--grpc-port", "0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {tmp_path / 'no-such-rerun'}: -: ") and err.count("\n") == 1, err
