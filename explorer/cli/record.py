"""`explorer record`: simulations to a rerun .rrd file, one recording per scene or sweep value."""

from __future__ import annotations

import argparse
import itertools
import math
import sys
import time

from ..core.errors import InputError, echo
from ..core.outputs import HELP as OUTPUT_HELP, distinct_outputs
from ..scene.builtin import default_scene
from .progress import Progress

# Each recording costs ~0.1-0.3 s and ~1-4 MB of the file at 3600 steps with the parts: a thousand
# is minutes and gigabytes, and a viewer that shows them side by side. Wider sweeps are a typo
# (--sweep 1,2,...,3000; 50 x 50 x 50) or a job for `explorer simulate` in a loop.
MAX_RUNS = 1000
# --magnification: the parts' deviations from rigid motion (micrometres) drawn this many times. The
# browser's slider stops at 50; past a thousand a deviation of tens of micrometres is drawn tens of
# millimetres off, beyond any lift, and a large factor overflows the file's float32 poses.
MAX_MAGNIFICATION = 1000.0

HELP = """\
Record one revolution of each scene into a rerun file (.rrd): the series s, v, p, jerk, forces and
every other column the scene's effects compute, the 3D parts moving step by step, the events as a
log, and a default layout. Several scenes, or a --sweep over a scene value, become separate
recordings in the same file, so the runs can be compared in one viewer (`explorer view FILE`).

Timelines: cam_angle_0.01deg (hundredths of a degree, 12345 = 123.45 deg, every sample its own
place; the default: plots span one revolution, which plays in 6 s at 1x), time (s), step (index). Lengths in mm as in the browser explorer, the rest
SI. Entity paths: /valve/lift, /valve/velocity, /valve/acceleration, /valve/jerk, /follower/...,
/forces/<name>, /torque/..., /stress/..., /angles/..., /parts/<part>, /events, /summary
(full mapping: `python -c "import explorer.view.rerun.recording as r; help(r)"`). Sweep recordings are
named by the varied value first ("drive.rpm=600 · Cycloidal demo"); several runs get one more
recording, "overlay: all N runs", that draws their s, v, p and forces over each other.

The file appears only when complete (written to a temporary name, then renamed); -o - (stdout),
/dev/stdout or a FIFO gets the finished file's bytes (`explorer record SCENE -o - > run.rrd`).
Runs are simulated and written one at a time. At most {max_runs} recordings per file (scenes times
the combinations of the --sweep values), checked before any work.
"""

EPILOG = """\
examples:
  explorer record assets/scenes/cycloidal_demo.toml -o run.rrd
  explorer record A.toml B.toml -o compare.rrd
  explorer record SCENE --sweep drive.rpm=1000,2000,3000 -o speeds.rrd
  explorer record SCENE --sweep valve.lash="0.1 mm","0.3 mm" --set linkage.stiffness=1e6 -o lash.rrd
  explorer record pushrod_train.toml --magnification 50 -o train.rrd
  explorer view speeds.rrd
"""


def register(sub) -> None:
    p = sub.add_parser("record", help="simulations to a rerun .rrd file (series, 3D motion, events)",
                       description=HELP.format(max_runs=MAX_RUNS) + "\n" + OUTPUT_HELP, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenes", nargs="*", metavar="SCENE",
                   help="scene files (TOML) or built-in scenes by name (cycloidal_demo.toml); default: the built-in default scene")
    p.add_argument("-o", "--output", required=True, metavar="OUT.rrd", help="the rerun file to write")
    p.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
        help='override a scene value in every scene, e.g. --set drive.rpm=600 (repeatable)',
    )
    p.add_argument(
        "--sweep", action="append", default=[], metavar="SECTION.KEY=V1,V2,...",
        help="one recording per value, V1,V2,... or START:STOP:COUNT[:log] (repeatable: every combination)",
    )
    p.add_argument("--no-parts", action="store_true", help="leave out the 3D parts (series and events only)")
    p.add_argument("--magnification", default=None, metavar="X",
                   help="draw each moving mass of the 3D parts at its rigid pose plus X times its computed deviation "
                        "from it (an elastic valve, each mass of a train, the lash adjuster's plunger travel), as the "
                        f"browser's slider does; a positive number up to {MAX_MAGNIFICATION:g}; default: the scene's "
                        "own (x20 for a train of masses or a lash adjuster, x1 otherwise); written in each "
                        "recording's summary")
    p.add_argument("--checks", action="store_true",
                   help="also the design checks of each run's scene (as `explorer check SCENE`): each rule that warns "
                        "or fails a marker in the event log at the cam angle of its worst, the limits as lines beside "
                        "the velocity, pressure angle and Hertz stress")
    p.set_defaults(run=run)



# a sweep's values are counted before any is made (a COUNT of 10^9 must not make 10^9 strings);
# the product of the sweeps is then held to MAX_RUNS, with a message that names the factors
MAX_SWEEP_POINTS = 10_000_000


def sweep_shape(text: str):
    """(key, shape) of one --sweep in the range grammar of every command (explorer.core.grids)."""
    from ..core import grids  # local: loads when the command runs, not at `explorer --help`

    if "=" not in text:
        raise InputError("--sweep", text, "a sweep must look like section.key=v1,v2,... or section.key=START:STOP:COUNT")
    key, _, values_text = text.partition("=")
    key = key.strip()
    parts = key.split(".")
    if not key or len(parts) < 2 or any(not p for p in parts):
        raise InputError("--sweep", key or text, "sweep key must be dotted, such as drive.rpm")
    return key, grids.read(values_text, file="--sweep", key=key, max_points=MAX_SWEEP_POINTS)


def _size(shape) -> int:
    from ..core import grids  # local: loads when the command runs, not at `explorer --help`

    return len(shape.values) if isinstance(shape, grids.Listed) else int(shape.count)


def parse_sweep(text: str) -> tuple[str, list[str]]:
    """'drive.rpm=100,200' -> ('drive.rpm', ['100', '200']); 'drive.rpm=100:300:3' -> ('drive.rpm',
    ['100', '200', '300']): each value in the unit it was written in, checked by the scene loader."""
    from ..core import grids  # local: loads when the command runs, not at `explorer --help`

    key, shape = sweep_shape(text)
    return key, grids.texts(shape, file="--sweep", key=key)


def plan_runs(scene_paths: list[str], overrides: list[str], sweeps: list[str]):
    """(label, scene) for every scene and every combination of sweep values; all validated here."""
    from ..core import grids  # local: loads when the command runs, not at `explorer --help`
    from ..scene.scene import load_scene  # local: loads when the command runs, not at `explorer --help`
    scene_paths = scene_paths or [str(default_scene())]
    shapes = [sweep_shape(s) for s in sweeps]
    count = len(scene_paths) * math.prod(_size(shape) for _, shape in shapes)
    if count > MAX_RUNS:
        factors = ([f"{len(scene_paths)} scenes"] if len(scene_paths) > 1 else []) + [str(_size(v)) for _, v in shapes]
        product = " x ".join(factors) + " = " if len(factors) > 1 else ""
        raise InputError("--sweep", ", ".join(key for key, _ in shapes) or "SCENE",
                         f"{product}{count} recordings; at most {MAX_RUNS} per file")
    parsed = [(key, grids.texts(shape, file="--sweep", key=key)) for key, shape in shapes]
    combos = list(itertools.product(*[[(key, v) for v in values] for key, values in parsed])) or [()]
    plans = []
    for path in scene_paths:
        for combo in combos:
            extra = [f"{key}={value}" for key, value in combo]
            scene = load_scene(path, [*overrides, *extra])
            # the varied value first: the viewer's recording list cuts long names at the end
            label = f"{', '.join(extra)} · {scene.name}" if combo else scene.name
            plans.append((label, scene))
    labels = [label for label, _ in plans]
    # labels name the recordings in the viewer: make repeated ones distinguishable
    seen: dict[str, int] = {}
    for i, label in enumerate(labels):
        if labels.count(label) > 1:
            seen[label] = seen.get(label, 0) + 1
            plans[i] = (f"{label} #{seen[label]}", plans[i][1])
    return plans


def parse_magnification(text: str | None, no_parts: bool = False) -> float | None:
    """--magnification as a number (None: the scene's default): positive, finite, at most
    MAX_MAGNIFICATION; it draws the parts, so --no-parts leaves it nothing to do."""
    if text is None:
        return None
    if no_parts:
        raise InputError("<command line>", "--magnification", "draws the 3D parts, which --no-parts leaves out")
    try:
        value = float(text)
    except (ValueError, OverflowError):
        value = None
    if value is None or not math.isfinite(value) or not 0.0 < value <= MAX_MAGNIFICATION:
        raise InputError("<command line>", "--magnification",
                         f"must be a number above 0 and at most {MAX_MAGNIFICATION:g} (1 = true scale), got {echo(text)}")
    return value


def _with_parts_or_warn(label: str, result, magnification: float | None = None):
    """The run with its 3D parts at `magnification` (None: the scene's default); if the meshes
    cannot be built for this gear, the series and events are still worth recording: say so and
    leave the parts out."""
    from ..view.rerun.recording import Run, with_parts  # local: loads when the command runs, not at `explorer --help`

    try:
        return with_parts(label, result, magnification)
    except Exception as exc:  # noqa: BLE001 - a viewer extra must not lose the recording
        print(f"warning: {label}: 3D parts left out ({type(exc).__name__}: {exc})", file=sys.stderr)
        return Run(label=label, result=result)


def run(args) -> int:
    # local: loads when the command runs, not at `explorer --help`
    from dataclasses import replace

    from ..checks.viewer import evaluate as check_design
    from ..effects.pipeline import simulate
    from ..view.rerun.recording import Run, check_rrd_path, write_recordings

    magnification = parse_magnification(args.magnification, args.no_parts)
    out = check_rrd_path(args.output, "--output")
    plans = plan_runs(args.scenes, args.overrides, args.sweep)  # every input error before any work
    distinct_outputs((out,), {scene.source for _, scene in plans})
    done = []  # (label, steps, events, warnings): all that is kept of a run once it is written

    def runs():
        for label, scene in plans:
            result = simulate(scene)
            run = Run(label=label, result=result) if args.no_parts else _with_parts_or_warn(label, result, magnification)
            yield replace(run, checks=check_design(scene)) if args.checks else run

    progress = Progress(sys.stderr, unit="recordings")  # a --sweep of many values takes minutes
    started = time.perf_counter()

    def written(r) -> None:
        done.append((r.label, len(r.result.columns["time_s"]), len(r.result.events), len(r.result.warnings)))
        progress(len(done), len(plans), time.perf_counter() - started)

    try:
        write_recordings(out, runs(), on_run=written)
    except (OSError, RuntimeError) as exc:  # disk full, rerun CLI missing: not the user's input
        progress.end()
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        print(f"error: {InputError(out.name, '--output', f'writing failed: {reason}')}", file=sys.stderr)
        return 1
    finally:
        progress.end()
    report = sys.stderr if out.is_stdout() else sys.stdout  # stdout may be the file itself
    steps = sum(d[1] for d in done)
    print(f"{out.name}: {len(done)} recording{'s' if len(done) != 1 else ''}, {steps} steps", file=report)
    for label, n, n_events, n_warn in done:
        print(f"  {label}: {n} steps, {n_events} events, {n_warn} warnings", file=report)
    if not out.direct:
        print(f"view it with: explorer view {out.name}", file=report)
    return 0
