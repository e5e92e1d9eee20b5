"""Where a user waits (issue #27, items 3, 5, 7, 8): two checkouts side by side in one run, each
figure measured in child processes that alternate between the checkouts, so that a change of the
machine's load hits both alike; CPU time throughout (time.process_time in a child, the children's
rusage for whole processes: on a 2-core machine shared with other work a process waits for a core
as long again as it computes, and a wall clock would time the waits).

    git archive <commit> | tar -x -C /tmp/before     # the code before
    (cd /tmp/before && /path/to/.venv/bin/python -m explorer.dynamics.exact_kernel --warm)
    .venv/bin/python benchmarks/bench_wait.py /tmp/before [--rounds 5] [--pool]
    .venv/bin/python benchmarks/bench_wait.py --stages [--rounds 5]   # this checkout's fresh process
    .venv/bin/python benchmarks/bench_wait.py --aot [--rounds 5]      # this checkout: numba's JIT vs AOT
    .venv/bin/python benchmarks/bench_wait.py --single [--rounds 5]   # this checkout: #27.8 alone

Rows (medians over the rounds; the ratio after / before or the ratio the target names):
- #27.5: a 1000-speed sweep of valve_float_demo.toml with all its effects (forces, contact,
  elastic), one core: CPU of run_plan after a warm-up sweep in the same child (median of 3 a child);
- #27.3: the first sweep in a fresh process (10 speeds of the float demo, imports included:
  `import explorer; explorer.sweep(...)`), the child's whole CPU (rusage); and a whole
  `explorer sweep` of 200 speeds against a whole `explorer simulate` of the same scene (each a
  fresh process, `python -m explorer`, its rusage);
- #27.8: `simulate` of one elastic revolution (the float scenes) against scipy DOP853 at rtol
  1e-10 on the same model (explorer.studies.bench.speed_ratio's baseline), and the solver alone
  (solve(method="exact")) against it: the difference is the cost outside the solver; the same with
  only the elastic effect and [solver] method = "exact-compiled" (where the checkout has it), that
  solver alone, and the effects' own times in that simulate (what is left outside the solver);
- #27.3 (--aot, this checkout only): the #27.5 sweep, elastic revolutions/s of one batch in one
  process, and the same three whole processes with numba's kernels (from
  its cache; EXPLORER_AOT=0) and with the kernels compiled ahead of time (explorer/core/aot.py),
  alternating, and the CPU and wall time of building the AOT modules (make's two steps);
- #27.7 (--pool, this checkout only): 20 000 runs of elastic_float.toml on 1 and 2 local workers
  (run_plan's pool), wall time (two workers can only gain wall time) and the load.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

from _timing import ROOT, print_table

ENV = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}


def child_sweep(root: str, speeds: int, repeat: int) -> None:
    sys.path.insert(0, root)
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_run import plan_from, run_plan

    demo = load_scene(Path(root) / "assets" / "scenes" / "valve_float_demo.toml")
    run_plan(demo, plan_from(demo, {"drive.rpm": "1000:6000:10"}), workers=1)  # imports, kernels
    plan = plan_from(demo, {"drive.rpm": f"1000:6000:{speeds}"})
    times = []
    for _ in range(repeat):
        t = time.process_time()
        run_plan(demo, plan, workers=1)
        times.append(time.process_time() - t)
    print(json.dumps(statistics.median(times)))


COMPILED = "exact-compiled"  # the solver table's compiled exact solver (a checkout without it: its rows "-")


def child_single(root: str, repeat: int) -> None:
    """simulate whole, the exact solver alone and DOP853 on the float scenes (CPU, alternating);
    where the checkout's solver table has exact-compiled, simulate with only the elastic effect and
    that solver, the solver alone, and simulate's effects' own times in that run (Result.timings)."""
    sys.path.insert(0, root)
    import math

    import numpy as np

    from explorer.dynamics import solvers
    from explorer.dynamics.solvers import solve
    from explorer.effects.pipeline import simulate
    from explorer.scene.scene import load_scene
    from explorer.studies.bench import model_and_drive

    out = {}
    for name in ("valve_float_demo.toml", "elastic_float.toml"):
        scene = load_scene(Path(root) / "assets" / "scenes" / name)
        elastic = load_scene(Path(root) / "assets" / "scenes" / name, ['effects=["elastic"]'])
        model, drive = model_and_drive(scene)
        n = scene.solver.steps_per_revolution
        t = np.arange(n) * (2.0 * math.pi / drive.omega / n)
        runs = {
            "dop853": lambda: solve(model, drive, t, method="scipy", rtol=1e-10, atol=1e-13, watch_extrema=False),
            "solver": lambda: solve(model, drive, t, method="exact"),
            "simulate_elastic": lambda: simulate(elastic),
            "simulate": lambda: simulate(scene),
        }
        effects: dict[str, list[float]] = {}
        if COMPILED in solvers.names():
            compiled = load_scene(Path(root) / "assets" / "scenes" / name,
                                  ['effects=["elastic"]', f'solver.method="{COMPILED}"'])

            def simulate_compiled():
                result = simulate(compiled)
                for effect, timing in result.timings.items():
                    effects.setdefault(f"effect:{effect}", []).append(timing.compute_time_s)

            runs["simulate_compiled"] = simulate_compiled
            runs["compiled"] = lambda: solve(model, drive, t, method=COMPILED)
        samples = {k: [] for k in runs}
        for fn in runs.values():
            fn()
        effects.clear()
        for _ in range(repeat):
            for k, fn in runs.items():
                c = time.process_time()
                fn()
                samples[k].append(time.process_time() - c)
        out[name] = {k: statistics.median(v) for k, v in {**samples, **effects}.items()}
    print(json.dumps(out))


def child_rate(root: str, runs: int, repeat: int) -> None:
    """Elastic revolutions/s of elastic_float.toml (3600 steps) through exact_kernel.run_batch with
    numba's revolutions and the AOT module's, alternating in this process (CPU)."""
    sys.path.insert(0, root)
    import math

    import numpy as np

    from explorer.core import aot
    from explorer.dynamics import exact_kernel
    from explorer.dynamics.kernel_figures import revolutions
    from explorer.effects.elastic_batch import _residual_reference
    from explorer.effects.lift import build_lift
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared

    scene = load_scene(Path(root) / "assets" / "scenes" / "elastic_float.toml")
    lift = build_lift(scene)
    grid = exact_kernel.revolution_grid(lift, 1.0, 3600)
    ref, dwell, S_dwell = _residual_reference(_Shared(), lift, 1.0, scene.valve.lash, 3600)
    v, sp, link = scene.valve, scene.spring, scene.linkage
    closing = sp.preload + scene.loads.closing_total
    rpm = np.linspace(1500.0, 6000.0, runs)
    params = np.array([[r * 2 * math.pi / 60, v.mass, v.oscillating_mass or v.mass, link.stiffness, link.damping,
                        v.lash, closing, sp.rate, scene.loads.friction, scene.seat.restitution, closing, 0.0]
                       for r in rpm])
    paths = {"jit": revolutions, "aot": aot.load(exact_kernel.AOT_MODULE, exact_kernel.aot_sources()).revolutions}
    times: dict[str, list[float]] = {k: [] for k in paths}
    for _ in range(repeat + 1):
        for label, function in paths.items():
            exact_kernel.batch_function = lambda function=function: function
            c = time.process_time()
            exact_kernel.run_batch(grid, 1.0, params, ref, dwell, S_dwell)
            times[label].append(time.process_time() - c)
    print(json.dumps({k: runs / statistics.median(v[1:]) for k, v in times.items()}))


STAGES = """
import time, json, sys
T = time.process_time; c = [("start", T())]
import numpy; c.append(("import numpy", T()))
import explorer.studies.sweep_run, explorer.scene.scene; c.append(("import the sweep's modules (explorer)", T()))
{numba}import explorer.dynamics.exact_kernel; c.append(("import the kernel's modules", T()))
import explorer
s = explorer.load_scene("assets/scenes/valve_float_demo.toml"); c.append(("load the scene", T()))
explorer.sweep(s, vary={{"drive.rpm": "2000:5000:10"}}, workers=1)
c.append(("{first}", T()))
explorer.sweep(s, vary={{"drive.rpm": "2000:5000:10"}}, workers=1); c.append(("the same sweep again", T()))
total = ["all but the same sweep again (numba loaded: " + str("numba" in sys.modules) + ")", c[-2][1] - c[0][1]]
print(json.dumps([[b, y - x] for (a, x), (b, y) in zip(c, c[1:])] + [total] + [["modules using scipy", sorted({{m.split(".")[1] for m in sys.modules if m.startswith("scipy.") and m.count(".") >= 1}})]]))
"""
MODES = {  # the stage script and EXPLORER_AOT of each path
    "JIT (numba's cache)": (STAGES.format(numba='import numba; c.append(("import numba", T()))\n', first=(
        "first sweep: numba's target set-up (its registries, which import scipy.linalg), cache loads, the runs")), "0"),
    "AOT (explorer/core/aot.py)": (STAGES.format(numba="", first="first sweep: the AOT modules' loads, the runs"), "1"),
}


def stages(rounds: int) -> None:
    """Where a fresh process's first sweep spends its CPU, stage by stage (this checkout), with
    numba's JIT kernels and with the ahead-of-time ones (alternating processes)."""
    runs: dict[str, list] = {mode: [] for mode in MODES}
    for _ in range(rounds):
        for mode, (script, setting) in MODES.items():
            out = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True, check=True,
                                 env={**ENV, "EXPLORER_AOT": setting})
            runs[mode].append(json.loads(out.stdout.strip().splitlines()[-1]))
    print(f"a fresh process's first sweep, CPU by stage (median of {rounds} processes a path, alternating); load "
          f"average {os.getloadavg()[0]:.1f}")
    for mode, done in runs.items():
        names = [row[0] for row in done[0][:-1]]
        print(f"\n{mode}; scipy subpackages loaded: {', '.join(done[0][-1][1]) or 'none'}")
        print_table(["stage", "CPU s"], [[name, f"{statistics.median(r[i][1] for r in done):.3f}"]
                                         for i, name in enumerate(names)])


def aot_rows(rounds: int, speeds: int) -> None:
    """#27.3 in this checkout: whole processes with numba's kernels against the ahead-of-time
    ones (alternating), and the AOT modules' build."""
    tmp = Path(os.environ.get("TMPDIR", "/tmp"))
    load0 = os.getloadavg()[0]
    f: dict[str, list[float]] = {}
    for r in range(rounds):
        for label, setting in (("jit", "0"), ("aot", "1")) if r % 2 == 0 else (("aot", "1"), ("jit", "0")):
            env = {**ENV, "EXPLORER_AOT": setting}
            f.setdefault(f"{label}:sweep", []).append(run_child(ROOT, "sweep", speeds, 3, env=env))
            f.setdefault(f"{label}:first", []).append(process_cpu(ROOT, [sys.executable, "-c", FIRST], env))
            f.setdefault(f"{label}:cli_sweep", []).append(process_cpu(ROOT, [
                sys.executable, "-m", "explorer", "sweep", "assets/scenes/valve_float_demo.toml", "--vary",
                "drive.rpm=1000:6000:200", "--workers", "1", "-o", str(tmp / f"bench_wait_{label}.csv")], env))
            f.setdefault(f"{label}:cli_simulate", []).append(process_cpu(ROOT, [
                sys.executable, "-m", "explorer", "simulate", "assets/scenes/valve_float_demo.toml", "-o",
                str(tmp / f"bench_wait_{label}_sim.csv")], env))
    rate = run_child(ROOT, "rate", 500, 2 * rounds + 1)
    build_cpu, build_wall = 0.0, 0.0
    for module in ("explorer.dynamics.exact_kernel", "explorer.mechanics.sweep_loops"):
        wall = time.perf_counter()
        build_cpu += process_cpu(ROOT, [sys.executable, "-m", module, "--aot"])
        build_wall += time.perf_counter() - wall
    load1 = os.getloadavg()[0]
    m = {k: statistics.median(v) for k, v in f.items()}
    print(f"bench_wait --aot: {ROOT}; medians of {rounds} rounds (alternating child processes), CPU time (rusage); "
          f"load average {load0:.1f} -> {load1:.1f} on {os.cpu_count()} cores")
    print_table(["case", "JIT (numba's cache)", "AOT", "AOT/JIT", "target"], [
        [f"#27.5 {speeds}-speed sweep, valve_float_demo, all effects, 1 core (after a first sweep)",
         f"{m['jit:sweep']:.3f} s", f"{m['aot:sweep']:.3f} s", f"{m['aot:sweep'] / m['jit:sweep']:.2f}x", ""],
        ["#27.3 first sweep in a fresh process (10 speeds, imports included)", f"{m['jit:first']:.2f} s",
         f"{m['aot:first']:.2f} s", f"{m['aot:first'] / m['jit:first']:.2f}x", "<= 0.5 s"],
        ["#27.3 whole `explorer sweep` 200 speeds", f"{m['jit:cli_sweep']:.2f} s", f"{m['aot:cli_sweep']:.2f} s",
         f"{m['aot:cli_sweep'] / m['jit:cli_sweep']:.2f}x", ""],
        ["#27.3 whole `explorer simulate` (float demo)", f"{m['jit:cli_simulate']:.2f} s",
         f"{m['aot:cli_simulate']:.2f} s", f"{m['aot:cli_simulate'] / m['jit:cli_simulate']:.2f}x", ""],
        ["#27.3 sweep 200 / simulate 1 (whole processes)", f"{m['jit:cli_sweep'] / m['jit:cli_simulate']:.2f}x",
         f"{m['aot:cli_sweep'] / m['aot:cli_simulate']:.2f}x", "", "<= 1.2x"],
        ["elastic revolutions/s, elastic_float.toml, 3600 steps, 500 runs a batch (one process)",
         f"{rate['jit']:,.0f}", f"{rate['aot']:,.0f}", f"{rate['aot'] / rate['jit']:.2f}x", ""],
        ["AOT modules' build (make: exact_kernel --aot, sweep_loops --aot)", "",
         f"{build_cpu:.1f} s CPU, {build_wall:.1f} s wall", "", ""],
    ])


def run_child(root: Path, *args, env: dict | None = None) -> object:
    out = subprocess.run([sys.executable, __file__, "--child", str(root), *map(str, args)], capture_output=True,
                         text=True, check=True, env=env or ENV)
    return json.loads(out.stdout.strip().splitlines()[-1])


def process_cpu(root: Path, argv: list[str], env: dict | None = None) -> float:
    """CPU (user + system, rusage) of one whole child process run in the checkout `root`."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(argv, cwd=root, check=True, capture_output=True, env=env or ENV)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


FIRST = ("import explorer; explorer.sweep('assets/scenes/valve_float_demo.toml', vary={'drive.rpm': '2000:5000:10'}, "
         "workers=1)")


def single_rows(scene: str, trees: list[dict]) -> list:
    """The #27.8 rows of one scene: (case, a value per checkout's medians, target); "-" where a
    checkout has no exact-compiled solver."""
    def ratio(m, x, y):
        return f"{m[f'{scene}:{x}'] / m[f'{scene}:{y}']:.1f}x" if f"{scene}:{y}" in m else "-"

    def ms(m, names):
        return " | ".join(f"{1e3 * m[f'{scene}:{x}']:.2f}" if f"{scene}:{x}" in m else "-" for x in names)

    effects = sorted({k.split(":", 1)[1] for m in trees for k in m if k.startswith(f"{scene}:effect:")})
    return [
        [f"#27.8 {scene}: DOP853 rtol 1e-10 / simulate (its effects, solver exact)",
         [ratio(m, "dop853", "simulate") for m in trees], ">= 100x"],
        [f"#27.8 {scene}: DOP853 / simulate (elastic effect only, solver exact)",
         [ratio(m, "dop853", "simulate_elastic") for m in trees], ">= 100x"],
        [f"#27.8 {scene}: DOP853 / simulate (elastic effect only, solver {COMPILED})",
         [ratio(m, "dop853", "simulate_compiled") for m in trees], ">= 100x"],
        [f"#27.8 {scene}: DOP853 / exact solver alone", [ratio(m, "dop853", "solver") for m in trees], ""],
        [f"#27.8 {scene}: DOP853 / {COMPILED} solver alone", [ratio(m, "dop853", "compiled") for m in trees], ""],
        [f"#27.8 {scene}: CPU ms DOP853 | exact | {COMPILED} | simulate elastic (exact) | (with {COMPILED}) | "
         "simulate", [ms(m, ("dop853", "solver", "compiled", "simulate_elastic", "simulate_compiled", "simulate"))
                      for m in trees], ""],
        [f"#27.8 {scene}: simulate elastic with {COMPILED}, effects' wall ms {' | '.join(e.split(':')[1] for e in effects)}",
         [ms(m, effects) for m in trees], ""],
    ]


def single_revolution(rounds: int) -> None:
    """#27.8 alone, in this checkout: child processes of child_single, medians over the rounds."""
    load0 = os.getloadavg()[0]
    figures: dict[str, list[float]] = {}
    for _ in range(rounds):
        for scene, values in run_child(ROOT, "single", 5).items():
            for k, v in values.items():
                figures.setdefault(f"{scene}:{k}", []).append(v)
    med = {k: statistics.median(v) for k, v in figures.items()}
    print(f"bench_wait --single: {ROOT}; medians of {rounds} child processes (each the median of 5 alternating "
          f"runs), CPU time (the effects' own times: wall, in the same runs); load average {load0:.1f} -> "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print_table(["case", "this checkout", "target"],
                [[case, values[0], target] for scene in ("valve_float_demo.toml", "elastic_float.toml")
                 for case, values, target in single_rows(scene, [med])])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("before", type=Path, nargs="?", help="checkout of the code before (git archive)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--speeds", type=int, default=1000)
    parser.add_argument("--pool", action="store_true", help="also time 20 000 runs on 1 and 2 local workers")
    parser.add_argument("--stages", action="store_true", help="only: a fresh process's first sweep by stage")
    parser.add_argument("--aot", action="store_true", help="only: #27.3 with numba's JIT kernels vs the AOT ones")
    parser.add_argument("--sweep-only", action="store_true", help="only the #27.5 row (the 1000-speed sweep)")
    parser.add_argument("--single", action="store_true", help="only: #27.8 (one revolution) in this checkout")
    parser.add_argument("--child", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.stages:
        stages(args.rounds)
        return
    if args.aot:
        aot_rows(args.rounds, args.speeds)
        return
    if args.single:
        single_revolution(args.rounds)
        return
    if args.child:
        root, *rest = args.child
        if rest[0] == "sweep":
            child_sweep(root, int(rest[1]), int(rest[2]))
        elif rest[0] == "rate":
            child_rate(root, int(rest[1]), int(rest[2]))
        else:
            child_single(root, int(rest[1]))
        return

    trees = {"before": args.before.resolve(), "after": ROOT}
    load0 = os.getloadavg()[0]
    figures: dict[str, dict[str, list[float]]] = {k: {} for k in trees}
    tmp = Path(os.environ.get("TMPDIR", "/tmp"))
    for r in range(args.rounds):
        for label in (list(trees) if r % 2 == 0 else list(trees)[::-1]):
            root = trees[label]
            f = figures[label]
            f.setdefault("sweep", []).append(run_child(root, "sweep", args.speeds, 3))
            if args.sweep_only:
                continue
            f.setdefault("first", []).append(process_cpu(root, [sys.executable, "-c", FIRST]))
            f.setdefault("cli_sweep", []).append(process_cpu(root, [
                sys.executable, "-m", "explorer", "sweep", "assets/scenes/valve_float_demo.toml", "--vary",
                "drive.rpm=1000:6000:200", "--workers", "1", "-o", str(tmp / f"bench_wait_{label}.csv")]))
            f.setdefault("cli_simulate", []).append(process_cpu(root, [
                sys.executable, "-m", "explorer", "simulate", "assets/scenes/valve_float_demo.toml", "-o",
                str(tmp / f"bench_wait_{label}_sim.csv")]))
            single = run_child(root, "single", 5)
            for scene, values in single.items():
                for k, v in values.items():
                    f.setdefault(f"{scene}:{k}", []).append(v)
    load1 = os.getloadavg()[0]
    med = {label: {k: statistics.median(v) for k, v in f.items()} for label, f in figures.items()}
    b, a = med["before"], med["after"]
    if args.sweep_only:
        print(f"bench_wait: before {trees['before']}, after {trees['after']}; medians of {args.rounds} rounds "
              f"(alternating child processes, each the median of 3 sweeps), CPU time; load average {load0:.1f} -> "
              f"{load1:.1f} on {os.cpu_count()} cores")
        print_table(["case", "before", "after", "after/before", "target"], [
            [f"#27.5 {args.speeds}-speed sweep, valve_float_demo, all effects, 1 core", f"{b['sweep']:.3f} s",
             f"{a['sweep']:.3f} s", f"{a['sweep'] / b['sweep']:.2f}x", "after/before <= 0.5"]])
        return
    print(f"bench_wait: before {trees['before']}, after {trees['after']}; medians of {args.rounds} rounds "
          f"(alternating child processes), CPU time; load average {load0:.1f} -> {load1:.1f} on {os.cpu_count()} cores")
    rows = [
        [f"#27.5 {args.speeds}-speed sweep, valve_float_demo, all effects, 1 core", f"{b['sweep']:.3f} s",
         f"{a['sweep']:.3f} s", f"{a['sweep'] / b['sweep']:.2f}x", "after/before <= 0.5"],
        ["#27.3 first sweep in a fresh process (10 speeds, imports included)", f"{b['first']:.2f} s",
         f"{a['first']:.2f} s", f"{a['first'] / b['first']:.2f}x", "after <= 0.5 s"],
        ["#27.3 whole `explorer sweep` 200 speeds", f"{b['cli_sweep']:.2f} s", f"{a['cli_sweep']:.2f} s",
         f"{a['cli_sweep'] / b['cli_sweep']:.2f}x", ""],
        ["#27.3 whole `explorer simulate` (float demo)", f"{b['cli_simulate']:.2f} s", f"{a['cli_simulate']:.2f} s",
         f"{a['cli_simulate'] / b['cli_simulate']:.2f}x", ""],
        ["#27.3 sweep 200 / simulate 1 (whole processes)", f"{b['cli_sweep'] / b['cli_simulate']:.2f}x",
         f"{a['cli_sweep'] / a['cli_simulate']:.2f}x", "", "<= 1.2x"],
    ]
    for scene in ("valve_float_demo.toml", "elastic_float.toml"):
        rows += [[case, *values, "", target] for case, values, target in single_rows(scene, [b, a])]
    print_table(["case", "before", "after", "after/before", "target"], rows)

    if args.pool:
        sys.path.insert(0, str(ROOT))
        from explorer.scene.scene import load_scene
        from explorer.studies.sweep_run import plan_from, run_plan

        flt = load_scene(ROOT / "assets" / "scenes" / "elastic_float.toml")
        run_plan(flt, plan_from(flt, {"drive.rpm": "3000:5000:16"}), workers=1)
        plan = plan_from(flt, {"drive.rpm": "3000:5000:20000"})
        walls = {1: [], 2: []}
        for _ in range(3):
            for w in (1, 2):
                t = time.perf_counter()
                run_plan(flt, plan, workers=w)
                walls[w].append(time.perf_counter() - t)
        w1, w2 = statistics.median(walls[1]), statistics.median(walls[2])
        print(f"\n#27.7 20 000 runs of elastic_float.toml, local pool, wall time (median of 3); load average "
              f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
        print_table(["workers", "wall s", "runs/s", "speed-up"],
                    [["1", f"{w1:.2f}", f"{20000 / w1:,.0f}", "1.00x"], ["2", f"{w2:.2f}", f"{20000 / w2:,.0f}",
                                                                        f"{w1 / w2:.2f}x"]])


if __name__ == "__main__":
    main()
