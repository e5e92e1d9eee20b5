"""Bit-identity check of `simulate`, `sweep` and the 3D parts on every built-in scene (issue #12:
results bit-identical; issue #23: the plug-in refactor changes no figure, table or part).

    .venv/bin/python benchmarks/golden_scenes.py save  [DIR]   # from the unchanged code
    .venv/bin/python benchmarks/golden_scenes.py check [DIR]   # after a change: exit 1 on any difference

Stores in DIR (default /tmp/gears-golden), per scene:
- the result's columns (.npz) and summary (.json, timings removed: they are measured, not
  computed), and the JSON text itself with the timings zeroed (.txt: the text, key order included);
- the table of a small sweep (.sweep.npz): five speeds about the scene's own, and with a [valve]
  two lashes too (so the sweep engine's speed groups and every engine -- compiled, shared,
  simulate -- are exercised);
- a digest of the 3D parts (.parts.json): the layout, every part's vertices and faces and every
  pose of the browser's and the recordings' drawing (explorer.view.parts), as SHA-256 of the bytes.
Columns are compared with np.array_equal (bit for bit, NaN-aware via equal_nan where the golden
column has NaNs), summaries with == (a difference names its keys: +added, -gone, changed), texts and
digests as strings.
Golden data is never committed: it is made from the code before a change.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

# One LAPACK thread, as `make` runs everything: a threaded LAPACK sums in another order, and the
# tabulated law's spline (table_demo) and the spring chain's eigen-decomposition (spring_surge)
# then differ by ~1e-9 relative between one and two threads. Set before numpy loads OpenBLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

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


def _zero_timings(value):
    if isinstance(value, dict):
        return {k: (0.0 if k in TIMING_KEYS else _zero_timings(v)) for k, v in value.items()}
    if isinstance(value, list):
        return [_zero_timings(v) for v in value]
    return value


def json_text(path: Path) -> str:
    """The result's JSON text with its measured timings zeroed (key order as written)."""
    sys.path.insert(0, str(ROOT))
    from explorer import load_scene, simulate

    return json.dumps(_zero_timings(json.loads(simulate(load_scene(path)).json_text())), indent=2)


def sweep_columns(path: Path) -> dict:
    sys.path.insert(0, str(ROOT))
    from explorer import load_scene, sweep

    scene = load_scene(path)
    rpm = scene.drive.rpm
    vary = {"drive.rpm": [f * rpm for f in (0.8, 0.9, 1.0, 1.1, 1.2)]}
    if scene.valve is not None:
        lash = scene.valve.lash
        vary["valve.lash"] = [f"{lash!r} m", f"{lash + 2e-5!r} m"]
    table = sweep(scene, vary=vary, workers=1)
    return {k: np.asarray(v) for k, v in table.columns.items()}


def parts_digest(path: Path) -> dict:
    """SHA-256 of the layout, of every part's vertices and faces and of every pose."""
    import dataclasses
    import hashlib

    sys.path.insert(0, str(ROOT))
    from explorer import load_scene, simulate
    from explorer.view import parts as meshes

    def digest(*arrays) -> str:
        h = hashlib.sha256()
        for a in arrays:
            h.update(np.ascontiguousarray(np.asarray(a)).tobytes())
        return h.hexdigest()

    scene = load_scene(path)
    result = simulate(scene)
    lay = meshes.layout(scene, result)
    out = {"layout": repr(dataclasses.astuple(lay))}
    for name, mesh in sorted(meshes.build_parts(scene, result, lay=lay).items()):
        out[f"part {name}"] = digest(mesh.vertices, mesh.faces)
        out[f"colour {name}"] = repr(meshes.PART_COLORS[name])
    for name, (pos, wxyz) in sorted(meshes.part_poses(scene, result, magnification=3.0, lay=lay).items()):
        out[f"pose {name}"] = digest(pos, wxyz)
    return out


def save(directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    for path in SCENES:
        columns, summary = run(path)
        np.savez(directory / f"{path.stem}.npz", **columns)
        (directory / f"{path.stem}.json").write_text(json.dumps(summary, sort_keys=True, indent=1))
        (directory / f"{path.stem}.txt").write_text(json_text(path))
        np.savez(directory / f"{path.stem}.sweep.npz", **sweep_columns(path))
        (directory / f"{path.stem}.parts.json").write_text(json.dumps(parts_digest(path), indent=1))
        print(f"saved {path.stem}: {len(columns)} columns, sweep, parts")


def summary_differences(golden, new, prefix: str = "") -> list[str]:
    """The summary's keys that differ, dotted paths: +key added, -key gone, key changed."""
    if not (isinstance(golden, dict) and isinstance(new, dict)):
        return [] if golden == new else [prefix or "(the summary)"]
    out = [f"+{prefix}{k}" for k in sorted(set(new) - set(golden))]
    out += [f"-{prefix}{k}" for k in sorted(set(golden) - set(new))]
    for k in sorted(set(golden) & set(new)):
        out += summary_differences(golden[k], new[k], f"{prefix}{k}.") if isinstance(golden[k], dict) else (
            [] if golden[k] == new[k] else [f"{prefix}{k}"])
    return out


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
            problems.append("summary differs (" + ", ".join(summary_differences(golden_summary, summary)) + ")")
        if (directory / f"{path.stem}.txt").exists() and json_text(path) != (directory / f"{path.stem}.txt").read_text():
            problems.append("JSON text differs")
        if (directory / f"{path.stem}.sweep.npz").exists():
            table = sweep_columns(path)
            with np.load(directory / f"{path.stem}.sweep.npz") as golden:
                if set(golden.files) != set(table):
                    problems.append(f"sweep columns differ: {sorted(set(golden.files) ^ set(table))}")
                problems += [f"sweep column {name} differs" for name in sorted(set(golden.files) & set(table))
                             if not np.array_equal(golden[name], table[name], equal_nan=golden[name].dtype.kind == "f")]
        if (directory / f"{path.stem}.parts.json").exists():
            golden_parts = json.loads((directory / f"{path.stem}.parts.json").read_text())
            parts = parts_digest(path)
            problems += [f"3D {key} differs" for key in sorted(set(golden_parts) | set(parts))
                         if golden_parts.get(key) != parts.get(key)]
        status = "identical" if not problems else "DIFFERENT: " + "; ".join(problems)
        print(f"{path.stem}: {len(columns)} columns {status}")
        failures += bool(problems)
    print(f"{len(checked) - failures}/{len(checked)} scenes bit-identical")
    return 1 if failures else 0


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mode", nargs="?", choices=("save", "check"), default="check",
                        help="save from the unchanged code, or check after a change (default)")
    parser.add_argument("dir", nargs="?", type=Path, default=Path("/tmp/gears-golden"),
                        help="where the golden data is (default /tmp/gears-golden)")
    args = parser.parse_args()
    if args.mode == "save":
        save(args.dir)
    else:
        sys.exit(check(args.dir))
