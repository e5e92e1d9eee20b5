"""Where a 1000-speed sweep of valve_float_demo.toml (all its effects, one process) spends its CPU
(issue #27.5): timers around the sweep's stages (the functions as the sweep calls them), the
median of --repeat sweeps after a warm-up, time.process_time. A stage indented under another is
part of it; the compiled elastic revolutions are run_batch.

    .venv/bin/python benchmarks/bench_sweep_stages.py [--repeat 9]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

from _timing import ROOT

STAGES = [  # (module, function, label) wrapped where the sweep looks them up
    ("explorer.studies.sweep_engine", "rigid_over_speeds", "rigid figures (rigid_over_speeds)"),
    ("explorer.studies.sweep_rigid", "min_contact_forces", "  min_contact_forces"),
    ("explorer.mechanics.forces", "_zoom_minima", "    its bounded zoom (_zoom_minima)"),
    ("explorer.studies.sweep_rigid", "smooth_pieces", "  smooth_pieces (once a sweep)"),
    ("explorer.studies.sweep_rigid", "float_speed", "  float_speed (once a sweep)"),
    ("explorer.studies.sweep_rigid", "peak_torques", "  peak_torques"),
    ("explorer.studies.sweep_rigid", "figures", "  torque factors' kinematics (once a sweep)"),
    ("explorer.studies.sweep_engine", "elastic_chunk_values", "elastic figures (elastic_chunk_values)"),
    ("explorer.effects.elastic_batch", "lash_take_ups", "  lash_take_ups (once a sweep)"),
    ("explorer.dynamics.exact_kernel", "run_batch", "  compiled revolutions (run_batch)"),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=9)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    import importlib

    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_run import plan_from, run_plan

    spent: dict[str, float] = {}

    def timed(function, label):
        def call(*a, **k):
            start = time.process_time()
            try:
                return function(*a, **k)
            finally:
                spent[label] = spent.get(label, 0.0) + time.process_time() - start
        return call

    for module, name, label in STAGES:
        mod = importlib.import_module(module)
        setattr(mod, name, timed(getattr(mod, name), label))
    demo = load_scene(ROOT / "assets" / "scenes" / "valve_float_demo.toml")
    run_plan(demo, plan_from(demo, {"drive.rpm": "1000:6000:10"}), workers=1)  # imports, kernels
    plan = plan_from(demo, {"drive.rpm": "1000:6000:1000"})
    run_plan(demo, plan, workers=1)
    load = os.getloadavg()[0]
    totals, stages = [], []
    for _ in range(args.repeat):
        spent.clear()
        start = time.process_time()
        run_plan(demo, plan, workers=1)
        totals.append(time.process_time() - start)
        stages.append(dict(spent))
    print(f"bench_sweep_stages: {ROOT}, valve_float_demo.toml, 1000 speeds, all effects, 1 core; CPU per sweep, "
          f"medians of {args.repeat}; load average {load:.1f} -> {os.getloadavg()[0]:.1f}")
    print(f"{'whole sweep (run_plan)':46s} {1e3 * statistics.median(totals):7.1f} ms")
    for _, _, label in STAGES:
        print(f"{label:46s} {1e3 * statistics.median(s.get(label, 0.0) for s in stages):7.1f} ms")


if __name__ == "__main__":
    main()
