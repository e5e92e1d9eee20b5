"""How wrong is a tolerance study that judges each draw only at the speeds where the nominal design
was worst (phase one of `explorer check`)? Against every draw run at every speed of the range, and
beside the check's own estimate (phase one, plus phase two where the rule is not exact there).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/check_tolerance_accuracy.py \\
        [SCENE RPM RUNS KEY=DISTRIBUTION ...]

Default: valve_float_demo.toml over 800..3200 rpm (100 speeds) and over 800..6500 rpm (200 speeds),
300 lash draws, seed 1 (docs/guide/checks.md quotes this table). Prints, per rule the draws judge at
a few speeds: P(fail) of phase one alone, the check's P(fail) with its interval and method, and
P(fail) with every draw over every speed (the reference: draws x speeds elastic runs, one core).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from _timing import ROOT

DEFAULTS = [
    ("valve_float_demo.toml", "800:3200:100", 300, {"valve.lash": "normal(0.25 mm, 0.03 mm)"}),
    ("valve_float_demo.toml", "800:6500:200", 300, {"valve.lash": "normal(0.25 mm, 0.02 mm)"}),
]


def study(scene_file: str, rpm: str, runs: int, sample: dict, seed: int = 1) -> None:
    import explorer
    from explorer import load_scene
    from explorer.checks.case import Case, Draws
    from explorer.checks.registry import measure_function, rules
    from explorer.checks.rule import verdicts
    from explorer.checks.run import _focus_speeds, operating_speeds
    from explorer.checks.settings import resolve
    from explorer.studies.sweep_spec import make_plan, parse_sample

    path = scene_file if "/" in scene_file else str(ROOT / "assets" / "scenes" / scene_file)
    scene = load_scene(path)
    started = time.process_time()
    report = explorer.check(scene, rpm=rpm, sample=sample, runs=runs, seed=seed, workers=1)
    check_cpu = time.process_time() - started
    speeds, _ = operating_speeds(scene, rpm)
    plan = make_plan((), [parse_sample(k, v) for k, v in sample.items()], runs=runs, seed=seed, yes=True)
    draws = Draws(plan.keys, plan.values)
    settings, off = resolve([scene.checks])
    nominal = Case(scene, speeds, workers=1)
    ends = speeds[[0, -1]]
    rows = []
    started = time.process_time()
    for spec in rules():
        r = report.result(spec.name)
        if r.samples is None or not r.sample_method or r.sample_method.startswith("exact: every draw's worst"):
            continue  # not judged, or exact in phase one
        m0 = measure_function(spec)(nominal, settings[spec.name])
        focus = {spec.name: _focus_speeds(spec, m0, speeds)}
        first = measure_function(spec)(Case(scene, ends, draws, focus, workers=1), settings[spec.name])
        full = measure_function(spec)(Case(scene, ends, draws, {spec.name: np.union1d(speeds, focus[spec.name])},
                                           workers=1), settings[spec.name])

        def share(m):
            return float(np.mean(verdicts(m.value, m.fail, m.warn, spec.sense).max(axis=1) == 2))

        rows.append((spec.name, share(first), r.p_fail, r.p_fail_interval, share(full), r.sample_method))
    print(f"{scene.name}: {rpm} rpm ({speeds.size} speeds), {runs} draws of {'; '.join(f'{k} = {v}' for k, v in sample.items())}"
          f", seed {seed}")
    print(f"  check: {check_cpu:.2f} s CPU; reference (every draw at every speed): {time.process_time() - started:.1f} s CPU")
    for name, p1, p, (lo, hi), ref, method in rows:
        print(f"  {name:18s} phase one {p1:.3f}  check {p:.3f} [{lo:.3f}, {hi:.3f}]  every speed {ref:.3f}  ({method})")


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if argv:
        scene, rpm, runs, *pairs = argv
        study(scene, rpm, int(runs), dict(p.split("=", 1) for p in pairs))
    else:
        for scene, rpm, runs, sample in DEFAULTS:
            study(scene, rpm, runs, sample)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
