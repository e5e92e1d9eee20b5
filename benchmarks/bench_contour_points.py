"""Cam given as a point list: accuracy and cost against the point density ("accuracy costs time").

    .venv/bin/python benchmarks/bench_contour_points.py [--repeat N]

The exact contour of a lift (synthesis) is sampled at n points, a periodic quintic spline is run
through them and the follower lift is analysed back (Newton iteration for the contact). Errors
are against the law itself: lift in metres, velocity/acceleration/jerk relative to their peaks.
Cases: a cosine lift (analytic contour: the spline converges like h^6), a 4-5-6-7 law (its
contour's third derivative jumps: h^4), a cycloidal law (jerk jumps: h^3 in the lift, no
convergence of the jerk), and Schenker's arc cam (curvature jumps: the acceleration never
settles). Time is the median of several runs of "build spline + analyse 3600 cam angles"; "x base"
is that time over a fixed numpy workload timed in this process, so figures compare across machines.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
from _timing import baseline_workload, median_time, print_table

COUNTS = (90, 180, 360, 720, 1440, 2880)
HEADER = ["case", "points", "lift err m", "v err", "a err", "j err", "time", "x base"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)

    from explorer.lift.contours.arcs import build_arc_contour, make_arc_lift
    from explorer.lift.contours.parametric import SplineContour, make_parametric_lift, points_accuracy
    from explorer.lift.contours.schenker_fig2 import PAPER_DESIGN, arcs
    from explorer.lift.curves import LawLift

    base = median_time(baseline_workload, args.repeat)
    theta = np.arange(3600) * 2 * math.pi / 3600
    print(f"baseline (numpy yardstick): {base * 1e3:.2f} ms")
    cases = {
        "cosine (harmonic 180+180 deg)": LawLift(0.008, 0.0, math.pi, 0.0, math.pi, "harmonic", "harmonic"),
        "polynomial-4567": LawLift(0.008, 0.5, 1.6, 0.3, 1.6, "polynomial-4567", "polynomial-4567"),
        "cycloidal": LawLift(0.008, 0.5, 1.6, 0.3, 1.6, "cycloidal", "cycloidal"),
    }

    def cells(name, n, errors, seconds):
        return [name, str(n), *(f"{e:.2e}" for e in errors), f"{seconds * 1e3:.1f}ms", f"{seconds / base:.2f}"]

    for name, lift in cases.items():
        rows = []
        for row in points_accuracy(lift, 0.03, 0.01, 0.0, counts=COUNTS):
            from explorer.lift.contours.translating import translating_profile

            n = row["points"]
            pts = translating_profile(lift, np.arange(n) * 2 * math.pi / n, 0.03, 0.01, 0.0).contour
            seconds = median_time(lambda: make_parametric_lift(SplineContour(pts), 0.01, 0.0, 0.03).derivatives(theta), args.repeat)
            errors = [row[key] for key in ("max_lift_error_m", "max_velocity_error_rel", "max_accel_error_rel", "max_jerk_error_rel")]
            rows.append(cells(name, n, errors, seconds))
        print_table(HEADER, rows)
    contour = build_arc_contour(arcs(PAPER_DESIGN))
    exact = make_arc_lift(contour, 0.01, 0.0, PAPER_DESIGN.base_radius)
    want = exact.derivatives(theta)
    rows = []
    for n in COUNTS:
        pts = contour.points_by_arc_length(n)
        analysed = make_parametric_lift(SplineContour(pts), 0.01, 0.0, PAPER_DESIGN.base_radius)
        got = analysed.derivatives(theta)
        err = [np.abs(got[k] - want[k]).max() / (np.abs(want[k]).max() if k else 1.0) for k in range(4)]
        seconds = median_time(lambda: make_parametric_lift(SplineContour(pts), 0.01, 0.0, PAPER_DESIGN.base_radius).derivatives(theta), args.repeat)
        rows.append(cells("Schenker Fig. 2 arcs", n, err, seconds))
    print_table(HEADER, rows)
    arc_seconds = median_time(lambda: make_arc_lift(contour, 0.01, 0.0, PAPER_DESIGN.base_radius).derivatives(theta), args.repeat)
    print(f"the same cam as arcs (closed form, exact): {arc_seconds * 1e3:.2f} ms ({arc_seconds / base:.3f} x base)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
