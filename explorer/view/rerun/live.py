"""The live rerun stream of `explorer serve --rerun` / `--rerun-save PATH`.

Every result the browser explorer computes (a profile swap, a parameter change) becomes a new
recording, labelled "#n <label>", with the same content as `explorer record` writes (series,
3D parts, events, summary, layout; see explorer.view.rerun.recording). The design checks, which
the browser computes after the result is shown, join that recording when they come (`log_checks`):
the markers and limit lines of `explorer record --checks`, logged by the same functions under the
recording's id (a second piece of the same recording in the viewer and in the merged file).

- `--rerun`: a gRPC server bound to 127.0.0.1 (rerun's own default is every interface) at
  --rerun-port (default 9876). One hidden host stream owns the server for the whole session;
  each recording connects to it as a client, so the server outlives any single recording and a
  viewer that connects late still gets every recording (up to the server's memory limit). That
  host shows as the recording "explorer live session": a log (/session) of every recording sent.
  Watch it with `explorer view rerun+http://127.0.0.1:9876/proxy` or `rerun --connect ...`.
- `--rerun-save PATH`: each recording is written, complete, to its own file in a hidden
  directory beside PATH; `close()` merges them into PATH (temp name, then rename). Should the
  process die first, that directory still holds every finished recording as a valid .rrd.

`log()` only hands the result to a background writer and returns: building the meshes and
logging take a fraction of a second that the explorer's compute thread should not wait for. While
a recording is being written, a newer result replaces one still waiting (newest wins, as in the
explorer's own worker), so the stream never falls behind; so do checks waiting to be added
(those of a result not yet written go into its recording). `flush()` waits for the writer.

The recordings are logged in the helper process of explorer.view.rerun.worker (rerun keeps every
stream made in a process, with its threads, until that process ends; a long session would grow
with every change). Exit never hangs: every recording is flushed with a timeout and disconnected
before the next starts; `close()` (also registered with atexit, before rerun's own shutdown hook runs) drains
the writer, then disconnects the server stream.
"""

from __future__ import annotations

import atexit
import dataclasses
import shutil
import socket
import sys
import tempfile
import threading
import uuid
from pathlib import Path

from ...core.errors import InputError, check_port_number
from ...core.outputs import as_output, output_path
from . import recording  # its functions looked up when called (tests replace them)
from .worker import RecordingWorker, send

DEFAULT_PORT = 9876
BIND_IP = "127.0.0.1"
FLUSH_TIMEOUT_S = 10.0
SERVER_MEMORY_LIMIT = "1GiB"
# recordings whose design checks may still come (the browser computes them after the result, and
# a newer result stops them): the last few, so that a session holds a bounded number of results
CHECKABLE_RECORDINGS = 4


def add_live_arguments(parser) -> None:
    """--rerun, --rerun-save, --rerun-port for a command that streams (e.g. `explorer serve`)."""
    parser.add_argument("--rerun", action="store_true",
                        help=f"stream every computed run to rerun (gRPC server on {BIND_IP})")
    parser.add_argument("--rerun-save", metavar="PATH", help="record every computed run into this .rrd file")
    parser.add_argument("--rerun-port", type=int, default=DEFAULT_PORT,
                        help=f"port of the rerun gRPC server (default {DEFAULT_PORT}; 0 = any free port)")


def open_live_stream(args) -> "LiveStream":
    """A LiveStream from parsed arguments: `args.rerun` (bool), `args.rerun_save` (path or None),
    optional `args.rerun_port` (int, default 9876). Bad values raise InputError before anything
    starts. With neither flag the stream is disabled and `log` does nothing."""
    serve = bool(getattr(args, "rerun", False))
    save = getattr(args, "rerun_save", None)
    port = getattr(args, "rerun_port", None)
    port = DEFAULT_PORT if port is None else int(port)
    if save:
        save = check_save_path(save)
    if serve:
        port = check_port(port)
    stream = LiveStream(serve=serve, port=port, save_path=save)
    if stream.url:
        print(f"rerun: live stream at {stream.url}  (watch it: explorer view {stream.url})", flush=True)
    if stream.save_path:
        print(f"rerun: recording every run into {stream.save_path} (complete when the explorer stops)", flush=True)
    return stream


def check_save_path(path: str):
    """The --rerun-save path, checked by the rules of explorer.core.outputs (an Output)."""
    return recording.check_rrd_path(path, "--rerun-save")


def check_port(port: int) -> int:
    """The port, if free on 127.0.0.1 (0 -> a free one). rerun's server sink does not report a
    busy port, it only logs an error later, so test it here."""
    check_port_number(port, "--rerun-port")
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((BIND_IP, port))
        except OSError:
            raise InputError("<command line>", "--rerun-port", f"port {port} on {BIND_IP} is in use") from None
        return s.getsockname()[1]


@dataclasses.dataclass(slots=True)
class _Written:
    """A recording the stream has written, to which its result's design checks may still come."""

    result: object
    name: str
    recording_id: str
    checked: bool  # its checks are in it (with the recording or added since)


def checks_line(name: str, checks) -> str:
    """The session index's line for the checks added to recording `name`."""
    counts = checks.counts()
    return f"{name} | checks {checks.verdict.upper()}: {counts['fail']} fail, {counts['warn']} warn"


def session_line(name: str, result) -> str:
    """One line per recording in the session index: label, speed, events, warnings."""
    parts = [name, f"{result.summary.get('rpm', float('nan')):g} rpm", f"{len(result.events)} events"]
    if result.warnings:
        parts.append(f"{len(result.warnings)} warnings")
    return " | ".join(parts)


class LiveStream:
    """Recordings of successive results to a gRPC server on 127.0.0.1 and/or a file."""

    def __init__(self, *, serve: bool = False, port: int = DEFAULT_PORT, save_path=None, parts: bool = True):

        self.url: str | None = None
        self._save_output = as_output(save_path, "--rerun-save") if save_path else None
        self.save_path: Path | None = Path(self._save_output.name) if save_path else None
        self.parts = parts
        self.labels: list[str] = []  # recordings written so far, in order
        self.errors: list[str] = []
        self._host = None
        self._paths: list[str] = []  # entity paths of every recording so far (for the layout)
        self._bounds = None  # where the first recording's parts are: the 3D camera looks there
        self._pieces: list[Path] = []
        self._pieces_dir: Path | None = None
        self._cond = threading.Condition()
        self._pending: tuple | None = None  # (name, result, checks or None): the next recording
        self._pending_checks: tuple | None = None  # (result, checks): to add to the result's recording
        # the last CHECKABLE_RECORDINGS recordings written
        self._recorded: list[_Written] = []
        self._busy = False
        self._closed = False
        self._count = 0
        self.enabled = bool(serve or save_path)
        if not self.enabled:
            return
        if serve:
            import rerun as rr

            # the host stream owns the server for the whole session; the recordings are clients
            self._host = rr.RecordingStream(recording.APP_ID, recording_id=f"live-session-{uuid.uuid4().hex[:12]}",
                                            send_properties=False)
            self._host.set_sinks(rr.GrpcServerSink(bind_ip=BIND_IP, port=port,
                                                   server_memory_limit=SERVER_MEMORY_LIMIT))
            # the host shows in the viewer as a recording of its own: make it the session's index
            self._host.send_recording_name("explorer live session")
            self.url = f"rerun+http://{BIND_IP}:{port}/proxy"
        if self._save_output is not None:
            # beside the target, so that they survive a crash where the user looks; a device's
            # or pipe's in the system's temporary directory
            parent = None if self._save_output.direct else self._save_output.target.parent
            self._pieces_dir = Path(tempfile.mkdtemp(prefix=f".{self.save_path.name}.", suffix=".parts", dir=parent))
        self._worker = RecordingWorker()  # started by the writer thread at its first recording
        self._thread = threading.Thread(target=self._run, name="rerun-live", daemon=True)
        self._thread.start()
        atexit.register(self.close)

    # -- public -------------------------------------------------------------------------------

    def log(self, result, label: str | None = None) -> None:
        """Queue `result` as a new recording named "#n label" (newest wins while one is written)."""
        if not self.enabled:
            return
        with self._cond:
            if self._closed:
                raise RuntimeError("the live rerun stream is closed")
            self._count += 1
            name = f"#{self._count} {label or getattr(result.scene, 'name', 'run')}"
            self._pending = (name, result, None)
            self._cond.notify_all()

    def log_checks(self, result, checks) -> None:
        """Add the design checks `checks` (an explorer.view.verdicts.CheckSummary) of `result` to
        that result's recording: WARN/ERROR markers at each rule's worst cam angle in the event
        log and the limits as series beside their quantities, as `explorer record --checks`.
        Checks of a result that is not recorded (replaced before it was written), or whose
        recording has them already, are dropped; a newer call replaces one still waiting."""
        if not self.enabled:
            return
        with self._cond:
            if self._closed:
                raise RuntimeError("the live rerun stream is closed")
            if self._pending is not None and self._pending[1] is result:
                self._pending = (*self._pending[:2], checks)  # not written yet: in one recording
            else:
                self._pending_checks = (result, checks)
            self._cond.notify_all()

    def flush(self, timeout: float | None = None) -> bool:
        """Wait until every queued result is written; False on timeout."""
        if not self.enabled:
            return True
        with self._cond:
            return self._cond.wait_for(lambda: self._pending is None and self._pending_checks is None
                                       and not self._busy, timeout)

    def close(self) -> None:
        """Write what is queued, stop the writer, close the server, merge the file. Idempotent."""
        with self._cond:
            if self._closed or not self.enabled:
                self._closed = True
                return
            self._closed = True
            self._cond.notify_all()
        try:
            atexit.unregister(self.close)
        except Exception:
            pass
        self._thread.join()
        self._worker.close()  # the helper ends with the session it wrote for
        if self._host is not None:
            try:
                self._host.flush(timeout_sec=FLUSH_TIMEOUT_S)
            except Exception as exc:  # a slow viewer must not keep us from exiting
                self.errors.append(f"flush: {exc}")
            self._host.disconnect()
            self._host = None
        if self._pieces_dir is not None:
            pieces_dir = self._pieces_dir
            try:
                self._finish_file()
            except Exception as exc:  # noqa: BLE001 - keep the pieces, say where they are
                self.errors.append(f"{self.save_path}: {exc}")
                print(f"warning: rerun: could not write {self.save_path} ({exc}); the recordings are in "
                      f"{pieces_dir}, one complete .rrd each", file=sys.stderr)

    def __enter__(self) -> "LiveStream":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- writer thread ------------------------------------------------------------------------

    def _run(self) -> None:
        while True:
            with self._cond:
                self._cond.wait_for(lambda: self._pending is not None or self._pending_checks is not None
                                    or self._closed)
                # a recording first: the checks waiting may be its own
                job, later = (self._pending, None) if self._pending is not None else (None, self._pending_checks)
                if job is None and later is None:  # closed and drained
                    return
                if job is not None:
                    self._pending = None
                else:
                    self._pending_checks = None
                self._busy = True
            name = job[0] if job is not None else "checks"
            try:
                if job is not None:
                    self._write(*job)
                    self.labels.append(name)
                else:
                    self._write_checks(*later)
            except Exception as exc:  # one bad result must not end the stream
                self.errors.append(f"{name}: {type(exc).__name__}: {exc}")
            finally:
                with self._cond:
                    self._busy = False
                    self._cond.notify_all()

    def _sinks(self) -> tuple[list[tuple[str, str]], Path | None]:
        """Where one write goes: the server, and/or a new piece of the file."""
        sinks, piece = [], None
        if self.url is not None:
            sinks.append(("grpc", self.url))
        if self._pieces_dir is not None:
            piece = self._pieces_dir / f"{len(self._pieces):05d}.rrd"
            sinks.append(("file", str(piece)))
        return sinks, piece

    def _add_paths(self, paths) -> bool:
        """Entity paths for the layout; whether any was new (the layout then changes)."""
        seen = len(self._paths)
        self._paths.extend(dict.fromkeys(p for p in paths if p not in self._paths))
        return len(self._paths) != seen

    def _write(self, name: str, result, checks=None) -> None:
        import rerun as rr

        run = recording.with_parts(name, result) if self.parts else recording.Run(name, result)
        run = dataclasses.replace(run, checks=checks)
        changed = self._add_paths(recording.recording_paths(result, (run.parts or {}).keys(), checks))
        if self._bounds is None and run.parts:
            self._bounds = recording.parts_bounds(run.parts, run.poses or {})
        sinks, piece = self._sinks()
        rid = recording.recording_id(name)
        # Logged in the helper process (explorer.view.rerun.worker): a stream made here would stay,
        # with its threads, for the rest of the session. The blueprint is sent explicitly, not as
        # the sinks' default: a viewer that is already showing the session keeps its own layout
        # otherwise. It is made active only when it changes (first recording, new kinds of
        # series), so a user's rearrangement survives a parameter change.
        send(self._worker, sinks, run, (list(self._paths), self._bounds), make_active=changed,
             flush_timeout=FLUSH_TIMEOUT_S, recording_id=rid)
        if piece is not None:
            self._pieces.append(piece)
        self._recorded = [*self._recorded, _Written(result, name, rid, checks is not None)][-CHECKABLE_RECORDINGS:]
        if self._host is not None:
            self._host.set_time("recording", sequence=len(self.labels) + 1)
            self._host.log("/session", rr.TextLog(session_line(name, result)))
            if checks is not None:
                self._host.log("/session", rr.TextLog(checks_line(name, checks)))

    def _write_checks(self, result, checks) -> None:
        """The checks of a result already recorded, added to its recording (same id)."""
        import rerun as rr

        entry = next((e for e in reversed(self._recorded) if e.result is result), None)
        if entry is None or entry.checked:  # not recorded (replaced while waiting), or checked already
            return
        name, rid = entry.name, entry.recording_id
        changed = self._add_paths(recording.recording_paths(result, (), checks))
        sinks, piece = self._sinks()
        send(self._worker, sinks, recording.Run(name, result, checks=checks), (list(self._paths), self._bounds),
             make_active=changed, flush_timeout=FLUSH_TIMEOUT_S, recording_id=rid, checks_only=True)
        if piece is not None:
            self._pieces.append(piece)
        entry.checked = True
        if self._host is not None:
            self._host.log("/session", rr.TextLog(checks_line(name, checks)))

    def _finish_file(self) -> None:
        pieces_dir, self._pieces_dir = self._pieces_dir, None
        if self._pieces:
            with output_path(self._save_output) as tmp:
                if len(self._pieces) == 1:
                    shutil.copyfile(self._pieces[0], tmp)
                else:
                    recording.merge_rrd(self._pieces, tmp)  # on failure the pieces stay, each a complete .rrd
                recording.check_complete(tmp)
        shutil.rmtree(pieces_dir, ignore_errors=True)
