"""`explorer view`: rerun's web viewer on 127.0.0.1 for a recording (offline, from the wheel)."""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import time
import urllib.parse
from pathlib import Path

from ..core.errors import InputError, check_port_number
from ..core.files import check_regular
from ..core.processes import Supervisor

HELP = """\
Open a rerun recording (.rrd, e.g. from `explorer record`) in rerun's web viewer, served from
this machine only (127.0.0.1; the viewer ships with the rerun-sdk package, no network needed).
Also takes the gRPC address that `explorer serve --rerun` prints, to watch a live stream.
Prints the URL to open in a browser; Ctrl-C stops it.
"""

HOST = "127.0.0.1"
DEFAULT_WEB_PORT = 9090
DEFAULT_GRPC_PORT = 9877  # not rerun's 9876, which `explorer serve --rerun` uses for its stream
STARTUP_TIMEOUT_S = 60.0


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer view run.rrd
  explorer view run.rrd --port 0 --grpc-port 0
"""


def register(sub) -> None:
    p = sub.add_parser("view", help="open a .rrd file in rerun's web viewer (127.0.0.1)", description=HELP,
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("source", metavar="FILE.rrd|URL", help="a .rrd file, or a rerun+http://127.0.0.1:PORT/proxy address")
    p.add_argument("--port", type=int, default=DEFAULT_WEB_PORT,
                   help=f"web viewer port (default {DEFAULT_WEB_PORT}; 0 = any free port)")
    p.add_argument("--grpc-port", type=int, default=DEFAULT_GRPC_PORT,
                   help=f"port of the viewer's data server (default {DEFAULT_GRPC_PORT}; 0 = any free port)")
    p.set_defaults(run=run)


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((HOST, 0))
        return s.getsockname()[1]


def _check_port(port: int, option: str) -> int:
    check_port_number(port, option)
    if port == 0:
        return _free_port()
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((HOST, port))
        except OSError:
            raise InputError("<command line>", option, f"port {port} on {HOST} is in use; pick another (0 = any)") from None
    return port


def _is_url(source: str) -> bool:
    return source.startswith(("rerun://", "rerun+http://", "rerun+https://"))


def _check_source(source: str) -> str:
    if _is_url(source):
        return source
    path = Path(source)
    if not path.exists():
        raise InputError(source, "-", "file not found")
    if path.is_dir():
        raise InputError(source, "-", "is a directory, not a .rrd file")
    check_regular(path, file=source, key="-")  # a FIFO would block the open below
    try:
        with open(path, "rb") as handle:
            magic = handle.read(4)
    except OSError as exc:
        raise InputError(source, "-", f"cannot read: {exc.strerror}") from None
    if magic[:3] != b"RRF":  # every .rrd starts with "RRF" and an encoding version digit
        raise InputError(source, "-", "not a rerun recording (.rrd)")
    return str(path)


def _wait_listening(port: int, proc: subprocess.Popen, timeout: float, stopping) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and not stopping.is_set():
        if proc.poll() is not None:
            return False
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.settimeout(0.2)
            if s.connect_ex((HOST, port)) == 0:
                return True
        stopping.wait(0.1)
    return False


def viewer_url(web_port: int, data_url: str) -> str:
    """The page to open: the web viewer, told where its data comes from."""
    return f"http://{HOST}:{web_port}/?url={urllib.parse.quote(data_url, safe='')}"


def run(args) -> int:
    source = _check_source(args.source)
    web_port = _check_port(args.port, "--port")
    grpc_port = 0 if _is_url(source) else _check_port(args.grpc_port, "--grpc-port")
    if web_port == grpc_port:
        raise InputError("<command line>", "--grpc-port", "must differ from --port")
    from ..view.rerun.recording import rerun_executable  # local: loads when the command runs, not at `explorer --help`

    try:
        executable = rerun_executable()
    except RuntimeError as exc:  # the rerun-sdk install lacks its CLI: not the user's input
        print(f"error: {exc}", file=sys.stderr)
        return 1
    # --serve-web, not --web-viewer: the latter also opens a browser on this machine, a process
    # outside our control (on a headless machine a browser that spins, left running after us)
    cmd = [*executable, source, "--serve-web", "--bind", HOST, "--web-viewer-port", str(web_port)]
    if _is_url(source):
        data_url = source  # the browser connects to that stream itself; no data server of ours
    else:
        cmd += ["--port", str(grpc_port)]  # the file is served to the browser from here
        data_url = f"rerun+http://{HOST}:{grpc_port}/proxy"
    env = {**os.environ, "RUST_LOG": os.environ.get("RUST_LOG", "warn")}
    with Supervisor("explorer view") as supervisor:
        # its own process group, dying with us; Ctrl-C reaches us and we end its whole group
        proc = supervisor.spawn(cmd, stdin=subprocess.DEVNULL, env=env)
        if not _wait_listening(web_port, proc, STARTUP_TIMEOUT_S, supervisor.stopping):
            if supervisor.stopping.is_set():
                print("stopping", file=sys.stderr)
                return 0
            code = proc.poll()
            print(f"error: the rerun viewer did not start (exit status {code})", file=sys.stderr)
            return 1
        print(f"rerun web viewer: {viewer_url(web_port, data_url)}  (Ctrl-C stops)", flush=True)
        while not supervisor.stopping.wait(0.25):
            if proc.poll() is not None:
                return 0 if proc.returncode == 0 else 1
        print("stopping", file=sys.stderr)
        return 0
