"""`explorer spectrum`: harmonics of the valve drive's acceleration against cam order."""

from __future__ import annotations

import argparse

from ..core.errors import InputError
from ..core.outputs import HELP as OUTPUT_HELP, all_or_none, check_output, distinct_outputs, write_checked
from .simulate import add_scene_arguments, scene_from_args

HELP = """\
Harmonic content of the drive acceleration ratio * w^2 * L'' of the scene at its speed, against
cam order (times per revolution), from the FFT of the analytic curve, with the linkage's natural
frequency marked as a cam order. Table as CSV (stdout without -o), chart as PNG.
"""


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer spectrum elastic_float.toml --orders 60 -o spectrum.csv --plot spectrum.png
  explorer spectrum cycloidal_demo.toml --orders 30 --set drive.rpm=6000
"""


def register(sub) -> None:
    p = sub.add_parser("spectrum", help="harmonics of the valve acceleration against cam order (table, plot)",
                       description=HELP + "\n" + OUTPUT_HELP, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--orders", type=int, default=100, metavar="N", help="orders 1..N (default 100)")
    p.add_argument("-o", "--output", metavar="TABLE.csv", help="write the table here, a name ending in .csv (default: stdout)")
    p.add_argument("--plot", metavar="CHART.png", help="write the chart here")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..effects.lift import build_lift  # local: loads when the command runs, not at `explorer --help`
    # local: loads when the command runs, not at `explorer --help`
    from ..studies.spectrum import MAX_ORDERS, acceleration_spectrum, chart_png, table_text

    if not 1 <= args.orders <= MAX_ORDERS:
        raise InputError("<command line>", "--orders", f"must be between 1 and {MAX_ORDERS}, got {args.orders}")
    scene = scene_from_args(args)
    table_out = check_output("-" if args.output is None else args.output, "--output", suffix=".csv")
    plot_out = check_output(args.plot, "--plot", suffix=".png") if args.plot is not None else None
    distinct_outputs((table_out, plot_out), (scene.source,))
    spectrum = acceleration_spectrum(scene, build_lift(scene), args.orders)
    with all_or_none():  # the table and its chart, or neither
        write_checked(table_out, table_text(scene, spectrum))
        if plot_out is not None:
            write_checked(plot_out, chart_png(scene, spectrum))
    return 0
