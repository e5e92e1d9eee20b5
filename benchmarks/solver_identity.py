"""Bit-identity check of the elastic solvers across a refactor (a local safety net, not a test).

    .venv/bin/python benchmarks/solver_identity.py record  [DIR]   # golden .npz from this code
    .venv/bin/python benchmarks/solver_identity.py compare [DIR]   # bit for bit against them

For every scene in assets/scenes/*.toml whose effects include "elastic" (as written, and with
effects = ["elastic"] added to those that do not list it), and for each solver method, the
result columns of `simulate` (and the elastic events) are saved; a scene/method pair that the
loader or a solver refuses is recorded with its error message, which must also stay the same.
DIR defaults to /tmp/solver-golden. Golden files are not committed.
"""

from __future__ import annotations

import json
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from explorer import load_scene, simulate  # noqa: E402

METHODS = ("exact", "schenker1902", "scipy", "taylor")


def cases():
    for path in sorted((ROOT / "assets" / "scenes").glob("*.toml")):
        base = load_scene(path)
        variants = []
        if "elastic" in base.effects:
            variants.append(("as-is", []))
        else:
            effects = list(base.effects) + ["elastic"]
            variants.append(("with-elastic", ["effects=" + json.dumps(effects)]))
        for tag, overrides in variants:
            for method in METHODS:
                yield f"{path.stem}.{tag}.{method}", path, overrides + [f'solver.method="{method}"']


def run(path, overrides) -> dict:
    try:
        scene = load_scene(path, overrides)
        result = simulate(scene)
    except Exception as exc:  # noqa: BLE001 - the refusal itself is recorded
        return {"error": np.array(f"{type(exc).__name__}: {exc}")}
    out = {f"col:{name}": np.asarray(values) for name, values in result.columns.items()}
    events = [e.as_dict() for e in result.events]
    out["events"] = np.array(json.dumps(events, sort_keys=True, default=repr))
    counts = result.summary.get("elastic_event_counts")
    out["event_counts"] = np.array(json.dumps(counts, sort_keys=True))
    return out


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Bit for bit (NaN columns too, which np.array_equal calls different from themselves)."""
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def main(argv) -> int:
    mode = argv[1] if len(argv) > 1 else "compare"
    folder = pathlib.Path(argv[2] if len(argv) > 2 else "/tmp/solver-golden")
    folder.mkdir(parents=True, exist_ok=True)
    failures = 0
    for name, path, overrides in cases():
        t0 = time.perf_counter()
        got = run(path, overrides)
        dt = time.perf_counter() - t0
        file = folder / f"{name}.npz"
        if mode == "record":
            np.savez(file, **got)
            what = "error" if "error" in got else f"{sum(k.startswith('col:') for k in got)} columns"
            print(f"recorded {name:55s} {what} ({dt:.1f} s)", flush=True)
            continue
        with np.load(file) as golden:
            want = {k: golden[k] for k in golden.files}
        bad = sorted(set(want) ^ set(got))
        bad += [k for k in want if k in got and not _same_bits(want[k], got[k])]
        if bad:
            failures += 1
            print(f"DIFFERS  {name:55s} {bad[:6]}", flush=True)
            if "error" in want or "error" in got:
                print("   golden:", want.get("error"), "\n   now:   ", got.get("error"))
        else:
            print(f"same     {name:55s} ({dt:.1f} s)", flush=True)
    if mode == "compare":
        print("ALL BIT-IDENTICAL" if not failures else f"{failures} case(s) differ")
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
