"""What holding the valve's open area costs `explorer design` (`--open-area keep`), and how exactly
the optimum holds it.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_design_area.py [--repeat N] [--objectives a,b]

Rows: each objective on spline_demo (the built-in scene with a spline lift and "free" station
values), with the open area kept and without it, under the guide's limits (pressure angle 30 deg,
radius margin 2 mm: without them the residual-vibration optimum is an undercut cam, refused). Columns: the median CPU time (time.process_time:
the machine is shared) of design() (the optimisation, its validity check and the comparison with
the standard laws), the optimiser's iterations, whether the limits were met, and the kept
optimum's open area against the start's, both by scipy quad split at the breakpoints and the lash
crossings (independent of explorer.lift.open_area; runs on any tree, e.g. PYTHONPATH=<main>).
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from _timing import ROOT, median_times, print_table

OBJECTIVES = ("peak-acceleration", "peak-jerk", "jerk-energy", "residual-vibration")


def quad_open_area(scene, lift) -> float:
    from scipy.integrate import quad

    from explorer.mechanics.kinematics import lash_crossings

    ratio, lash = scene.follower.ratio, scene.valve.lash
    ups, downs = lash_crossings(lift, ratio, lash)
    marks = np.sort(np.mod(np.concatenate([lift.breakpoints(), ups, downs]) - scene.lift.start, 2 * math.pi))
    edges = np.unique(np.concatenate([[0.0], marks, [2 * math.pi]]))
    return sum(quad(lambda x: max(ratio * float(lift.derivatives(np.array([scene.lift.start + x]))[0][0]) - lash, 0.0),
                    a, b, epsabs=0.0, epsrel=1e-13, limit=200)[0] for a, b in zip(edges[:-1], edges[1:]))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5, help="runs per row (default 5)")
    parser.add_argument("--objectives", default=",".join(OBJECTIVES))
    args = parser.parse_args(argv)

    from explorer import load_scene
    from explorer.effects.lift import build_lift
    from explorer.lift.spline import solve_spline
    from explorer.studies.design import DesignLimits, design

    scene = load_scene(ROOT / "assets" / "scenes" / "spline_demo.toml")
    start_area = quad_open_area(scene, build_lift(scene))
    rows = []
    guide = dict(max_pressure_angle=math.radians(30.0), radius_margin=0.002)
    for objective in args.objectives.split(","):
        cases = {"free": DesignLimits(**guide), "keep": DesignLimits(**guide, open_area="keep")}
        keep = design(scene, objective, cases["keep"])
        times = median_times({key: (lambda limits=limits: design(scene, objective, limits)) for key, limits in cases.items()},
                             args.repeat, warmup=0, clock=time.process_time)
        lift = solve_spline(keep.options.stations, keep.options.continuity, scene.lift.start)
        rows.append([objective, f"{times['free']:.2f}", f"{times['keep']:.2f}", str(keep.iterations),
                     "met" if keep.success else "NOT met", f"{quad_open_area(scene, lift) / start_area - 1:.2g}"])
    print(f"explorer design on spline_demo, open area kept: median CPU s of {args.repeat} runs, "
          f"load average {os.getloadavg()[0]:.2f}")
    print_table(["objective", "free s", "keep s", "keep iterations", "keep limits", "area / start's - 1 (quad)"], rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
