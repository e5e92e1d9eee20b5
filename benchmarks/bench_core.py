"""Benchmark of the motion core against the targets of issue 2.

    .venv/bin/python benchmarks/bench_core.py [--repeat N]

Rows: kinematics of one revolution at 3600 steps (lift derivatives + valve motion), contour
synthesis (exact roller envelope, 3600 points), scene load (default scene, warm process), the
first scene load in a fresh interpreter (import + load; pint must not be needed), `import
explorer` in a fresh interpreter, and the table law's spline fit (360 samples). Each row is the
median of several runs; "ratio" is median / target (<= 1 meets it) and "x base" the median over
a fixed numpy workload timed in this same process, so figures compare across machines.
"""

from __future__ import annotations

import argparse
import math
import statistics
import subprocess
import sys
import time

import numpy as np
from _timing import ROOT, baseline_workload, median_time, print_table


def fresh_python(code: str, repeat: int) -> float:
    """Median wall time of `python -c code` minus that of `python -c pass` (interpreter start)."""

    def run(snippet):
        started = time.perf_counter()
        subprocess.run([sys.executable, "-c", snippet], check=True, cwd=ROOT)
        return time.perf_counter() - started

    base = statistics.median(run("pass") for _ in range(repeat))
    return statistics.median(run(code) for _ in range(repeat)) - base


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=21, help="runs per in-process row (default 21)")
    parser.add_argument("--fresh-repeat", type=int, default=7, help="runs per fresh-interpreter row (default 7)")
    args = parser.parse_args(argv)

    from explorer import load_scene
    from explorer.effects.pipeline import Context
    from explorer.lift.contours.translating import translating_profile
    from explorer.effects.kinematics import kinematics_effect
    from explorer.effects.lift import build_lift
    from explorer.lift.table import fit_periodic_spline
    from explorer.scene.builtin import default_scene

    demo = ROOT / "assets" / "scenes" / "cycloidal_demo.toml"
    scene = load_scene(demo)
    n = 3600
    theta = np.arange(n) * (2.0 * math.pi / n)
    t_time = theta / scene.omega

    def kinematics():
        lift = build_lift(scene)
        return kinematics_effect(Context(scene, theta, t_time, lift, {}, {}))

    lift = build_lift(scene)
    f = scene.follower

    def synthesis():
        return translating_profile(lift, theta, f.base_radius, f.roller_radius, f.offset)

    default = default_scene()

    samples = np.arange(360) * (2.0 * math.pi / 360)
    measured = lift.derivatives(samples)[0] + 5e-6 * np.random.default_rng(0).standard_normal(360)

    def table_fit():
        return fit_periodic_spline(samples, measured)

    base = median_time(baseline_workload, args.repeat)
    rows = [
        ("kinematics, 1 revolution, 3600 steps", median_time(kinematics, args.repeat), 1e-3),
        ("contour synthesis, 3600 points", median_time(synthesis, args.repeat), 5e-3),
        *[(f"scene load ({path.name}), warm", median_time(lambda: load_scene(path), args.repeat), 50e-3)
          for path in dict.fromkeys([default, demo])],
        (f"import explorer + scene load ({default.name}), fresh interpreter",
         fresh_python(f"import explorer; explorer.load_scene({str(default)!r})", args.fresh_repeat), None),
        ("import explorer, fresh interpreter", fresh_python("import explorer", args.fresh_repeat), 0.3),
        ("table law: spline fit of 360 samples (GCV)", median_time(table_fit, max(5, args.repeat // 3)), None),
    ]
    print(f"baseline (numpy yardstick): {1e3 * base:.2f} ms; python {sys.version.split()[0]}, numpy {np.__version__}")
    failed = any(target and seconds > target for _name, seconds, target in rows)
    print_table(["task", "median", "target", "ratio", "x base"],
                [(name, f"{1e3 * seconds:.3f}ms", f"{1e3 * target:.1f}ms" if target else "-",
                  f"{seconds / target:.2f}" if target else "-", f"{seconds / base:.2f}")
                 for name, seconds, target in rows])
    print("all targets met" if not failed else "SOME TARGETS MISSED")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
