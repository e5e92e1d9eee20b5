"""Bit-identity check of `simulate` on every built-in scene (issue #12: results bit-identical).

    .venv/bin/python benchmarks/golden_scenes.py save  [DIR]   # from the unchanged code
    .venv/bin/python benchmarks/golden_scenes.py check [DIR]   # after a change: exit 1 on any difference

Stores each scene's result columns (.npz) and summary (.json, timings removed: they are measured,
not computed) in DIR (default /tmp/gears-golden). Columns are compared with np.array_equal
(bit for bit, NaN-aware via equal_nan where the golden column has NaNs), summaries with ==.
Golden data is never committed: it is made from the code before a change.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "assets" / "scenes").glob("*.toml"))
TIMING_KEYS = ("compute_time_s",)


def _strip_timings(value):
    if isinstance(value, dict):
        return {k: _strip_timings(v) for k, v in value.items() if k not in TIMING_KEYS}
    if isinstance(value, list):
        return [_strip_timings(v) for v in value]
    return value


def run(path: Path):
    sys.path.insert(0, str(ROOT))
    from explorer import load_scene, simulate

    result = simulate(load_scene(path))
    summary = json.loads(result.json_text())  # floats round-trip exactly through repr
    return {k: np.asarray(v) for k, v in result.columns.items()}, _strip_timings(summary)


def save(directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    for path in SCENES:
        columns, summary = run(path)
        np.savez(directory / f"{path.stem}.npz", **columns)
        (directory / f"{path.stem}.json").write_text(json.dumps(summary, sort_keys=True, indent=1))
        print(f"saved {path.stem}: {len(columns)} columns")


def check(directory: Path) -> int:
    failures = 0
    checked = [path for path in SCENES if (directory / f"{path.stem}.npz").exists()]
    for path in sorted(set(SCENES) - set(checked)):
        print(f"{path.stem}: no golden data (a scene newer than it), not compared")
    for path in checked:
        columns, summary = run(path)
        with np.load(directory / f"{path.stem}.npz") as golden:
            names = set(golden.files)
            problems = []
            if names != set(columns):
                problems.append(f"column names differ: {sorted(names ^ set(columns))}")
            for name in sorted(names & set(columns)):
                if not np.array_equal(golden[name], columns[name], equal_nan=golden[name].dtype.kind == "f"):
                    problems.append(f"column {name} differs")
        golden_summary = json.loads((directory / f"{path.stem}.json").read_text())
        if json.loads(json.dumps(summary, sort_keys=True)) != golden_summary:
            problems.append("summary differs")
        status = "identical" if not problems else "DIFFERENT: " + "; ".join(problems)
        print(f"{path.stem}: {len(columns)} columns {status}")
        failures += bool(problems)
    print(f"{len(checked) - failures}/{len(checked)} scenes bit-identical")
    return 1 if failures else 0


if __name__ == "__main__":
    mode = sys.argv[1] if len(sys.argv) > 1 else "check"
    where = Path(sys.argv[2]) if len(sys.argv) > 2 else Path("/tmp/gears-golden")
    if mode == "save":
        save(where)
    else:
        sys.exit(check(where))
