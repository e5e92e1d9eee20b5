"""The `explorer` command. Each subcommand lives in its own module with `register(subparsers)`;
modules are light to import (viser and rerun load only inside the command that runs)."""

from __future__ import annotations

import argparse
import os
import re
import sys

# One LAPACK thread unless the user chose otherwise, set before anything loads numpy: a threaded
# LAPACK sums in another order, and results would then depend on the machine's cores in their
# last digits (the tabulated law's spline and the spring chain's eigen-decomposition move by
# ~1e-9 relative between one and two threads). The matrices are small: threads gain nothing.
# The children the commands start (compute, viewers, Dask workers) inherit it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ..core.errors import InputError, echo
from ..core.plugins import resolve
from ..core.processes import Stopped, stop_signals_raise
from ..core.version import __version__

COMMAND_MODULES = [
    "explorer.cli.simulate",
    "explorer.cli.serve",
    "explorer.cli.record",
    "explorer.cli.view",
    "explorer.cli.bench",
    "explorer.cli.fit",
    "explorer.cli.sweep",
    "explorer.cli.export",
    "explorer.cli.residual",
    "explorer.cli.design",
    "explorer.cli.spectrum",
    "explorer.cli.check",
]

DESCRIPTION = """\
Valve-Gear Explorer: how a cam moves a valve.

A scene file (TOML) describes one valve gear at one camshaft speed and lists the effects to
compute; exactly those run (plus what they need), each timed:
  kinematics  lift, velocity, acceleration, jerk; pressure angle, radii of curvature
  lash        take-up and seating instants with the finite impact velocities (Schenker's v1, v2)
  forces      spring, friction, loads, contact force, required spring force, float speed
  contact     contact force, self-locking margin, camshaft torque, Hertz stress, cam width
  elastic     elastic linkage: lift-off, separation, re-contact, seat impact, linkage force
  gear        lever ratios and statics of the lever, rocking-cam, rolling-lever and trip gears
Built-in scenes are in assets/scenes; with no scene, the default is Schenker's 1902 exhaust
cam (Fig. 2 of his paper), computed exactly from its circular arcs.
"""

EPILOG = """\
examples:
  explorer serve                       3D explorer of the default scene on http://127.0.0.1:8080
  explorer simulate assets/scenes/schenker1902_fig2.toml -o out.csv --summary out.json
  explorer simulate SCENE --set drive.rpm=300 --set valve.lash="0.3 mm" --set 'effects=["elastic"]'
  explorer record SCENE -o run.rrd --sweep drive.rpm=200,240,300 && explorer view run.rrd
  explorer bench assets/scenes/schenker1902_fig2.toml --output-dir out   (accuracy vs CPU time)
  explorer fit assets/scenes/rocking_cam.toml --lift "9 mm" --open-angle "220 deg"   (rocking-cam contour)
  explorer sweep SCENE --vary drive.rpm=1000:6000:500 -o speeds.parquet --plot speeds.png   (operating range)
  explorer export SCENE --format dxf --tolerance "1 um"   (the cam to make it: csv, dxf, stl, glb, grind)
  explorer residual assets/scenes/polydyne_demo.toml --rpm 1000:3000:21 --plot r.png   (vibration vs speed)
  explorer design assets/scenes/spline_demo.toml --objective peak-acceleration --max-pressure-angle 30   (spline lift)
  explorer spectrum SCENE --orders 60 --plot s.png   (harmonics of the valve acceleration vs cam order)
  explorer check SCENE --rpm 800:6500:200 -o report.json   (is the design acceptable? rules, limits, sources)
  explorer <command> --help            details of one command

Quantities in scene files carry units ("20 mm", "385 kgf", "2.9 kgf*s**2/m"); a bare number
means the SI unit of its key, except angles (deg) and drive.rpm (rev/min).
Bad input ends with one line 'error: FILE: KEY: reason' and exit status 2; nothing is written.
"""


class Parser(argparse.ArgumentParser):
    """argparse with the program's one-line errors: `error: <command line>: OPTION: reason`, exit
    status 2, the value cut to a readable length (argparse prints its usage and the whole value)."""

    def error(self, message: str):
        option = "-"
        if message.startswith("argument "):  # "argument --seed: invalid int value: '...'"
            option, _, message = message[len("argument "):].partition(": ")
            option = option.split("/")[-1]
        # the values argparse quotes ('...'), each cut by echo; the rest of its message kept
        reason = _QUOTED.sub(lambda m: echo(m.group(1)), message.replace("\n", " "))
        raise SystemExit(_one_line(InputError("<command line>", option, f"{reason} (see {self.prog} --help)")))


_QUOTED = re.compile(r"'((?:[^'\\]|\\.)*)'", re.DOTALL)


def _one_line(exc: InputError) -> int:
    print(f"error: {exc}", file=sys.stderr)
    return 2


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="explorer", description=DESCRIPTION, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        resolve(f"{name}:register")(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 0
    try:
        with stop_signals_raise():  # SIGTERM/SIGHUP unwind like Ctrl-C: temporaries go, workers end
            return int(args.run(args) or 0)
    except Stopped as exc:
        print(f"stopped by {exc}", file=sys.stderr)
        return 128 + exc.signum
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file or port the user named cannot be used: one line, no traceback
        return _one_line(InputError(exc.filename or "-", "-", exc.strerror or exc))  # cut like any message
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
