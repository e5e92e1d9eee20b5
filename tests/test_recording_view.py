"""`explorer view`: rerun's web viewer for a recording, bound to 127.0.0.1 only, stopped by Ctrl-C."""

from __future__ import annotations

import queue
import signal
import socket
import subprocess
import sys
import threading
import urllib.request
from pathlib import Path

import psutil
import pytest

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


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM])
def test_view_serves_on_localhost_and_stops_on_ctrl_c(recording, stop):
    web, grpc = free_port(), free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "explorer", "view", str(recording), "--port", str(web), "--grpc-port", str(grpc)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in proc.stdout], daemon=True).start()
    try:
        line = lines.get(timeout=90)
        assert line.startswith("rerun web viewer: http://127.0.0.1:")
        url = line.split()[3]
        assert url.startswith(f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy")
        ports = listening(psutil.Process(proc.pid))
        assert ports.get(web) == {"127.0.0.1"} and ports.get(grpc) == {"127.0.0.1"}, ports
        with urllib.request.urlopen(f"http://127.0.0.1:{web}/", timeout=10) as page:
            assert page.status == 200 and b"<html" in page.read(4096).lower()
        children = psutil.Process(proc.pid).children(recursive=True)
        assert children  # the rerun process
        proc.send_signal(stop)
        assert proc.wait(timeout=30) == 0
        gone, alive = psutil.wait_procs(children, timeout=15)
        assert not alive
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_view_bad_input(tmp_path, capsys, recording):
    not_rrd = tmp_path / "notes.rrd"
    not_rrd.write_text("hello")
    cases = [
        ([str(tmp_path / "missing.rrd")], "file not found"),
        ([str(not_rrd)], "not a rerun recording"),
        ([str(tmp_path)], "directory"),
        ([str(recording), "--port", "70000"], "between 0 and 65535"),
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
    import explorer.recording as recording_module

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
