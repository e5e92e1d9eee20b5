"""How long recording one revolution (3600 steps) into a .rrd file takes.

    .venv/bin/python benchmarks/bench_recording.py [SCENE] [--repeats 5]

Rows (median of the repeats; the simulation and the meshes are computed once, outside the timing):
- columns, series only:  explorer.view.rerun.recording writing the series and events with send_columns
- columns, with 3D:      the same plus the 3D parts (meshes + one Transform3D per step per part);
                         this is what `explorer record` does per scene (target <= 0.5 s)
- loop (baseline):       the series written the naive way, rr.set_time + rr.log per step and
                         series, into a file in the same process; the ratio column is
                         baseline time / row time (how much faster whole columns are)
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
from _timing import ROOT, median_time, print_table

from explorer import load_scene
from explorer.effects.pipeline import simulate
from explorer.view.rerun.recording import (
    APP_ID, TIMELINE_ANGLE, TIMELINE_STEP, TIMELINE_TIME, Run, series_layout, step_indexes, with_parts,
    write_recordings,
)

TARGET_S = 0.5


def loop_baseline(path: Path, result) -> None:
    """Per-step logging: what send_columns replaces."""
    import rerun as rr

    rec = rr.RecordingStream(APP_ID, recording_id="baseline")
    rec.set_sinks(rr.FileSink(str(path)))
    index = step_indexes(result)
    layout = series_layout(result.columns)
    values = {s.path: np.asarray(result.columns[s.column], dtype=float) for s in layout}
    for i in range(index[TIMELINE_STEP].size):
        rec.set_time(TIMELINE_TIME, duration=float(index[TIMELINE_TIME][i]))
        rec.set_time(TIMELINE_STEP, sequence=int(index[TIMELINE_STEP][i]))
        rec.set_time(TIMELINE_ANGLE, sequence=int(index[TIMELINE_ANGLE][i]))
        for path, v in values.items():
            rec.log(path, rr.Scalars(float(v[i])))
    rec.disconnect()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene", nargs="?", default=str(ROOT / "assets" / "scenes" / "valve_float_demo.toml"))
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)

    scene = load_scene(args.scene)
    result = simulate(scene)
    steps = result.columns["time_s"].size
    run_3d = with_parts(scene.name, result)
    run_series = Run(scene.name, result)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.rrd"
        write_recordings(out, [run_series])  # warm-up: imports, rerun's threads
        rows = [
            ("columns, series only", median_time(lambda: write_recordings(out, [run_series]), args.repeats, warmup=0)),
            ("columns, with 3D", median_time(lambda: write_recordings(out, [run_3d]), args.repeats, warmup=0)),
        ]
        size_3d = out.stat().st_size
        baseline = median_time(lambda: loop_baseline(Path(tmp) / "loop.rrd", result), max(1, args.repeats // 2),
                               warmup=0)
    rows.append(("loop (baseline)", baseline))
    n_series = len(series_layout(result.columns))
    print(f"scene {scene.name}: {steps} steps, {n_series} series, {len(run_3d.parts)} parts, "
          f"file {size_3d / 1e6:.1f} MB with 3D; median of {args.repeats}")
    print_table(["method", "time [s]", "ratio"], [(name, f"{seconds:.4f}", f"{baseline / seconds:.1f}") for name, seconds in rows])
    with_3d = rows[1][1]
    verdict = "meets" if with_3d <= TARGET_S else "MISSES"
    print(f"recording with 3D: {with_3d:.3f} s, {verdict} the target of {TARGET_S} s per revolution")
    return 0


if __name__ == "__main__":
    sys.exit(main())
