"""The sweep's batch engine of two checkouts side by side in one run: elastic revolutions per second
on one core (bench_sweep's first row: elastic_float.toml, 3600 steps, 400 speeds from 3000 to
5000 rpm, the compiled path's compute_chunk after a warm-up call) of the code before a change and
of this checkout, measured in alternating child processes so that a change of the machine's load
hits both alike.

    git archive <commit> | tar -x -C /tmp/before     # the code before (compiled on first use)
    .venv/bin/python benchmarks/bench_engine_trees.py /tmp/before [--rounds 5] [--repeat 5]

Each round runs one child per checkout (the order alternates); a child times --repeat sweeps and
reports the median CPU time per revolution (time.process_time: on a machine shared with other
work a process waits for a core for as long again as it computes, and a wall clock would time the
waits); the table shows each checkout's median over the rounds (and its fastest round) and the
ratio, with the load average before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from _timing import ROOT, print_table


def child(root: str, repeat: int, speeds: int) -> None:
    """Time the engine of the checkout at root (run in a child process)."""
    sys.path.insert(0, root)
    import numpy as np

    import explorer
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns

    assert Path(explorer.__file__).resolve().is_relative_to(Path(root).resolve()), explorer.__file__
    flt = load_scene(Path(root) / "assets" / "scenes" / "elastic_float.toml")
    names = result_columns(flt)
    rpm = np.linspace(3000.0, 5000.0, speeds)[:, None]
    shared = _Shared()
    engine = engine_for(flt, shared).name
    compute_chunk(flt, ("drive.rpm",), rpm[:2], names, shared)  # imports, the lift, the grid
    times = []
    for _ in range(repeat):
        t = time.process_time()
        compute_chunk(flt, ("drive.rpm",), rpm, names, shared)
        times.append((time.process_time() - t) / speeds)
    print(json.dumps({"per_revolution_s": statistics.median(times), "engine": engine}))


def measure(root: Path, repeat: int, speeds: int) -> dict:
    out = subprocess.run([sys.executable, __file__, "--child", str(root), "--repeat", str(repeat),
                          "--speeds", str(speeds)], capture_output=True, text=True, check=True, cwd=root)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("before", nargs="?", help="a checkout of the code before the change")
    parser.add_argument("--after", default=str(ROOT), help="the checkout after (default: this one)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--speeds", type=int, default=400)
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child, args.repeat, args.speeds)
        return
    trees = {"before": Path(args.before).resolve(), "after": Path(args.after).resolve()}
    for root in trees.values():  # compile (or load) each checkout's kernels before the clock runs
        measure(root, 1, 2)
    load0 = os.getloadavg()[0]
    samples: dict[str, list[float]] = {name: [] for name in trees}
    engines = {}
    for r in range(args.rounds):
        for name in (list(trees) if r % 2 == 0 else list(trees)[::-1]):
            got = measure(trees[name], args.repeat, args.speeds)
            samples[name].append(got["per_revolution_s"])
            engines[name] = got["engine"]
    load1 = os.getloadavg()[0]
    med = {name: statistics.median(v) for name, v in samples.items()}
    print(f"bench_engine_trees: elastic_float.toml, 3600 steps, {args.speeds} speeds 3000-5000 rpm; medians of "
          f"{args.rounds} rounds x {args.repeat} sweeps; load average {load0:.1f} -> {load1:.1f} on "
          f"{os.cpu_count()} cores")
    rows = [[f"{name} ({trees[name]}; engine: {engines[name]})", f"{1 / med[name]:,.0f}",
             f"{1 / min(samples[name]):,.0f}", f"{med[name] * 1e6:.1f} us"] for name in trees]
    rows.append(["after / before", f"{med['before'] / med['after']:.2f}x",
                 f"{min(samples['before']) / min(samples['after']):.2f}x", ""])
    print_table(["checkout", "revolutions/s of CPU (median)", "(fastest round)", "CPU per revolution"], rows)


if __name__ == "__main__":
    main()
