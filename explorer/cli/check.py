"""`explorer check`: is this design acceptable? Every design rule over the operating range and the
tolerances: a table of verdicts, JSON or CSV with -o; exit status 1 when a rule fails."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..core.errors import InputError
from ..core.outputs import HELP as OUTPUT_HELP, check_output, distinct_outputs, write_checked
from .simulate import add_scene_arguments, scene_from_args
from .progress import Progress
from .sweep import _split

HELP = """\
Check a design against the rules of the field (explorer/checks/registry.py): pressure angle and
self-locking, cam curvature against the roller (or a flat face's radius and width), the opening
velocity at the end of the lash ramp, seating velocity, float margin and seat bounce (elastic,
through the sweep engine), Hertz stress against the material's allowable, the oil film along the
profile (lambda ratio, entrainment reversal, Blok's flash temperature; [lubricant]), the valve
spring (shear stress, Goodman fatigue, coil bind, surge) and the gears' own (trip-gear latch,
rocking-cam swing). Each rule has a default limit with its source and how firm it is; a scene's
[checks] section or --rules FILE (TOML) overrides a limit or switches a rule off:

    [checks.seating_velocity]        # in a --rules file: [seating_velocity]
    fail = "0.8 m/s"
    [checks]
    pressure_angle = false

The operating range: --rpm START:STOP:COUNT (or a list), else [drive] operating_range = [LOW, HIGH]
(200 speeds), else the scene's own speed. Tolerances: --sample KEY="normal(MEAN, SD)" or
"uniform(LOW, HIGH)" (the sweep's grammar and keys) with --runs N and --seed: each rule judges every
draw at the speeds where the nominal design is worst for it (and the range's ends); the table adds
the share of draws that fail with its 95 % Wilson score interval.

Output: the table on stdout; -o OUT.json or OUT.csv writes the report (every rule: verdict, worst
value, speed and cam angle, limits, source, firmness, probabilities). Exit status 0 when no rule
fails (warnings allowed), 1 when one fails, 2 on bad input.
"""

EPILOG = """\
examples:
  explorer check assets/scenes/valve_float_demo.toml --rpm 800:6500:200
  explorer check SCENE --rpm 1000:6000:100 --rules my_rules.toml -o report.json
  explorer check SCENE --sample valve.lash="normal(0.25 mm, 0.02 mm)" --runs 10000 --seed 1 -o lash.csv
"""

FORMATS = (".json", ".csv")


def register(sub) -> None:
    p = sub.add_parser("check", help="is this design acceptable? design rules over the speed range and tolerances",
                       description=HELP + "\n" + OUTPUT_HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--rpm", metavar="A:B:N|A,B,...", help="the operating range: N speeds from A to B rpm, or a list")
    p.add_argument("--sample", action="append", default=[], metavar='KEY="normal(MEAN, SD)"',
                   help="a tolerance: normal(MEAN, SD) or uniform(LOW, HIGH) (repeatable)")
    p.add_argument("--runs", type=int, help="draws of the tolerances (with --sample)")
    p.add_argument("--seed", type=int, help="seed of the draws (default: fresh)")
    p.add_argument("--verify", type=int, metavar="N",
                   help="draws run over every speed of the range to bound what judging the others at the nominal's "
                        "worst speeds misses (default: as many as 10^4 runs allow, at least 10)")
    p.add_argument("--rules", metavar="FILE.toml", help="rule settings: limits, rules switched off")
    p.add_argument("-o", "--output", metavar="OUT.json|OUT.csv", help="write the report here")
    p.add_argument("--workers", type=int, help="local worker processes for the elastic runs (default: every core)")
    p.add_argument("--yes", action="store_true", help="allow more than 10^7 draws")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..checks import check  # local: loads when the command runs, not at `explorer --help`
    sample = {}
    for text in args.sample:
        key, value = _split(text, "--sample")
        if key in sample:
            raise InputError("--sample", key, "sampled twice")
        sample[key] = value
    if args.workers is not None and args.workers < 1:
        raise InputError("--workers", str(args.workers), "at least 1")
    out = None
    if args.output:
        kind = Path(args.output).suffix.lower()
        out = check_output(args.output, "--output")
        if not out.direct and kind not in FORMATS:
            raise InputError(args.output, "--output", f"the file name must end in {' or '.join(FORMATS)}")
        if out.direct and kind not in FORMATS:
            kind = ".json"
    scene = scene_from_args(args)
    distinct_outputs((out,), (scene.source, args.rules))
    progress = Progress(sys.stderr)
    try:
        report = check(scene, args.rpm, sample or None, runs=args.runs, seed=args.seed, rules=args.rules,
                       workers=args.workers, progress=progress, yes=args.yes, verify=args.verify)
    finally:
        progress.end()
    text = report.table_text()
    if out is not None:
        write_checked(out, report.to_json() if kind == ".json" else report.to_csv())
    (sys.stderr if out is not None and out.is_stdout() else sys.stdout).write(text)
    return report.exit_status
