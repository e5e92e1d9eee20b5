"""Benchmark of the forces and contact effects and the speed sweep.

    .venv/bin/python benchmarks/bench_forces.py [--repeat 7]

Prints the median of several runs of each case and its ratio against a baseline measured in the
same process: the effects against the kinematics effect of the same scene (3600 steps), the
vectorised 1000-speed sweep against the per-speed loop over the same arrays (target: <= 0.2 s for
1000 speeds) and against running the whole forces effect once per speed.
"""

from __future__ import annotations

import argparse
import statistics

import numpy as np
from _timing import ROOT, median_time, print_table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    from explorer.effects.pipeline import simulate
    from explorer.mechanics.forces import TrainLoads, float_speed
    from explorer.effects.lift import build_lift
    from explorer.scene.scene import load_scene
    from explorer.effects.spring_design import advise_spring
    from explorer.studies.sweeps import contact_margin_loop, contact_margin_sweep

    path = ROOT / "assets" / "scenes" / "valve_float_demo.toml"
    base = load_scene(path)
    plain = base.with_changes(spring_design=None)
    kin = load_scene(path, ['effects=["kinematics"]'])

    def median_effect(scene, name):
        simulate(scene)
        return statistics.median(simulate(scene).timings[name].compute_time_s for _ in range(args.repeat))

    rows = []
    t_kin = median_effect(kin, "kinematics")
    rows.append(("kinematics effect, 3600 steps (baseline)", t_kin, 1.0))
    t_forces = median_effect(plain, "forces")
    rows.append(("forces effect (exact jump speed, refined minimum)", t_forces, t_forces / t_kin))
    t_contact = median_effect(plain, "contact")
    rows.append(("contact effect", t_contact, t_contact / t_kin))
    t_design = median_effect(base, "forces")
    rows.append(("forces effect with [spring_design] (4 LPs)", t_design, t_design / t_kin))

    lift = build_lift(base)
    loads = TrainLoads.from_scene(base)
    t_jump = median_time(lambda: float_speed(lift, loads, base.follower.ratio, base.valve.lash), args.repeat)
    rows.append(("float_speed alone", t_jump, t_jump / t_kin))
    t_adv = median_time(lambda: advise_spring(base, lift=lift), args.repeat)
    rows.append(("advise_spring alone", t_adv, t_adv / t_kin))

    rpms = np.linspace(200, 8000, 1000)
    t_loop = median_time(lambda: contact_margin_loop(base, rpms, lift=lift), args.repeat)
    t_vec = median_time(lambda: contact_margin_sweep(base, rpms, lift=lift), args.repeat)
    rows.append(("sweep 1000 speeds, per-speed loop (baseline)", t_loop, 1.0))
    rows.append(("sweep 1000 speeds, vectorised", t_vec, t_vec / t_loop))
    # what a user would do without the sweep: one simulate() per speed (20 speeds, scaled to 1000)
    forces_only = load_scene(path, ['effects=["forces"]']).with_changes(spring_design=None)
    from explorer.scene.scene import Drive

    few = rpms[:: len(rpms) // 20][:20]
    t_sim = median_time(lambda: [simulate(forces_only.with_changes(drive=Drive(rpm=float(r)))) for r in few],
                        max(1, args.repeat // 3)) * (len(rpms) / len(few))
    rows.append(("sweep 1000 speeds, simulate() per speed (x50 of 20)", t_sim, t_sim / t_loop))

    print_table(["case", "median", "ratio"], [(name, f"{seconds * 1e3:.3f} ms", f"{ratio:.3f}") for name, seconds, ratio in rows])
    print(f"\nscene: {path.name}, {args.repeat} runs each; sweep target <= 200 ms: "
          f"{'met' if t_vec <= 0.2 else 'MISSED'} ({t_vec * 1e3:.1f} ms)")


if __name__ == "__main__":
    main()
