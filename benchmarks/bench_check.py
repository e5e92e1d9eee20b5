"""Benchmark of `explorer check` (issue #26): every rule on the float demo over 200 speeds, and over
10^4 tolerance draws of its lash, on one core; each against a baseline measured in the same run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_check.py [--repeat 5] [--draws 10000]

Rows (medians of --repeat alternating runs, after a warm-up; ratios within this run):
- check, 200 speeds, all rules (valve_float_demo.toml, 800..6500 rpm), in this process, against
  the elastic sweep of the same 200 speeds alone (explorer.sweep, the scene's effects): what the
  rules cost beyond the sweep engine's runs; target <= 1 s;
- check with --draws draws of valve.lash = normal(0.25 mm, 0.02 mm) (one core: workers = 1)
  against the sweep of as many draws at one speed with the elastic effect only (what one elastic
  run per draw costs); target <= 10 s;
- `explorer check` in a fresh interpreter (imports and the compiled solver's load included),
  against `explorer sweep` of the same speeds in a fresh interpreter.
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
LASH = "normal(0.25 mm, 0.02 mm)"


def _fresh(args: list[str]) -> float:
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "explorer", *args], cwd=ROOT, check=False, capture_output=True,
                   env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    return time.perf_counter() - started


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

    speeds = median_times({
        "check": lambda: explorer.check(scene, rpm=RPM, workers=1),
        "sweep": lambda: explorer.sweep(scene, vary={"drive.rpm": RPM}, workers=1),
    }, args.repeat, warmup=1)
    repeat_draws = max(1, min(args.repeat, 3))
    draws = median_times({
        "check": lambda: explorer.check(scene, rpm=RPM, sample={"valve.lash": LASH}, runs=args.draws, seed=1,
                                        workers=1),
        "sweep": lambda: explorer.sweep(elastic, vary={"drive.rpm": "6500"}, sample={"valve.lash": LASH},
                                        runs=args.draws, seed=1, workers=1),
    }, repeat_draws, warmup=1)
    cold_check = sorted(_fresh(["check", SCENE, "--rpm", RPM, "--workers", "1"]) for _ in range(3))[1]
    cold_sweep = sorted(_fresh(["sweep", SCENE, "--vary", f"drive.rpm={RPM}", "-o", "/dev/null", "--workers", "1"])
                        for _ in range(3))[1]
    report = explorer.check(scene, rpm=RPM, sample={"valve.lash": LASH}, runs=args.draws, seed=1, workers=1)
    runs = sum(1 for r in report.results if r.samples) and report.runs
    rows = [
        ["check, 200 speeds, all rules (in process)", f"{speeds['check']:.3f} s", f"{speeds['sweep']:.3f} s",
         f"{speeds['check'] / speeds['sweep']:.2f}x", "<= 1 s", "met" if speeds["check"] <= 1.0 else "MISSED"],
        [f"check, {args.draws} lash draws, one core", f"{draws['check']:.2f} s", f"{draws['sweep']:.2f} s",
         f"{draws['check'] / draws['sweep']:.2f}x", "<= 10 s", "met" if draws["check"] <= 10.0 else "MISSED"],
        ["fresh interpreter: check vs sweep, 200 speeds", f"{cold_check:.2f} s", f"{cold_sweep:.2f} s",
         f"{cold_check / cold_sweep:.2f}x", "-", ""],
    ]
    print()
    print_table(["case", "check", "baseline", "ratio", "target", ""], rows)
    print(f"\nbaselines: explorer.sweep of the same 200 speeds (scene's effects); of {args.draws} lash draws at 6500 rpm "
          f"with the elastic effect only (one elastic run per draw); `explorer sweep` in a fresh interpreter")
    elastic_rules = [r.name for r in report.results if r.samples and r.group == "dynamics" and r.name != "ramp_velocity"]
    print(f"the tolerance study judged {runs} draws; elastic rules {', '.join(elastic_rules)} run the sweep engine at "
          "their nominal worst speeds")
    load = os.getloadavg()
    print(f"load average after: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
