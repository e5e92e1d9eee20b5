"""The helper process of explorer.view.rerun.worker: it receives recording jobs on a pipe and logs
them with explorer.view.rerun.recording (rerun), one reply per job (None, or the error in one line).

Its own module so that the explorer's side (recording_worker, which explorer.view.rerun.recording uses to
write) and the helper's side (which uses explorer.view.rerun.recording to log) import each other in one
direction only: recording_job -> recording -> recording_worker.
"""

from __future__ import annotations

import os
import signal
from multiprocessing.connection import Connection

from .recording import APP_ID, blueprint, log_checks, log_overlay, log_result, new_recording


def _execute(job: dict) -> None:
    import rerun as rr


    layout = blueprint(*job["layout"]) if job.get("layout") is not None else None
    if job["kind"] == "blueprint":
        layout.save(APP_ID, job["path"])
        return
    if job["kind"] == "overlay":
        rec = new_recording("overlay")
        rec.set_sinks(rr.FileSink(job["path"]))
        try:
            log_overlay(rec, job["runs"], job["label"])
            rec.flush()
        finally:
            rec.disconnect()
        return
    sinks = [rr.FileSink(where) if kind == "file" else rr.GrpcSink(where) for kind, where in job["sinks"]]
    run = job["run"]
    # "checks": the design checks of a run already recorded, added to that recording (its id)
    appending = job["kind"] == "checks"
    rec = new_recording(run.label, job.get("recording_id"), send_properties=not appending)
    if layout is not None and job.get("default_blueprint"):
        rec.set_sinks(*sinks, default_blueprint=layout)
    else:
        rec.set_sinks(*sinks)
    try:
        if layout is not None and job.get("send_blueprint"):
            rec.send_blueprint(layout, make_active=job.get("make_active", True), make_default=True)
        if appending:
            log_checks(rec, run.result, run.checks)
        else:
            log_result(rec, run.result, run.label, run.parts, run.poses, run.scales, run.colors, run.points,
                       run.magnification, getattr(run, "checks", None))
        timeout = job.get("flush_timeout")
        if timeout is None:
            rec.flush()
        else:
            rec.flush(timeout_sec=timeout)
    finally:
        rec.disconnect()  # closes a file with its footer


def _serve(inbox, outbox) -> None:
    while True:
        try:
            job = inbox.recv()
        except (EOFError, OSError):  # the explorer has gone
            return
        if job is None:
            return
        try:
            _execute(job)
            outbox.send(None)
        except Exception as exc:  # noqa: BLE001 - reported by the explorer, the helper goes on
            outbox.send(f"{type(exc).__name__}: {exc}")


def main() -> None:
    """The helper's entry point: jobs arrive on stdin, replies leave on the descriptor that was
    stdout, which from here on is stderr's, so nothing printed can corrupt a reply."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.environ.setdefault("RUST_LOG", "off")
    replies = os.dup(1)
    os.dup2(2, 1)
    _serve(Connection(os.dup(0), writable=False), Connection(replies, readable=False))
