"""The kinematics effect's cost per scene: what every `explorer simulate` and every change in the
browser pays before any other effect runs.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_kinematics.py [--repeat N] [SCENE ...]

Per scene (default: those whose kinematics has a cost of its own: a translating roller's exact
pressure-angle and curvature extremes, explorer.effects.contour.geometry_extremes, and the arm
clearance check of the finger follower and the rocker, explorer.gears.envelope.first_crossing):
the median CPU time (time.process_time: the machine is shared, wall time counts the others'
work) of `simulate` with effects=["kinematics"] on the loaded scene, and of geometry_extremes
alone where the scene's gear has it. "x base" is the effect's time over a fixed numpy workload
timed in this process (benchmarks/_timing.py), so that figures compare across machines and load;
the load average is printed with them. The last row is a whole `simulate` of the elastic
effect with the compiled exact solver (`--set 'effects=["elastic"]' --set
'solver.method="exact-compiled"'`), of which the kinematics effect is a part.
"""

from __future__ import annotations

import argparse
import os
import time

from _timing import ROOT, baseline_workload, median_times, print_table

SCENES = ("valve_float_demo", "cycloidal_demo", "spline_demo", "table_demo", "polydyne_spline",
          "finger_follower", "ohc_rocker")
ELASTIC = ("valve_float_demo", ['effects=["elastic"]', 'solver.method="exact-compiled"'])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("scenes", nargs="*", default=list(SCENES), help="built-in scene names (without .toml)")
    args = parser.parse_args(argv)

    from explorer import load_scene, simulate
    from explorer.effects.contour import geometry_extremes
    from explorer.effects.lift import build_lift

    print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    clock = time.process_time
    base = median_times({"base": baseline_workload}, args.repeat, clock=clock)["base"]
    print(f"baseline (numpy yardstick): {base * 1e3:.2f} ms CPU")
    rows = []
    for name in args.scenes:
        path = ROOT / "assets" / "scenes" / f"{name}.toml"
        scene = load_scene(path, ['effects=["kinematics"]'])
        jobs = {"effect": lambda scene=scene: simulate(scene)}
        if getattr(scene.follower, "roller_envelope", False):
            lift = build_lift(scene)
            jobs["extremes"] = lambda lift=lift, f=scene.follower: geometry_extremes(lift, f)
        times = median_times(jobs, args.repeat, clock=clock)
        extremes = f"{times['extremes'] * 1e3:.2f}" if "extremes" in times else "-"
        rows.append([name, f"{times['effect'] * 1e3:.2f}", extremes, f"{times['effect'] / base:.2f}"])
    name, overrides = ELASTIC
    scene = load_scene(ROOT / "assets" / "scenes" / f"{name}.toml", overrides)
    seconds = median_times({"": lambda: simulate(scene)}, args.repeat, clock=clock)[""]
    rows.append([f"{name}, simulate elastic exact-compiled", f"{seconds * 1e3:.2f}", "-", f"{seconds / base:.2f}"])
    print_table(["scene", "kinematics ms", "geometry_extremes ms", "x base"], rows)
    print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
