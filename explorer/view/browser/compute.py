"""The browser's compute thread: newest request wins, each computed in a killable child process
(explorer.view.browser.worker) that runs `model.prepare`; time and memory limits."""

from __future__ import annotations

import dataclasses
import sys
import threading
import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable

from .model import AdviceTask, COMPUTE_TIME_LIMIT_S, MEMORY_LIMIT_BYTES, Prepared, Request, SUPERSEDE_AFTER_S
from .speedsweep import NoSweep, SpeedSweep, SweepTask, with_elastic
from .worker import ComputeProcess, Superseded, TimeLimitExceeded, WorkerDied


# How long a parameter change may wait for a speed-sweep step in progress before that step is
# stopped (its child killed; a fresh one starts in about half a second). Most steps are shorter:
# one elastic run of the default scene takes ~0.17 s on the loaded 2-core machine.
SWEEP_YIELD_S = 0.3
# The sweep starts only once no change has come for this long: while someone drags a slider or
# types, every change goes straight to the child, and no sweep step stands in its way.
SWEEP_QUIET_S = 0.5


def time_limit_message(seconds: float, previous: bool) -> str:
    shown = "the previous result is shown" if previous else "nothing to show yet"
    return f"computation took longer than {seconds:g} s and was stopped; {shown}"


def memory_limit_message(limit_bytes: int, previous: bool) -> str:
    shown = "the previous result is shown" if previous else "nothing to show yet"
    return f"computation needed more than {limit_bytes / 2**30:g} GB of memory and was stopped; {shown}"


@dataclass
class ComputeWorker:
    """One background thread; `submit` replaces any request not yet started (newest wins, no
    queue). Results go to `on_ready(prepared)`, bad input to `on_error(request, message)`.

    The thread hands each request to a child process and waits at most `time_limit` seconds for
    it (None: no limit); past that the child is killed, `on_error` gets the time-limit message,
    and the next request starts a fresh child. A computation past SUPERSEDE_AFTER_S is killed
    as soon as a newer request waits."""

    on_ready: Callable[[Prepared], None]
    on_error: Callable[[Request, str], None]
    on_result: Callable[[Prepared], None] | None = None  # e.g. the rerun live stream
    # the speed sweep of each new result (explorer.view.browser.speedsweep), computed in the same
    # child between requests, one step at a time; None: no sweep
    on_sweep: Callable[[int, Any], None] | None = None  # (serial, SpeedSweep or NoSweep)
    # the read-out with the spring advice of a result whose advice was left out of the path to
    # its plots (Prepared.advice_pending), computed in the child once nothing newer waits
    on_advice: Callable[[int, str], None] | None = None  # (serial, read-out markdown)
    # whether the compiled solver may be called (explorer.view.browser.kernels); None: always
    compiled: Callable[[], bool] | None = None
    # the design checks of each new result (explorer.view.verdicts.CheckRunner, run in the child
    # after the advice and the speed sweep, once the compiled solver is ready) and where their
    # summary goes: (serial, CheckSummary or the reason there is none); None: no checks
    checks: Any = None
    on_checks: Callable[[int, Any], None] | None = None
    # the checked result and its CheckSummary, when the checks judged one (not why there are
    # none): e.g. the rerun live stream, which adds them to that result's recording
    on_checked: Callable[[Prepared, Any], None] | None = None
    time_limit: float | None = COMPUTE_TIME_LIMIT_S
    memory_limit: int = MEMORY_LIMIT_BYTES
    _pending: Request | None = None
    _busy: bool = False
    _stop: bool = False
    _last: Prepared | None = None
    _cond: threading.Condition = field(default_factory=threading.Condition)
    _thread: threading.Thread | None = None
    _process: Any = None  # worker.ComputeProcess
    computed: int = 0  # how many requests were actually computed (for tests and benchmarks)
    submitted: int = 0
    internal_errors: int = 0  # exceptions other than InputError (should stay 0)
    abandoned: int = 0  # computations stopped at the time or memory limit
    superseded: int = 0  # slow computations stopped for a newer request
    sweep_steps: int = 0  # speed-sweep steps computed (for tests)
    _pending_at: float = 0.0  # when the waiting request came
    _sweep: Any = None  # the SpeedSweep being filled in, or a SweepTask still to start
    _advice: int | None = None  # serial of the result whose spring advice is still to compute
    _checks: int | None = None  # serial of the result whose design checks are still to run
    _background: bool = False  # an advice or sweep step is being computed
    _span: tuple[str, tuple[float, float]] | None = None  # (scene path, speed range) last swept

    def start(self) -> "ComputeWorker":
        self._process = ComputeProcess(memory_bytes=self.memory_limit)
        self._thread = threading.Thread(target=self._run, name="explorer-compute", daemon=True)
        self._thread.start()
        return self

    @property
    def process_id(self) -> int | None:
        """The computing child's pid (None while there is none): tests check it is gone."""
        return None if self._process is None else self._process.pid

    def submit(self, request: Request) -> None:
        with self._cond:
            self._pending = request
            self._pending_at = time.monotonic()
            self.submitted += 1
            self._cond.notify_all()

    def waiting(self) -> bool:
        """Whether a request waits that the thread has not taken yet."""
        with self._cond:
            return self._pending is not None

    def idle(self) -> bool:
        with self._cond:
            return self._pending is None and not self._busy

    def wait_idle(self, timeout: float = 30.0) -> bool:
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._pending is not None or self._busy:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(left)
        return True

    def stop(self) -> None:
        with self._cond:
            self._stop = True
            self._cond.notify_all()
        if self._process is not None:
            self._process.shutdown()  # a computation in progress ends now, not at its limit
        if self._thread is not None:
            self._thread.join(timeout=10.0)
        if self._process is not None:
            self._process.reap()

    def _run(self) -> None:
        # the child is started, called and reaped from this thread only: its death signal
        # (PR_SET_PDEATHSIG) fires when the thread that started it ends
        try:
            while True:
                with self._cond:
                    while self._pending is None and not self._stop:
                        if self._sweep is None and self._advice is None and not self._checks_due():
                            self._cond.wait()
                            continue
                        quiet = time.monotonic() - self._pending_at
                        if quiet >= SWEEP_QUIET_S:
                            break
                        self._cond.wait(SWEEP_QUIET_S - quiet)
                    if self._stop:
                        return
                    if self._pending is None:
                        # nothing newer to compute: the spring advice, then one step of the speed
                        # sweep (not counted as busy: the result shown is complete; these fill in
                        # behind it)
                        advice, self._advice = self._advice, None
                        # the checks last: one that runs past the time limit loses the child and
                        # with it the result the advice and the sweep are computed on
                        checks = None
                        if advice is None and self._sweep is None and self._checks_due():
                            checks, self._checks = self._checks, None
                        sweep = self._sweep
                        request = None
                        self._background = True
                    else:
                        request, self._pending = self._pending, None
                        self._busy = True
                if request is None:
                    try:
                        if advice is not None:
                            self._advice_step(advice)
                        elif checks is not None:
                            self._checks_step(checks)
                        elif sweep is not None:
                            self._sweep_step(sweep)
                    finally:
                        with self._cond:
                            self._background = False
                            self._cond.notify_all()
                    continue
                try:
                    self._compute(request)
                finally:
                    with self._cond:
                        self._busy = False
                        self._cond.notify_all()
        finally:
            self._process.reap()

    def _compute(self, request: Request) -> None:
        started = time.monotonic()

        def superseded() -> bool:
            # read without the lock: a stale answer only delays the check by one poll
            return self._stop or (self._pending is not None and time.monotonic() - started > SUPERSEDE_AFTER_S)

        try:
            kind, payload = self._process.call(request, self.time_limit, superseded)
        except Superseded:
            if not self._stop:
                self.superseded += 1  # the newer request is next; no message for this one
            return
        except TimeLimitExceeded:
            self.abandoned += 1
            self.on_error(request, time_limit_message(self.time_limit, self._last is not None))
            return
        except WorkerDied as exc:
            if not self._stop:
                self.internal_errors += 1
                self.on_error(request, f"internal error: {exc}")
            return
        except Exception as exc:  # a bug must not end this thread: show it, start a fresh child
            self.internal_errors += 1
            traceback.print_exc()
            self._process.kill()
            self._process.reap()  # the child's previous result is no longer the one held here
            self.on_error(request, f"internal error: {type(exc).__name__}: {exc}")
            return
        if kind == "input":
            self.on_error(request, payload)
        elif kind == "memory":
            self.abandoned += 1
            self.on_error(request, memory_limit_message(self.memory_limit, self._last is not None))
        elif kind == "internal":
            self.internal_errors += 1
            self.on_error(request, payload)
        else:
            prepared = self._relink(*payload)
            # a result not shown before (a magnification change is the same result; so is a
            # fresh child's recomputation of it, linked by _relink)
            fresh = self._last is None or prepared.result is not self._last.result
            self._last = prepared
            self.computed += 1
            self.on_ready(prepared)
            if self.on_advice is not None and prepared.new_result:
                with self._cond:
                    self._advice = prepared.request.serial if prepared.advice_pending else None
            if self.checks is not None and self.on_checks is not None and prepared.new_result:
                with self._cond:
                    self._checks = prepared.request.serial
            if self.on_sweep is not None and prepared.new_result:
                path = prepared.request.path
                span = self._span[1] if self._span is not None and self._span[0] == path else None
                with self._cond:
                    self._sweep = SweepTask(prepared.request.serial, None, span)
            if self.on_result is not None and fresh:
                try:
                    self.on_result(prepared)
                except Exception:
                    traceback.print_exc()

    def sweep_idle(self) -> bool:
        """Whether nothing is waiting and the advice and speed sweep of the newest result are complete."""
        with self._cond:
            return (self._pending is None and not self._busy and self._sweep is None and self._advice is None
                    and self._checks is None and not self._background)

    def _checks_due(self) -> bool:
        """Whether design checks wait and may run: the elastic rules call the compiled solver,
        which a child must not compile itself (minutes) while the server warms it up."""
        return self._checks is not None and (self.compiled is None or self.compiled())

    def checks_idle(self) -> bool:
        """Whether no design checks wait or run (for tests)."""
        with self._cond:
            return self._checks is None and not self._background

    def _yield_to_request(self) -> bool:
        """Whether a background step must give way: the worker stops, or a request has waited
        SWEEP_YIELD_S for it (an elastic run at a sweep's top speed, or the checks, can take a
        second; past that the step is dropped and the child restarted)."""
        # read without the lock: a stale answer only delays the check by one poll
        return self._stop or (self._pending is not None and time.monotonic() - self._pending_at > SWEEP_YIELD_S)

    def _background_call(self, task) -> tuple[str, Any]:
        """(kind, payload) of a background `task` in the child; ("time-limit", None) past the time
        limit, ("stopped", None) when a request took precedence or the child died or failed (a
        failed child is restarted on the next call)."""
        try:
            return self._process.call(task, self.time_limit, self._yield_to_request)
        except TimeLimitExceeded:
            return "time-limit", None
        except (Superseded, WorkerDied):
            return "stopped", None
        except Exception:
            traceback.print_exc()
            self._process.kill()
            self._process.reap()
            return "stopped", None

    def _checks_step(self, serial: int) -> None:
        """The design checks of request `serial`'s result, from the child (explorer.view.
        browser.checks_panel); a newer request stops them (the newer result asks again); past the
        time limit the panel says so."""
        from .checks_panel import ChecksTask

        kind, payload = self._background_call(ChecksTask(serial, self.checks))
        if kind == "time-limit":
            kind, payload = "checks", (f"the design checks took longer than {self.time_limit:g} s and were stopped; "
                                       "`explorer check SCENE` has no time limit")
        if kind == "internal":
            self.internal_errors += 1  # the panel shows the child's message
        if kind in ("checks", "internal"):
            try:
                self.on_checks(serial, payload)
            except Exception:
                traceback.print_exc()
        # the child judged the result it holds, which is _last's (a newer result makes the task stale)
        if kind == "checks" and not isinstance(payload, str) and self.on_checked is not None and self._last is not None:
            try:
                self.on_checked(self._last, payload)
            except Exception:
                traceback.print_exc()

    def resweep(self) -> None:
        """Sweep the newest result again (the compiled solver became ready: all speeds at once)."""
        with self._cond:
            if self._last is not None and self.on_sweep is not None:
                span = self._span[1] if self._span is not None and self._span[0] == self._last.request.path else None
                self._sweep = SweepTask(self._last.request.serial, None, span)
                self._cond.notify_all()

    def _advice_step(self, serial: int) -> None:
        """The read-out with the spring advice, from the child; dropped when a newer request
        stops it (the newer result asks again)."""
        kind, payload = self._background_call(AdviceTask(serial))
        if kind == "advice":
            try:
                self.on_advice(serial, payload)
            except Exception:
                traceback.print_exc()
        elif kind == "internal":
            self.internal_errors += 1
            print(payload, file=sys.stderr)  # the child's message (no exception is being handled here)

    def _sweep_step(self, sweep) -> None:
        """Start the sweep (rigid figures at every speed) or compute its next elastic speed,
        in the child; hand the sweep so far to `on_sweep`. A request waiting for more than
        SWEEP_YIELD_S stops a slow step (the child is restarted); the sweep then ends (the new
        result starts its own)."""
        if isinstance(sweep, SweepTask):
            task = dataclasses.replace(sweep, compiled=self.compiled is None or self.compiled())
        elif sweep.batched:
            task = SweepTask(sweep.serial, rpms=tuple(sweep.elastic_rpm.tolist()))
        else:
            task = SweepTask(sweep.serial, sweep.next_elastic())

        kind, payload = self._background_call(task)  # "time-limit", "stopped": the sweep ends below
        self.sweep_steps += 1
        if kind == "sweep" and isinstance(payload, NoSweep):
            done = payload
        elif kind == "sweep" and isinstance(payload, SpeedSweep):
            self._span = (self._last.request.path if self._last is not None else "", payload.span)
            done = payload
        elif kind == "sweep" and isinstance(sweep, SpeedSweep):
            done = with_elastic(sweep, payload)
        else:
            done = None  # stale, failed or stopped: this sweep ends here
        unfinished = isinstance(done, SpeedSweep) and done.next_elastic() is not None
        with self._cond:
            if self._sweep is sweep:  # no newer result meanwhile
                self._sweep = done if unfinished else None
            current = self._sweep is None or self._sweep is done
            self._cond.notify_all()
        if done is not None and current:
            try:
                self.on_sweep(task.serial, done)
            except Exception:
                traceback.print_exc()

    def _relink(self, prepared: Prepared, reused: int | None) -> Prepared:
        """A bundle that reused the previous simulation (only the magnification changed) shares
        the previous bundle's objects again, as it did in the child: the viewer tells what to
        redraw by identity, and a pickled copy would redraw the plots and every mesh. `reused`
        is the serial of the bundle the child reused; only that one may be linked to.

        A child restarted meanwhile (a sweep step stopped for this request, SWEEP_YIELD_S) has
        nothing to reuse and simulates again; its bundle for the same scene and overrides is
        linked too, by the child's own criterion (model.prepare), but stays `new_result`: the
        sweep and the advice, whose child state was lost, start again."""
        last = self._last
        if last is None:
            return prepared
        same = (last.request.path, last.request.overrides) == (prepared.request.path, prepared.request.overrides)
        if last.request.serial != reused and not (reused is None and same):
            return prepared
        return dataclasses.replace(
            prepared, scene=last.scene, result=last.result, layout=last.layout, lift=last.lift,
            meshes=last.meshes, plots=last.plots, readout=last.readout, values=last.values,
            plot_note=last.plot_note, events=last.events, events_html=last.events_html,
        )
