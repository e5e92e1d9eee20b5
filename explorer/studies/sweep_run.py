"""Running a sweep: the plan's runs in chunks, serially, on every local core, or on a Dask
distributed cluster; results gathered in run order, whatever order the chunks finish in.

- Locally (the default) a pool of worker processes, one per core this process may use, started
  by fork (nothing is re-imported; the scene is passed once, at start). The workers ignore
  Ctrl-C (the parent decides), die with the parent (PR_SET_PDEATHSIG), and are ended when the
  sweep ends, however it ends. A sweep of a few chunks runs in this process.
- `scheduler="tcp://HOST:PORT"`: chunks of runs are tasks on that cluster (dask[distributed], the
  `cluster` extra). A worker that dies takes its tasks with it; the scheduler runs them again
  elsewhere, and each chunk's result is kept once, under its first run's index: no run is lost
  or counted twice.
- Ctrl-C (KeyboardInterrupt) or an error in the progress callback ends the sweep early: the runs
  finished so far make a valid table marked incomplete (metadata complete = False).

A chunk is compute_chunk (explorer.studies.sweep_engine) on the scene, pickled once here with its
read-only mappings (MappingProxyType, which plain pickle refuses) written as dicts and restored.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import pickle
import re
import signal
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Callable

import numpy as np

from ..core.errors import InputError
from ..core.outputs import write_output
from ..core.pickling import dumps as dumps_scene
from ..core.processes import _PR_SET_PDEATHSIG, _load_prctl
from ..scene.scene import load_scene
from .sweep_engine import _Shared, compute_chunk, engine_for, result_columns
from .sweep_plots import sweep_png, record
from .sweep_spec import SIGN_CONVENTIONS, SWEEP_KEYS, Plan, check_scene, make_plan, parse_axis, parse_sample
from .sweep_table import SweepTable

# Runs per chunk: enough that a task's overhead (pickling, a round trip; ~1-5 ms locally, more
# on a cluster) is small against its runs, few enough that progress and an interrupt come often
# and the cores stay busy to the end. The engine says how many (RowEngine.max_chunk: 64 runs of
# ~5-50 ms each through the effects, 4096 of ~0.1-0.2 ms each through the compiled solver).



def loads_scene_bytes(data: bytes):
    return pickle.loads(data)


def local_cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not Linux
        return max(1, os.cpu_count() or 1)


def worker_count(requested: int | None) -> tuple[int, str | None]:
    """(local worker processes, a note when the request was capped): every usable core by
    default, never more. A worker beyond the cores adds no speed, only a copy of the process
    (~100 MB each, 1.7 GB for 40 on a 2-core machine) and a share of the others' time."""
    cores = local_cores()
    if requested is None:
        return cores, None
    if requested > cores:
        return cores, f"--workers {requested}: capped at the {cores} usable core{'s' if cores != 1 else ''}"
    return max(1, int(requested)), None


def chunk_size(runs: int, workers: int, max_chunk: int = 64) -> int:
    """About four chunks per worker, at most max_chunk runs each."""
    return max(1, min(max_chunk, math.ceil(runs / (4 * max(1, workers)))))


# ------------------------------------------------------------------ worker side
_WORKER: dict = {}  # the scene and shared caches of this worker process (set by _init_worker)


def _init_worker(parent: int, scene_bytes: bytes, keys, names) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C and ends us
    for sig in (signal.SIGTERM, signal.SIGHUP):  # the parent's handlers (forked with us) are not ours
        signal.signal(sig, signal.SIG_DFL)

    prctl = _load_prctl()
    if prctl is not None:
        prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # the parent died between our fork and the line above
        os._exit(1)
    _WORKER.update(scene=loads_scene_bytes(scene_bytes), keys=tuple(keys), names=tuple(names), shared=_Shared())


def _worker_chunk(start: int, values: np.ndarray):
    w = _WORKER
    return start, compute_chunk(w["scene"], w["keys"], values, w["names"], w["shared"])


def dask_chunk(scene_bytes: bytes, keys, names, start: int, values: np.ndarray):
    """One chunk as a Dask task (a plain function of its arguments: any worker can run it)."""
    return start, compute_chunk(loads_scene_bytes(scene_bytes), tuple(keys), values, tuple(names))


# ------------------------------------------------------------------ the sweep
def metadata(scene, plan: Plan, names, complete: bool, finished: int, seconds: float) -> dict:
    signs = {n: SIGN_CONVENTIONS[n] for n in names if n in SIGN_CONVENTIONS}
    return {
        "scene": scene.name,
        "source": scene.source,
        "keys": list(plan.keys),
        "axes": [{"key": a.key, "points": int(a.values.size), "start": float(a.values[0]),
                  "stop": float(a.values[-1]), "log": a.log} for a in plan.axes],
        "samples": [{"key": s.key, "distribution": s.text} for s in plan.samples],
        "seed": plan.seed,
        "effects": list(scene.effects),
        "steps_per_revolution": scene.solver.steps_per_revolution,
        "complete": complete,
        "runs_planned": plan.runs,
        "runs_finished": finished,
        "compute_time_s": seconds,
        **({"conventions": signs} if signs else {}),
    }


def run_plan(scene, plan: Plan, *, workers: int | None = None, scheduler: str | None = None,
             progress: Callable[[int, int, float], None] | None = None, chunk: int | None = None) -> SweepTable:
    """The table of the plan's runs (see the module docstring). `progress(done, total, seconds)`
    is called as chunks finish. `workers`: local processes, at most the usable cores (more are
    capped: worker_count)."""
    names = result_columns(scene)
    workers = worker_count(workers)[0]
    shared = _Shared()  # this process's chunks share it (a serial sweep); workers make their own
    engine = engine_for(scene, shared)
    size = chunk or chunk_size(plan.runs, workers if scheduler is None else 8, engine.max_chunk)
    starts = list(range(0, plan.runs, size))
    results: dict[int, np.ndarray] = {}
    started = time.perf_counter()
    complete = False

    def done(start: int, block: np.ndarray) -> None:
        if start not in results:  # a chunk run twice (a lost worker's task redone) is kept once
            results[start] = block
        if progress is not None:
            progress(sum(len(b) for b in results.values()), plan.runs, time.perf_counter() - started)

    try:
        if scheduler is not None:
            _run_dask(scene, plan, names, starts, size, scheduler, done)
        elif workers == 1 or len(starts) <= 2 or plan.runs < engine.pool_min_runs:
            for start in starts:  # the engine chosen once for the sweep, not again per chunk
                done(start, compute_chunk(scene, plan.keys, plan.values[start:start + size], names, shared, engine))
        else:
            _run_local(scene, plan, names, starts, size, workers, done)
        complete = True
    except KeyboardInterrupt:
        pass
    seconds = time.perf_counter() - started
    return _table(scene, plan, names, results, size, complete, seconds)


def _table(scene, plan: Plan, names, results: dict, size: int, complete: bool, seconds: float) -> SweepTable:
    order = sorted(results)
    idx = np.concatenate([np.arange(s, s + len(results[s])) for s in order]) if order else np.zeros(0, np.int64)
    figures = np.concatenate([results[s] for s in order]) if order else np.zeros((0, len(names)))
    columns: dict[str, np.ndarray] = {"run": idx.astype(np.int64)}
    for j, key in enumerate(plan.keys):
        columns[SWEEP_KEYS[key].column] = plan.values[idx, j]
    for j, name in enumerate(names):
        columns[name] = figures[:, j]
    return SweepTable.build(columns, metadata(scene, plan, names, complete, len(idx), seconds))


def _run_local(scene, plan: Plan, names, starts, size, workers, done) -> None:
    pool = ProcessPoolExecutor(max_workers=min(workers, len(starts)), mp_context=multiprocessing.get_context("fork"),
                               initializer=_init_worker, initargs=(os.getpid(), dumps_scene(scene), plan.keys, names))
    try:
        pending = {pool.submit(_worker_chunk, s, plan.values[s:s + size]) for s in starts}
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in finished:
                done(*fut.result())
    finally:
        _end_pool(pool)


def _end_pool(pool) -> None:
    """Cancel what has not started, end the workers (a chunk under way is abandoned) and reap
    them: no process outlives the sweep."""
    processes = list(getattr(pool, "_processes", {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        proc.join(timeout=5.0)
        if proc.is_alive():
            proc.kill()
            proc.join()


_ADDRESS = re.compile(r"^(?:(?:tcp|tls|ws|wss)://)?(?:\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):(?P<port>[0-9]{1,5})$")


def check_scheduler(address: str) -> None:
    """A scheduler address is [tcp://]HOST:PORT (tls, ws, wss too; [IPv6] in brackets)."""
    m = _ADDRESS.match(str(address or ""))
    if m is None or not 0 < int(m.group("port")) < 65536:
        raise InputError("--scheduler", str(address)[:80], "expected tcp://HOST:PORT, such as tcp://127.0.0.1:8786")


def _run_dask(scene, plan: Plan, names, starts, size, scheduler: str, done) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise InputError("--scheduler", scheduler, "needs dask[distributed]: pip install 'valve-gear-explorer[cluster]'") \
            from None
    check_scheduler(scheduler)
    data = dumps_scene(scene)
    token = os.urandom(6).hex()
    try:
        client = Client(scheduler, timeout="10s", set_as_default=False)
    except (OSError, ValueError, TypeError) as exc:  # refused, timed out, not an address
        reason = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
        raise InputError("--scheduler", scheduler, f"cannot connect to the Dask scheduler: {reason}") from None
    with client:
        blob = client.scatter(data, broadcast=True)
        futures = [client.submit(dask_chunk, blob, plan.keys, names, s, plan.values[s:s + size],
                                 key=f"explorer-sweep-{token}-{s}", pure=False, retries=3) for s in starts]
        try:
            for fut in as_completed(futures, loop=client.loop):
                done(*fut.result())
        finally:
            client.cancel(futures)


class SweepResult:
    """What `explorer.sweep` returns: the table (.table, .columns of numpy arrays, .to_arrow(),
    .to_pandas() when pandas is installed) and its pictures (.png(), .plot(path), .record(path))."""

    def __init__(self, table: SweepTable):
        self.table = table

    @property
    def columns(self):
        return self.table.columns

    @property
    def metadata(self):
        return self.table.metadata

    @property
    def complete(self) -> bool:
        return self.table.complete

    def __len__(self) -> int:
        return len(self.table)

    def to_arrow(self):
        return self.table.to_arrow()

    def to_pandas(self):
        return self.table.to_pandas()

    def write(self, path) -> None:
        """Parquet or CSV by the extension, atomically."""
        self.table.write(path)

    def png(self) -> bytes:
        return sweep_png(self.table)

    def plot(self, path) -> None:
        write_output(path, self.png(), "--plot")

    def record(self, path) -> None:
        record(self.table, path)

    def __repr__(self) -> str:
        state = "complete" if self.complete else "incomplete"
        return f"<SweepResult {len(self)} runs ({state}), columns: {', '.join(self.columns)}>"


def plan_from(scene, vary=None, sample=None, runs=None, seed=None, yes=False, log=()) -> Plan:
    """The plan of `explorer.sweep`'s arguments: vary {key: "START:STOP:COUNT[:log]" | [values]},
    sample {key: "normal(MEAN, SD)" | "uniform(LOW, HIGH)"}; `log`: keys spaced geometrically."""
    axes = [parse_axis(k, v, log=k in log) for k, v in (vary or {}).items()]
    samples = [parse_sample(k, v) for k, v in (sample or {}).items()]
    plan = make_plan(axes, samples, runs=runs, seed=seed, yes=yes, figures=len(result_columns(scene)))
    check_scene(scene, plan)
    return plan


def sweep(scene, vary=None, sample=None, *, runs=None, seed=None, workers=None, scheduler=None, yes=False,
          log=(), progress=None) -> SweepResult:
    """Sweep a scene (a Scene or a scene file's path) over grids and random samples; see
    explorer.studies.sweep_spec for the forms of `vary` and `sample`. Bad input raises InputError
    before any work."""
    if not hasattr(scene, "effects"):
        scene = load_scene(scene)
    plan = plan_from(scene, vary, sample, runs, seed, yes, log)
    return SweepResult(run_plan(scene, plan, workers=workers, scheduler=scheduler, progress=progress))
