"""Run every benchmark script here, one after another (`make bench`).

    .venv/bin/python benchmarks/run_all.py [--only NAME ...] [--skip NAME ...] [--quick]

Each script runs in its own interpreter (cold imports are part of some rows) and prints its own
table; this prints a header per script and, at the end, how long each took and whether it
failed. --quick passes a small --repeat to the scripts that take one. NAME is the part after
"bench_", e.g. `--only dynamics core`.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
QUICK_REPEAT = {"core": "3", "dynamics": "3", "forces": "3", "gears_contact": "3", "contour_points": "3", "kinematics": "3",
                "recording": "2", "viewer": "5", "design_area": "2"}
REPEAT_FLAG = {"recording": "--repeats"}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", nargs="+", default=[], metavar="NAME")
    parser.add_argument("--skip", nargs="+", default=[], metavar="NAME")
    parser.add_argument("--quick", action="store_true", help="fewer repeats (rough figures, a few minutes)")
    args = parser.parse_args()
    scripts = sorted(HERE.glob("bench_*.py"))
    names = [p.stem.removeprefix("bench_") for p in scripts]
    unknown = sorted(set(args.only + args.skip) - set(names))
    if unknown:
        print(f"run_all: unknown benchmark(s) {', '.join(unknown)}; known: {', '.join(names)}", file=sys.stderr)
        return 2
    outcome = []
    for path, name in zip(scripts, names):
        if (args.only and name not in args.only) or name in args.skip:
            continue
        command = [sys.executable, str(path)]
        if args.quick and name in QUICK_REPEAT:
            command += [REPEAT_FLAG.get(name, "--repeat"), QUICK_REPEAT[name]]
        print(f"\n=== {path.name} ===", flush=True)
        started = time.perf_counter()
        code = subprocess.call(command)
        outcome.append((name, time.perf_counter() - started, code))
    print("\nbenchmark          seconds  status")
    for name, seconds, code in outcome:
        print(f"{name:<18} {seconds:7.1f}  {'ok' if code == 0 else f'FAILED ({code})'}")
    return 0 if all(code == 0 for _, _, code in outcome) else 1


if __name__ == "__main__":
    sys.exit(main())
