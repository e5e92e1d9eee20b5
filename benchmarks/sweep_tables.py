"""Bit-identity of whole sweep tables before/after a change (issue #27.5): golden_scenes.py checks
a five-speed sweep per scene; this one the long sweeps whose rigid figures are computed in
batches (the float demo's 1000 speeds, speed x lash and speed x preload maps, elastic_float's 400
speeds, 12 speeds of five more scenes). Every column compared with np.array_equal, NaN positions
included.

    .venv/bin/python benchmarks/sweep_tables.py save  /tmp/sweep-tables.pkl   # the code before
    .venv/bin/python benchmarks/sweep_tables.py check /tmp/sweep-tables.pkl   # after: exit 1 on a difference
"""

from __future__ import annotations

import argparse
import pickle
import sys

import numpy as np

from _timing import ROOT

CASES = [
    ("valve_float_demo.toml", {"drive.rpm": "1000:6000:1000"}),
    ("valve_float_demo.toml", {"drive.rpm": "500:9000:300", "valve.lash": "0.0001:0.0005:4"}),
    ("valve_float_demo.toml", {"drive.rpm": "100:20000:200", "spring.preload": "50:400:3"}),
    ("elastic_float.toml", {"drive.rpm": "3000:5000:400"}),
] + [(name, {"drive.rpm": "500:4000:12"}) for name in
     ("acceleration_demo.toml", "bucket_tappet.toml", "cycloidal_demo.toml", "finger_follower.toml",
      "finger_hla_pumpup.toml")]


def tables() -> dict:
    sys.path.insert(0, str(ROOT))
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_run import plan_from, run_plan

    out = {}
    for name, vary in CASES:
        scene = load_scene(ROOT / "assets" / "scenes" / name)
        table = run_plan(scene, plan_from(scene, vary, yes=True), workers=1)
        out[(name, str(vary))] = {k: np.array(v) for k, v in table.columns.items()}
        print(f"{name} {vary}: {len(table)} runs", flush=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("action", choices=("save", "check"))
    parser.add_argument("path")
    args = parser.parse_args()
    got = tables()
    if args.action == "save":
        with open(args.path, "wb") as handle:
            pickle.dump(got, handle)
        return
    with open(args.path, "rb") as handle:
        ref = pickle.load(handle)
    bad = [f"{case}: {'columns' if ref[case].keys() != got[case].keys() else column}"
           for case in ref for column in ref[case]
           if ref[case].keys() != got[case].keys()
           or not np.array_equal(ref[case][column], got[case][column], equal_nan=ref[case][column].dtype.kind == "f")]
    print("\n".join(f"differs: {b}" for b in bad) if bad else f"{len(ref)} sweep tables identical")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
