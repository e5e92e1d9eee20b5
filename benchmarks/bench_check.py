"""Benchmark of `explorer check` (issue #26): every rule on the float demo over 200 speeds, and over
10^4 tolerance draws of its lash, on one core; each against a baseline measured in the same run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_check.py [--repeat 5] [--draws 10000]

Rows (CPU time of one core: medians of --repeat alternating runs after a warm-up, time.process_time
with numba and numpy single-threaded; the wall time of one run beside it, which on a shared machine
is the CPU time stretched by the load; ratios of CPU times within this run):
- check, 200 speeds, all rules (valve_float_demo.toml, 800..6500 rpm), in this process, against
  the elastic sweep of the same 200 speeds alone (explorer.sweep, the scene's effects): what the
  rules cost beyond the sweep engine's runs; target <= 1 s;
- check with --draws draws of valve.lash = normal(0.25 mm, 0.02 mm) (one core: workers = 1)
  against the sweep of as many draws at one speed with the elastic effect only (what one elastic
  run per draw costs); target <= 10 s;
- `explorer check` in a fresh interpreter (imports and the compiled solver's load included),
  against `explorer sweep` of the same speeds in a fresh interpreter;
- check, a gear scene (rocking_cam.toml over 100..200 rpm, 200 speeds, all rules, one core) against
  the sweep of the same speeds with its elastic effect only (the runs its elastic rules need; the
  gear's lift is built once for the runs: explorer.gears.registry's lift_reads). Before that a
  check ran every elastic run through `simulate` whole, the lift rebuilt each time, and the float
  margin ran the seating velocity's speeds again: ~17 s for one speed at a load of ~12.
The machine's load average is printed before and after (the machine is shared: ratios hold
better than seconds).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

from _timing import ROOT, median_times, print_table

SCENE = str(ROOT / "assets" / "scenes" / "valve_float_demo.toml")
RPM = "800:6500:200"
GEAR = str(ROOT / "assets" / "scenes" / "rocking_cam.toml")
GEAR_RPM = "100:200:200"
LASH = "normal(0.25 mm, 0.02 mm)"


def _fresh(args: list[str]) -> tuple[float, float]:
    """(wall seconds, CPU seconds) of `python -m explorer ARGS` in a fresh interpreter."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "explorer", *args], cwd=ROOT, check=False, capture_output=True,
                          env={**os.environ, "OPENBLAS_NUM_THREADS": "1"}, text=True)
    wall = time.perf_counter() - started
    if done.returncode not in (0, 1):  # check exits 1 on a failed rule; anything else is a broken measurement
        raise SystemExit(f"explorer {' '.join(args)} exited {done.returncode}: {done.stderr.strip()[-300:]}")
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--draws", type=int, default=10_000)
    args = p.parse_args(argv)
    import explorer
    from explorer import load_scene

    load = os.getloadavg()
    print(f"load average before: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} ({os.cpu_count()} cores)")
    scene = load_scene(SCENE)
    elastic = scene.with_changes(effects=("elastic",))
    gear = load_scene(GEAR)

    cases = {
        "range": {
            "check": lambda: explorer.check(scene, rpm=RPM, workers=1),
            "sweep": lambda: explorer.sweep(scene, vary={"drive.rpm": RPM}, workers=1),
        },
        "draws": {
            "check": lambda: explorer.check(scene, rpm=RPM, sample={"valve.lash": LASH}, runs=args.draws, seed=1,
                                            workers=1),
            "sweep": lambda: explorer.sweep(elastic, vary={"drive.rpm": "6500"}, sample={"valve.lash": LASH},
                                            runs=args.draws, seed=1, workers=1),
        },
        "gear": {
            "check": lambda: explorer.check(gear, rpm=GEAR_RPM, workers=1),
            "sweep": lambda: explorer.sweep(gear.with_changes(effects=("elastic",)), vary={"drive.rpm": GEAR_RPM},
                                            workers=1),
        },
    }
    cpu, wall = {}, {}
    for name, functions in cases.items():
        repeat = args.repeat if name == "range" else max(1, min(args.repeat, 3))  # the long ones fewer times
        # CPU time of this process (one core: numba and numpy single-threaded) and the wall time
        cpu[name] = median_times(functions, repeat, warmup=1, clock=time.process_time)
        wall[name] = median_times(functions, 1, warmup=0)
    fresh_check = sorted(_fresh(["check", SCENE, "--rpm", RPM, "--workers", "1"]) for _ in range(3))[1]
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        table = os.path.join(tmp, "sweep.csv")
        fresh_sweep = sorted(_fresh(["sweep", SCENE, "--vary", f"drive.rpm={RPM}", "-o", table, "--workers", "1"])
                             for _ in range(3))[1]
    report = explorer.check(scene, rpm=RPM, sample={"valve.lash": LASH}, runs=args.draws, seed=1, workers=1)
    runs = report.runs

    def row(label, key, target):
        c, w = cpu[key], wall[key]
        return [label, f"{c['check']:.3f} s", f"{w['check']:.3f} s", f"{c['sweep']:.3f} s",
                f"{c['check'] / c['sweep']:.2f}x", f"<= {target:g} s", "met" if c["check"] <= target else "MISSED"]

    rows = [
        row("check, 200 speeds, all rules (in process)", "range", 1.0),
        row(f"check, {args.draws} lash draws", "draws", 10.0),
        ["check, rocking cam, 200 speeds, all rules", f"{cpu['gear']['check']:.3f} s", f"{wall['gear']['check']:.3f} s",
         f"{cpu['gear']['sweep']:.3f} s", f"{cpu['gear']['check'] / cpu['gear']['sweep']:.2f}x", "-", ""],
        ["fresh interpreter: check, 200 speeds", f"{fresh_check[1]:.2f} s", f"{fresh_check[0]:.2f} s",
         f"{fresh_sweep[1]:.2f} s", f"{fresh_check[1] / fresh_sweep[1]:.2f}x", "-", ""],
    ]
    print()
    print_table(["case", "CPU (one core)", "wall", "baseline CPU", "ratio", "target", ""], rows)
    print(f"\nbaselines: explorer.sweep of the same 200 speeds (scene's effects); of {args.draws} lash draws at 6500 rpm "
          f"with the elastic effect only (one elastic run per draw); `explorer sweep` in a fresh interpreter")
    print(f"baseline of the gear row: the elastic sweep of the same 200 speeds of {os.path.basename(GEAR)} "
          f"({GEAR_RPM} rpm)")
    print(f"the tolerance study judged {runs} draws:")
    for r in report.results:
        if r.samples and r.sample_method.startswith("two-phase"):
            print(f"  {r.name}: P(fail) {r.p_fail:.4g} [{r.p_fail_interval[0]:.4g}, {r.p_fail_interval[1]:.4g}]; "
                  f"{r.sample_method}")
    load = os.getloadavg()
    print(f"load average after: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
