"""`explorer design`: optimise a spline lift's free station values."""

from __future__ import annotations

import argparse
import sys

from ..core.errors import InputError, echo
from ..core.units import to_si
from ..studies.design import MAX_EVALUATIONS, OBJECTIVES
from .simulate import add_scene_arguments, scene_from_args

HELP = """\
Choose the "free" station values of a spline lift (law = "spline") to minimise an objective at
the scene's speed, subject to limits (scipy.optimize SLSQP, on a grid of the event):
  --objective peak-acceleration | peak-jerk | jerk-energy | residual-vibration (over --band)
  --max-pressure-angle A, --radius-margin L (convex pitch radius >= roller radius + L),
  --contact-margin F with --contact-rpm N (rigid contact force >= F at every speed up to N;
    without --contact-rpm up to the scene's drive.rpm, printed with the result)
  --open-area keep | AREA: hold the valve's open area (lift over cam angle, e.g. "1500 mm*deg")
    at the starting lift's or at AREA (the duration is always held: the stations do not move)
Prints the optimum, each constraint's slack (relative, >= 0 met) and the standard laws on the
same event; --toml prints the optimised [[lift.stations]] to paste into the scene.
Limits no lift of the event can meet (a contact margin above the seat force at rest, or one the
deceleration of the rise and return rules out at --contact-rpm; an open area beyond 1 m of lift)
are refused at once, in one line. The optimisation stops after {budget} evaluations (the result
is then reported as not met, exit status 1); from the first second a line on stderr shows them.
"""


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer design spline_demo.toml --objective peak-acceleration --max-pressure-angle 30
  explorer design spline_demo.toml --objective peak-jerk --toml
"""


def register(sub) -> None:
    p = sub.add_parser("design", help="optimise a spline lift (peak acceleration, jerk, residual vibration)",
                       description=HELP.format(budget=MAX_EVALUATIONS), epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--objective", required=True, choices=OBJECTIVES)
    p.add_argument("--max-pressure-angle", metavar="ANGLE")
    p.add_argument("--radius-margin", metavar="LENGTH")
    p.add_argument("--contact-margin", metavar="FORCE")
    p.add_argument("--contact-rpm", metavar="RPM",
                   help="the contact margin holds at every speed up to this (default: drive.rpm); needs --contact-margin")
    p.add_argument("--band", metavar="A:B", help="speed band of the residual-vibration objective, rpm (default: "
                   "drive.rpm alone); the range grammar of every command (explorer.core.grids)")
    p.add_argument("--open-area", metavar="keep|AREA",
                   help='hold the valve open area (integral of the valve lift over cam angle): "keep" the '
                        'starting lift\'s, or a value such as "1500 mm*deg"')
    p.add_argument("--toml", action="store_true", help="print only the optimised stations")
    p.set_defaults(run=run)


class EvaluationProgress:
    """A line on stderr from the first second on: evaluations spent of the budget, time."""

    def __init__(self, stream, budget: int):
        self.stream, self.budget = stream, budget
        self.shown, self.last = False, 0.0

    def __call__(self, evaluations: int, seconds: float) -> None:
        if seconds < 1.0 or seconds - self.last < 0.2:
            return
        self.last = seconds
        self.stream.write(f"\roptimising: {evaluations} of at most {self.budget} evaluations, {seconds:5.1f} s")
        self.stream.flush()
        self.shown = True

    def end(self) -> None:
        if self.shown:
            self.stream.write("\n")
            self.stream.flush()


def _quantity(text, dimension, option):
    if text is None:
        return None
    value = to_si(text, dimension, file="<command line>", key=option)
    if value < 0.0:
        raise InputError("<command line>", option, f"must not be negative, got {echo(text)}")
    return value


ANGLE_UNITS = ("radian", "degree", "turn", "revolution", "arcminute", "arcsecond", "gradian", "milliradian")


def _angle_power(text: str) -> int:
    """The power of angle units in a quantity's unit (mm*deg: 1, mm: 0, mm/deg: -1)."""
    from ..core.units import parse_quantity, registry  # pint: loads when the command runs

    _, unit = parse_quantity(text.strip(), file="<command line>", key="--open-area")
    if not unit:
        return 0
    return int(sum(power for name, power in registry().Unit(unit)._units.items() if name in ANGLE_UNITS))


def _speeds(text: str, option: str, interval: bool = False):
    """Speeds in rev/min (a bare number) or with a unit, each in drive.rpm's valid range: one
    speed, or an interval A:B in the range grammar of every command."""
    from ..core import grids  # local: loads when the command runs, not at `explorer --help`
    # local: loads when the command runs, not at `explorer --help`
    from ..studies.sweep_spec import SWEEP_KEYS, check_values, quantity

    info = SWEEP_KEYS["drive.rpm"]
    if interval:
        shape = grids.read(text, file=option, key=info.key, max_points=2, interval=True)
    else:
        shape = grids.Listed((str(text),))
    values = grids.values(shape, lambda value: quantity(value, info, option), file=option, key=info.key)
    check_values(info, values, option)
    return values


def run(args) -> int:
    import math

    # local: loads when the command runs, not at `explorer --help`
    from ..studies.design import MAX_EVALUATIONS, DesignLimits, design, report_text, stations_toml

    angle = _quantity(args.max_pressure_angle, "angle", "--max-pressure-angle")
    if angle is not None and not 0.0 < angle < math.pi / 2:
        raise InputError("<command line>", "--max-pressure-angle", "must lie between 0 and 90 deg")
    band = None
    if args.band is not None:
        if args.objective != "residual-vibration":
            raise InputError("<command line>", "--band", "only the residual-vibration objective has a speed band")
        band = tuple(float(x) for x in _speeds(args.band, "--band", interval=True))
    contact_rpm = None
    if args.contact_rpm is not None:
        if args.contact_margin is None:
            raise InputError("<command line>", "--contact-rpm", "sets the speed range of --contact-margin: give "
                             "--contact-margin too")
        contact_rpm = float(_speeds(args.contact_rpm, "--contact-rpm")[0])
    area = args.open_area
    if area is not None and area.strip() != "keep":
        # mm*deg has the dimension of a length (deg is a number); its SI value is in m*rad. So the
        # angle must be named: "5 mm" would pass as 286 mm*deg (0.005 m*rad) without it
        wrong = f"expected keep or an area of lift over cam angle such as '1500 mm*deg', got {echo(area)}"
        try:
            area = _quantity(area, "length", "--open-area")
        except InputError:
            raise InputError("<command line>", "--open-area", wrong) from None
        if _angle_power(args.open_area) != 1:
            raise InputError("<command line>", "--open-area", wrong + " (a lift times one cam-angle unit: mm*deg or m*rad)")
        if area == 0.0:
            raise InputError("<command line>", "--open-area", "must be positive (or keep)")
    elif area is not None:
        area = "keep"
    limits = DesignLimits(angle, _quantity(args.radius_margin, "length", "--radius-margin"),
                          _quantity(args.contact_margin, "force", "--contact-margin"), contact_rpm, band,
                          open_area=area)
    scene = scene_from_args(args)
    progress = EvaluationProgress(sys.stderr, MAX_EVALUATIONS)
    try:
        report = design(scene, args.objective, limits, progress=progress)
    finally:
        progress.end()
    sys.stdout.write(stations_toml(scene, report) if args.toml else report_text(scene, report))
    return 0 if report.success else 1
