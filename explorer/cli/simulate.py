"""`explorer simulate`: one revolution of a scene to CSV and a JSON summary."""

from __future__ import annotations

import argparse
import sys

from ..core.outputs import HELP as OUTPUT_HELP, all_or_none, check_output, distinct_outputs, write_checked
from ..scene.builtin import default_scene
from .progress import ticking


HELP = """\
Simulate one revolution of a scene: every effect the scene lists, nothing else.

Writes one CSV row per step and a JSON summary (peaks, impact velocities, events, each effect
with its compute time). The CSV's columns, in this order (SI units in the names):
  cam_angle_deg, time_s,
  follower_lift_m, follower_velocity_m_s, follower_accel_m_s2, follower_jerk_m_s3,
  valve_lift_m, valve_velocity_m_s, valve_accel_m_s2, valve_jerk_m_s3,
  rigid_valve_lift_m, rigid_valve_velocity_m_s, rigid_valve_accel_m_s2, rigid_valve_jerk_m_s3,
then one column per further quantity the effects compute, in the order the effects run
(docs/reference/outputs.md lists them; the elastic effect adds valve_in_contact, 1 while the
linkage is loaded, and valve_phase, 0 seated, 1 contact, 2 flight, 3 stuck).
Without -o/--summary it prints the summary; with an output on /dev/stdout, the brief report
goes to stderr.
"""


def add_scene_arguments(parser: argparse.ArgumentParser, optional: bool = True) -> None:
    parser.add_argument(
        "scene", nargs="?" if optional else None, help="scene file (TOML) or a built-in scene by name (cycloidal_demo.toml); default: the built-in default scene"
    )
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
        help='override a scene value, e.g. --set drive.rpm=600 --set valve.lash="0.5 mm" (repeatable)',
    )


def scene_from_args(args):
    from ..scene.scene import load_scene  # local: loads when the command runs, not at `explorer --help`
    path = args.scene if args.scene is not None else str(default_scene())
    return load_scene(path, args.overrides)


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer simulate cycloidal_demo.toml -o run.csv --summary run.json
  explorer simulate schenker1902_fig2.toml --set drive.rpm=300 --set valve.lash="0.3 mm" --summary slow.json
  explorer simulate valve_float_demo.toml --set drive.rpm=3500 --set 'effects=["kinematics", "forces"]'
"""


def register(sub) -> None:
    p = sub.add_parser("simulate", help="one revolution to CSV + JSON summary", description=HELP + "\n" + OUTPUT_HELP,
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("-o", "--output", metavar="OUT.csv", help="write the per-step columns here")
    p.add_argument("--summary", metavar="OUT.json", help="write the summary here")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..effects.pipeline import simulate  # local: loads when the command runs, not at `explorer --help`
    scene = scene_from_args(args)
    # both outputs before any work, so that a bad --summary does not leave the CSV written
    # and the summary missing
    csv_out = check_output(args.output, "--output") if args.output is not None else None
    json_out = check_output(args.summary, "--summary") if args.summary is not None else None
    distinct_outputs((csv_out, json_out), (scene.source,))
    # hundreds of thousands of steps take seconds: the time elapsed on a terminal's stderr
    with ticking(sys.stderr, "simulate"):
        result = simulate(scene)
        with all_or_none():  # the columns and the summary, or neither
            if csv_out is not None:
                write_checked(csv_out, result.csv_chunks())  # in pieces: the largest step counts are gigabytes of text
            if json_out is not None:
                write_checked(json_out, result.json_text())
    if csv_out is None and json_out is None:
        sys.stdout.write(result.json_text())
    else:
        to_stdout = any(o is not None and o.is_stdout() for o in (csv_out, json_out))
        _print_brief(result, sys.stderr if to_stdout else sys.stdout)
    return 0


def _print_brief(result, stream) -> None:
    s = result.summary
    parts = [f"{s['scene']}: {s['steps_per_revolution']} steps at {s['rpm']:g} rpm"]
    for name, timing in result.timings.items():
        parts.append(f"  {name:<11s} {1e3 * timing.compute_time_s:9.3f} ms")
    for w in result.warnings:
        parts.append(f"  warning: {w}")
    print("\n".join(parts), file=stream)
