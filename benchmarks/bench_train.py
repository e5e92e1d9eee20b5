"""Cost of the valve train of parts (issue #25) per revolution, ratios measured in one run.

Rows (median CPU of alternating runs, one revolution of 3600 steps each):
  one mass, massless exact    today's model: the valve on one linkage (dynamics/exact.py)
  one mass, train solver      the same valve as a train of one element (chain_exact, bit for bit
                              the spring-chain model)
  3 masses                    lifter, rocker and valve held together, the cam contact open or closed
  3 masses + HLA              the finger on its lash adjuster: finger, plunger and valve, the chamber
  3 masses rattling           the same with the rocker's cup and the pad one-sided: after the valve
                              seats the parts rattle in the lash (many more events)
  3 masses, scipy DOP853      the same train with scipy at rtol 1e-10 (chain_reference)
and the ratios the issue asks for: 3 masses / one mass (<= 3), with HLA / one mass (<= 5), scipy /
3 masses (>= 30). The machine's load is printed: the ratios hold under load, the times do not.
The train solver's first call (its numba kernels loaded or compiled) is timed apart.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_train.py [--repeat 5] [--rpm 2000]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one core: the ratios compare single-core work

import argparse  # noqa: E402
from dataclasses import replace  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from _timing import ROOT, median_times, print_table  # noqa: E402
from explorer import load_scene  # noqa: E402
from explorer.dynamics import chain_exact, chain_reference  # noqa: E402
from explorer.dynamics.model import Drive, LinkageModel  # noqa: E402
from explorer.dynamics.solvers import solve  # noqa: E402
from explorer.dynamics.chain import ChainModel  # noqa: E402
from explorer.dynamics.train import Joint, Part, TrainModel  # noqa: E402
from explorer.effects.lift import build_lift  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rpm", type=float, default=2000.0)
    args = ap.parse_args()
    omega = args.rpm * math.pi / 30.0
    t = np.linspace(0.0, 2.0 * math.pi / omega, 3601)

    # the pushrod train's lifter and rocker (its pushrod in series with the rocker's cup) and valve,
    # held together (the cam contact alone can open, with the lash): a 3-mass train without rattle;
    # the same masses on one linkage (the joints in series) for the one-mass model
    scene = load_scene(ROOT / "assets" / "scenes" / "pushrod_train.toml")
    els = scene.linkage.elements
    drive = Drive(build_lift(scene), scene.follower.ratio, omega)
    chain = ChainModel.from_scene(scene)
    lash = scene.valve.lash
    r2 = els[0].ratio ** 2
    cup = 1.0 / (1.0 / els[1].stiffness + 1.0 / els[2].stiffness) / r2
    joints = (Joint("cam", els[0].stiffness / r2, els[0].damping / r2, lash),
              Joint("rocker", cup, els[2].damping / r2, one_sided=False),
              Joint("valve", scene.linkage.stiffness, scene.linkage.damping, one_sided=False))
    train3 = TrainModel(chain, (Part("lifter", els[0].referred_mass), Part("rocker", els[2].referred_mass)), joints)
    k1 = 1.0 / sum(1.0 / j.stiffness for j in joints)
    c1 = 1.0 / sum(1.0 / j.damping for j in joints)
    m1 = float(chain.masses[0]) + sum(p.mass for p in train3.parts)
    one = TrainModel(replace(chain, valve_mass=m1, stiffness=k1, damping=c1, lash=lash), (),
                     (Joint("cam", k1, c1, lash),))
    massless = LinkageModel(mass=m1, oscillating_mass=m1, stiffness=k1, damping=c1, lash=lash, preload=chain.preload,
                            spring_rate=chain.spring_rate, closing_load=chain.closing_load)
    rattle = TrainModel.from_scene(scene.with_changes(linkage=replace(
        scene.linkage, elements=(els[0], replace(els[2], stiffness=1.0 / (1.0 / els[1].stiffness
                                                                          + 1.0 / els[2].stiffness))))))
    finger_scene = load_scene(ROOT / "assets" / "scenes" / "finger_hla_pumpup.toml")
    finger = TrainModel.from_scene(finger_scene)
    drive_f = Drive(build_lift(finger_scene), finger_scene.follower.ratio, omega)

    started = time.perf_counter()
    chain_exact.solve(train3, drive, t[:50])
    first = time.perf_counter() - started
    runs = {
        "one mass, massless exact": lambda: solve(massless, drive, t),
        "one mass, train solver": lambda: chain_exact.solve(one, drive, t),
        "3 masses": lambda: chain_exact.solve(train3, drive, t),
        "3 masses + HLA": lambda: chain_exact.solve(finger, drive_f, t),
        "3 masses rattling in their lash": lambda: chain_exact.solve(rattle, drive, t),
        "3 masses, scipy DOP853": lambda: chain_reference.solve(train3, drive, t),
    }
    med = median_times(runs, args.repeat, warmup=1, clock=time.process_time)
    ex = chain_exact.solve(train3, drive, t)
    ref = chain_reference.solve(train3, drive, t)
    hla = chain_exact.solve(finger, drive_f, t)
    rat = chain_exact.solve(rattle, drive, t)
    single = chain_exact.solve(one, drive, t)
    base = med["one mass, massless exact"]
    print(f"{args.rpm:g} rpm camshaft, 3600 steps per revolution, median CPU of {args.repeat} alternating runs, "
          f"load {os.getloadavg()[0]:.2f} (1 min) on {os.cpu_count()} cores")
    print_table(("case", "ms/rev", "x one mass"),
                [(k, f"{v * 1e3:.2f}", f"{v / base:.2f}") for k, v in med.items()], indent="  ")
    print(f"  3 masses / one mass:         {med['3 masses'] / base:.2f}x   (target <= 3)")
    print(f"  3 masses + HLA / one mass:   {med['3 masses + HLA'] / base:.2f}x   (target <= 5)")
    print(f"  scipy / 3 masses:            {med['3 masses, scipy DOP853'] / med['3 masses']:.1f}x   (target >= 30)")
    print(f"  events: one mass {len(single.events)}, 3 masses {len(ex.events)}, with HLA {len(hla.events)}, "
          f"rattling {len(rat.events)}; "
          f"max |s_exact - s_scipy| = {np.max(np.abs(ex.s - ref.s)):.2e} m")
    print(f"  first train call (numba kernels from the disk cache, or compiled): {first:.2f} s wall")


if __name__ == "__main__":
    main()
