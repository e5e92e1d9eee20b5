"""Benchmark of `explorer sweep` (issue #14): the batch engine against a loop around `simulate`,
measured side by side in one process, plus the first sweep in a fresh process, the memory per
row and the rows per second on a Dask LocalCluster of 1 and 2 workers.

    .venv/bin/python benchmarks/bench_sweep.py [--repeat 5] [--speeds 1000] [--no-cluster]

Rows (medians of --repeat alternating runs; ratios within this run):
- elastic revolutions per second on one core, float scene (elastic_float.toml, 3600 steps, with
  separations): the engine, the loop around simulate, and the ratio to the loop and to the
  hardware limit of about 100 000 (3600 steps x some 30 flops at a few GFLOP/s);
- a sweep of --speeds speeds of valve_float_demo.toml with its effects (forces, contact,
  elastic) on one core: the engine (measured), the loop (per-run median x speeds);
- bytes per row of the table and the peak memory of a sweep against its run count (memory grows
  with runs x columns, not runs x steps);
- the first sweep in a fresh interpreter (imports included);
- rows per second on a LocalCluster of 1 and 2 worker processes (127.0.0.1).
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
import tracemalloc

import numpy as np
from _timing import ROOT, print_table

HARDWARE_LIMIT = 100_000.0  # elastic revolutions per second per core (issue #14)


def _loop(base, keys, values, names):
    from explorer.studies.sweep_engine import reference_row
    from explorer.studies.sweep_spec import scene_for

    for row in values:
        reference_row(scene_for(base, keys, row), names)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--speeds", type=int, default=1000)
    parser.add_argument("--no-cluster", action="store_true")
    args = parser.parse_args()

    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns
    from explorer.studies.sweep_run import plan_from, run_plan

    scenes = ROOT / "assets" / "scenes"
    rows = []

    # 1. elastic revolutions per second on one core, float scene with separations: the engine on
    # 400 speeds (its compiled batches), the loop around simulate on 16 of them
    flt = load_scene(scenes / "elastic_float.toml")
    names = result_columns(flt)
    rpm = np.linspace(3000.0, 5000.0, 400)[:, None]
    rpm_loop = rpm[::25]
    shared = _Shared()
    engine = engine_for(flt, shared).name
    compute_chunk(flt, ("drive.rpm",), rpm[:2], names, shared)  # warm: imports, the lift, the grid
    _loop(flt, ("drive.rpm",), rpm_loop[:2], names)
    eng, loop = [], []
    for _ in range(args.repeat):
        t = time.perf_counter()
        table = compute_chunk(flt, ("drive.rpm",), rpm, names, shared)
        eng.append((time.perf_counter() - t) / len(rpm))
        t = time.perf_counter()
        _loop(flt, ("drive.rpm",), rpm_loop, names)
        loop.append((time.perf_counter() - t) / len(rpm_loop))
    seps = table[:, names.index("separations")]
    e, l = statistics.median(eng), statistics.median(loop)
    rows.append([f"elastic revolutions/s, 1 core (elastic_float, 3600 steps, {int(seps.min())}-{int(seps.max())} "
                 f"separations; engine: {engine})", f"{1 / e:,.0f}", f"{1 / l:,.0f}",
                 f"{l / e:.1f}x", f"{(1 / e) / HARDWARE_LIMIT:.1%} of 100 000"])

    # 2. a 1000-speed sweep of the float demo with its effects, one core
    demo = load_scene(scenes / "valve_float_demo.toml")
    plan = plan_from(demo, {"drive.rpm": f"1000:6000:{args.speeds}"})
    dnames = result_columns(demo)
    sample = plan.values[:: max(1, args.speeds // 20)]
    _loop(demo, plan.keys, sample[:1], dnames)
    t = time.perf_counter()
    _loop(demo, plan.keys, sample, dnames)
    loop_per_run = (time.perf_counter() - t) / len(sample)
    t = time.perf_counter()
    full = run_plan(demo, plan, workers=1)
    engine_total = time.perf_counter() - t
    rows.append([f"{args.speeds}-speed sweep, valve_float_demo (forces, contact, elastic), 1 core",
                 f"{engine_total:.2f} s", f"{loop_per_run * args.speeds:.1f} s (from {len(sample)} runs)",
                 f"{loop_per_run * args.speeds / engine_total:.1f}x", "target 0.5 s"])
    # the same sweep's elastic figures alone (the compiled part), to show where the time goes
    elastic_only = load_scene(scenes / "valve_float_demo.toml", ['effects=["elastic"]'])
    eplan = plan_from(elastic_only, {"drive.rpm": f"1000:6000:{args.speeds}"})
    run_plan(elastic_only, plan_from(elastic_only, {"drive.rpm": "1000:6000:4"}), workers=1)
    t = time.perf_counter()
    run_plan(elastic_only, eplan, workers=1)
    rows.append([f"  the same {args.speeds} speeds, elastic effect only", f"{time.perf_counter() - t:.2f} s", "", "",
                 ""])

    # 3. memory: bytes per row and peak memory against runs (a forces-only sweep: quick runs)
    per_row = sum(np.asarray(c).itemsize for c in full.columns.values())
    forces = load_scene(scenes / "valve_float_demo.toml", ['effects=["forces"]'])
    run_plan(forces, plan_from(forces, sample={"valve.lash": "uniform(0.2 mm, 0.3 mm)"}, runs=50, seed=2), workers=1)
    peaks = []
    for n in (500, 2000):
        p = plan_from(forces, sample={"valve.lash": "uniform(0.2 mm, 0.3 mm)"}, runs=n, seed=1)
        tracemalloc.start()
        run_plan(forces, p, workers=1)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    growth = (peaks[1] - peaks[0]) / 1500
    rows.append([f"table bytes per row (float demo, {len(full.columns)} columns) / peak growth per run (forces sweep)",
                 f"{per_row} B", f"{growth:.0f} B/run", "", f"10^6 runs: ~{growth * 1e6 / 2**20:.0f} MB"])

    # 4. the first sweep in a fresh process, imports included
    code = ("import time; t = time.perf_counter(); import explorer; "
            "r = explorer.sweep('assets/scenes/valve_float_demo.toml', vary={'drive.rpm': '2000:5000:10'}, workers=1); "
            "print(time.perf_counter() - t)")
    fresh = []
    for _ in range(max(1, args.repeat // 2)):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
        fresh.append(float(out.stdout.strip().splitlines()[-1]))
    rows.append(["first sweep in a fresh process (10 speeds, float demo, imports included)",
                 f"{statistics.median(fresh):.2f} s", "", "", "target 2 s"])

    # 5. Dask LocalCluster, 1 and 2 workers
    if not args.no_cluster:
        try:
            import distributed
        except ImportError:
            distributed = None
        if distributed is not None:
            cplan = plan_from(flt, {"drive.rpm": "3000:5000:20000"})  # ~2 s of compiled work on one core
            rates = {}
            for workers in (1, 2):
                with distributed.LocalCluster(n_workers=workers, threads_per_worker=1, host="127.0.0.1",
                                              dashboard_address="127.0.0.1:0", silence_logs=50) as cluster:
                    # every worker loads numba and the compiled solver before the clock starts
                    run_plan(flt, plan_from(flt, {"drive.rpm": "3000:5000:16"}), scheduler=cluster.scheduler_address,
                             chunk=1)
                    t = time.perf_counter()
                    run_plan(flt, cplan, scheduler=cluster.scheduler_address)  # the engine's chunks (625 runs)
                    rates[workers] = cplan.runs / (time.perf_counter() - t)
            rows.append(["Dask LocalCluster rows/s (elastic_float, 20 000 runs, chunks of 625)", f"1 worker: {rates[1]:.1f}",
                         f"2 workers: {rates[2]:.1f}", f"{rates[2] / rates[1]:.2f}x", ""])
            import multiprocessing.resource_tracker as tracker

            getattr(tracker._resource_tracker, "_stop", lambda: None)()

    load = os.getloadavg()[0]
    print(f"bench_sweep: medians of {args.repeat}; load average {load:.1f} on {os.cpu_count()} cores")
    print_table(["case", "engine", "loop around simulate", "ratio", "note"], rows)


if __name__ == "__main__":
    main()
