"""Benchmark of the contact statics on the gear scenes and of the rocking cam's lift evaluation.

    .venv/bin/python benchmarks/bench_gears_contact.py [--repeat 7]

Table 1: the forces and contact effects on each gear scene (3600 steps), median compute time and
ratio against the kinematics effect of the same run.
Table 2: the rocking cam's lift at one angle (what the forces effect's Brent refinements ask for,
about a hundred times per run) and at 4096 angles, with the contact Newton seeded with first-order
jets (current) against the full third-order jets (the former code: same iterates, bit for bit),
and the whole forces effect both ways.
"""

from __future__ import annotations

import argparse
import statistics
from types import MappingProxyType

import numpy as np
from _timing import ROOT, median_times, print_table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    from explorer.effects.pipeline import Context, simulate
    from explorer.effects.forces import forces_effect
    from explorer.gears import jet as J
    from explorer.effects.lift import build_lift
    from explorer.scene.scene import load_scene

    rows = []
    for name in ("pivoted_roller_lever", "rocking_cam", "rolling_lever"):
        scene = load_scene(ROOT / "assets" / "scenes" / f"{name}.toml",
                           ['effects=["kinematics", "lash", "forces", "contact"]'])
        simulate(scene)
        runs = [simulate(scene).timings for _ in range(args.repeat)]
        t = {k: statistics.median(r[k].compute_time_s for r in runs) for k in ("kinematics", "forces", "contact")}
        rows.append([name, f"{t['kinematics'] * 1e3:.2f}", f"{t['forces'] * 1e3:.2f}", f"{t['forces'] / t['kinematics']:.2f}",
                     f"{t['contact'] * 1e3:.2f}", f"{t['contact'] / t['kinematics']:.2f}"])
    print_table(["scene", "kinematics ms", "forces ms", "x kin", "contact ms", "x kin"], rows)
    print()

    scene = load_scene(ROOT / "assets" / "scenes" / "rocking_cam.toml", ['effects=["kinematics", "lash", "forces"]'])
    lift = build_lift(scene)
    result = simulate(scene, lift)
    cols = dict(result.columns)
    theta = np.radians(cols["cam_angle_deg"])
    ctx = Context(scene, theta, cols["time_s"], lift, MappingProxyType(cols), MappingProxyType({}))
    one, many = np.array([2.5]), np.linspace(0.0, 2.0 * np.pi, 4096, endpoint=False)
    newton = J.newton

    def full_order(*a, **k):
        k.pop("order", None)
        return newton(*a, **k)

    def both(function):
        """(first-order Newton, full-jet Newton) timings of one case."""
        J.newton = full_order
        try:
            base = median_times({"": function}, args.repeat)[""]
        finally:
            J.newton = newton
        return median_times({"": function}, args.repeat)[""], base

    rows = []
    for label, function, unit, scale in (
        ("lift at 1 angle", lambda: lift.derivatives(one), "us", 1e6),
        ("lift at 4096 angles", lambda: lift.derivatives(many), "ms", 1e3),
        ("forces effect", lambda: forces_effect(ctx), "ms", 1e3),
    ):
        now, base = both(function)
        rows.append([label, f"{base * scale:.1f} {unit}", f"{now * scale:.1f} {unit}", f"{now / base:.2f}"])
    print_table(["rocking cam", "full-jet Newton", "first-order Newton", "ratio"], rows)


if __name__ == "__main__":
    main()
