"""`explorer fit`: a rocking cam's contour for a wanted valve lift and open angle ([gear.target])."""

from __future__ import annotations

import argparse
import json
import math
import sys

from ..core.errors import InputError, echo
from ..core.files import MAX_SCENE_FILE_BYTES, read_regular
from ..core.reader import toml_loads
from ..effects.context import sample_grid
from ..gears.registry import GEARS
from ..scene.scene import apply_overrides, load_scene

HELP = """\
Choose the contour of a rocking cam (follower.type = "rocking-cam", seed 004 "Schwingdaumen")
for a wanted valve lift and open angle, and print it in scene-file syntax.

How: the valve lift of a rocking cam depends on its swing alone and rises with it, so the valve
is open exactly while the swing exceeds the swing at which the lash is taken up. The wanted open
angle therefore fixes that swing through the eccentric four-bar alone; the fit then places the
flank (gear.rocking_cam.lift_start) and scales it (rise) so that the valve leaves its seat at
that swing and lifts the wanted amount, after valve.lash, at the eccentric's dead centre. The
flank's length (flank), its law and the dwell radius stay as written: they are the contour's
shape, your choice; try another flank with --set gear.rocking_cam.flank=... .

The target is the scene's [gear.target] (lift, open_angle, optional max_pressure_angle), or
--lift / --open-angle / --max-pressure-angle, which set those keys like --set does.

Prints wanted, written ("given") and fitted contour side by side (flank start and rise, valve
lift, open angle, dwell at full lift, largest pressure angle at the roller), the open angles a
flank of this length reaches at the wanted lift, and the fitted [gear.rocking_cam] table to
paste over the scene's own. Or keep the scene's table and set use = "fitted" in [gear.target]:
every command then simulates the fitted contour. Without the fit, the written one is simulated.
A target no flank of this length reaches ends in one error line naming gear.target.lift or
gear.target.open_angle and the limit.
"""

EPILOG = """\
examples:
  explorer fit assets/scenes/rocking_cam.toml
  explorer fit assets/scenes/rocking_cam.toml --lift "9 mm" --open-angle "220 deg"
  explorer fit SCENE --open-angle 180 --set gear.rocking_cam.flank="32 deg"   (longer flank, lower pressure angle)
  explorer fit SCENE --toml > fitted.toml                                     (the table only)
  explorer fit SCENE --json                                                   (the report as JSON)
"""


def register(sub) -> None:
    p = sub.add_parser("fit", help="a rocking cam's contour for a wanted valve lift and open angle",
                       description=HELP, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", help='scene file (TOML) with follower.type = "rocking-cam"')
    p.add_argument("--lift", metavar="LENGTH", help='wanted valve lift after the lash, e.g. "10 mm" (gear.target.lift)')
    p.add_argument("--open-angle", metavar="ANGLE",
                   help='shaft angle the valve is off its seat, e.g. "200 deg" (gear.target.open_angle)')
    p.add_argument("--max-pressure-angle", metavar="ANGLE",
                   help='warn where the pressure angle at the roller exceeds this, e.g. "35 deg" '
                        "(gear.target.max_pressure_angle)")
    p.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
        help='override a scene value, e.g. --set valve.lash="0.3 mm" (repeatable)',
    )
    output = p.add_mutually_exclusive_group()
    output.add_argument("--toml", action="store_true", help="print only the fitted [gear.rocking_cam] table")
    output.add_argument("--json", action="store_true", help="print the report (SI values, angles in deg) as JSON")
    p.set_defaults(run=run)


def _follower_type(path: str, overrides: list[str]):
    """follower.type as written (after --set), or None when the file cannot tell: then loading
    the scene reports what is wrong with it."""
    try:
        text = read_regular(path, file=path, key="-", limit=MAX_SCENE_FILE_BYTES).decode("utf-8")
        data = apply_overrides(toml_loads(text, path), overrides, path)
        return data["follower"]["type"]
    except Exception:  # noqa: BLE001 - any failure here is load_scene's to report, with its key
        return None


def load_target_scene(args):
    """The scene with its [gear.target] completed by --lift/--open-angle/--max-pressure-angle."""
    kind = _follower_type(args.scene, args.overrides)
    fitters = [name for name, gear in GEARS.items() if gear.fits_target]
    if kind is not None and kind not in fitters:
        raise InputError(args.scene, "follower.type", f"explorer fit chooses a rocking cam's contour; this scene's "
                         f"follower.type is {echo(kind)}, not " + " or ".join(f'"{t}"' for t in fitters))
    overrides = list(args.overrides)
    for key, value in (("lift", args.lift), ("open_angle", args.open_angle),
                       ("max_pressure_angle", args.max_pressure_angle)):
        if value is not None:
            overrides.append(f"gear.target.{key}={value}")
    scene = load_scene(args.scene, overrides)
    if not scene.gear_plugin.fits_target:
        raise InputError(args.scene, "follower.type", "explorer fit chooses a rocking cam's contour; set "
                         "follower.type = " + " or ".join(f'"{t}"' for t in fitters))
    if "target" not in scene.gear.parts:
        raise InputError(args.scene, "gear.target", "missing section: explorer fit needs the wanted lift and open "
                         "angle, from [gear.target] lift and open_angle or from --lift and --open-angle")
    return scene


def fit_report(scene) -> tuple[dict, list[str]]:
    """The gear's fit of its contour to [gear.target], on the simulation's grid (the same pressure
    angles as the 'gear' effect's)."""
    theta, _ = sample_grid(scene)
    return scene.gear_plugin.fit(scene, theta)


def _table(scene, report: dict, warnings: list[str]) -> str:
    part = scene.gear.part("rocking_cam")
    wanted, given, fitted = report["wanted"], report["given"], report["fitted"]

    def mm(x):
        return f"{x * 1e3:.4f} mm"

    def deg(x):
        return f"{x:.4f} deg"

    rows = [
        ("lift_start", "", deg(given["lift_start_deg"]), deg(fitted["lift_start_deg"])),
        ("rise", "", mm(given["rise_m"]), mm(fitted["rise_m"])),
        ("valve lift", mm(wanted["valve_lift_m"]), mm(given["valve_lift_m"]), mm(fitted["valve_lift_m"])),
        ("open angle", deg(wanted["open_angle_deg"]), deg(given["open_angle_deg"]), deg(fitted["open_angle_deg"])),
        ("dwell at full lift", "", deg(given["full_lift_dwell_deg"]), deg(fitted["full_lift_dwell_deg"])),
        ("max pressure angle", deg(wanted["max_pressure_angle_deg"]) if "max_pressure_angle_deg" in wanted else "",
         deg(given["max_pressure_angle_deg"]), deg(fitted["max_pressure_angle_deg"])),
    ]
    lines = [
        f"{scene.name}: rocking-cam contour for a wanted valve lift and open angle",
        f"  lash {mm(report['lash_m'])}; kept as written: flank {math.degrees(part['flank']):.4g} deg, law "
        f"{part['law']}, dwell radius {part['dwell_radius'] * 1e3:.4g} mm",
        "",
        f"  {'':<20s}{'wanted':>16s}{'given':>16s}{'fitted':>16s}",
    ]
    lines += [f"  {name:<20s}{a:>16s}{b:>16s}{c:>16s}" for name, a, b, c in rows]
    lines.append("")
    lift = mm(wanted["valve_lift_m"])
    lines.append(f"  A {math.degrees(part['flank']):.4g} deg flank at {lift} lift keeps the valve open at most "
                 f"{report['max_open_angle_deg']:.4f} deg (flank starting at the closed end).")
    if report["full_flank_open_angle_deg"] is not None:
        lines.append(f"  From {report['full_flank_open_angle_deg']:.4f} deg up the roller reaches the top arc (a dwell "
                     "at full lift); below it the swing ends on the flank.")
    else:
        lines.append("  The flank is longer than the swing: the roller never reaches the top arc.")
    if report["use"] == "fitted":
        lines.append('  Simulated: the fitted contour (use = "fitted").')
    else:
        lines.append('  Simulated: the given contour; set use = "fitted" in [gear.target] to simulate the fitted one.')
    lines += [f"  warning: {w}" for w in warnings]
    lines += ["", f"# fitted contour: paste over [gear.rocking_cam] in {scene.source}", report["fitted_toml"]]
    return "\n".join(lines)


def run(args) -> int:
    scene = load_target_scene(args)
    report, warnings = fit_report(scene)
    if args.toml:
        sys.stdout.write(report["fitted_toml"])
    elif args.json:
        sys.stdout.write(json.dumps({**report, "warnings": warnings}, indent=2) + "\n")
    else:
        sys.stdout.write(_table(scene, report, warnings))
    return 0
