"""`explorer residual`: residual vibration of the elastic valve over a speed range."""

from __future__ import annotations

import argparse
import sys

from ..core.outputs import HELP as OUTPUT_HELP, all_or_none, check_output, distinct_outputs, write_checked
from .simulate import add_scene_arguments, scene_from_args
from .progress import Progress
from .sweep import check_workers


HELP = """\
A sweep of drive.rpm (the engine and table of `explorer sweep`) with the elastic effect's residual
columns: residual_deviation_m, the largest distance of the valve from the lift the cam is made
for (a polydyne cam's wanted lift, else the rigid valve lift) over the revolution;
residual_amplitude_m, the vibration amplitude in the dwell after the rise; and, for a polydyne
cam with a polynomial rise, residual_closed_form_m, the linear closed form of that amplitude in
the runs where the valve never leaves the cam. The cam is not changed: a polydyne cam keeps its
design speed. The table as CSV (stdout without -o) or Parquet (-o X.parquet), with the sweep's
'# key: value' metadata lines; the chart as PNG.
"""


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer residual polydyne_demo.toml --rpm 1000:3000:21 -o residual.csv --plot residual.png
  explorer residual valve_float_demo.toml --rpm 1000,2000,3000 --workers 1 -o residual.parquet
"""


def register(sub) -> None:
    p = sub.add_parser("residual", help="residual vibration of the elastic valve over a speed range (table, plot)",
                       description=HELP + "\n" + OUTPUT_HELP, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--rpm", required=True, metavar="A:B:N|A,B,...", help="speeds: N from A to B rpm, or a list")
    p.add_argument("-o", "--output", metavar="TABLE.csv|TABLE.parquet", help="write the table here (default: stdout, CSV)")
    p.add_argument("--plot", metavar="CHART.png", help="write the chart here")
    p.add_argument("--workers", type=int, help="local worker processes (default: every core; 1: this process)")
    p.set_defaults(run=run)


def run(args) -> int:
    # local: loads when the command runs, not at `explorer --help`
    from ..studies.residual import chart_png, parse_speeds, residual_table
    from ..studies.sweep_table import table_format  # local: loads when the command runs, not at `explorer --help`
    speeds = parse_speeds(args.rpm)
    scene = scene_from_args(args)
    if args.output is not None:
        kind = table_format(args.output)
        table_out = check_output(args.output, "--output")
    else:
        kind, table_out = ".csv", check_output("-", "--output")
    plot_out = check_output(args.plot, "--plot", suffix=".png") if args.plot is not None else None
    distinct_outputs((table_out, plot_out), (scene.source,))
    workers = check_workers(args.workers)
    progress = Progress(sys.stderr)
    try:
        table = residual_table(scene, speeds, workers=workers, progress=progress)
    finally:
        progress.end()
    if not table.complete:
        return 130
    with all_or_none():  # the table and its chart, or neither
        write_checked(table_out, table.parquet_bytes() if kind == ".parquet" else table.csv_text())
        if plot_out is not None:
            write_checked(plot_out, chart_png(scene, table))
    return 0
