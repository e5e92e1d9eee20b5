"""The sweep's batch engine of two checkouts side by side in one run: elastic revolutions per second
on one core (bench_sweep's first row: elastic_float.toml, 3600 steps, 400 speeds from 3000 to
5000 rpm, the compiled path's compute_chunk after a warm-up call) of the code before a change and
of this checkout, measured in alternating child processes so that a change of the machine's load
hits both alike.

    git archive <commit> | tar -x -C /tmp/before     # the code before (compiled on first use)
    .venv/bin/python benchmarks/bench_engine_trees.py /tmp/before [--rounds 5] [--repeat 5]

Each round runs one child per checkout (the order alternates); a child times --repeat sweeps and
reports the median CPU time per revolution (time.process_time: on a machine shared with other
work a process waits for a core for as long again as it computes, and a wall clock would time the
waits); the table shows each checkout's median over the rounds (and its fastest round) and the
ratio, with the load average before and after.

--analysis (issue #27.4) adds a table for the checkout after, in one child process: the CPU per
revolution at 1800, 3600 and 7200 steps per revolution and its straight line a + b n (least
squares), whose intercept a is the fixed per-run cost (its share of a 3600-step revolution is
printed) and whose slope gives the limit 1 / (3600 b), the revolutions/s with no fixed cost; and a
numba RK4 of the same model (benchmarks/_rk4_valve.py: events located by bisection, on the exact
solver's grid cut into m substeps) at the smallest m = 1, 2, 4, ... whose valve lift is within
RK4_TOLERANCE of the exact solver's at every output sample of RK4_SPEEDS speeds, timed on those
speeds against the engine in the same process.

--stages (no checkout before needed) prints where a revolution's CPU goes in this checkout, at
1800, 3600 and 7200 steps with each stage's fixed cost and per-step cost: the Python of a chunk
around its compiled call, the compiled call, and within it the stepping and the events alone
(kernel_phase.run_nodes called per speed) against the figures.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from _timing import ROOT, print_table


def child(root: str, repeat: int, speeds: int) -> None:
    """Time the engine of the checkout at root (run in a child process)."""
    sys.path.insert(0, root)
    import numpy as np

    import explorer
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns

    assert Path(explorer.__file__).resolve().is_relative_to(Path(root).resolve()), explorer.__file__
    flt = load_scene(Path(root) / "assets" / "scenes" / "elastic_float.toml")
    names = result_columns(flt)
    rpm = np.linspace(3000.0, 5000.0, speeds)[:, None]
    shared = _Shared()
    engine = engine_for(flt, shared).name
    compute_chunk(flt, ("drive.rpm",), rpm[:2], names, shared)  # imports, the lift, the grid
    times = []
    for _ in range(repeat):
        t = time.process_time()
        compute_chunk(flt, ("drive.rpm",), rpm, names, shared)
        times.append((time.process_time() - t) / speeds)
    print(json.dumps({"per_revolution_s": statistics.median(times), "engine": engine}))


RK4_TOLERANCE = 1e-13  # m: the RK4's largest lift difference from the exact solver (1e-11 of the 9.25 mm lift)
RK4_SPEEDS = 8  # speeds (of the sweep's) at which the RK4's accuracy is checked and its time measured
MAX_SUBSTEPS = 64  # the largest m tried


def analysis(root: str, repeat: int, speeds: int) -> None:
    """The fixed per-run cost, the limit and the RK4 ratio of the checkout at root (a child)."""
    sys.path.insert(0, root)
    from dataclasses import replace

    import numpy as np

    from explorer.effects.elastic_batch import elastic_run
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared, compute_chunk, result_columns
    from _rk4_valve import rk4_lift

    flt = load_scene(Path(root) / "assets" / "scenes" / "elastic_float.toml")
    rpm = np.linspace(3000.0, 5000.0, speeds)[:, None]
    per_rev = {}
    for n in (1800, 3600, 7200):
        scene = replace(flt, solver=replace(flt.solver, steps_per_revolution=n))
        names = result_columns(scene)
        shared = _Shared()
        compute_chunk(scene, ("drive.rpm",), rpm[:2], names, shared)
        times = []
        for _ in range(repeat):
            t = time.process_time()
            compute_chunk(scene, ("drive.rpm",), rpm, names, shared)
            times.append((time.process_time() - t) / speeds)
        per_rev[n] = statistics.median(times)
    ns = np.array(sorted(per_rev), dtype=float)
    b, a = np.polyfit(ns, np.array([per_rev[n] for n in sorted(per_rev)]), 1)
    # the RK4 at the smallest m within RK4_TOLERANCE of the exact solver at every checked speed
    picked = rpm[:: max(1, speeds // RK4_SPEEDS), 0][:RK4_SPEEDS]
    runs = []
    for value in picked:
        scene = replace(flt, drive=replace(flt.drive, rpm=float(value)))
        shared = _Shared()
        from explorer.effects.lift import build_lift

        shared.lift = build_lift(scene)
        _, column, _ = elastic_run(scene, shared)
        grid = shared.grids[(scene.follower.ratio, scene.solver.steps_per_revolution)]  # (the unsplit grid)
        sp, v, link = scene.spring, scene.valve, scene.linkage
        W0 = sp.preload + scene.loads.closing_total
        params = np.array([scene.drive.omega, v.mass, v.oscillating_mass if v.oscillating_mass is not None else v.mass,
                           link.stiffness, link.damping, v.lash, W0, sp.rate, scene.loads.friction,
                           scene.seat.restitution])
        runs.append((grid, scene.drive.omega, params, np.roll(column, -grid.i0)))  # run order
    m, error = 1, math.inf
    while m <= MAX_SUBSTEPS:
        error = max(float(np.max(np.abs(rk4_lift(g, w, m, p) - ref))) for g, w, p, ref in runs)
        if error <= RK4_TOLERANCE:
            break
        m *= 2
    rk4_times, engine_times = [], []
    names = result_columns(flt)
    shared = _Shared()
    compute_chunk(flt, ("drive.rpm",), rpm[:2], names, shared)
    for _ in range(repeat):
        t = time.process_time()
        for g, w, p, _ in runs:
            rk4_lift(g, w, m, p)
        rk4_times.append((time.process_time() - t) / len(runs))
        t = time.process_time()
        compute_chunk(flt, ("drive.rpm",), rpm, names, shared)
        engine_times.append((time.process_time() - t) / speeds)
    print(json.dumps({"per_revolution_s": {str(n): t for n, t in per_rev.items()}, "fixed_s": a, "per_step_s": b,
                      "rk4_m": m, "rk4_error_m": error, "rk4_s": statistics.median(rk4_times),
                      "engine_s": statistics.median(engine_times)}))


def stages(root: str, repeat: int, speeds: int) -> None:
    """Where a revolution's CPU goes (the checkout at root, a child), per revolution at 3600 steps:
    the whole chunk (compute_chunk), the compiled batch call in it (exact_kernel.run_batch), the
    compiled run alone (kernel_phase.run_nodes called per speed from Python: the stepping and the
    events, without the figures), each at 1800, 3600 and 7200 steps; the intercept of each against
    the steps is its fixed per-run cost."""
    sys.path.insert(0, root)
    import math
    from dataclasses import replace

    import numpy as np

    from explorer.dynamics import exact_kernel
    from explorer.dynamics.kernel_grid import grid_bounds
    from explorer.dynamics.kernel_phase import run_buffers, run_nodes
    from explorer.dynamics.kernel_steps import phase_rate, taylor_terms
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared, compute_chunk, result_columns

    flt = load_scene(Path(root) / "assets" / "scenes" / "elastic_float.toml")
    rpm = np.linspace(3000.0, 5000.0, speeds)[:, None]
    batch = {"t": 0.0}
    run_batch = exact_kernel.run_batch

    def timed(*args, **kwargs):
        t = time.process_time()
        try:
            return run_batch(*args, **kwargs)
        finally:
            batch["t"] += time.process_time() - t

    exact_kernel.run_batch = timed
    out = {}
    for n in (1800, 3600, 7200):
        scene = replace(flt, solver=replace(flt.solver, steps_per_revolution=n))
        names = result_columns(scene)
        shared = _Shared()
        compute_chunk(scene, ("drive.rpm",), rpm[:2], names, shared)
        grid = shared.grids[(scene.follower.ratio, n)]
        blk, win = grid_bounds(grid.h, grid.Dn, grid.Sb)
        v, sp, link = scene.valve, scene.spring, scene.linkage
        M, M1, k, c, rate = v.mass, v.oscillating_mass, link.stiffness, link.damping, sp.rate
        W0 = sp.preload + scene.loads.closing_total
        omegas = rpm[:, 0] * 2.0 * math.pi / 60.0
        terms = [taylor_terms(phase_rate(M, M1, k, c, rate) * grid.h_max / w) for w in omegas]
        buffers = run_buffers(grid.h.size + 1, max(terms), grid.h_unique.size)

        def nodes_only():
            for w, N in zip(omegas, terms):
                run_nodes(grid.nodes, grid.h, 1.0 / w, grid.PT, grid.Dn, grid.Sb, w, grid.hidx, grid.h_unique, M, M1,
                          k, c, v.lash, W0, rate, scene.loads.friction, scene.seat.restitution, 1e-12, 100_000, N, blk,
                          win, buffers)

        nodes_only()
        chunk, call, alone = [], [], []
        for _ in range(repeat):
            batch["t"] = 0.0
            t = time.process_time()
            compute_chunk(scene, ("drive.rpm",), rpm, names, shared)
            chunk.append((time.process_time() - t) / speeds)
            call.append(batch["t"] / speeds)
            t = time.process_time()
            nodes_only()
            alone.append((time.process_time() - t) / speeds)
        out[n] = [statistics.median(x) for x in (chunk, call, alone)]
    print(json.dumps(out))


def measure(root: Path, repeat: int, speeds: int) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", str(root), "--repeat", str(repeat),
                          "--speeds", str(speeds)], capture_output=True, text=True, check=True, cwd=root)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("before", nargs="?", help="a checkout of the code before the change")
    parser.add_argument("--after", default=str(ROOT), help="the checkout after (default: this one)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--speeds", type=int, default=400)
    parser.add_argument("--analysis", action="store_true", help="the fixed cost, the limit and the RK4 ratio")
    parser.add_argument("--stages", action="store_true", help="where a revolution's CPU goes (the checkout after)")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--stages-child", help=argparse.SUPPRESS)
    parser.add_argument("--analysis-child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child, args.repeat, args.speeds)
        return
    if args.analysis_child:
        analysis(args.analysis_child, args.repeat, args.speeds)
        return
    if args.stages_child:
        stages(args.stages_child, args.repeat, args.speeds)
        return
    if args.stages:
        root = Path(args.after).resolve()
        load0 = os.getloadavg()[0]
        out = subprocess.run([sys.executable, __file__, "--stages-child", str(root), "--repeat", str(args.repeat),
                              "--speeds", str(args.speeds)], capture_output=True, text=True, check=True, cwd=root)
        got = {int(n): v for n, v in json.loads(out.stdout.strip().splitlines()[-1]).items()}
        print(f"bench_engine_trees --stages: {root}, elastic_float.toml, {args.speeds} speeds 3000-5000 rpm; CPU per "
              f"revolution, medians of {args.repeat} sweeps; load average {load0:.1f} -> {os.getloadavg()[0]:.1f}")
        ns = sorted(got)
        rows = []
        parts = [("whole chunk (compute_chunk)", lambda n: got[n][0]),
                 ("  Python around the compiled call", lambda n: got[n][0] - got[n][1]),
                 ("  compiled call (run_batch: revolutions)", lambda n: got[n][1]),
                 ("    stepping and events (run_nodes alone)", lambda n: got[n][2]),
                 ("    figures and the rest (call - run_nodes)", lambda n: got[n][1] - got[n][2])]
        for label, f in parts:  # the fixed cost a and the per-step cost b: least squares a + b n
            vals = [f(n) for n in ns]
            b, a = np.polyfit(np.array(ns, dtype=float), np.array(vals), 1)
            rows.append([label] + [f"{x * 1e6:.1f} us" for x in vals] + [f"{a * 1e6:.1f} us", f"{b * 1e9:.2f} ns"])
        print_table(["stage", *[f"{n} steps" for n in ns], "fixed a", "per step b"], rows)
        return
    trees = {"before": Path(args.before).resolve(), "after": Path(args.after).resolve()}
    for root in trees.values():  # compile (or load) each checkout's kernels before the clock runs
        measure(root, 1, 2)
    load0 = os.getloadavg()[0]
    samples: dict[str, list[float]] = {name: [] for name in trees}
    engines = {}
    for r in range(args.rounds):
        for name in (list(trees) if r % 2 == 0 else list(trees)[::-1]):
            got = measure(trees[name], args.repeat, args.speeds)
            samples[name].append(got["per_revolution_s"])
            engines[name] = got["engine"]
    load1 = os.getloadavg()[0]
    med = {name: statistics.median(v) for name, v in samples.items()}
    print(f"bench_engine_trees: elastic_float.toml, 3600 steps, {args.speeds} speeds 3000-5000 rpm; medians of "
          f"{args.rounds} rounds x {args.repeat} sweeps; load average {load0:.1f} -> {load1:.1f} on "
          f"{os.cpu_count()} cores")
    rows = [[f"{name} ({trees[name]}; engine: {engines[name]})", f"{1 / med[name]:,.0f}",
             f"{1 / min(samples[name]):,.0f}", f"{med[name] * 1e6:.1f} us"] for name in trees]
    rows.append(["after / before", f"{med['before'] / med['after']:.2f}x",
                 f"{min(samples['before']) / min(samples['after']):.2f}x", ""])
    print_table(["checkout", "revolutions/s of CPU (median)", "(fastest round)", "CPU per revolution"], rows)
    if args.analysis:
        load0 = os.getloadavg()[0]
        out = subprocess.run([sys.executable, __file__, "--analysis-child", str(trees["after"]), "--repeat",
                              str(args.repeat), "--speeds", str(args.speeds)], capture_output=True, text=True,
                             check=True, cwd=trees["after"])
        got = json.loads(out.stdout.strip().splitlines()[-1])
        load1 = os.getloadavg()[0]
        t = got["per_revolution_s"]
        t3600 = t["3600"]
        print(f"\nafter, one child: medians of {args.repeat} sweeps of {args.speeds} speeds (CPU time); load average "
              f"{load0:.1f} -> {load1:.1f}")
        arows = [[f"CPU per revolution at {n} steps", f"{t[n] * 1e6:.1f} us", f"{1 / t[n]:,.0f} rev/s"]
                 for n in ("1800", "3600", "7200")]
        arows.append(["fixed per-run cost a (intercept of a + b n)", f"{got['fixed_s'] * 1e6:.1f} us",
                      f"{got['fixed_s'] / t3600:.0%} of a 3600-step revolution"])
        arows.append(["per step b", f"{got['per_step_s'] * 1e9:.2f} ns", ""])
        limit = 1.0 / (3600 * got["per_step_s"])
        arows.append(["limit 1 / (3600 b) (no fixed cost)", f"{limit:,.0f} rev/s",
                      f"engine at {1 / t3600:,.0f} rev/s = {(1 / t3600) / limit:.0%} of it"])
        arows.append([f"numba RK4, m = {got['rk4_m']} substeps a step ({got['rk4_error_m']:.1e} m from the exact "
                      f"lift; {RK4_SPEEDS} speeds)", f"{got['rk4_s'] * 1e6:.1f} us",
                      f"engine (same child) {got['engine_s'] * 1e6:.1f} us: {got['rk4_s'] / got['engine_s']:.1f}x"])
        print_table(["elastic_float.toml", "CPU", "ratio"], arows)


if __name__ == "__main__":
    main()
