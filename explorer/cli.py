"""The `explorer` command. Each subcommand lives in its own module with `register(subparsers)`;
modules are light to import (viser and rerun load only inside the command that runs)."""

from __future__ import annotations

import argparse
import importlib
import sys

from .errors import InputError

COMMAND_MODULES = [
    "explorer.cli_simulate",
    "explorer.cli_serve",
    "explorer.cli_record",
    "explorer.cli_view",
    "explorer.cli_bench",
]

DESCRIPTION = """\
Valve-Gear Explorer: how a cam moves a valve.

A scene file (TOML) describes one valve gear at one camshaft speed and lists the effects to
compute: kinematics (lift, velocity, acceleration, jerk), lash (take-up and seating impacts),
forces (spring requirement, float speed), contact (pressure angle, Hertz stress, torque),
elastic (linkage dynamics with lift-off, separation, re-contact and seat impact).
Built-in scenes are in assets/scenes; with no scene, the default is Schenker's 1902 exhaust
cam (Fig. 2 of his paper).
"""

EPILOG = """\
examples:
  explorer simulate assets/scenes/schenker1902_fig2.toml -o out.csv --summary out.json
  explorer simulate SCENE --set drive.rpm=300 --set valve.lash="0.3 mm"
  explorer <command> --help     details of one command

Bad input ends with one line 'error: FILE: KEY: reason' and exit status 2.
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="explorer", description=DESCRIPTION, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    from . import __version__

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "run", None):
        parser.print_help()
        return 0
    try:
        return int(args.run(args) or 0)
    except InputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a file or port the user named cannot be used: one line, no traceback
        print(f"error: {exc.filename or '-'}: -: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
