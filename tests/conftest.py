import contextlib
import ctypes
import ctypes.util
import os
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest
from hypothesis import settings

# The suite is a gate (CI runs it on every stop): property tests draw the same examples each run
# (derandomize), so a result never depends on the draw. HYPOTHESIS_EXPLORE=1 draws fresh
# examples, for hunting new failures locally.
settings.register_profile("gate", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("explore" if os.environ.get("HYPOTHESIS_EXPLORE") else "gate")

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "assets" / "scenes"

# One setting for every wait on another process (its start, its answer, its stop): seconds a
# child may take on a slow, loaded machine. Tests derive their limits from it and never assume
# an idle machine; raise it with EXPLORER_TEST_TIMEOUT on a slower one.
PROCESS_TIMEOUT = float(os.environ.get("EXPLORER_TEST_TIMEOUT", "120"))


def process_timeout(share: float = 1.0) -> float:
    """A limit for waiting on a child process: a share of PROCESS_TIMEOUT."""
    return PROCESS_TIMEOUT * share


@pytest.fixture
def scenes_dir() -> Path:
    return SCENES


def run_cli(*args, cwd=None, timeout=None):
    """Run `python -m explorer ...` in a subprocess; returns CompletedProcess (text). On a timeout
    the child's whole process tree is ended before the error propagates."""
    env = dict(os.environ)
    env.setdefault("PYTHONWARNINGS", "ignore")
    proc = subprocess.Popen([sys.executable, "-m", "explorer", *map(str, args)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=cwd or ROOT, env=env)
    try:
        out, err = proc.communicate(timeout=process_timeout() if timeout is None else timeout)
    except BaseException:
        kill_tree(proc.pid)
        proc.communicate()
        raise
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def kill_tree(pid: int) -> None:
    """SIGKILL a process and all its descendants (their groups too), then reap what is ours."""
    try:
        root = psutil.Process(pid)
        procs = [root, *root.children(recursive=True)]
    except psutil.NoSuchProcess:
        return
    for p in procs:
        try:
            os.killpg(p.pid, 9) if os.getpgid(p.pid) == p.pid else p.kill()
        except (ProcessLookupError, psutil.NoSuchProcess, PermissionError):
            pass
        try:
            p.kill()
        except psutil.NoSuchProcess:
            pass
    psutil.wait_procs(procs, timeout=process_timeout(0.1))


# ------------------------------------------------------------------------------------------------
# No process outlives its test. The test process makes itself a child subreaper, so a process
# whose parent died (an orphaned viewer, a daemon that forked away) is re-parented here instead
# of to init, and every process the tests started is found among our descendants. After each
# test, anything it started that is still running fails it (and is killed); at the end of the
# session, anything left at all fails the run.

_PR_SET_CHILD_SUBREAPER = 36


def _become_subreaper() -> bool:
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(_PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


_SUBREAPER = _become_subreaper()


def _children(pid: int) -> list[int]:
    """Direct children of `pid` (Linux: /proc/PID/task/*/children, cheap enough to run around
    every test; elsewhere psutil)."""
    if not _SUBREAPER:
        try:
            return [c.pid for c in psutil.Process(pid).children()]
        except psutil.NoSuchProcess:
            return []
    out = []
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for tid in tasks:
        try:
            with open(f"/proc/{pid}/task/{tid}/children") as handle:
                out.extend(int(x) for x in handle.read().split())
        except OSError:
            pass
    return out


def _is_zombie(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except (OSError, IndexError):
        try:
            return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return True


def _alive_descendants(skip: frozenset[int] = frozenset()) -> set[int]:
    """Running descendants of the test process, not looking below the processes in `skip` (a
    module fixture's browser may start and end helpers of its own during a test)."""
    found, todo = set(), _children(os.getpid())
    while todo:
        pid = todo.pop()
        if pid in found:
            continue
        if _is_zombie(pid):
            try:
                os.waitpid(pid, os.WNOHANG)  # an orphan handed to us, or a child nobody waited for
            except ChildProcessError:
                pass
            continue
        found.add(pid)
        if pid not in skip:
            todo.extend(_children(pid))
    return found


def _describe(pids) -> str:
    lines = []
    for pid in sorted(pids):
        try:
            lines.append(f"pid {pid}: {' '.join(psutil.Process(pid).cmdline())[:200]}")
        except psutil.NoSuchProcess:
            pass
    return "; ".join(lines)


def _left_behind(before: frozenset[int]) -> set[int]:
    """Processes started since `before` that are still running after a short grace (a child
    killed in the test's last line may take a moment to end and be reaped on a loaded machine)."""
    deadline = time.monotonic() + process_timeout(0.05)
    while True:
        left = _alive_descendants(before) - before
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.05)


@pytest.fixture(autouse=True)
def _no_process_left_behind():
    before = frozenset(_alive_descendants())
    yield
    left = _left_behind(before)
    if left:
        text = _describe(left)
        for pid in left:
            kill_tree(pid)
        pytest.fail(f"the test left processes running: {text}", pytrace=False)


def pytest_sessionfinish(session, exitstatus):
    left = _left_behind(frozenset())
    if left:
        text = _describe(left)
        for pid in left:
            kill_tree(pid)
        sys.stderr.write(f"\nerror: processes started by the tests were still running at the end: {text}\n")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


def still_running(pids, timeout: float) -> list[int]:
    """The pids of `pids` still running (not counting zombies) after waiting up to `timeout` s."""
    procs = []
    for pid in pids:
        try:
            procs.append(psutil.Process(pid))
        except psutil.NoSuchProcess:
            pass
    _, alive = psutil.wait_procs(procs, timeout=timeout)
    return [p.pid for p in alive if not _is_zombie(p.pid)]


@contextlib.contextmanager
def started(cmd, **kwargs):
    """`subprocess.Popen(cmd, **kwargs)` whose whole process tree is killed when the block ends,
    however it ends (a failed assertion, a timeout)."""
    proc = subprocess.Popen(list(map(str, cmd)), **kwargs)
    try:
        yield proc
    finally:
        if proc.poll() is None or _children(proc.pid):
            kill_tree(proc.pid)
        with contextlib.suppress(Exception):
            proc.communicate(timeout=process_timeout(0.1))
