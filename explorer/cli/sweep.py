"""`explorer sweep`: many runs of a scene, one row of figures per run, to Parquet or CSV."""

from __future__ import annotations

import argparse
import sys
import time

from ..core.errors import InputError
from ..core.outputs import HELP as OUTPUT_HELP, all_or_none, check_output, distinct_outputs
from ..scene.builtin import default_scene
from ..studies.sweep_spec import SWEEP_KEYS
from .progress import Progress

HELP = """\
Sweep a scene over grids of its values and random samples: one run (one revolution, the scene's
effects) per point, one table row per run with the varied inputs and the figures a designer
reads -- rigid minimum contact force and float speed (forces); peak camshaft torque (contact);
first separation angle, separations, flight time, largest deviation from the rigid lift, peak
linkage force and camshaft back-pressure, lift-off delay, seating velocity, seat impacts and the
largest bounce (elastic). SI units in the column names; only what the scene's effects compute.

Grids: --vary KEY=START:STOP:COUNT (COUNT points, ends included; --log after it spaces that one
geometrically), or KEY=V1,V2,...; several --vary make the product. Samples (tolerance studies):
--sample KEY="normal(MEAN, SD)" or "uniform(LOW, HIGH)" with --runs N draws per grid point and
--seed. Values carry units as in scene files ("0.3 mm", "3 kN/mm"; bare: the key's SI unit,
drive.rpm in rev/min; a unit written once applies to both ends: 0.1:0.5 mm:5).
Sweepable keys: {keys}.

The table (-o, .parquet or .csv) is written when the sweep ends, atomically; Ctrl-C stops it and
writes the runs finished so far, marked incomplete (Parquet metadata explorer.complete = false;
CSV: a '# complete: false' line); SIGTERM stops it and writes nothing. Runs use every core here by
default (--workers, at most the usable cores), or a Dask cluster (--scheduler tcp://HOST:8786, needs
the `cluster` extra). More than 10^7 runs need --yes; a plan whose table would not fit in the
available memory is refused, --yes or not (docs/reference/bad-input.md).
"""

EPILOG = """\
examples:
  explorer sweep assets/scenes/valve_float_demo.toml --vary drive.rpm=1000:6000:500 -o speeds.parquet --plot speeds.png
  explorer sweep SCENE --vary drive.rpm=2000:6000:60 --vary linkage.stiffness=1e6:1e8:40 --log -o map.parquet --plot map.png
  explorer sweep SCENE --sample valve.lash="normal(0.25 mm, 0.02 mm)" --runs 10000 --seed 1 -o lash.csv --plot lash.png
  explorer sweep SCENE --vary drive.rpm=1000:6000:200 -o s.parquet --record s.rrd && explorer view s.rrd
"""


class _Vary(argparse.Action):
    """--vary appends a grid; --log marks the grid before it as geometric."""

    def __call__(self, parser, namespace, values, option_string=None):
        grids = getattr(namespace, "grids", None) or []
        if option_string == "--log":
            if not grids:  # reported by run(): an error here would escape as a traceback
                namespace.stray_log = True
                return
            grids[-1] = (grids[-1][0], True)
        else:
            grids.append((values, False))
        namespace.grids = grids


def register(sub) -> None:
    p = sub.add_parser("sweep", help="many runs of a scene: a table of figures per run (Parquet/CSV), maps, tolerances",
                       description=HELP.format(keys=", ".join(SWEEP_KEYS)) + "\n" + OUTPUT_HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", nargs="?", help="scene file (TOML); default: the built-in default scene")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
                   help="override a scene value in every run (repeatable)")
    p.add_argument("--vary", action=_Vary, metavar="KEY=START:STOP:COUNT", help="a grid over a key (repeatable: product)")
    p.add_argument("--log", action=_Vary, nargs=0, help="the --vary before it is spaced geometrically")
    p.add_argument("--sample", action="append", default=[], metavar='KEY="normal(MEAN, SD)"',
                   help="a random draw per run: normal(MEAN, SD) or uniform(LOW, HIGH) (repeatable)")
    p.add_argument("--runs", type=int, help="draws per grid point (with --sample)")
    p.add_argument("--seed", type=int, help="seed of the random draws, 0 to 2**128 - 1 (default: fresh)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.parquet|OUT.csv", help="the table")
    p.add_argument("--plot", metavar="OUT.png", help="a picture: lines (1 key), heat maps (2), histograms (samples)")
    p.add_argument("--record", metavar="OUT.rrd", help="a rerun recording with the swept keys as timelines")
    p.add_argument("--workers", type=int, help="local worker processes (default: every core; 1: this process; "
                   "more than the usable cores are capped)")
    p.add_argument("--scheduler", metavar="tcp://HOST:PORT", help="run on this Dask distributed scheduler")
    p.add_argument("--yes", action="store_true", help="allow more than 10^7 runs")
    p.set_defaults(run=run, grids=None)


def _split(text: str, option: str) -> tuple[str, str]:
    if "=" not in text:
        raise InputError(option, text[:60], "write KEY=VALUE, such as drive.rpm=1000:6000:100")
    key, _, value = text.partition("=")
    return key.strip(), value.strip().strip('"').strip("'")


def check_workers(workers: int | None, scheduler: str | None = None) -> int | None:
    """--workers: at least 1, at most the usable cores (capped, with a note on stderr); not with
    --scheduler (the cluster has its own)."""
    from ..studies.sweep_run import worker_count  # local: loads when the command runs, not at `explorer --help`

    if workers is None:
        return None
    if scheduler is not None:
        raise InputError("<command line>", "--workers", "sets local worker processes; with --scheduler the cluster's "
                         "workers run the sweep")
    if workers < 1:
        raise InputError("<command line>", "--workers", f"at least 1, got {workers}")
    count, note = worker_count(workers)
    if note is not None:
        print(f"note: {note}", file=sys.stderr)
    return count


def run(args) -> int:
    from ..scene.scene import load_scene  # local: loads when the command runs, not at `explorer --help`
    # local: loads when the command runs, not at `explorer --help`
    from ..studies.sweep_run import SweepResult, plan_from, run_plan
    from ..studies.sweep_table import table_format  # local: loads when the command runs, not at `explorer --help`

    if getattr(args, "stray_log", False):
        raise InputError("--log", "-", "--log follows the --vary it applies to")
    scene = load_scene(str(default_scene()) if args.scene is None else args.scene, args.overrides)
    vary, log = {}, []
    for text, is_log in args.grids or []:
        key, value = _split(text, "--vary")
        if key in vary:
            raise InputError("--vary", key, "varied twice")
        vary[key] = value
        if is_log:
            log.append(key)
    sample = {}
    for text in args.sample:
        key, value = _split(text, "--sample")
        if key in sample:
            raise InputError("--sample", key, "sampled twice")
        sample[key] = value
    plan = plan_from(scene, vary, sample, args.runs, args.seed, args.yes, tuple(log))
    # every output checked before any work
    table_format(args.output)
    out = check_output(args.output, "--output")
    plot_out = check_output(args.plot, "--plot", ".png") if args.plot is not None else None
    record_out = check_output(args.record, "--record", ".rrd") if args.record is not None else None
    distinct_outputs((out, plot_out, record_out), (scene.source,))
    workers = check_workers(args.workers, args.scheduler)
    report = sys.stderr if out.is_stdout() else sys.stdout
    progress = Progress(sys.stderr)
    started = time.perf_counter()
    try:
        table = run_plan(scene, plan, workers=workers, scheduler=args.scheduler, progress=progress)
    finally:
        progress.end()
    result = SweepResult(table)
    with all_or_none():  # the table, its picture and its recording, or none of them
        try:
            result.write(out)
            if plot_out is not None:
                result.plot(plot_out)
            if record_out is not None:
                result.record(record_out)
        except OSError as exc:  # a full disk while writing a temporary
            raise InputError(getattr(exc, "filename", None) or out.name, "-", f"cannot write: {exc.strerror or exc}") from None
    seconds = time.perf_counter() - started
    failed = int(sum(table.columns["run_failed"])) if len(table) else 0
    state = "" if table.complete else f" (INCOMPLETE: interrupted, {len(table)} of {plan.runs} runs kept)"
    print(f"{out.name}: {len(table)} runs{state}, {len(table.columns)} columns, {seconds:.2f} s "
          f"({len(table) / max(seconds, 1e-9):.1f} runs/s)", file=report)
    if failed:
        print(f"  warning: {failed} runs failed (run_failed = 1, figures NaN): see `explorer simulate` on one of them",
              file=report)
    if not table.complete:
        return 130
    return 0
