"""`explorer record`: simulations to a rerun .rrd file, one recording per scene or sweep value."""

from __future__ import annotations

import argparse
import itertools
import math
import sys

from .errors import InputError

HELP = """\
Record one revolution of each scene into a rerun file (.rrd): the series s, v, p, jerk, forces and
every other column the scene's effects compute, the 3D parts moving step by step, the events as a
log, and a default layout. Several scenes, or a --sweep over a scene value, become separate
recordings in the same file, so the runs can be compared in one viewer (`explorer view FILE`).

Timelines: time (s), step (index), cam_angle_mdeg (cam angle in millidegrees). Entity paths:
/valve/lift, /valve/velocity, /valve/acceleration, /valve/jerk, /follower/..., /forces/<name>,
/torque/..., /stress/..., /angles/..., /parts/<part>, /events, /summary
(full mapping: `python -c "import explorer.recording as r; help(r)"`).

The file appears only when complete (written to a temporary name, then renamed).
"""

EPILOG = """\
examples:
  explorer record assets/scenes/cycloidal_demo.toml -o run.rrd
  explorer record A.toml B.toml -o compare.rrd
  explorer record SCENE --sweep drive.rpm=1000,2000,3000 -o speeds.rrd
  explorer record SCENE --sweep valve.lash="0.1 mm","0.3 mm" --set linkage.stiffness=1e6 -o lash.rrd
  explorer view speeds.rrd
"""


def register(sub) -> None:
    p = sub.add_parser("record", help="simulations to a rerun .rrd file (series, 3D motion, events)",
                       description=HELP, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenes", nargs="*", metavar="SCENE",
                   help="scene files (TOML); default: the built-in default scene")
    p.add_argument("-o", "--output", required=True, metavar="OUT.rrd", help="the rerun file to write")
    p.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
        help='override a scene value in every scene, e.g. --set drive.rpm=600 (repeatable)',
    )
    p.add_argument(
        "--sweep", action="append", default=[], metavar="SECTION.KEY=V1,V2,...",
        help="one recording per value (repeatable: every combination of the sweeps)",
    )
    p.add_argument("--no-parts", action="store_true", help="leave out the 3D parts (series and events only)")
    p.set_defaults(run=run)


MAX_RUNS = 1000  # recordings per command (scenes x sweep values)


def parse_sweep(text: str) -> tuple[str, list[str]]:
    """'drive.rpm=100,200' -> ('drive.rpm', ['100', '200'])."""
    if "=" not in text:
        raise InputError("--sweep", text, "a sweep must look like section.key=v1,v2,...")
    key, _, values_text = text.partition("=")
    key = key.strip()
    parts = key.split(".")
    if not key or len(parts) < 2 or any(not p for p in parts):
        raise InputError("--sweep", key or text, "sweep key must be dotted, such as drive.rpm")
    values = [v.strip() for v in values_text.split(",")]
    if not values or any(not v for v in values):
        raise InputError("--sweep", key, f"empty value in {values_text!r}; give v1,v2,...")
    return key, values


def plan_runs(scene_paths: list[str], overrides: list[str], sweeps: list[str]):
    """(label, scene) for every scene and every combination of sweep values; all validated here."""
    from .scene import load_scene
    from .scenes import default_scene

    scene_paths = scene_paths or [str(default_scene())]
    parsed = [parse_sweep(s) for s in sweeps]
    count = len(scene_paths) * math.prod(len(values) for _, values in parsed)
    if count > MAX_RUNS:  # each run is a scene load and a simulation: a hostile product never ends
        raise InputError("--sweep", parsed[0][0] if parsed else "-", f"{count} runs requested, at most {MAX_RUNS}")
    combos = list(itertools.product(*[[(key, v) for v in values] for key, values in parsed])) or [()]
    plans = []
    for path in scene_paths:
        for combo in combos:
            extra = [f"{key}={value}" for key, value in combo]
            scene = load_scene(path, [*overrides, *extra])
            label = scene.name
            if combo:
                label += " [" + ", ".join(extra) + "]"
            plans.append((label, scene))
    labels = [label for label, _ in plans]
    # labels name the recordings in the viewer: make repeated ones distinguishable
    seen: dict[str, int] = {}
    for i, label in enumerate(labels):
        if labels.count(label) > 1:
            seen[label] = seen.get(label, 0) + 1
            plans[i] = (f"{label} #{seen[label]}", plans[i][1])
    return plans


def _with_parts_or_warn(label: str, result):
    """The run with its 3D parts; if the meshes cannot be built for this gear, the series and
    events are still worth recording: say so and leave the parts out."""
    from .recording import Run, with_parts

    try:
        return with_parts(label, result)
    except Exception as exc:  # noqa: BLE001 - a viewer extra must not lose the recording
        print(f"warning: {label}: 3D parts left out ({type(exc).__name__}: {exc})", file=sys.stderr)
        return Run(label=label, result=result)


def run(args) -> int:
    from .effects import simulate

    from .recording import check_rrd_path

    out = check_rrd_path(args.output, "--output")
    plans = plan_runs(args.scenes, args.overrides, args.sweep)  # every input error before any work
    from .recording import Run, write_recordings

    runs = []
    for label, scene in plans:
        result = simulate(scene)
        runs.append(Run(label=label, result=result) if args.no_parts else _with_parts_or_warn(label, result))
    try:
        write_recordings(out, runs)
    except (OSError, RuntimeError) as exc:  # disk full, rerun CLI missing: not the user's input
        print(f"error: {out}: --output: writing failed: {exc}", file=sys.stderr)
        return 1
    steps = sum(len(r.result.columns["time_s"]) for r in runs)
    print(f"{out}: {len(runs)} recording{'s' if len(runs) != 1 else ''}, {steps} steps")
    for r in runs:
        n_events = len(r.result.summary.get("events", []))
        n_warn = len(r.result.summary.get("warnings", []))
        print(f"  {r.label}: {len(r.result.columns['time_s'])} steps, {n_events} events, {n_warn} warnings")
    print(f"view it with: explorer view {out}")
    return 0
