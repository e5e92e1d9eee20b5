"""Cost of the spring-chain model (issue #15): per revolution, the exact chain solver with 8
elements against the massless exact model and against scipy DOP853 (rtol 1e-10) on the same
chain model, medians of alternating runs in one process (ratios measured in one run). The
chain solver's first call (its numba kernels loaded or compiled) is timed apart.

    .venv/bin/python benchmarks/bench_spring_chain.py [--repeat 5] [--rpm 3000] [--elements 8]
"""

from __future__ import annotations

import argparse
import math
import pathlib
import statistics
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from explorer import load_scene  # noqa: E402
from explorer.dynamics import chain_exact, chain_reference  # noqa: E402
from explorer.dynamics.chain import ChainModel  # noqa: E402
from explorer.dynamics.model import Drive, LinkageModel  # noqa: E402
from explorer.dynamics.solvers import solve  # noqa: E402
from explorer.effects.lift import build_lift  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--rpm", type=float, default=3000.0)
    ap.add_argument("--elements", type=int, default=8)
    args = ap.parse_args()
    scene = load_scene(ROOT / "assets" / "scenes" / "spring_surge.toml", overrides=[f"spring.elements={args.elements}"])
    omega = args.rpm * math.pi / 30.0
    drive = Drive(build_lift(scene), 1.0, omega)
    chain = ChainModel.from_scene(scene)
    share = chain.spring_mass / 3.0  # the massless model: the spring's third on the valve
    massless = LinkageModel(mass=chain.valve_mass + share, oscillating_mass=chain.valve_mass + share,
                            stiffness=chain.stiffness, damping=chain.damping, lash=chain.lash, preload=chain.preload,
                            spring_rate=chain.spring_rate, closing_load=chain.closing_load, restitution=0.0)
    t = np.linspace(0.0, 2.0 * math.pi / omega, 3601)
    runs = {"massless exact": lambda: solve(massless, drive, t),
            "chain exact": lambda: chain_exact.solve(chain, drive, t),
            "chain scipy DOP853": lambda: chain_reference.solve(chain, drive, t)}
    times: dict[str, list[float]] = {k: [] for k in runs}
    # the chain solver's compiled kernels (numba) load from their disk cache, or compile when the
    # cache is cold, on the first call: timed apart, not in the medians
    t0 = time.perf_counter()
    chain_exact.solve(chain, drive, t[:50])
    first = time.perf_counter() - t0
    out = {}
    for i in range(args.repeat):
        for name, run in runs.items():
            t0 = time.process_time()
            out[name] = run()
            times[name].append(time.process_time() - t0)
        print(f"run {i + 1}/{args.repeat}", file=sys.stderr)
    med = {k: statistics.median(v) for k, v in times.items()}
    err = float(np.max(np.abs(out["chain exact"].s - out["chain scipy DOP853"].s)))
    print(f"{args.rpm:g} rpm, {args.elements} elements, 3600 steps, median CPU of {args.repeat} alternating runs")
    for k, v in med.items():
        print(f"  {k:20s} {v * 1e3:9.2f} ms")
    print(f"  chain exact / massless exact: {med['chain exact'] / med['massless exact']:.1f}x")
    print(f"  scipy / chain exact:          {med['chain scipy DOP853'] / med['chain exact']:.1f}x")
    print(f"  events: {len(out['chain exact'].events)}; max |s_exact - s_scipy| = {err:.2e} m")
    print(f"  first chain call (numba kernels from the disk cache, or compiled): {first:.2f} s wall")


if __name__ == "__main__":
    main()
