"""Cost of the spring-chain model (issue #15): per revolution, the exact chain solver with 8
elements against the massless exact model and against scipy DOP853 (rtol 1e-10) on the same
chain model, medians of alternating runs in one process (ratios measured in one run). The
chain solver's first call (its numba kernels loaded or compiled) is timed apart.

--scaling (issue #27, item 6): the exact chain solver's cost per revolution against the number of
elements (8, 16, 24, 32, 48, 64), medians of alternating runs, each as a ratio to 8 elements and
per element, with the load; the target is <= 4x the 8-element cost at 64.

    .venv/bin/python benchmarks/bench_spring_chain.py [--repeat 5] [--rpm 3000] [--elements 8]
    .venv/bin/python benchmarks/bench_spring_chain.py --scaling [--repeat 7]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one core: LAPACK's threads would share it

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
    ap.add_argument("--scaling", action="store_true", help="cost against the number of elements (issue #27)")
    args = ap.parse_args()
    if args.scaling:
        scaling(args.repeat, args.rpm)
        return
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


def scaling(repeat: int, rpm: float, counts=(8, 16, 24, 32, 48, 64)) -> None:
    """The chain solver's median CPU per revolution against the number of elements."""
    omega = rpm * math.pi / 30.0
    t = np.linspace(0.0, 2.0 * math.pi / omega, 3601)
    runs = {}
    for N in counts:
        scene = load_scene(ROOT / "assets" / "scenes" / "spring_surge.toml", overrides=[f"spring.elements={N}"])
        chain = ChainModel.from_scene(scene)
        drive = Drive(build_lift(scene), 1.0, omega)
        runs[N] = (lambda chain=chain, drive=drive: chain_exact.solve(chain, drive, t))
    for run in runs.values():  # the kernels and the structured path's compiled root finder
        run()
    times: dict[int, list[float]] = {N: [] for N in runs}
    for _ in range(repeat):
        for N, run in runs.items():
            t0 = time.process_time()
            run()
            times[N].append(time.process_time() - t0)
    med = {N: statistics.median(v) for N, v in times.items()}
    base = med[counts[0]]
    print(f"{rpm:g} rpm, 3600 steps, median CPU of {repeat} alternating runs, load {os.getloadavg()[0]:.2f} "
          f"(1 min) on {os.cpu_count()} cores")
    print(f"  {'elements':>8s} {'ms/rev':>8s} {'x 8 el.':>8s} {'us/el.':>8s}")
    for N, v in med.items():
        print(f"  {N:8d} {v * 1e3:8.2f} {v / base:8.2f} {v / N * 1e6:8.1f}")
    print(f"  64 elements / 8 elements: {med[counts[-1]] / base:.2f}x (target <= 4)")


if __name__ == "__main__":
    main()
