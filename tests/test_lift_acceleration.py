"""The `acceleration` law: exact integration, closure checks, units, and bad input.

Oracles: the closed-form integral of a linear acceleration piece; a converged reference (points
sampled from the cycloidal law's acceleration integrate back to the cycloidal lift with the
h^2 error of linear interpolation); time-domain quadrature of the simulated columns (integral
of p dt and of v dt over the revolution); the shipped demo's designed peak lift.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import trapezoid

from explorer import InputError, load_scene, loads_scene, simulate
from explorer.lift.curves import LawLift
from explorer.effects.lift import build_lift
from explorer.lift.acceleration import AccelerationLift, AccelerationOptions

from conftest import SCENES, process_timeout

DEMO = SCENES / "acceleration_demo.toml"
# symmetric about 50 deg with zero acceleration area on each half: closes exactly
CLOSED = [(0, 0.0), (20, 30.0), (40, -30.0), (60, -30.0), (80, 30.0), (100, 0.0)]


def scene_text(points, extra="", rpm=240):
    rows = ", ".join(f"[{a!r}, {v!r}]" for a, v in points)
    return f"""
effects = ["kinematics", "lash"]
[drive]
rpm = {rpm}
[lift]
law = "acceleration"
start = "30 deg"
points = [{rows}]
{extra}
[valve]
mass = "1 kg"
lash = "0.2 mm"
"""


def test_single_linear_piece_is_the_closed_form():
    """L'' = a0 + (a1 - a0) x / w integrates to L = a0 x^2/2 + (a1 - a0) x^3 / (6 w)."""
    w, a0, a1 = 1.3, 0.02, -0.05
    options = AccelerationOptions(angles=(0.0, w), values=(a0, a1))
    lift = AccelerationLift.from_options(options, start=0.0)
    x = np.linspace(0.0, w, 101, endpoint=False)
    d = lift.derivatives(x)
    k = (a1 - a0) / w
    assert d[0] == pytest.approx(a0 * x**2 / 2 + k * x**3 / 6, rel=1e-14, abs=1e-18)
    assert d[1] == pytest.approx(a0 * x + k * x**2 / 2, rel=1e-14, abs=1e-18)
    assert d[2] == pytest.approx(a0 + k * x, rel=1e-14)
    assert d[3] == pytest.approx(np.full_like(x, k), rel=1e-14)
    outside = lift.derivatives(np.array([w + 0.1, 2 * math.pi - 1e-9]))
    assert not np.any(outside)


@pytest.mark.parametrize("n", [40, 80, 160])
def test_sampled_cycloidal_acceleration_integrates_back_to_the_cycloid(n):
    """Linear interpolation of L'' has error h^2/8 max|L''''|; integrated twice over the rise
    and return the lift error is bounded by about beta^2/2 times that. Halving h quarters it."""
    beta, h = math.radians(70), 0.01
    law = LawLift(h, 0.0, beta, 0.0, beta, "cycloidal", "cycloidal")
    x = np.linspace(0.0, 2 * beta, 2 * n + 1)
    options = AccelerationOptions(angles=tuple(x), values=tuple(law.derivatives(x)[2]))
    lift = AccelerationLift.from_options(options, start=0.0)
    check = np.linspace(0.0, 2 * beta, 2001)
    step = x[1] - x[0]
    l4 = (2 * math.pi) ** 3 * h / beta**4  # max |L''''| of the cycloid
    bound = step**2 / 8 * l4 * (2 * beta) ** 2 / 2
    error = np.abs(lift.derivatives(check)[0] - law.derivatives(check)[0]).max()
    assert error < bound
    assert error > bound / 100  # the bound is realistic, not vacuous
    c = lift.closure_check()
    assert abs(c.end_velocity) < 1e-15 and abs(c.end_lift) < 1e-15  # symmetric samples close exactly


def test_demo_closes_and_reports_its_checks():
    result = simulate(load_scene(DEMO))
    s = result.report()
    assert abs(s["closure_integral_p_dt_m_s"]) < 1e-8  # points given to 10 digits
    assert abs(s["closure_integral_v_dt_m"]) < 1e-10
    assert s["acceleration_area_above_m_s"] == pytest.approx(-s["acceleration_area_below_m_s"], rel=1e-8)
    assert s["acceleration_law_peak_lift_m"] == pytest.approx(0.0206, rel=1e-8)  # designed so
    assert s["acceleration_law_event_deg"] == 160.0
    assert s["warnings"] == []
    # t' = 160 deg at 240 rpm = 0.111 s (Schenker's gear), and the time columns agree
    assert math.radians(160) / load_scene(DEMO).omega == pytest.approx(60 * 160 / (240 * 360), rel=1e-14)


def test_time_domain_quadrature_of_the_columns_confirms_closure():
    """Independent of the PPoly: trapezoid sums of p dt and v dt over the sampled revolution."""
    result = simulate(load_scene(DEMO, overrides=["solver.steps_per_revolution=36000"]))
    c = result.columns
    t = np.append(c["time_s"], result.summary["revolution_time_s"])
    p = np.append(c["follower_accel_m_s2"], c["follower_accel_m_s2"][0])
    v = np.append(c["follower_velocity_m_s"], c["follower_velocity_m_s"][0])
    # trapezoid error on piecewise-linear p with kinks between samples: <= max|p| * dt * (number of kinks)
    dt = t[1] - t[0]
    assert abs(trapezoid(p, t)) < 8 * 41 * dt
    assert abs(trapezoid(v, t)) < 1e-9
    above = trapezoid(np.clip(p, 0, None), t)
    assert above == pytest.approx(result.summary["acceleration_area_above_m_s"], rel=1e-4)


def test_per_angle_units_equal_time_units_at_the_reference_speed():
    """a [m/s^2] at w_ref equals L'' = a / w_ref^2 [m/rad^2]; in mm/deg^2 that is
    a / w^2 * 1000 * (pi/180)^2."""
    w = 240 * math.pi / 30
    pts = CLOSED
    a = simulate(loads_scene(scene_text(pts)))
    per_angle = [(x, v / w**2 * 1e3 * (math.pi / 180) ** 2) for x, v in pts]
    b = simulate(loads_scene(scene_text(per_angle, 'acceleration_unit = "mm/deg**2"')))
    assert b.columns["follower_lift_m"] == pytest.approx(a.columns["follower_lift_m"], rel=1e-12, abs=1e-15)  # abs: rounding near the closed end, 1e-13 of the peak
    # the peak acceleration is the largest point value, at the scene's (= reference) speed
    assert a.summary["max_valve_accel_m_s2"] == pytest.approx(30.0, rel=1e-12)


def test_reference_rpm_keeps_the_cam_when_the_speed_changes():
    pts = CLOSED
    fixed = 'reference_rpm = "240 rpm"'
    slow = simulate(loads_scene(scene_text(pts, fixed)))
    fast = simulate(loads_scene(scene_text(pts, fixed), overrides=["drive.rpm=480"]))
    assert fast.columns["follower_lift_m"] == pytest.approx(slow.columns["follower_lift_m"], rel=1e-12, abs=1e-15)  # abs: rounding near the closed end, 1e-13 of the peak
    assert fast.summary["max_valve_accel_m_s2"] == pytest.approx(4 * 30.0, rel=1e-12)
    # without reference_rpm the values are at the file's own drive.rpm (240), not at the speed an
    # override runs it at: the same cam (a sweep keeps it too; tests/test_cam_written_speed.py)
    follow = simulate(loads_scene(scene_text(pts), overrides=["drive.rpm=480"]))
    assert follow.columns["follower_lift_m"] == pytest.approx(slow.columns["follower_lift_m"], rel=1e-12, abs=1e-15)
    assert follow.summary["max_valve_accel_m_s2"] == pytest.approx(4 * 30.0, rel=1e-12)


def test_step_interpolation_holds_values():
    """Constant pieces +a, -a, -a, +a over equal angles: a closed event with v piecewise linear."""
    pts = [(0, 10.0), (30, -10.0), (90, 10.0), (120, 0.0)]
    scene = loads_scene(scene_text(pts, 'interpolation = "step"'))
    lift = build_lift(scene)
    w = scene.omega
    d = lift.derivatives(np.radians([30 + 15, 30 + 45, 30 + 105]))
    assert w**2 * d[2] == pytest.approx([10.0, -10.0, 10.0], rel=1e-12)
    assert not np.any(d[3])
    c = lift.closure_check()
    assert abs(c.end_velocity) < 1e-16 and abs(c.end_lift) < 1e-16
    # peak lift at 60 deg: s = a t1^2 (accelerate then decelerate over t1 = 30 deg / w)
    t1 = math.radians(30) / w
    assert c.peak_lift == pytest.approx(10.0 * t1**2, rel=1e-12)


def test_small_closure_error_warns_and_large_one_fails():
    pts = CLOSED
    nearly = [(x, a * (1 + 1e-4) if x == 40 else a) for x, a in CLOSED]
    result = simulate(loads_scene(scene_text(nearly)))
    assert any("does not close" in w for w in result.warnings)
    assert result.summary["closure_relative_error"] > 1e-6
    assert simulate(loads_scene(scene_text(pts))).summary["closure_relative_error"] < 1e-12
    gross = [(x, a * 1.2 if x == 40 else a) for x, a in CLOSED]
    with pytest.raises(InputError, match="does not close"):
        loads_scene(scene_text(gross))


@pytest.mark.parametrize(
    "points,extra,key,words",
    [
        ([(5, 0.0), (20, 1.0)], "", "lift.points", "first point must be at angle 0"),
        ([(0, 0.0), (20, 1.0), (20, 2.0)], "", "lift.points", "increase strictly"),
        ([(0, 0.0), (200, 1.0), (400, 0.0)], "", "lift.points", "more than 360"),
        ([(0, 0.0)], "", "lift.points", "at least two"),
        ([(0, 0.0), (20, float("nan"))], "", "lift.points", "finite"),
        ([(0, 0.0), (20, 0.0)], "", "lift.points", "no lift"),
        ([(0, 0.0), (20, 3e7), (60, -3e7), (80, 0.0)], "", "lift.points", "more than 1 m"),
        ([(0, 0.0), (20, 1.0), (80, 0.0)], 'acceleration_unit = "mm/deg"', "lift.acceleration_unit", "squared"),
        ([(0, 0.0), (20, 1.0), (80, 0.0)], 'acceleration_unit = "kg"', "lift.acceleration_unit", "neither"),
        ([(0, 0.0), (20, 1.0), (80, 0.0)], 'acceleration_unit = "mm/deg**2"\nreference_rpm = 300', "lift.reference_rpm", "time-based"),
        ([(0, 0.0), (20, 1.0), (80, 0.0)], 'interpolation = "cubic"', "lift.interpolation", "unknown value"),
        ([(0, 0.0), (20, 1.0), (80, 0.0)], 'height = "10 mm"', "lift.height", "not used"),
        ([(0, 0.0), (20, 1.0), (80, 0.0)], 'reference_rpm = -5', "lift.reference_rpm", "greater than zero"),
    ],
)
def test_bad_points_and_options(points, extra, key, words):
    with pytest.raises(InputError) as info:
        loads_scene(scene_text(points, extra), source="acc.toml")
    assert info.value.file == "acc.toml" and info.value.key == key and words in info.value.reason


def test_dip_below_base_circle_is_rejected():
    # a closed hump, then a closed hump half as high downwards: the follower would have to sink
    # into the base circle
    dip = CLOSED + [(100 + x, -a / 2) for x, a in CLOSED[1:]]
    with pytest.raises(InputError) as info:
        loads_scene(scene_text(dip))
    assert "dip below the base circle 0.5 of the peak lift" in info.value.reason
    with pytest.raises(InputError, match="no lift above the base circle"):
        loads_scene(scene_text([(x, -a) for x, a in CLOSED]))


@pytest.mark.parametrize("bad", ['[[0, 0], "x"]', '[[0, true], [10, 1]]', '"0, 1"', '[[0, 1, 2], [3, 4, 5]]'])
def test_points_of_the_wrong_shape(bad):
    text = scene_text([(0, 0.0), (10, 1.0)]).replace("points = [[0, 0.0], [10, 1.0]]", f"points = {bad}")
    with pytest.raises(InputError) as info:
        loads_scene(text)
    assert info.value.key == "lift.points"


def test_load_time_closure_equals_the_ppoly_closure():
    """Two independent computations of the closure: closed-form piece sums in numpy (used when
    a scene loads) and scipy PPoly antiderivatives (used for the curve). Random curves, fixed seed."""
    from explorer.lift.acceleration import closure_of_points

    rng = np.random.default_rng(1902)
    for _ in range(200):
        n = int(rng.integers(2, 12))
        x = np.concatenate([[0.0], np.sort(rng.uniform(0.0, 6.0, n - 1))])
        a = rng.normal(size=n) * (rng.random(n) < 0.8)
        for interpolation in ("linear", "step"):
            c1 = closure_of_points(x, a, interpolation)
            c2 = AccelerationLift.from_options(AccelerationOptions(tuple(x), tuple(a), interpolation), 0.0).closure_check()
            scale = max(c2.peak_lift, c2.peak_velocity, 1e-300)
            for name in ("end_velocity", "end_lift", "area_above", "area_below", "peak_velocity", "peak_lift", "min_lift"):
                assert abs(getattr(c1, name) - getattr(c2, name)) <= 1e-12 * scale, name


def test_loading_needs_no_scipy():
    """The load-time check is numpy only, so loading an acceleration scene stays fast."""
    import subprocess
    import sys

    code = f"import sys, explorer; explorer.load_scene({str(DEMO)!r}); print('scipy' in sys.modules)"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=process_timeout())
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "False"
