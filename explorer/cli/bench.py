"""`explorer bench`: what accuracy costs in time, for every dynamics solver, on one scene."""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

from ..core.errors import InputError
from ..core.files import check_path
from ..core.outputs import HELP as OUTPUT_HELP, all_or_none, check_output, distinct_outputs, write_checked
from .simulate import add_scene_arguments, scene_from_args

# timed runs per case: a median of 100 is already steady; more only multiplies minutes of timing
MAX_REPEATS = 100


def _names(names) -> str:
    names = list(names)
    return ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else "".join(names)


def _help() -> str:
    """The help text, naming the solvers from the solver table (explorer/dynamics/solvers.py)."""
    import textwrap

    from ..dynamics import solvers

    closed = [n for n in solvers.of_kind("piecewise") if not solvers.solver(n).varying_stiffness]
    stepped = _names([*closed, *solvers.of_kind("fixed-step")])
    ref = solvers.reference()
    baseline = f"{ref.name} {ref.reference.label}"
    varying = solvers.of_kind("piecewise", varying=True)[0]
    first = (f"Time every dynamics solver on the scene's elastic model over one revolution and measure its "
             f"accuracy: {stepped} at 90 ... 360 000 steps per revolution ({_names(solvers.of_kind('fixed-step'))} "
             f"only where it is stable), {baseline} at rtol 1e-3 ... 1e-12. Each run's largest valve-lift error "
             f"against a converged reference of the other kind ({stepped} against {baseline} rtol 1e-12, {ref.name} "
             f"against {closed[0]} at the finest grid; the two references are cross-checked), CPU time (median of "
             f"repeats) and events found. Also the speed ratio {closed[0]} (default steps) vs {baseline} rtol 1e-10, "
             f"measured side by side, and the errors of v and p when a measured lift is differentiated.")
    last = (f"The scene needs [valve], [spring] and [linkage]; its effects list does not matter. A rolling lever "
            f"with its own stiffness (k changing along the cycle) cannot be run by the closed forms: the {varying} "
            f"solver takes their place everywhere, up to 36 000 steps.")
    return (textwrap.fill(first, 96) + "\n\nPrints a table and writes into --output-dir: bench_<scene>.csv (one row "
            "per run),\nbench_<scene>.png (error versus CPU time, the Pareto front), bench_<scene>.txt (the table) "
            "and,\nwith the differentiation study, bench_<scene>_differentiation.csv/.png.\n" + textwrap.fill(last, 96)
            + "\n")


# real commands on built-in scenes; tests/test_cli_audit.py runs or parses every line
EPILOG = """\
examples:
  explorer bench schenker1902_fig2.toml --quick --output-dir bench
  explorer bench cycloidal_demo.toml --quick --repeats 1 --no-differentiation --output-dir bench
"""


def register(sub) -> None:
    p = sub.add_parser("bench", help="accuracy versus time of the dynamics solvers (table, CSV, chart)",
                       description=_help() + "\n" + OUTPUT_HELP, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_scene_arguments(p)
    p.add_argument("--output-dir", default=".", metavar="DIR", help="where the CSV, PNG and text files go (default: .)")
    p.add_argument("--quick", action="store_true", help="few resolutions (90, 900, 3600 steps; rtol 1e-4, 1e-8): seconds, for tests")
    p.add_argument("--repeats", type=int, default=3, metavar="N", help=f"timed runs per case, median reported (default 3, at most {MAX_REPEATS})")
    p.add_argument("--no-differentiation", action="store_true", help="skip the measured-lift differentiation study")
    p.set_defaults(run=run)


def _slug(name: str) -> str:
    out = "".join(ch.lower() if ch.isalnum() else "_" for ch in name)
    return "_".join(part for part in out.split("_") if part) or "scene"


def run(args) -> int:
    if not 1 <= args.repeats <= MAX_REPEATS:
        raise InputError("<command line>", "--repeats", f"must be between 1 and {MAX_REPEATS}, got {args.repeats}")
    scene = scene_from_args(args)
    check_path(args.output_dir, file="<command line>", key="--output-dir")
    out_dir = Path(args.output_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(str(out_dir), "--output-dir", "exists and is not a directory")
    made = False
    if not out_dir.exists():
        if not out_dir.resolve().parent.is_dir():
            raise InputError(str(out_dir), "--output-dir", f"parent directory {out_dir.resolve().parent} does not exist")
        out_dir.mkdir()
        made = True
    try:
        return _bench(args, scene, out_dir)
    except BaseException:
        if made:  # a directory we made for files that never came
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise


def _bench(args, scene, out_dir: Path) -> int:
    # local: loads when the command runs, not at `explorer --help`
    from ..studies.bench import ProgressBar, chart_png, differentiation_png, run_bench
    stem = Path(scene.source).stem if scene.source != "<memory>" else _slug(scene.name)
    base = out_dir / f"bench_{stem}"
    names = [".csv", ".txt", ".png"]
    if not args.no_differentiation:
        names += ["_differentiation.csv", "_differentiation.png"]
    # every file checked before the minutes of timing, so that a directory that takes no file
    # costs one line, not a run
    outs = {name: check_output(f"{base}{name}", "--output-dir") for name in names}
    distinct_outputs(outs.values(), (scene.source,))
    report = run_bench(scene, quick=args.quick, repeats=args.repeats, progress=ProgressBar(sys.stderr),
                       differentiation=not args.no_differentiation)
    table = report.table()
    sys.stdout.write(table)
    written = [f"{base}.csv", f"{base}.png", f"{base}.txt"]
    with all_or_none():  # every file of the report, or none
        write_checked(outs[".csv"], report.csv_text())
        write_checked(outs[".txt"], table)
        write_checked(outs[".png"], chart_png(report))
        if report.differentiation is not None:
            study = report.differentiation
            cols = study.columns()
            lines = [",".join(cols)]
            lines += [",".join(repr(float(cols[k][i])) for k in cols) for i in range(len(study.rows))]
            write_checked(outs["_differentiation.csv"], "\n".join(lines) + "\n")
            write_checked(outs["_differentiation.png"], differentiation_png(study))
            written += [f"{base}_differentiation.csv", f"{base}_differentiation.png"]
    print("wrote " + ", ".join(written))
    return 0
