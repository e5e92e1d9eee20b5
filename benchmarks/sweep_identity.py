"""Bit-identity of the batch engine's sweep rows across a change of the compiled kernel (a local
safety net, not a test): random runs over all ten sweep keys on elastic_float.toml and
valve_float_demo.toml (and speed-only sweeps), each table computed by the compiled path
(sweep_engine.compute_chunk) and saved, then compared with np.array_equal (NaN equal to NaN).

    .venv/bin/python benchmarks/sweep_identity.py record  /tmp/rows_before.npz [--root /tmp/before]
    .venv/bin/python benchmarks/sweep_identity.py compare /tmp/rows_before.npz

--root: the checkout whose engine computes the rows (default: this one). 700 runs: per scene 300
runs with all keys (stiffness log-uniform 1e6..1e11, a fifth with zero lash, a third with
restitution 0.9, a third undamped, a third without friction) and 50 speed-only runs.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

KEYS = ("drive.rpm", "linkage.stiffness", "linkage.damping", "valve.mass", "valve.oscillating_mass", "valve.lash",
        "spring.preload", "spring.rate", "loads.friction", "seat.restitution")
SCENES = ("elastic_float.toml", "valve_float_demo.toml")
RUNS, SPEED_RUNS = 300, 50


def _values(rng, n):
    v = np.empty((n, len(KEYS)))
    v[:, 0] = rng.uniform(1500.0, 6000.0, n)
    v[:, 1] = np.exp(rng.uniform(math.log(1e6), math.log(1e11), n))
    v[:, 2] = rng.uniform(0.0, 20.0, n)
    v[rng.random(n) < 1 / 3, 2] = 0.0
    v[:, 3] = rng.uniform(0.08, 0.2, n)
    v[:, 4] = rng.uniform(0.5, 1.0, n) * v[:, 3]
    v[:, 5] = rng.uniform(0.0, 4e-4, n)
    v[rng.random(n) < 0.2, 5] = 0.0
    v[:, 6] = rng.uniform(120.0, 320.0, n)
    v[:, 7] = rng.uniform(5e3, 6e4, n)
    v[:, 8] = rng.uniform(0.0, 40.0, n)
    v[rng.random(n) < 1 / 3, 8] = 0.0
    v[:, 9] = rng.choice([0.0, 0.3, 0.9], n)
    return v


def tables(root: Path) -> tuple[dict[str, np.ndarray], dict[str, tuple[str, ...]]]:
    """(table per key, its column names)."""
    sys.path.insert(0, str(root))
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns

    out, columns = {}, {}
    rng = np.random.default_rng(2704)
    for name in SCENES:
        base = load_scene(root / "assets" / "scenes" / name, ['effects=["elastic"]'])
        names = result_columns(base)
        shared = _Shared()
        assert engine_for(base, shared).name == "compiled"
        out[f"{name}:all"] = compute_chunk(base, KEYS, _values(rng, RUNS), names, shared)
        columns[f"{name}:all"] = columns[f"{name}:rpm"] = tuple(names)
        rpm = rng.uniform(1500.0, 6000.0, (SPEED_RUNS, 1))
        out[f"{name}:rpm"] = compute_chunk(base, ("drive.rpm",), rpm, names, shared)
    return out, columns


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mode", choices=("record", "compare"))
    ap.add_argument("file")
    ap.add_argument("--root", default=str(Path(__file__).resolve().parents[1]))
    args = ap.parse_args()
    got, columns = tables(Path(args.root).resolve())
    if args.mode == "record":
        np.savez(args.file, **got)
        print(f"recorded {sum(t.shape[0] for t in got.values())} rows to {args.file}")
        return
    ref = np.load(args.file)
    bad = 0
    for key, table in got.items():
        same = table.shape == ref[key].shape and np.array_equal(table, ref[key], equal_nan=True)
        print(f"{key:32s} {table.shape[0]:4d} rows  {'identical' if same else 'DIFFERENT'}")
        if not same and table.shape == ref[key].shape:  # which columns, in how many rows
            for j, name in enumerate(columns[key]):
                a, b = table[:, j], ref[key][:, j]
                rows = int(np.count_nonzero(~((a == b) | (np.isnan(a) & np.isnan(b)))))
                if rows:
                    print(f"    {name}: {rows} rows differ")
        bad += not same
    print(f"{sum(t.shape[0] for t in got.values())} rows: {'all identical' if not bad else f'{bad} tables differ'}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
