"""What the validity check of every cam costs (explorer.lift.validity, issue #22 item 2).

    .venv/bin/python benchmarks/bench_validity.py [--repeat N]

Rows: each built-in scene with a computed or translating-roller cam. Columns: the check itself
(lift_fault on 7200 samples plus the breakpoints, as at load and build), the scene's load and its
lift's build (both include the check where the law checks itself), `simulate` of the scene, and
the check's share of load + build and of simulate. Medians of --repeat runs, functions taking
turns; the load average is printed with the table. The polydyne's refusal (bisection for the
stiffness and speed that pass) is timed on the issue's case, linkage.stiffness = 1 N/m.
"""

from __future__ import annotations

import argparse
import os

from _timing import ROOT, median_times, print_table

SCENES = ("polydyne_demo", "polydyne_spline", "spline_demo", "table_demo", "acceleration_demo", "cycloidal_demo")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=11, help="runs per row (default 11)")
    args = parser.parse_args(argv)

    from explorer import load_scene
    from explorer.effects.pipeline import simulate
    from explorer.core.errors import InputError
    from explorer.effects.lift import build_lift
    from explorer.lift.validity import lift_fault

    rows = []
    for name in SCENES:
        path = ROOT / "assets" / "scenes" / f"{name}.toml"
        scene = load_scene(path)
        lift = build_lift(scene)
        times = median_times({
            "check": lambda: lift_fault(lift, scene.follower),
            "load+build": lambda: build_lift(load_scene(path)),
            "simulate": lambda: simulate(scene, lift),
        }, args.repeat, warmup=1)
        rows.append([name, f"{times['check'] * 1e3:.2f}", f"{times['load+build'] * 1e3:.1f}",
                     f"{times['simulate'] * 1e3:.1f}", f"{100 * times['check'] / times['load+build']:.1f} %",
                     f"{100 * times['check'] / times['simulate']:.1f} %"])

    def refusal():
        try:
            load_scene(ROOT / "assets" / "scenes" / "polydyne_demo.toml", ['linkage.stiffness="1 N/m"'])
        except InputError:
            return
        raise AssertionError("the 1 N/m polydyne must be refused")

    refused = median_times({"refusal": refusal}, max(3, args.repeat // 3), warmup=1)["refusal"]
    print(f"validity check of every cam: median of {args.repeat} runs, load average {os.getloadavg()[0]:.2f}")
    print_table(["scene", "check ms", "load+build ms", "simulate ms", "check/load+build", "check/simulate"], rows)
    print(f"polydyne refusal with its advice (linkage.stiffness = 1 N/m, bisection): {refused * 1e3:.0f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
