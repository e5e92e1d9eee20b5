"""The explorer's recomputations run in a child process that can be killed.

A recomputation holds the GIL for as long as it likes (a unit like "10**10**10 mm" is one C-level
big-integer power), so neither a thread nor a flag can stop it, and while it runs the server's
own threads starve. In a child process it cannot starve the server, and past its time limit it is
killed and replaced. The child keeps its previous result, so the reuse `prepare` does (only the
magnification changed, the cam unchanged) works as before; only the finished bundle crosses the
pipe (about 3 MB pickled for the built-in scenes, a few milliseconds).

The child lives in its own session (Ctrl-C in the terminal is for the server, which then stops
it), dies with the thread that started it (Linux PR_SET_PDEATHSIG) and when its pipe closes.

The child runs `main(READ_FD, WRITE_FD, MEMORY_BYTES)` (see CHILD_MAIN).
"""

from __future__ import annotations

import os
import pickle
import signal
import subprocess
import threading
import time
from multiprocessing.connection import Connection

from ...core.pickling import dumps
from ...core.processes import spawn_python
from typing import Callable

READY = "ready"
SUPERSEDED_POLL_S = 0.05  # how often a running computation asks whether a newer request waits
START_TIMEOUT_S = 120.0  # the child imports numpy, scipy, pint, trimesh: seconds on a busy machine
# not `-m explorer.view.browser.worker`: the module would run as __main__, and what it pickles (the
# mapping-proxy rebuilder) would name __main__, which the server cannot find
CHILD_MAIN = "import sys; from explorer.view.browser.worker import main; sys.exit(main(sys.argv[1:]))"


class TimeLimitExceeded(Exception):
    pass


class WorkerDied(Exception):
    pass


class Superseded(Exception):
    pass



# ---------------------------------------------------------------------------------------------
# parent side


class ComputeProcess:
    """One child process computing `prepare(request)`; `call` waits at most `time_limit` seconds.
    Start, call and reap from one thread (the death signal follows the starting thread); `kill`
    may come from any thread."""

    def __init__(self, memory_bytes: int = 0):
        self.memory_bytes = memory_bytes
        self._lock = threading.Lock()
        self._proc: subprocess.Popen | None = None
        self._conn: _Pipe | None = None
        self._closed = False

    @property
    def pid(self) -> int | None:
        with self._lock:
            return None if self._proc is None else self._proc.pid

    def start(self) -> None:
        to_child_r, to_child_w = os.pipe()
        from_child_r, from_child_w = os.pipe()
        try:
            # own session, dies with the thread that starts it (explorer.core.processes.spawn)
            proc = spawn_python(
                CHILD_MAIN, str(to_child_r), str(from_child_w), str(int(self.memory_bytes)),
                # stdout is the server's (it prints its URL there); tracebacks go to stderr
                pass_fds=(to_child_r, from_child_w), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            )
        except BaseException:
            for fd in (to_child_r, to_child_w, from_child_r, from_child_w):
                os.close(fd)
            raise
        os.close(to_child_r)
        os.close(from_child_w)
        with self._lock:
            self._proc = proc
            self._conn = _Pipe(from_child_r, to_child_w)
            closed = self._closed
        if closed:  # shut down while this child was being created: it must not outlive that
            self.reap()
            raise WorkerDied("the computation process was shut down")
        if not self._conn.poll(START_TIMEOUT_S):
            self.kill()
            self.reap()
            raise WorkerDied(f"the computation process did not start within {START_TIMEOUT_S:g} s")
        try:
            message = self._conn.recv()
        except (EOFError, OSError):
            self.reap()
            raise WorkerDied("the computation process ended while starting") from None
        if message != READY:
            self.kill()
            self.reap()
            raise WorkerDied(f"the computation process said {message!r} instead of {READY!r}")

    def alive(self) -> bool:
        with self._lock:
            return self._proc is not None and self._proc.poll() is None

    def call(self, request, time_limit: float | None, superseded: Callable[[], bool] | None = None):
        """("ok", (Prepared, serial of the previous request it reused or None)) | ("input",
        message) | ("internal", message) | ("memory", ""); raises TimeLimitExceeded or, when
        `superseded()` turns true meanwhile, Superseded (the child is killed and reaped), or
        WorkerDied."""
        if not self.alive():
            self.reap()
            self.start()
        conn = self._conn
        try:
            conn.send(request)
        except (OSError, EOFError):
            self.reap()
            raise WorkerDied("the computation process ended") from None
        deadline = None if time_limit is None else time.monotonic() + time_limit
        while True:
            wait = None if deadline is None else max(0.0, deadline - time.monotonic())
            if superseded is not None:
                wait = SUPERSEDED_POLL_S if wait is None else min(wait, SUPERSEDED_POLL_S)
            if conn.poll(wait):
                break
            if deadline is not None and time.monotonic() >= deadline:
                self.kill()
                self.reap()
                raise TimeLimitExceeded()
            if superseded is not None and superseded():
                self.kill()
                self.reap()
                raise Superseded()
        try:
            kind, payload = conn.recv()
        except (EOFError, OSError):
            self.reap()
            raise WorkerDied("the computation process ended (out of memory or killed)") from None
        return kind, payload

    def kill(self) -> None:
        """SIGKILL the child's process group. The child is reaped only by `reap`, so its pid (and
        group id) cannot be reused by another process meanwhile."""
        with self._lock:
            proc = self._proc
            if proc is None or proc.returncode is not None:
                return
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def reap(self) -> None:
        with self._lock:
            proc, conn = self._proc, self._conn
            self._proc = self._conn = None
        if proc is not None:
            if proc.poll() is None:
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            proc.wait()
        if conn is not None:
            conn.close()

    def shutdown(self) -> None:
        """Kill the child and refuse to start another (any thread; the caller's thread or the
        one using this reaps)."""
        with self._lock:
            self._closed = True
        self.kill()


class _Pipe:
    """A Connection pair over two plain pipe fds (read, write)."""

    def __init__(self, read_fd: int, write_fd: int):
        self._r = Connection(read_fd, writable=False)
        self._w = Connection(write_fd, readable=False)

    def poll(self, timeout):
        return self._r.poll(timeout)

    def send(self, obj) -> None:
        self._w.send_bytes(dumps(obj))

    def recv(self):
        return pickle.loads(self._r.recv_bytes())

    def close(self) -> None:
        self._r.close()
        self._w.close()


# ---------------------------------------------------------------------------------------------
# child side


def _limit_memory(memory_bytes: int) -> None:
    if memory_bytes > 0:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))


def _background_reply(task, last, result_serial: int, advice_cache: dict):
    """("sweep", figures) for a speed-sweep task, ("advice", read-out) for an advice task,
    ("checks", CheckSummary or why none) for a checks task, on the result held; ("stale", None)
    when the child no longer holds that result (a newer one came, or the child was restarted)."""
    # local: this module is the parent's handle on the child too; the computing modules load in the child
    from .checks_panel import ChecksTask, run_checks
    from .model import AdviceTask, advice_readout
    from .speedsweep import run_task

    if last is None or task.serial != result_serial:
        return ("stale", None)
    try:
        if isinstance(task, ChecksTask):
            return run_checks(task, last.scene)
        if isinstance(task, AdviceTask):
            return ("advice", advice_readout(last, advice_cache))
        return ("sweep", run_task(task, last))
    except MemoryError:
        return ("memory", "")
    except Exception as exc:  # a background task that fails must not end the child: the viewer shows why
        import traceback

        traceback.print_exc()
        return ("internal", f"internal error in {type(task).__name__}: {type(exc).__name__}: {exc}")


def main(argv: list[str]) -> int:
    read_fd, write_fd, memory_bytes = (int(a) for a in argv[:3])
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the server handles Ctrl-C and stops us
    pipe = _Pipe(read_fd, write_fd)

    # local: imported in the child, after SIGINT is ignored and before its memory limit
    from ...core.errors import InputError
    from .checks_panel import ChecksTask
    from .model import AdviceTask, prepare
    from .speedsweep import SweepTask

    # what `prepare` imports on first use, imported before the first time limit starts counting
    from ...effects import pipeline as effects  # noqa: F401
    from ... import gears  # noqa: F401
    from ...lift import curves as lift  # noqa: F401
    from .. import parts as meshes  # noqa: F401
    from ...scene import scene  # noqa: F401

    _limit_memory(memory_bytes)
    pipe.send(READY)
    last = None
    result_serial = -1  # the request whose simulation `last` holds (a magnification reuses it)
    advice_cache: dict = {}  # the last spring advice and what it depends on (model.advice_readout)
    while True:
        try:
            request = pipe.recv()
        except (EOFError, OSError):
            return 0  # the server closed the pipe: it is done with us
        if isinstance(request, (SweepTask, AdviceTask, ChecksTask)):
            pipe.send(_background_reply(request, last, result_serial, advice_cache))
            continue
        try:
            prepared = prepare(request, last)
        except InputError as exc:
            reply = ("input", f"error: {exc}")
        except MemoryError:
            last = None  # whatever was half built is garbage; start clean
            reply = ("memory", "")
        except Exception as exc:
            import traceback

            traceback.print_exc()
            reply = ("internal", f"internal error: {type(exc).__name__}: {exc}")
        else:
            reused = None if prepared.new_result else last.request.serial
            if prepared.new_result:
                result_serial = prepared.request.serial
            last = prepared
            reply = ("ok", (prepared, reused))
        try:
            pipe.send(reply)
        except MemoryError:
            pipe.send(("memory", ""))

