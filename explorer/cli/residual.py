"""`explorer residual`: residual vibration of the elastic valve over a speed range."""

from __future__ import annotations

import argparse
import sys


HELP = """\
Run the scene's elastic linkage at each speed and compare the valve with the lift the cam is made
for (a polydyne cam's wanted lift, else the rigid valve lift): the largest deviation over the
revolution, the vibration amplitude where the dwell after the rise starts, and for a polydyne cam
with a polynomial rise its closed form while the valve stays in contact. The cam is not changed:
a polydyne cam keeps its design speed. Table as CSV (stdout without -o), chart as PNG.
"""


def register(sub) -> None:
    from .simulate import add_scene_arguments
    from ..core.outputs import HELP as OUTPUT_HELP

    p = sub.add_parser("residual", help="residual vibration of the elastic valve over a speed range (table, plot)",
                       description=HELP + "\n" + OUTPUT_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--rpm", required=True, metavar="A:B:N|A,B,...", help="speeds: N from A to B rpm, or a list")
    p.add_argument("-o", "--output", metavar="TABLE.csv", help="write the table here (default: stdout)")
    p.add_argument("--plot", metavar="CHART.png", help="write the chart here")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..studies.bench import ProgressBar
    from .simulate import scene_from_args
    from ..core.outputs import check_output, write_checked
    from ..studies.residual import chart_png, parse_speeds, residual_sweep, table_text

    speeds = parse_speeds(args.rpm)
    scene = scene_from_args(args)
    table_out = check_output(args.output, "--output") if args.output else check_output("-", "--output")
    plot_out = check_output(args.plot, "--plot", suffix=".png") if args.plot else None
    progress = ProgressBar(sys.stderr) if speeds.size > 4 and sys.stderr.isatty() else None
    rows = residual_sweep(scene, speeds, progress)
    write_checked(table_out, table_text(scene, rows))
    if plot_out is not None:
        write_checked(plot_out, chart_png(scene, rows))
    return 0
