"""Benchmark of the elastic dynamics: one revolution with contact loss at default settings.

    .venv/bin/python benchmarks/bench_dynamics.py [--repeat 9] [--scene PATH --set KEY=VALUE ...]
    .venv/bin/python benchmarks/bench_dynamics.py --rpm-sweep 120 240 400 600 [--scene PATH]

Baseline: scipy solve_ivp DOP853 at rtol 1e-10 (atol 1e-13 m), with event functions (plain
sign-change detection) and the step bounded by Tn/4 (explorer.dynamics.reference). Measured against it in the same process,
alternating run by run: the solver table's piecewise solvers (exact, exact-compiled, taylor) at the
scene's default steps (3600 per revolution), and for comparison its fixed-step ones (the 1902
scheme) at the same steps where stable. Prints the median CPU time of each, the ratio
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
    from explorer.studies.bench import model_and_drive
    from explorer.dynamics import solvers
    from explorer.dynamics.solvers import solve

    model, drive = model_and_drive(scene)
    n = scene.solver.steps_per_revolution
    t = np.arange(n) * (2.0 * math.pi / drive.omega / n)
    reference = solve(model, drive, t, method="scipy", rtol=1e-12, atol=1e-15)
    runs = {
        "scipy DOP853 rtol 1e-10 (baseline)": lambda: solve(model, drive, t, method="scipy", rtol=1e-10, atol=1e-13,
                                                            watch_extrema=False),
    }
    # the solver table's piecewise solvers that take this model, and its fixed-step ones where stable
    varying = model.stiffness_profile is not None
    for name in solvers.of_kind("piecewise", varying):
        runs[f"{name}, {n} steps"] = lambda name=name: solve(model, drive, t, method=name)
    for name in solvers.of_kind("fixed-step", varying):
        if n >= solvers.solver(name).min_stable_steps(model, drive.omega):
            runs[f"{name}, {n} steps"] = lambda name=name: solve(model, drive, t, method=name)
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


def rpm_sweep(path: Path, overrides: list[str], rpms: list[float], repeat: int) -> None:
    """The speed ratio against the camshaft speed on one scene: the baseline's cost follows the
    natural periods per revolution (its step is bounded by Tn/4 and must resolve them), the exact
    solver's mostly its fixed cost and the phases between events."""
    from explorer.studies.bench import model_and_drive
    from explorer.dynamics.solvers import solve
    from explorer.scene.scene import load_scene

    rows = []
    for rpm in rpms:
        scene = load_scene(path, [*overrides, f"drive.rpm={rpm:g}"])
        model, drive = model_and_drive(scene)
        n = scene.solver.steps_per_revolution
        t = np.arange(n) * (2.0 * math.pi / drive.omega / n)
        runs = {
            "scipy": lambda: solve(model, drive, t, method="scipy", rtol=1e-10, atol=1e-13, watch_extrema=False),
            "exact": lambda: solve(model, drive, t, method="exact"),
        }
        events = solve(model, drive, t, method="exact").events
        med = median_times(runs, repeat, warmup=1, clock=time.process_time)
        periods = 2.0 * math.pi / drive.omega / model.natural_period()
        separations = sum(e["kind"] == "separation" for e in events)
        rows.append((f"{rpm:g}", f"{periods:.0f}", f"{len(events)}", f"{separations}", f"{1e3 * med['scipy']:.2f}",
                     f"{1e3 * med['exact']:.2f}", f"{med['scipy'] / med['exact']:.1f}x"))
    print(f"\n{path.name}: speed ratio against rpm ({repeat} alternating runs each, median CPU)")
    print_table(["rpm", "Tn per rev", "events", "separations", "scipy ms", "exact ms", "ratio"], rows, indent="  ")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=9)
    parser.add_argument("--scene", help="one scene file instead of the default cases")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE")
    parser.add_argument("--rpm-sweep", nargs="+", type=float, metavar="RPM",
                        help="the ratio at these camshaft speeds on --scene (default: Schenker's Fig. 2)")
    args = parser.parse_args()

    from explorer.scene.scene import load_scene

    scenes = ROOT / "assets" / "scenes"
    if args.rpm_sweep:
        rpm_sweep(Path(args.scene) if args.scene else scenes / "schenker1902_fig2.toml", args.overrides,
                  args.rpm_sweep, args.repeat)
        return
    cases = [(Path(args.scene), args.overrides)] if args.scene else [(scenes / name, sets) for name, sets in CASES]
    for path, overrides in cases:
        if not path.exists():
            print(f"\n(skipped: {path.name} not found)")
            continue
        measure(load_scene(path, overrides), args.repeat)


if __name__ == "__main__":
    main()
