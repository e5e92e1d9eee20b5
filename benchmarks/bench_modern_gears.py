"""Benchmark of today's valve trains' kinematics (issue #24: one revolution at 3600 steps <= 5 ms).

    .venv/bin/python benchmarks/bench_modern_gears.py [--repeat 15] [--speeds 1000] [--sweep-repeat 3]

For each gear, the median time of its full kinematics over one revolution of 3600 cam angles:
valve lift with v, a, jerk (jets), the cam's contour, radius of curvature and contact point, the
pressure angle, the ratios, the sliding and entrainment velocities at the cam and at the valve
tip. Synthesis: the gear's own lift law (what a scene runs); analysis: the same gear over the cam
it synthesised, given as 720 points through a quintic spline (Newton on the contour for every
angle). Baseline in the same run: the translating roller's kinematics of the same law (lift law
and explorer.lift.contours.translating's closed-form profile), the gear the project started with.
The machine is shared (the load average is printed with the table): the times are CPU times of
this process (time.process_time), which a busy machine inflates far less than wall-clock times;
the wall-clock medians are printed beside them.

The built-in scenes of the gears (assets/scenes/bucket_tappet.toml, finger_follower.toml, ohc_rocker.toml,
pushrod_rocker.toml; phase B): the kinematics effect of one revolution at 3600 steps through the pipeline (the gear's lift
built anew for every run, so that its kinematics memo is not what is timed; baseline: the same
effect on the translating roller's scene cycloidal_demo at 3600 steps), and a 1000-speed sweep
(0.5 to 1.5 times the scene's speed, every figure of the scene's sweep row) through the sweep
engine the scene takes, after one warm-up chunk (numba's import and the compiled solver's load).

    .venv/bin/python benchmarks/bench_modern_gears.py --scenes-only [--repeat 15] [--speeds 1000]
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np
from _timing import median_times, print_table


def gears():
    from explorer.gears.arm import CamSide, make_arm, make_arm_gear
    from explorer.gears.flat_face import Tappet, synthesise_bucket
    from explorer.gears.pushrod import Lifter, make_pushrod_train
    from explorer.lift.curves import LawLift

    lift = LawLift(height=0.0093, start=math.radians(30), rise=math.radians(85), dwell=0.0, ret=math.radians(85),
                   rise_law="polynomial-345", return_law="polynomial-345")
    gentle = LawLift(height=0.0093, start=math.radians(30), rise=math.radians(105), dwell=0.0,
                     ret=math.radians(105), rise_law="polynomial-345", return_law="polynomial-345")
    finger = dict(base_radius=0.018, pivot=(-0.032, -0.036), branch=-1, valve_arm=math.hypot(0.056, 0.010),
                  valve_pad_radius=0.012, valve_axis=-0.5 * math.pi, tip_radius=0.0035)
    roller = CamSide("roller", math.hypot(0.032, 0.009), 0.009, width=0.010)
    pad = CamSide("pad", math.hypot(0.032, 0.016), math.inf, face_angle=-0.5 * math.pi, width=0.010)
    rocker_side = CamSide("roller", math.hypot(0.035, 0.004), 0.008, width=0.010)
    rocker_rest = make_arm(base_radius=0.018, pivot=(0.035, 0.030), cam_side=rocker_side, branch=-1).rest
    pivot, half = (0.020, 0.260), 0.13
    cup = (pivot[0] + 0.025 * math.cos(math.pi + half), pivot[1] + 0.025 * math.sin(math.pi + half))
    pad_centre = (pivot[0] + 0.040 * math.cos(half), pivot[1] + 0.040 * math.sin(half))
    train = dict(base_radius=0.017, rocker_pivot=pivot, cup=cup, valve_pad_centre=pad_centre, valve_pad_radius=0.010,
                 valve_axis=-0.5 * math.pi, tip_radius=0.004)
    return {
        "bucket tappet, flat": synthesise_bucket(Tappet(base_radius=0.018), lift),
        "bucket tappet, crowned": synthesise_bucket(Tappet(base_radius=0.018, face_radius=2.0), lift),
        "finger follower, roller": make_arm_gear(cam_side=roller, valve_angle=math.atan2(0.010, 0.056)
                                                 - math.atan2(0.009, 0.032), law=lift, **finger),
        "finger follower, flat pad": make_arm_gear(cam_side=pad, valve_angle=math.atan2(0.010, 0.056)
                                                   - math.atan2(0.016, 0.032), law=gentle, **finger),
        "OHC rocker, roller": make_arm_gear(base_radius=0.018, pivot=(0.035, 0.030), cam_side=rocker_side, branch=-1,
                                            valve_arm=0.055, valve_angle=-rocker_rest, valve_pad_radius=0.012,
                                            valve_axis=-0.5 * math.pi, law=lift, kind="rocker"),
        "pushrod, flat lifter": make_pushrod_train(lifter=Lifter("flat", socket_height=0.04), law=lift, **train),
        "pushrod, roller lifter": make_pushrod_train(lifter=Lifter("roller", radius=0.009, socket_height=0.03),
                                                     law=lift, **train),
    }, lift


def analysed(name, gear):
    """The same gear over its own cam as 720 points (a quintic spline through them)."""
    from dataclasses import replace

    from explorer.gears.arm import make_arm_gear
    from explorer.gears.flat_face import analyse_bucket
    from explorer.gears.pushrod import _lifter_motion
    from explorer.lift.contours.parametric import SplineContour

    points = SplineContour(gear.surface(np.linspace(0.0, 2.0 * math.pi, 720, endpoint=False)).contour)
    if name.startswith("bucket"):
        return analyse_bucket(gear.tappet, points)
    if name.startswith("pushrod"):
        return replace(gear, law=None, motion=_lifter_motion(gear, points), contour=points)
    v = gear.valve
    return make_arm_gear(base_radius=gear.arm.base_radius, pivot=gear.arm.pivot, cam_side=gear.arm.cam_side,
                         branch=gear.arm.branch, valve_arm=v.drive.arm, valve_angle=v.drive.angle,
                         valve_pad_radius=v.pad_radius, valve_axis=v.drive.axis, contour=points, kind=gear.kind,
                         check=False)


SCENES = ("bucket_tappet", "finger_follower", "ohc_rocker", "pushrod_rocker")


def scenes(repeat: int, speeds: int, sweeps: int) -> None:
    """The built-in scenes' kinematics effect and 1000-speed sweeps (module docstring)."""
    from dataclasses import replace
    from pathlib import Path

    from explorer.effects.pipeline import simulate
    from explorer.scene.scene import load_scene
    from explorer.studies.sweep_engine import _Shared, compute_chunk, engine_for, result_columns

    root = Path(__file__).resolve().parent.parent / "assets" / "scenes"
    loaded = {name: load_scene(root / f"{name}.toml", ["solver.steps_per_revolution=3600"])
              for name in ("cycloidal_demo", *SCENES)}
    only = {name: scene.with_changes(effects=("kinematics",)) for name, scene in loaded.items()}
    built = {name: scene.gear_plugin.build_lift(scene) for name, scene in only.items()}

    def fresh(name):
        lift = built[name]
        if not hasattr(lift, "memo"):  # no kinematics memo (the roller's law, the bucket's lift)
            return lambda: simulate(only[name], lift)
        return lambda: simulate(only[name], replace(lift, memo={}))  # the geometry, an empty memo

    cpu = median_times({name: fresh(name) for name in only}, repeat, clock=time.process_time)
    base = cpu["cycloidal_demo"]
    rows = [[name + (" (baseline)" if name == "cycloidal_demo" else ""), loaded[name].follower.type,
             f"{cpu[name] * 1e3:.2f}", f"{cpu[name] / base:.1f}"] for name in only]
    print(f"kinematics effect through the pipeline, one revolution at 3600 steps; CPU-time medians of {repeat} runs")
    print_table(["scene", "follower type", "ms", "x roller"], rows)
    rows = []
    for name in SCENES:
        scene = loaded[name]
        names = result_columns(scene)
        values = np.linspace(0.5, 1.5, speeds)[:, None] * scene.drive.rpm
        shared = _Shared()
        engine = engine_for(scene, shared).name
        compute_chunk(scene, ("drive.rpm",), values[:8], names, shared)  # warm-up: imports, the compiled solver
        times = []
        for _ in range(sweeps):
            started = time.perf_counter()
            table = compute_chunk(scene, ("drive.rpm",), values, names, _Shared())
            times.append(time.perf_counter() - started)
        failed = int(np.nansum(table[:, names.index("run_failed")]))
        rows.append([name, engine, str(speeds), f"{np.median(times):.3f}", f"{min(times):.3f}", str(failed)])
    print(f"{speeds}-speed sweep (0.5-1.5 x the scene's speed, every row figure), wall-clock median of {sweeps} "
          "(after a warm-up chunk)")
    print_table(["scene", "engine", "speeds", "median s", "best s", "failed runs"], rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--speeds", type=int, default=1000, help="speeds of the scenes' sweeps")
    parser.add_argument("--sweeps", type=int, default=3, help="sweeps timed per scene")
    parser.add_argument("--scenes-only", action="store_true", help="only the built-in scenes' table")
    args = parser.parse_args()
    if args.scenes_only:
        scenes(args.repeat, args.speeds, args.sweeps)
        print(f"load average (1, 5, 15 min): {', '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
        return

    from explorer.lift.contours.translating import profile_from_derivatives

    theta = np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False)
    built, lift = gears()

    def translating_roller():
        d = lift.derivatives(theta)
        return profile_from_derivatives(theta, d, 0.018, 0.009, 0.0)

    cases = {"translating roller (baseline)": translating_roller}
    for name, gear in built.items():
        cases[name] = (lambda g: lambda: g.kinematics(theta))(gear)
    cpu = median_times(cases, args.repeat, clock=time.process_time)
    wall = median_times(cases, args.repeat)
    over = {name: analysed(name, gear) for name, gear in built.items()}
    few = max(3, args.repeat // 3)
    slow = median_times({name: (lambda g: lambda: g.kinematics(theta))(g) for name, g in over.items()}, few,
                        clock=time.process_time)
    base = cpu["translating roller (baseline)"]
    rows = [["translating roller (baseline)", f"{base * 1e3:.2f}", "1.0", f"{wall['translating roller (baseline)'] * 1e3:.2f}",
             "", ""]]
    for name in built:
        rows.append([name, f"{cpu[name] * 1e3:.2f}", f"{cpu[name] / base:.1f}", f"{wall[name] * 1e3:.2f}",
                     f"{slow[name] * 1e3:.1f}", f"{slow[name] / base:.0f}"])
    print(f"one revolution, 3600 cam angles; CPU-time medians of {args.repeat} runs (analysis: of {few})")
    print_table(["gear", "synthesis ms", "x roller", "wall ms", "analysis ms", "x roller"], rows)
    print()
    scenes(args.repeat, args.speeds, args.sweeps)
    print(f"load average (1, 5, 15 min): {', '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
