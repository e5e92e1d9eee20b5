"""Child processes and stop signals for the long-running commands (`explorer view`, `serve`).

The rules, each for a failure seen on a loaded machine:

- Every child runs in its own process group (its own session) and is ended as a *group*:
  a program that forks (a viewer with helper processes) leaves nothing behind.
- A child never outlives us: on Linux it gets SIGKILL when the thread that started it dies
  (``PR_SET_PDEATHSIG``), so even ``kill -9`` of the explorer ends it; children are therefore
  started from the main thread. What *it* starts (a viewer may start helpers) is covered by a
  guard: a tiny shell in a session of its own that waits on a pipe only we hold open and kills
  the child's whole group when that pipe closes, which the kernel does however we die.
- Ctrl-C, SIGTERM and SIGHUP do not raise ``KeyboardInterrupt`` wherever the main thread happens
  to be (inside ``Popen.poll`` it could leave the Popen's internal lock held, and the final
  ``wait`` then blocked for ever); they set an event that the command's loop waits on.
- Stopping is bounded: the first signal arms a watchdog. If the clean shutdown (children, servers,
  streams, files, the interpreter's own exit handlers) has not ended the process within
  ``shutdown_timeout`` seconds, the watchdog kills every child group and exits at once; so does a
  second signal. A loaded machine makes a clean stop slower, never endless.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Callable, Sequence

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
# Seconds a clean stop may take before the watchdog ends the process. Generous, since a clean stop
# also completes files (a --rerun-save merge); EXPLORER_SHUTDOWN_TIMEOUT overrides it.
SHUTDOWN_TIMEOUT_S = 20.0
# How long each signal of the escalation (SIGINT, SIGTERM) waits before the next; then SIGKILL.
GRACE_S = 3.0
_PR_SET_PDEATHSIG = 1


class Stopped(BaseException):
    """A stop signal (SIGTERM, SIGHUP) delivered as an exception (see stop_signals_raise): like
    Ctrl-C's KeyboardInterrupt, every `finally` and `with` on the way out runs, so temporaries
    are removed and worker processes ended; unlike it, no command treats it as "keep what is
    done" (a sweep writes its finished runs on Ctrl-C, nothing on SIGTERM)."""

    def __init__(self, signum: int):
        self.signum = int(signum)
        super().__init__(signal.Signals(signum).name)


@contextlib.contextmanager
def stop_signals_raise(signals=(signal.SIGTERM, signal.SIGHUP)):
    """While the block runs, the stop signals raise Stopped in the main thread of this process.
    A child forked inside the block inherits the handler; there it takes the signal's default
    action (it ends), so that a worker never runs our clean-up. A second signal of the same kind
    during the clean-up ends the process at once (the default action). Outside the main thread
    (a test calling `main` from a thread) nothing is installed."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    owner = os.getpid()

    def handler(signum, frame):
        signal.signal(signum, signal.SIG_DFL)  # a second one: the default action, at once
        if os.getpid() != owner:
            os.kill(os.getpid(), signum)
            return
        raise Stopped(signum)

    previous = {}
    for sig in signals:
        with contextlib.suppress(ValueError, OSError):
            previous[sig] = signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, old in previous.items():
            with contextlib.suppress(ValueError, OSError, TypeError):
                signal.signal(sig, old)


def shutdown_timeout() -> float:
    text = os.environ.get("EXPLORER_SHUTDOWN_TIMEOUT", "")
    try:
        value = float(text)
    except ValueError:
        return SHUTDOWN_TIMEOUT_S
    return value if 0.0 < value < 86400.0 else SHUTDOWN_TIMEOUT_S


def _load_prctl() -> Callable[..., int] | None:
    # Loaded in the parent: the child between fork and exec must not import or allocate.
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl
    except (OSError, AttributeError):
        return None


def _child_setup(prctl, parent: int) -> Callable[[], None]:
    def setup() -> None:
        # A shell's background job starts with SIGINT ignored, and ignored signals survive exec:
        # the child must be stoppable by the escalation below.
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if prctl is not None:
            prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
            if os.getppid() != parent:  # the parent died before the line above took effect
                os._exit(1)

    return setup


def spawn(cmd: Sequence[str], **kwargs) -> subprocess.Popen:
    """`subprocess.Popen` in a new session (its own process group) that dies with its parent."""
    setup = _child_setup(_load_prctl(), os.getpid())
    return subprocess.Popen(list(cmd), start_new_session=True, preexec_fn=setup, **kwargs)


class GroupGuard:
    """Kills process group `pgid` when this process dies, by whatever means (see the module
    docstring); `release()` after the group has been ended normally."""

    def __init__(self, pgid: int):
        read_end, self._write_end = os.pipe()  # not inherited by other children (PEP 446)
        try:
            self._proc = subprocess.Popen(
                ["/bin/sh", "-c", 'read _ignored; kill -KILL "-$0" 2>/dev/null', str(pgid)],
                stdin=read_end, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        finally:
            os.close(read_end)

    def release(self) -> None:
        if self._write_end is None:
            return
        os.close(self._write_end)
        self._write_end = None
        try:
            self._proc.wait(timeout=GRACE_S)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()


def spawn_python(code: str, *args: str, env=None, **kwargs) -> subprocess.Popen:
    """`spawn` of a fresh interpreter running `code` (a helper of ours: not multiprocessing's
    spawn, which re-runs the caller's main script), importing this package from where this process
    found it."""
    env = dict(os.environ if env is None else env)
    root = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    return spawn([sys.executable, "-c", code, *args], env=env, **kwargs)


def _signal_group(proc: subprocess.Popen, sig: int) -> bool:
    """Send `sig` to the child's whole group; False when nothing of it is left."""
    try:
        os.killpg(proc.pid, sig)  # the child leads its group: pgid == pid
        return True
    except ProcessLookupError:
        return False
    except PermissionError:  # a group member changed user: at least the child itself
        try:
            proc.send_signal(sig)
            return True
        except ProcessLookupError:
            return False


def stop_group(proc: subprocess.Popen, grace: float = GRACE_S) -> int | None:
    """End the child and everything in its group: SIGINT, then SIGTERM, each given `grace`
    seconds, then SIGKILL. Returns the child's exit status."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        if proc.poll() is not None:
            break
        if not _signal_group(proc, sig):
            break
        try:
            proc.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            continue
    # The leader may be gone while a member it forked lives on: the group is killed regardless.
    _signal_group(proc, signal.SIGKILL)
    try:
        return proc.wait(timeout=max(grace, 1.0))
    except subprocess.TimeoutExpired:  # unkillable (D state): nothing more can be done
        return None


def run_child(cmd: Sequence[str], *, timeout: float, **kwargs) -> subprocess.CompletedProcess:
    """`subprocess.run` for a short-lived child: own group, dies with us, ended as a group on a
    timeout or any exception (a stop signal included)."""
    proc = spawn(cmd, **kwargs)
    try:
        out, err = proc.communicate(timeout=timeout)
    except BaseException:
        stop_group(proc, grace=1.0)
        raise
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


class Supervisor:
    """Signals, children and the shutdown watchdog of one command run, as a context manager::

        with Supervisor("explorer view") as sup:
            proc = sup.spawn([...])
            while not sup.stopping.wait(0.25) and proc.poll() is None:
                ...
        # every child group is ended here, on every path

    Outside the main thread (a test calling `main` from a thread) signal handlers cannot be
    installed: the run then stops only through `request_stop()` or its own end. Once a stop
    signal has armed the watchdog it stays armed after the block: the process is on its way out,
    and the interpreter's own exit is part of what it bounds.
    """

    def __init__(self, name: str, *, shutdown_timeout_s: float | None = None, grace: float = GRACE_S,
                 stderr=None):
        self.name = name
        self.stopping = threading.Event()
        self.signal_received: int | None = None
        self._timeout = shutdown_timeout() if shutdown_timeout_s is None else float(shutdown_timeout_s)
        self._grace = grace
        self._children: list[subprocess.Popen] = []
        self._guards: list[GroupGuard] = []
        self._previous: dict[int, object] = {}
        self._watchdog: threading.Thread | None = None
        self._lock = threading.Lock()
        self._stderr = stderr

    # -- context ------------------------------------------------------------------------------

    def __enter__(self) -> "Supervisor":
        if threading.current_thread() is threading.main_thread():
            for sig in STOP_SIGNALS:
                try:
                    self._previous[sig] = signal.signal(sig, self._on_signal)
                except (ValueError, OSError):
                    pass
        return self

    def __exit__(self, *exc) -> None:
        try:
            self.stop_children()
        finally:
            for sig, handler in self._previous.items():
                with contextlib.suppress(ValueError, OSError, TypeError):
                    signal.signal(sig, handler)
            self._previous.clear()

    # -- children -----------------------------------------------------------------------------

    def spawn(self, cmd: Sequence[str], **kwargs) -> subprocess.Popen:
        proc = spawn(cmd, **kwargs)
        with self._lock:
            self._children.append(proc)
        try:
            guard = GroupGuard(proc.pid) if os.name == "posix" and os.path.exists("/bin/sh") else None
        except OSError:
            guard = None  # no shell to guard with: the parent-death signal still ends the child
        if guard is not None:
            with self._lock:
                self._guards.append(guard)
        return proc

    def stop_children(self) -> None:
        with self._lock:
            children, self._children = list(self._children), []
            guards, self._guards = list(self._guards), []
        for proc in children:
            stop_group(proc, self._grace)
        for guard in guards:
            guard.release()

    # -- stopping -----------------------------------------------------------------------------

    def request_stop(self) -> None:
        """Ask the run to stop (what a stop signal does, without the watchdog)."""
        self.stopping.set()

    def _on_signal(self, signum, frame) -> None:
        if self.stopping.is_set() and self.signal_received is not None:
            # a second signal: the user does not want to wait
            self._force_exit(f"{signal.Signals(signum).name} again: stopping now")
        self.signal_received = signum
        self.stopping.set()
        self._arm_watchdog()

    def _arm_watchdog(self) -> None:
        """Bound the rest of this process's life. Armed only by a real stop signal, so that a run
        inside a test process never ends that process; once armed it stays armed to the end."""
        if self._watchdog is not None:
            return
        self._watchdog = threading.Thread(target=self._watch, name="shutdown-watchdog", daemon=True)
        self._watchdog.start()
        # The thread cannot act once the interpreter is finalizing (daemon threads lose the GIL
        # for good); the kernel's alarm can: SIGALRM's default action ends the process, and the
        # children follow through their parent-death signal.
        with contextlib.suppress(ValueError, OSError):
            signal.signal(signal.SIGALRM, signal.SIG_DFL)
            signal.alarm(int(self._timeout) + 3)

    def _watch(self) -> None:
        time.sleep(self._timeout)
        self._force_exit(f"clean shutdown took longer than {self._timeout:g} s: stopping now")

    def _force_exit(self, why: str) -> None:
        with contextlib.suppress(Exception):
            # no lock: this runs in a signal handler, maybe while the main thread holds it;
            # copying the list is atomic under the GIL
            for proc in list(self._children):
                _signal_group(proc, signal.SIGKILL)
        with contextlib.suppress(Exception):
            stream = self._stderr or sys.stderr
            stream.write(f"warning: {self.name}: {why}\n")
            stream.flush()
        os._exit(1)
