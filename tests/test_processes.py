"""Child processes end with their whole group on every path, and the test suite itself fails a
test that leaves one running (explorer/core/processes.py, tests/conftest.py)."""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import psutil
import pytest

from conftest import ROOT, process_timeout, started, still_running
from explorer.core.processes import Supervisor, run_child, spawn, stop_group


# A child that ignores SIGINT and SIGTERM and has a helper of its own in its group; it prints
# both pids.
STUBBORN = ("trap '' INT TERM; sleep 1000 & echo $$ $!; while :; do sleep 0.2; done")


def _stubborn_pids(proc) -> tuple[int, int]:
    return tuple(map(int, proc.stdout.readline().split()))


def test_stop_group_ends_a_child_that_ignores_signals_and_its_helpers():
    proc = spawn(["/bin/sh", "-c", STUBBORN], stdout=subprocess.PIPE, text=True)
    try:
        child, helper = _stubborn_pids(proc)
        assert psutil.Process(child).ppid() == proc.pid or child == proc.pid
        started_at = time.monotonic()
        stop_group(proc, grace=0.5)
        assert proc.returncode == -signal.SIGKILL  # it took the last step of the escalation
        assert time.monotonic() - started_at < process_timeout(0.25)
        assert still_running([child, helper], process_timeout(0.1)) == []
    finally:
        proc.stdout.close()


def test_a_spawned_child_dies_with_the_thread_that_started_it():
    """PR_SET_PDEATHSIG: a parent killed with SIGKILL cannot clean up, the kernel ends its child."""
    code = textwrap.dedent("""
        import sys, time
        from explorer.core.processes import spawn
        child = spawn(["sleep", "1000"])
        print(child.pid, flush=True)
        time.sleep(1000)
    """)
    with started([sys.executable, "-c", code], cwd=ROOT, stdout=subprocess.PIPE, text=True) as parent:
        child = int(parent.stdout.readline())
        parent.kill()
        parent.wait(timeout=process_timeout(0.25))
        assert still_running([child], process_timeout(0.25)) == []


def test_run_child_ends_the_group_on_a_timeout():
    with pytest.raises(subprocess.TimeoutExpired):
        run_child(["/bin/sh", "-c", "sleep 1000 & echo $! > /dev/null; wait"], timeout=0.5)
    # nothing of it is left: the per-test check of conftest.py fails the test otherwise


HANGING_SHUTDOWN = textwrap.dedent("""
    import sys, time
    from explorer.core.processes import Supervisor
    with Supervisor("hang test", shutdown_timeout_s=float(sys.argv[1])) as sup:
        child = sup.spawn(["/bin/sh", "-c", "trap '' INT TERM; sleep 1000"])
        print(child.pid, flush=True)
        while not sup.stopping.wait(0.1):
            pass
        time.sleep(1000)  # a clean-up that never ends
""")


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_the_watchdog_ends_a_shutdown_that_hangs(stop):
    with started([sys.executable, "-c", HANGING_SHUTDOWN, "1.0"], cwd=ROOT, stdout=subprocess.PIPE,
                 stderr=subprocess.PIPE, text=True) as proc:
        child = int(proc.stdout.readline())
        proc.send_signal(stop)
        _, err = proc.communicate(timeout=process_timeout(0.5))
        assert proc.returncode == 1
        assert "warning: hang test: clean shutdown took longer than 1 s: stopping now" in err
        assert still_running([child], process_timeout(0.1)) == []


def test_a_second_signal_ends_the_process_at_once():
    with started([sys.executable, "-c", HANGING_SHUTDOWN, "1000"], cwd=ROOT, stdout=subprocess.PIPE,
                 stderr=subprocess.PIPE, text=True) as proc:
        child = int(proc.stdout.readline())
        proc.send_signal(signal.SIGINT)
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=process_timeout(0.5))
        assert proc.returncode == 1 and "SIGINT again: stopping now" in err
        assert still_running([child], process_timeout(0.1)) == []


def test_supervisor_in_a_test_thread_installs_no_handlers_and_never_exits_the_process():
    import threading

    previous = signal.getsignal(signal.SIGTERM)
    seen = []

    def body():
        with Supervisor("thread") as sup:
            seen.append(signal.getsignal(signal.SIGTERM))
            sup.request_stop()
            assert sup.stopping.is_set()

    thread = threading.Thread(target=body)
    thread.start()
    thread.join(process_timeout(0.1))
    assert seen == [previous]


# ------------------------------------------------------------------------------------------------
# The suite's own guard: a planted test that leaves processes behind (one in a session of its own,
# one orphaned by its parent) fails, and both processes are ended.

PLANTED = textwrap.dedent("""
    import subprocess
    from pathlib import Path

    def test_leaves_processes_behind(tmp_path):
        daemon = subprocess.Popen(["sleep", "1000"], start_new_session=True)
        # the shell exits at once: its sleep is orphaned and re-parented to the test process
        subprocess.run(["/bin/sh", "-c", "sleep 1001 & echo $! > " + str(Path({pids!r}) / "orphan")])
        (Path({pids!r}) / "daemon").write_text(str(daemon.pid))

    def test_cleans_up():
        proc = subprocess.Popen(["sleep", "1000"])
        proc.kill()
        proc.wait()
""")


def test_the_suite_fails_a_test_that_leaves_a_process_running(tmp_path):
    suite = tmp_path / "suite"
    suite.mkdir()
    shutil.copy(ROOT / "tests" / "conftest.py", suite / "conftest.py")
    (suite / "test_planted.py").write_text(PLANTED.format(pids=str(tmp_path)))
    with started([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(suite)], cwd=tmp_path,
                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True) as proc:
        out, _ = proc.communicate(timeout=process_timeout())
    assert proc.returncode == 1, out
    assert "2 passed, 1 error" in out, out
    assert "the test left processes running" in out and "sleep 1000" in out and "sleep 1001" in out, out
    pids = [int((tmp_path / name).read_text()) for name in ("daemon", "orphan")]
    assert still_running(pids, process_timeout(0.1)) == []
