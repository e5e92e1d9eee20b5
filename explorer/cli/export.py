"""`explorer export`: the cam to make it (point table, DXF, STL/GLB solid, grinding table)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..core.errors import InputError, echo
from ..core.outputs import HELP as OUTPUT_HELP, check_output, distinct_outputs, write_checked
from ..core.units import to_si
from ..view.exports import FORMATS
from .progress import ticking
from .simulate import add_scene_arguments, scene_from_args

HELP = """\
Export a scene's cam to make it: a translating roller's, a bucket tappet's, a finger
follower's or a rocker arm's (a pivoted roller or a rocking cam is refused, naming why). A cam is
cut for its own follower: a crowned face's cam read by a flat face lifts more (by e^2 / 2 R).
Every file names the follower it is cut for (csv and grind: the first comment line; dxf: a note
on layer NOTES and the header property CUT_FOR).
  csv    point table: cam angle, contour and centre-path points, outward normal, signed
         curvature of both, pressure angle (SI units; --points rows, plus the lift's breakpoints;
         the centre path is a roller's pitch curve (pitch_*), a crowned face's or curved pad's
         centre (face_centre_*); a flat face has none and its table no such columns)
  dxf    drawing in mm: contour (layer CAM) and centre path (layer PITCH or FACE_CENTRE) as
         closed polylines whose chords stay within --tolerance of the exact curves
  stl    solid cam in mm (contour to --tolerance, extruded over --width along the cam axis z)
  glb    the same solid in metres (glTF)
  grind  grinding table: wheel-centre distance from the cam axis at --points uniform grinder
         angles, for a wheel of --grinding-wheel-radius fed radially
Every export comes from the closed-form contour of the analytic lift; the tests read each back
and measure its distance from the exact contour.
"""

DEFAULT_TOLERANCE = "1 um"
EXTENSIONS = {"csv": ".csv", "dxf": ".dxf", "stl": ".stl", "glb": ".glb", "grind": ".csv"}


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer export cycloidal_demo.toml --format dxf --tolerance "1 um" -o cam.dxf
  explorer export cycloidal_demo.toml --format stl --width "12 mm" -o cam.stl
  explorer export cycloidal_demo.toml --format grind --grinding-wheel-radius "150 mm" -o grind.csv
  explorer export cycloidal_demo.toml --format csv --points 720 -o points.csv
"""


def register(sub) -> None:
    p = sub.add_parser("export", help="the cam as a point table, DXF, STL/GLB solid or grinding table",
                       description=HELP + "\n" + OUTPUT_HELP, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--format", required=True, choices=FORMATS)
    p.add_argument("-o", "--output", metavar="PATH",
                   help="where to write, a name ending in the format's extension (.csv for csv and grind, .dxf, .stl, "
                        ".glb); default: the scene's name with that extension; - for stdout")
    p.add_argument("--tolerance", default=None, metavar="LENGTH",
                   help=f"largest distance of a chord from the exact curve (dxf, stl, glb; default {DEFAULT_TOLERANCE})")
    p.add_argument("--points", type=int, default=None, metavar="N", help="rows of the csv and grind tables (default 3600)")
    p.add_argument("--width", default=None, metavar="LENGTH", help="cam width of the solid (stl, glb; default: the 3D view's)")
    p.add_argument("--grinding-wheel-radius", default=None, metavar="LENGTH", help="wheel radius (grind; required)")
    p.add_argument("--wheel-margin", type=float, default=None, metavar="FRACTION",
                   help="grind: warn when the wheel is within this fraction of the smallest concave radius (default "
                        "0.05; a wheel at or above that radius is refused)")
    p.set_defaults(run=run)


def _length(text: str | None, option: str, default: str | None = None) -> float | None:
    if text is None and default is None:
        return None
    value = to_si(text if text is not None else default, "length", file="<command line>", key=option)
    if not value > 0.0:
        raise InputError("<command line>", option, f"must be positive, got {echo(text)}")
    return value


def _check_options(args) -> tuple[float, float | None, float | None, int]:
    # local: loads when the command runs, not at `explorer --help`
    from ..view.exports import MAX_POINTS, MAX_TOLERANCE, MIN_POINTS, MIN_TOLERANCE

    fmt = args.format
    unused = {
        "--tolerance": args.tolerance is not None and fmt not in ("dxf", "stl", "glb"),
        "--width": args.width is not None and fmt not in ("stl", "glb"),
        "--points": args.points is not None and fmt not in ("csv", "grind"),
        "--grinding-wheel-radius": args.grinding_wheel_radius is not None and fmt != "grind",
        "--wheel-margin": args.wheel_margin is not None and fmt != "grind",
    }
    for option, bad in unused.items():
        if bad:
            raise InputError("<command line>", option, f"not used by --format {fmt}")
    tolerance = _length(args.tolerance, "--tolerance", DEFAULT_TOLERANCE)
    if not MIN_TOLERANCE <= tolerance <= MAX_TOLERANCE:
        raise InputError("<command line>", "--tolerance",
                         f"must be between {MIN_TOLERANCE * 1e3:g} mm and {MAX_TOLERANCE * 1e3:g} mm, got {echo(args.tolerance)}")
    width = _length(args.width, "--width")
    if width is not None and width > 10.0:
        raise InputError("<command line>", "--width", f"more than 10 m is outside any cam, got {echo(args.width)}")
    wheel = _length(args.grinding_wheel_radius, "--grinding-wheel-radius")
    if fmt == "grind" and wheel is None:
        raise InputError("<command line>", "--grinding-wheel-radius", "--format grind needs the wheel radius, such as '150 mm'")
    if wheel is not None and wheel > 10.0:
        raise InputError("<command line>", "--grinding-wheel-radius", f"more than 10 m is outside any grinder, got {echo(args.grinding_wheel_radius)}")
    points = 3600 if args.points is None else args.points
    if not MIN_POINTS <= points <= MAX_POINTS:
        raise InputError("<command line>", "--points", f"must be between {MIN_POINTS} and {MAX_POINTS}, got {points}")
    return tolerance, width, wheel, points


def run(args) -> int:
    from ..view import exports  # local: loads when the command runs, not at `explorer --help`
    tolerance, width, wheel, points = _check_options(args)
    margin = _margin(args, exports.WHEEL_MARGIN)
    scene = scene_from_args(args)
    name = args.output if args.output is not None else f"{Path(scene.source).stem if scene.source != '<memory>' else 'cam'}{EXTENSIONS[args.format]}"
    # a name whose extension is another format's (`--format dxf -o cam.stl`) would give a file
    # that its extension's programs cannot open: refused, as --plot refuses a name not ending in .png
    out = check_output(name, "--output", EXTENSIONS[args.format])
    distinct_outputs((out,), (scene.source,))
    with ticking(sys.stderr, f"export {args.format}"):  # a million points, a fine solid: seconds
        data = _exported(exports, scene, args.format, tolerance, width, wheel, points, margin)
        write_checked(out, data)  # a million-point table is ~200 MB of text
    if not out.is_stdout():
        size = len(data)
        detail = f" to {tolerance * 1e6:.4g} um" if args.format in ("dxf", "stl", "glb") else ""
        print(f"{scene.name}: {args.format}{detail} -> {out.name} ({size} bytes)",
              file=sys.stdout)
    return 0


def _margin(args, default: float) -> float:
    margin = default if args.wheel_margin is None else args.wheel_margin
    if not 0.0 <= margin < 1.0:
        raise InputError("<command line>", "--wheel-margin", f"must be a fraction in [0, 1), got {echo(args.wheel_margin)}")
    return margin


def _exported(exports, scene, fmt, tolerance, width, wheel, points, margin=None):
    src = exports.cam_source(scene)
    if fmt == "csv":
        data = exports.point_table(src, points)
    elif fmt == "dxf":
        data = exports.dxf_text(src, tolerance)
    elif fmt in ("stl", "glb"):
        if width is None:
            from ..view.parts import layout  # heavy (PIL, scipy, trimesh): imported on use

            width = layout(scene).cam_width
        data = (exports.stl_bytes if fmt == "stl" else exports.glb_bytes)(src, tolerance, width)
    else:
        table = exports.grinding_table(src, wheel, points, exports.WHEEL_MARGIN if margin is None else margin)
        if table.warning is not None:
            print(f"warning: {table.warning}", file=sys.stderr)
        data = exports.grinding_text(src, table)
    return data

