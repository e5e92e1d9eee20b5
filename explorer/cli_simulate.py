"""`explorer simulate`: one revolution of a scene to CSV and a JSON summary."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .errors import InputError

HELP = """\
Simulate one revolution of a scene: every effect the scene lists, nothing else.

Writes one CSV row per step (cam_angle_deg, time_s, follower_lift_m, valve_lift_m,
valve_velocity_m_s, valve_accel_m_s2, valve_jerk_m_s3 and one column per further quantity the
effects compute; SI units in the names) and a JSON summary (peaks, impact velocities, events,
each effect with its compute time). Without -o/--summary it prints the summary.
"""


def add_scene_arguments(parser: argparse.ArgumentParser, optional: bool = True) -> None:
    parser.add_argument(
        "scene", nargs="?" if optional else None, help="scene file (TOML); default: the built-in default scene"
    )
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
        help='override a scene value, e.g. --set drive.rpm=600 --set valve.lash="0.5 mm" (repeatable)',
    )


def scene_from_args(args):
    from .scene import load_scene
    from .scenes import default_scene

    path = args.scene or str(default_scene())
    return load_scene(path, args.overrides)


def register(sub) -> None:
    p = sub.add_parser("simulate", help="one revolution to CSV + JSON summary", description=HELP,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("-o", "--output", metavar="OUT.csv", help="write the per-step columns here")
    p.add_argument("--summary", metavar="OUT.json", help="write the summary here")
    p.set_defaults(run=run)


def _check_writable(path: str, option: str) -> None:
    """Refuse an output path that cannot be written before any work, so that a bad --summary
    does not leave the CSV written and the summary missing."""
    target = Path(path)
    parent = target.resolve().parent
    if target.is_dir():
        raise InputError(path, option, "is a directory, not a file name")
    if not parent.is_dir():
        raise InputError(path, option, f"directory {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(path, option, f"directory {parent} is not writable")


def _write(path: str, option: str, text: str) -> None:
    from .result import write_atomic

    try:
        write_atomic(path, text)
    except OSError as exc:  # full disk, a race with the checks above: still one line
        raise InputError(path, option, f"cannot write: {exc.strerror or exc}") from None


def run(args) -> int:
    from .effects import simulate

    scene = scene_from_args(args)
    for path, option in ((args.output, "--output"), (args.summary, "--summary")):
        if path:
            _check_writable(path, option)
    result = simulate(scene)
    if args.output:
        _write(args.output, "--output", result.csv_text())
    if args.summary:
        _write(args.summary, "--summary", result.json_text())
    if not args.output and not args.summary:
        sys.stdout.write(result.json_text())
    else:
        _print_brief(result)
    return 0


def _print_brief(result) -> None:
    s = result.summary
    parts = [f"{s['scene']}: {s['steps_per_revolution']} steps at {s['rpm']:g} rpm"]
    for name, info in s["effects"].items():
        parts.append(f"  {name:<11s} {1e3 * info['compute_time_s']:9.3f} ms")
    for w in s.get("warnings", []):
        parts.append(f"  warning: {w}")
    print("\n".join(parts))
