"""Rerun recordings are logged in a helper process, replaced after every RECYCLE_AFTER recordings.

Why a process: rerun-sdk never frees a RecordingStream made from Python (rerun issue #2116, open
in 0.41). `disconnect()` closes its sinks, but the stream's batcher and forwarding threads (two for
the recording, two for the blueprint that goes with it) and what they hold stay until the process
exits: 4 threads and about 1.6 MB for every recording, so a 3000-run sweep died with "Failed to
spawn thread" and `serve --rerun-save` grew with every change. Deleting the stream, disconnecting
orphans or rerun's own shutdown() do not release them. In a helper process they end with it: the
explorer's thread count and memory stay flat however many recordings it makes, and the helper
never holds more than RECYCLE_AFTER recordings' worth.

The helper (explorer.view.rerun.job) is a fresh interpreter (a fork would copy the locks of rerun's and viser's threads),
in its own session so that Ctrl-C reaches only the explorer, which finishes what it writes and
then closes it; it exits when its pipe closes, so it never outlives the explorer. rerun's own log lines are off in it unless RUST_LOG says
otherwise: a failed write is reported by the explorer in one line (the file has no footer).
"""

from __future__ import annotations

import os
import subprocess
import threading
from dataclasses import replace
from multiprocessing.connection import Connection
from types import SimpleNamespace
from typing import Mapping

from ...core.processes import spawn_python

RECYCLE_AFTER = 32  # recordings per helper process: at most ~130 threads and ~50 MB of rerun's leftovers
JOB_TIMEOUT_S = 600.0  # one recording; the live stream's flush has its own, shorter timeout
STOP_TIMEOUT_S = 10.0
# The helper's side (it logs with explorer.view.rerun.recording, which imports this module for the
# explorer's side): a separate module, so that neither side imports the other back.
HELPER_MAIN = "from explorer.view.rerun.job import main; main()"


def _plain(value):
    """Summaries hold read-only mappings (MappingProxyType), which do not pickle."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def portable_run(run):
    """The run with a result the helper process can receive: columns, summary, events, warnings,
    timings, the scene's name and source (all that explorer.view.rerun.recording.log_result reads
    of it)."""
    result = run.result
    scene = getattr(result, "scene", None)
    light = SimpleNamespace(
        scene=SimpleNamespace(name=str(getattr(scene, "name", "")), source=str(getattr(scene, "source", ""))),
        columns={k: v for k, v in result.columns.items()},
        summary=_plain(result.summary),
        events=tuple(_plain(e) for e in result.events),
        warnings=tuple(result.warnings),
        timings=dict(result.timings),
    )
    return replace(run, result=light)


class RecordingWorker:
    """One helper process at a time, started when needed and replaced every `recycle_after` jobs.
    `run(job)` is synchronous and thread-safe (jobs are serialised). Whoever writes recordings owns
    one for as long as it writes (`with RecordingWorker() as worker:`, a LiveStream for its
    session): no helper outlives the work it was started for."""

    def __init__(self, recycle_after: int = RECYCLE_AFTER):
        self.recycle_after = recycle_after
        self._lock = threading.Lock()
        self._proc = None
        self._send = self._recv = None
        self._jobs = 0

    def _start(self) -> None:
        # own session (Ctrl-C in the terminal is the explorer's to handle), dies with the thread that
        # started it (and exits when its pipe closes)
        proc = spawn_python(HELPER_MAIN, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self._proc = proc
        self._send = Connection(os.dup(proc.stdin.fileno()), readable=False)
        self._recv = Connection(os.dup(proc.stdout.fileno()), writable=False)
        proc.stdin.close()
        proc.stdout.close()
        self._jobs = 0

    def _stop(self) -> None:
        proc = self._proc
        self._proc = None
        if proc is None:
            return
        try:
            self._send.send(None)
        except OSError:
            pass
        self._send.close()
        self._recv.close()
        try:
            proc.wait(STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()

    def run(self, job: dict, timeout: float = JOB_TIMEOUT_S) -> None:
        with self._lock:
            if self._proc is None:
                self._start()
            try:
                self._send.send(job)
                if not self._recv.poll(timeout):
                    raise TimeoutError(f"writing the recording took longer than {timeout:g} s")
                reply = self._recv.recv()
            except (EOFError, OSError) as exc:  # it died, or hangs (TimeoutError)
                proc = self._proc
                proc.kill()
                self._stop()
                why = str(exc) or f"exit status {proc.returncode}"
                raise RuntimeError(f"the rerun writer process failed ({why})") from None
            except BaseException:  # Ctrl-C while it works: its reply must not answer the next job
                self._proc.kill()
                self._stop()
                raise
            self._jobs += 1
            if self._jobs >= self.recycle_after:
                self._stop()
            if reply is not None:
                raise RuntimeError(reply)

    def close(self) -> None:
        with self._lock:
            self._stop()

    def __enter__(self) -> "RecordingWorker":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_file(worker: RecordingWorker, path, run, layout: tuple | None) -> None:
    """One run as one recording into the .rrd file `path`, with `layout` = (paths, bounds) of
    explorer.view.rerun.recording.blueprint as its default blueprint (None: no blueprint)."""
    worker.run({"kind": "record", "sinks": [("file", str(path))], "run": portable_run(run),
                         "layout": layout, "default_blueprint": layout is not None})


def write_overlay(worker: RecordingWorker, path, runs: list, label: str) -> None:
    """The overlay recording of a sweep (explorer.view.rerun.recording.log_overlay) into its own file."""
    worker.run({"kind": "overlay", "path": str(path), "runs": runs, "label": label})


def write_blueprint(worker: RecordingWorker, path, layout: tuple) -> None:
    """Only the blueprint, for the application id of every recording (merged in last)."""
    worker.run({"kind": "blueprint", "path": str(path), "layout": layout})


def send(worker: RecordingWorker, sinks: list[tuple[str, str]], run, layout: tuple, make_active: bool,
         flush_timeout: float, recording_id: str | None = None, checks_only: bool = False) -> None:
    """One recording to `sinks` [("file", path) | ("grpc", url)], its blueprint sent explicitly,
    under `recording_id` (None: a fresh one). `checks_only`: only the run's design checks
    (run.checks), added to the recording `recording_id` already holds (the live stream's, once
    the browser has computed them)."""
    worker.run({"kind": "checks" if checks_only else "record", "sinks": sinks, "run": portable_run(run),
                "layout": layout, "send_blueprint": True, "make_active": make_active, "flush_timeout": flush_timeout,
                "recording_id": recording_id},
               timeout=JOB_TIMEOUT_S + flush_timeout)
