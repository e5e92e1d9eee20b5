"""Benchmark of the elastic dynamics: one revolution with contact loss at default settings.

    .venv/bin/python benchmarks/bench_dynamics.py [--repeat 9] [--scene PATH --set KEY=VALUE ...]

Baseline: scipy solve_ivp DOP853 at rtol 1e-10 (atol 1e-13 m), with event functions (plain
sign-change detection) and the step bounded by Tn/4 (explorer.dynamics.reference). Measured against it in the same process,
alternating run by run: the exact solver at the scene's default steps (3600 per revolution), and
for comparison the 1902 scheme at the same steps. Prints the median CPU time of each, the ratio
to the baseline (issue 4: exact >= 30x faster, goal 100x, at equal or better accuracy) and each
one's largest valve-lift error against a converged reference (DOP853 at rtol 1e-12).

Default scenes: the valve float demo (4000 rpm, soft spring) given a linkage of 5e6 N/m, and,
when it exists, Schenker's Fig. 2 cam at 600 rpm -- both lose contact during the revolution.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
from _timing import ROOT, median_times, print_table

CASES = [
    ("valve_float_demo.toml", ['linkage.stiffness="5e6 N/m"']),
    ("schenker1902_fig2.toml", ["drive.rpm=600"]),
]


def measure(scene, repeat: int) -> list[tuple[str, float, float]]:
    from explorer.bench import model_and_drive
    from explorer.dynamics import schenker1902
    from explorer.dynamics.model import solve

    model, drive = model_and_drive(scene)
    n = scene.solver.steps_per_revolution
    t = np.arange(n) * (2.0 * math.pi / drive.omega / n)
    reference = solve(model, drive, t, method="scipy", rtol=1e-12, atol=1e-15)
    runs = {
        "scipy DOP853 rtol 1e-10 (baseline)": lambda: solve(model, drive, t, method="scipy", rtol=1e-10, atol=1e-13,
                                                            watch_extrema=False),
        f"exact, {n} steps": lambda: solve(model, drive, t, method="exact"),
    }
    if n >= schenker1902.min_stable_steps(model, drive.omega):
        runs[f"schenker1902, {n} steps"] = lambda: solve(model, drive, t, method="schenker1902")
    errors = {name: float(np.abs(fn().s - reference.s).max()) for name, fn in runs.items()}  # also the warm-up
    medians = median_times(runs, repeat, warmup=0, clock=time.process_time)
    kinds = sorted({e["kind"] for e in reference.events})
    print(f"\n{scene.name}: {scene.drive.rpm:g} rpm, {n} steps, events {', '.join(kinds)} "
          f"({len(reference.events)}), median CPU of {repeat} runs")
    base = medians[next(iter(runs))]
    print_table(["case", "CPU ms", "ratio", "max lift error m"],
                [(name, f"{1e3 * med:.2f}", f"{base / med:.1f}x", f"{errors[name]:.2e}") for name, med in medians.items()],
                indent="  ")
    return [(name, med, errors[name]) for name, med in medians.items()]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=9)
    parser.add_argument("--scene", help="one scene file instead of the default cases")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    args = parser.parse_args()

    from explorer.scene import load_scene

    scenes = ROOT / "assets" / "scenes"
    cases = [(Path(args.scene), args.overrides)] if args.scene else [(scenes / name, sets) for name, sets in CASES]
    for path, overrides in cases:
        if not path.exists():
            print(f"\n(skipped: {path.name} not found)")
            continue
        measure(load_scene(path, overrides), args.repeat)


if __name__ == "__main__":
    main()
