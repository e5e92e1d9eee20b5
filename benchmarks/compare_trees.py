"""CPU time of `import explorer` and of the benchmark scripts, this tree against another checkout
of the project (a baseline commit), measured in one run: old and new alternate run by run, each
in its own interpreter, so a change of the machine's load hits both alike.

    git worktree add /tmp/base <commit> --detach
    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/compare_trees.py --base /tmp/base [--pairs 5] [--only core ...]

Each figure is the child's CPU time (user + sys, resource.getrusage); the `import explorer` row is
the time.process_time() of the import alone. Per row: the median of each tree and the median of the
pairwise ratios new/old (below 1: faster), with the load average before and after. Scripts that
take longer than --limit seconds on this tree are left out (named at the end). The same
interpreter runs both trees (PYTHONPATH picks the tree; each child prints which explorer it ran).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
IMPORT = ("import sys, time; t = time.process_time(); import explorer; t = time.process_time() - t; "
          "print(f'{t!r} {explorer.__file__}', file=sys.stderr)")
# the scripts' own "small" settings (benchmarks/run_all.py --quick): their figures here are whole runs
QUICK = {"core": ["--repeat", "3"], "dynamics": ["--repeat", "3"], "forces": ["--repeat", "3"],
         "gears_contact": ["--repeat", "3"], "contour_points": ["--repeat", "3"], "recording": ["--repeats", "2"],
         "viewer": ["--repeat", "5"]}
SKIP = {"wait", "viewer", "check"}  # bench_wait/viewer drive a browser and servers; bench_check runs minutes


def run(tree: Path, command: list[str], timeout: float) -> tuple[float, str]:
    """(CPU seconds of the child, its stderr's last line) with explorer imported from `tree`."""
    env = dict(os.environ, PYTHONPATH=str(tree), OPENBLAS_NUM_THREADS="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(command, cwd=tree, env=env, capture_output=True, text=True, timeout=timeout)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} in {tree} failed:\n{proc.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, (proc.stderr.strip().splitlines() or [""])[-1]


def line(row) -> str:
    what, old_t, new_t, ratios = row
    scale, unit = (1e3, "ms") if what == "import explorer" else (1.0, "s")
    return (f"| {what} | {statistics.median(old_t) * scale:.3g} {unit} | {statistics.median(new_t) * scale:.3g} {unit} "
            f"| {statistics.median(ratios):.3f} | {min(ratios):.3f}-{max(ratios):.3f} |")


def show(row) -> None:
    """A row as soon as it is measured (stderr, with the load), in case the run is cut short."""
    print(f"{line(row)}  load {os.getloadavg()[0]:.2f}", file=sys.stderr, flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", required=True, type=Path, help="the baseline checkout")
    parser.add_argument("--pairs", type=int, default=5, help="alternating runs of each tree (import: 4x)")
    parser.add_argument("--limit", type=float, default=30.0, help="leave out scripts slower than this (s)")
    parser.add_argument("--only", nargs="+", default=None, metavar="NAME")
    args = parser.parse_args()
    if not 1 <= args.pairs <= 50:
        parser.error("--pairs: 1 to 50")
    base, new = args.base.resolve(), ROOT
    rows, left_out = [], []
    load0 = os.getloadavg()

    # import explorer: the import's own CPU time, printed by the child
    old_t, new_t, ratios = [], [], []
    for _ in range(4 * args.pairs):
        for tree, out in ((base, old_t), (new, new_t)):
            _, last = run(tree, [sys.executable, "-c", IMPORT], 60)
            seconds, path = last.split(" ", 1)
            if not path.startswith(str(tree)):
                raise RuntimeError(f"imported {path}, not the tree {tree}")
            out.append(float(seconds))
        ratios.append(new_t[-1] / old_t[-1])
    rows.append(("import explorer", old_t, new_t, ratios))
    show(rows[-1])

    names = sorted(p.stem.removeprefix("bench_") for p in HERE.glob("bench_*.py"))
    for name in names:
        if name in SKIP or (args.only and name not in args.only):
            continue
        command = [sys.executable, str(HERE / f"bench_{name}.py"), *QUICK.get(name, [])]
        try:
            first, _ = run(new, command, 3 * args.limit)  # warm-up (numba caches) and the size check
        except subprocess.TimeoutExpired:
            left_out.append(f"{name} (over {3 * args.limit:g} s)")
            continue
        if first > args.limit:
            left_out.append(f"{name} ({first:.0f} s CPU)")
            continue
        run(base, [sys.executable, str(args.base.resolve() / "benchmarks" / f"bench_{name}.py"), *QUICK.get(name, [])],
            3 * args.limit)
        old_t, new_t, ratios = [], [], []
        for _ in range(args.pairs):
            old_t.append(run(base, [sys.executable, str(base / "benchmarks" / f"bench_{name}.py"),
                                    *QUICK.get(name, [])], 3 * args.limit)[0])
            new_t.append(run(new, command, 3 * args.limit)[0])
            ratios.append(new_t[-1] / old_t[-1])
        rows.append((f"bench_{name}.py {' '.join(QUICK.get(name, []))}".strip(), old_t, new_t, ratios))
        show(rows[-1])

    load1 = os.getloadavg()
    print(f"base {base} vs {new}; {args.pairs} pairs per script, {4 * args.pairs} for the import; "
          f"load average {load0[0]:.2f} before, {load1[0]:.2f} after ({os.cpu_count()} CPUs)")
    print("| what | base CPU s (median) | new CPU s (median) | new/base (median of pairs) | min-max |")
    print("|---|---|---|---|---|")
    for row in rows:
        print(line(row))
    if left_out:
        print("left out: " + ", ".join(left_out))
    return 0


if __name__ == "__main__":
    started = time.perf_counter()
    code = main()
    print(f"({time.perf_counter() - started:.0f} s)", file=sys.stderr)
    sys.exit(code)
