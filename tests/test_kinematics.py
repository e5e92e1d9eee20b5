"""Rigid kinematics and lash against closed forms written out here, independently of the code.

Scene: cycloidal rise (70 deg from 20 deg), 10 deg dwell, harmonic return (80 deg), lever
ratio 1.5, lash 0.3 mm, 1200 rpm. Closed forms: cycloidal L = h (u - sin(2 pi u)/(2 pi)),
harmonic return L = h (1 + cos(pi u))/2; valve s = max(0, ratio L - lash), v = ratio w L',
p = ratio w^2 L'', j = ratio w^3 L''' while open. Tolerances: 1e-12 relative for the columns
(same formulas, different arithmetic order); 1e-9 deg for the roots (Brent to ~1e-15 rad).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from explorer import loads_scene, simulate

H, START, RISE, DWELL, RET = 0.008, math.radians(20), math.radians(70), math.radians(10), math.radians(80)
RATIO, LASH, RPM = 1.5, 3e-4, 1200.0
W = RPM * 2 * math.pi / 60

SCENE = f"""
name = "kinematics oracle"
effects = ["kinematics", "lash"]
[drive]
rpm = {RPM}
[lift]
law = "cycloidal"
return_law = "harmonic"
height = "8 mm"
start = "20 deg"
rise = "70 deg"
dwell = "10 deg"
return = "80 deg"
[follower]
ratio = {RATIO}
[valve]
mass = "0.1 kg"
lash = "0.3 mm"
[solver]
steps_per_revolution = 7200
"""


def closed_form(theta):
    """Follower L, L', L'', L''' (per rad) of the scene, written out by hand."""
    x = np.mod(theta - START, 2 * math.pi)
    out = np.zeros((4, x.size))
    u = x / RISE
    r = x < RISE
    a = 2 * math.pi * u[r]
    out[0, r] = H * (u[r] - np.sin(a) / (2 * math.pi))
    out[1, r] = H / RISE * (1 - np.cos(a))
    out[2, r] = 2 * math.pi * H / RISE**2 * np.sin(a)
    out[3, r] = 4 * math.pi**2 * H / RISE**3 * np.cos(a)
    d = (x >= RISE) & (x < RISE + DWELL)
    out[0, d] = H
    f = (x >= RISE + DWELL) & (x < RISE + DWELL + RET)
    b = math.pi * (x[f] - RISE - DWELL) / RET
    out[0, f] = H * (1 + np.cos(b)) / 2
    out[1, f] = -H * math.pi / (2 * RET) * np.sin(b)
    out[2, f] = -H * math.pi**2 / (2 * RET**2) * np.cos(b)
    out[3, f] = H * math.pi**3 / (2 * RET**3) * np.sin(b)
    return out


@pytest.fixture(scope="module")
def result():
    return simulate(loads_scene(SCENE))


def test_follower_columns_are_the_closed_form(result):
    theta = np.radians(result.columns["cam_angle_deg"])
    d = closed_form(theta)
    c = result.columns
    assert c["follower_lift_m"] == pytest.approx(d[0], rel=1e-12, abs=1e-17)
    assert c["follower_velocity_m_s"] == pytest.approx(W * d[1], rel=1e-12, abs=1e-14)
    assert c["follower_accel_m_s2"] == pytest.approx(W**2 * d[2], rel=1e-12, abs=1e-11)
    assert c["follower_jerk_m_s3"] == pytest.approx(W**3 * d[3], rel=1e-12, abs=1e-8)


def test_valve_is_max_of_zero_and_ratio_lift_minus_lash(result):
    theta = np.radians(result.columns["cam_angle_deg"])
    d = closed_form(theta)
    s = np.maximum(0.0, RATIO * d[0] - LASH)
    is_open = RATIO * d[0] > LASH
    c = result.columns
    assert c["valve_lift_m"] == pytest.approx(s, rel=1e-12, abs=1e-17)
    assert c["valve_velocity_m_s"] == pytest.approx(np.where(is_open, RATIO * W * d[1], 0.0), rel=1e-12, abs=1e-14)
    assert c["valve_accel_m_s2"] == pytest.approx(np.where(is_open, RATIO * W**2 * d[2], 0.0), rel=1e-12, abs=1e-11)
    assert c["valve_jerk_m_s3"] == pytest.approx(np.where(is_open, RATIO * W**3 * d[3], 0.0), rel=1e-12, abs=1e-8)
    assert result.summary["max_valve_lift_m"] == pytest.approx(RATIO * H - LASH, rel=1e-12)
    # peak velocity of the cycloidal rise: 2 h / beta per rad (Cv = 2), times ratio * w
    assert result.summary["max_valve_velocity_m_s"] == pytest.approx(RATIO * W * 2 * H / RISE, rel=1e-6)


def test_lash_take_up_and_seating_by_root_finding_match_closed_forms(result):
    # take-up on the cycloidal rise: ratio h (u - sin(2 pi u)/(2 pi)) = lash, solved here independently
    u_up = brentq(lambda u: RATIO * H * (u - math.sin(2 * math.pi * u) / (2 * math.pi)) - LASH, 0.0, 0.5, xtol=1e-16)
    theta_up = START + u_up * RISE
    # seating on the harmonic return, in closed form: ratio h (1 + cos(pi u))/2 = lash
    u_seat = math.acos(2 * LASH / (RATIO * H) - 1) / math.pi
    theta_seat = START + RISE + DWELL + u_seat * RET
    s = result.summary
    assert s["lash_take_up_angles_deg"] == pytest.approx([math.degrees(theta_up)], abs=1e-9)
    assert s["seating_angles_deg"] == pytest.approx([math.degrees(theta_seat)], abs=1e-9)
    v_open = RATIO * W * H / RISE * (1 - math.cos(2 * math.pi * u_up))
    v_close = RATIO * W * H * math.pi / (2 * RET) * math.sin(math.pi * u_seat)
    assert s["impact_velocity_opening_m_s"] == pytest.approx(v_open, rel=1e-9)
    assert s["impact_velocity_closing_m_s"] == pytest.approx(v_close, rel=1e-9)
    kinds = {e["kind"]: e for e in result.events}
    assert kinds["lash-take-up"]["time_s"] == pytest.approx(theta_up / W, rel=1e-12)
    assert kinds["seat"]["time_s"] == pytest.approx(theta_seat / W, rel=1e-12)
    assert kinds["seat"]["velocity_m_s"] == pytest.approx(-v_close, rel=1e-9)


def test_symmetric_harmonic_event_impacts_are_equal_and_closed_form():
    """Harmonic rise and return, both with closed-form roots: theta = beta/pi acos(1 - 2 lash/h)."""
    text = SCENE.replace('law = "cycloidal"\nreturn_law = "harmonic"', 'law = "harmonic"').replace(
        'dwell = "10 deg"', 'dwell = "0 deg"').replace('return = "80 deg"', 'return = "70 deg"')
    s = simulate(loads_scene(text)).summary
    u = math.acos(1 - 2 * LASH / (RATIO * H)) / math.pi
    assert s["lash_take_up_angles_deg"] == pytest.approx([math.degrees(START + u * RISE)], abs=1e-9)
    assert s["seating_angles_deg"] == pytest.approx([math.degrees(START + 2 * RISE - u * RISE)], abs=1e-9)
    v = RATIO * W * H * math.pi / (2 * RISE) * math.sin(math.pi * u)
    assert s["impact_velocity_opening_m_s"] == pytest.approx(v, rel=1e-9)
    assert s["impact_velocity_closing_m_s"] == pytest.approx(v, rel=1e-9)


def test_lash_larger_than_lift_never_opens():
    text = SCENE.replace('lash = "0.3 mm"', 'lash = "13 mm"')  # ratio * h = 12 mm
    result = simulate(loads_scene(text))
    assert not np.any(result.columns["valve_lift_m"])
    assert result.summary["impact_velocity_opening_m_s"] == 0.0
    assert any("never opens" in w for w in result.warnings)


def test_no_valve_section_means_no_lash():
    text = SCENE.replace('[valve]\nmass = "0.1 kg"\nlash = "0.3 mm"\n', "")
    result = simulate(loads_scene(text))
    c = result.columns
    assert c["valve_lift_m"] == pytest.approx(RATIO * c["follower_lift_m"], rel=1e-15, abs=0)


def _harmonic_scene(start_deg, dwell_deg, lash, height="8 mm", ratio=1.0):
    return loads_scene(f"""
effects = ["kinematics", "lash"]
[drive]
rpm = {RPM}
[lift]
law = "harmonic"
height = "{height}"
start = "{start_deg} deg"
rise = "60 deg"
dwell = "{dwell_deg} deg"
return = "60 deg"
[follower]
ratio = {ratio}
[valve]
mass = "0.1 kg"
lash = "{lash}"
""")


@pytest.mark.parametrize("dwell", [0, 30])
def test_lift_exactly_equal_to_lash_never_opens(dwell):
    """ratio * h == lash: the follower only touches the valve (at the top, or along a whole dwell).
    s = max(0, ratio L - lash) stays 0, so there is no take-up, no seating and no impact."""
    result = simulate(_harmonic_scene(20, dwell, "8 mm"))
    s = result.report()
    assert not np.any(result.columns["valve_lift_m"])
    assert s["lash_take_up_angles_deg"] == [] and s["seating_angles_deg"] == []
    assert s["impact_velocity_opening_m_s"] == 0.0 and s["impact_velocity_closing_m_s"] == 0.0
    assert not [e for e in result.events if e["kind"] in ("lash-take-up", "seat")]
    assert any("never opens" in w for w in s["warnings"])


@pytest.mark.parametrize("start, dwell", [(330, 0), (300, 20), (350, 40)])
def test_event_wrapping_through_zero(start, dwell):
    """An event that starts before 360 deg and ends after it: the take-up lies before 0 deg, the
    seating after it, both at the closed-form angles theta = start + beta/pi acos(1 - 2 lash/h)
    (mod 360) of the harmonic flank, with equal impact speeds."""
    result = simulate(_harmonic_scene(start, dwell, "0.3 mm"))
    s = result.summary
    beta = math.radians(60)
    u = math.acos(1 - 2 * LASH / H) / math.pi
    up = math.degrees(math.radians(start) + u * beta) % 360
    seat = math.degrees(math.radians(start) + 2 * beta + math.radians(dwell) - u * beta) % 360
    assert s["lash_take_up_angles_deg"] == pytest.approx([up], abs=1e-9)
    assert s["seating_angles_deg"] == pytest.approx([seat], abs=1e-9)
    assert seat < up  # the seating comes after 0 deg, in the next revolution's numbering
    v = W * H * math.pi / (2 * beta) * math.sin(math.pi * u)
    assert s["impact_velocity_opening_m_s"] == pytest.approx(v, rel=1e-9)
    assert s["impact_velocity_closing_m_s"] == pytest.approx(v, rel=1e-9)
    events = sorted((e for e in result.events if e["kind"] in ("lash-take-up", "seat")), key=lambda e: e["time_s"])
    assert [e["kind"] for e in events] == ["seat", "lash-take-up"]  # in time order over 0 .. 360 deg


@settings(max_examples=200, deadline=None)
@given(
    start=st.floats(0.0, 2 * math.pi, exclude_max=True),
    rise=st.floats(0.01, 2.0),
    dwell=st.floats(0.0, 1.5),
    ret=st.floats(0.01, 2.0),
    law=st.sampled_from(["cycloidal", "harmonic", "polynomial-345", "modified-sine"]),
)
def test_law_lift_is_continuous_at_its_breakpoints(start, rise, dwell, ret, law):
    """The lift is continuous everywhere, so at each breakpoint it must equal its neighbours 1e-9 rad
    away to within slope * 1e-9 (h / rise * C_v * 1e-9 < 1e-10 m here). A breakpoint that falls in
    no stretch of the event (it happened on the dwell's end by rounding) read 0 instead of h."""
    from hypothesis import assume

    from explorer.lift.curves import LawLift

    assume(rise + dwell + ret <= 2 * math.pi)
    lift = LawLift(0.01, start, rise, dwell, ret, law, law)
    marks = lift.breakpoints()
    at = lift.derivatives(marks)[0]
    before = lift.derivatives(marks - 1e-9)[0]
    after = lift.derivatives(marks + 1e-9)[0]
    assert np.all(np.abs(at - before) < 1e-9) and np.all(np.abs(at - after) < 1e-9)


class _Bump:
    """A smooth periodic lift with no breakpoints (as a table or contour lift has): the cosine
    bump L = h (1 + cos(theta - c)) / 2, its maximum h at c, between grid points."""

    def __init__(self, h, centre):
        self.h, self.c = h, centre

    def derivatives(self, theta):
        x = np.asarray(theta, dtype=float) - self.c
        h = self.h / 2
        return np.stack([h * (1 + np.cos(x)), -h * np.sin(x), -h * np.cos(x), h * np.sin(x)])

    def breakpoints(self):
        return np.zeros(0)


def test_a_brief_opening_inside_one_grid_cell_is_found():
    """Lash 1e-9 m below the peak: the valve is open for 2 acos(1 - 2e-9/h) ~ 0.05 deg, less than a
    grid cell (360/4096 deg), centred between grid points. Closed form of the crossings:
    theta = c -+ acos(2 lash/h - 1)."""
    from explorer.mechanics.kinematics import lash_crossings

    h, c = 0.01, (100.5 / 4096) * 2 * math.pi  # the peak half-way between grid points
    lash = h - 1e-9
    ups, downs = lash_crossings(_Bump(h, c), 1.0, lash)
    half = math.acos(2 * lash / h - 1)
    assert 2 * math.degrees(half) < 360 / 4096
    assert ups == pytest.approx([c - half], abs=1e-9) and downs == pytest.approx([c + half], abs=1e-9)


def test_summary_peaks_and_open_angle_are_exact_not_sampled():
    """The summary's velocity and acceleration peaks and the open angle against the closed forms
    above on a coarse grid of 97 samples, where no sample lies on a peak (the samples' extremes
    miss them by up to a few %): cycloidal rise, peak acceleration 2 pi H / RISE^2 at u = 1/4 and
    -2 pi H / RISE^2 at u = 3/4, velocity 2 H / RISE at u = 1/2; harmonic return, velocity
    -pi H / (2 RET) at u = 1/2; open from the take-up (brentq on the closed-form cycloid) to the
    seating, arccos(2 lash / (ratio H) - 1) / pi of the return. Tolerance 1e-12 relative (Brent
    to ~1e-15 rad on the analytic curve; the peaks are flat there)."""
    coarse = loads_scene(SCENE.replace("steps_per_revolution = 7200", "steps_per_revolution = 97"))
    s = simulate(coarse).summary
    accel, vel = RATIO * W**2 * 2 * math.pi * H / RISE**2, RATIO * W * 2 * H / RISE
    assert s["max_valve_accel_m_s2"] == pytest.approx(accel, rel=1e-12)
    assert s["min_valve_accel_m_s2"] == pytest.approx(-accel, rel=1e-12)
    assert s["max_valve_velocity_m_s"] == pytest.approx(vel, rel=1e-12)
    assert s["min_valve_velocity_m_s"] == pytest.approx(-RATIO * W * math.pi * H / (2 * RET), rel=1e-12)
    u_up = brentq(lambda u: RATIO * H * (u - math.sin(2 * math.pi * u) / (2 * math.pi)) - LASH, 0.0, 1.0, xtol=1e-15)
    u_down = math.acos(2 * LASH / (RATIO * H) - 1.0) / math.pi
    open_deg = math.degrees(RISE + DWELL + u_down * RET - u_up * RISE)
    assert s["valve_open_angle_deg"] == pytest.approx(open_deg, abs=1e-9)
    sampled = simulate(coarse).columns["valve_accel_m_s2"]
    assert sampled.max() < accel and sampled.min() > -accel  # the samples do miss the peaks


def test_a_jump_of_the_acceleration_counts_with_its_one_sided_limit():
    """A harmonic rise into a dwell: the acceleration jumps from -pi^2 H / (2 RISE^2) to 0 where the
    dwell begins (the valve open, at full lift), the largest deceleration of the revolution (the
    return is longer): valve_extremes gives that one-sided limit (1e-9 relative: it is taken 1e-12
    rad inside the rise) on any grid, the samples only near it. The largest acceleration is at the
    take-up (the open stretch's start: one of the `ends`). A valve never open: its
    motion is 0."""
    from explorer.lift.curves import LawLift
    from explorer.mechanics.kinematics import valve_extremes

    h, rise, dwell, ret = 0.008, math.radians(60), math.radians(20), math.radians(90)
    lift = LawLift(h, math.radians(30), rise, dwell, ret, "harmonic", "harmonic")
    theta = np.linspace(0.0, 2 * math.pi, 101, endpoint=False)
    d = lift.derivatives(theta)
    from explorer.mechanics.kinematics import lash_crossings

    top, bottom = valve_extremes(lift, theta, d, 1.0, 1e-4, {2: 1.0}, np.concatenate(lash_crossings(lift, 1.0, 1e-4)))[2]
    assert bottom == pytest.approx(-math.pi**2 * h / (2 * rise**2), rel=1e-9)
    assert bottom < d[2].min()  # below every sample
    # the largest acceleration: the harmonic rise's start, pi^2 H / (2 RISE^2) cos(pi u) at the
    # take-up (ratio L = lash: u = arccos(1 - 2 lash / H) / pi), the acceleration falling from there
    u_up = math.acos(1 - 2e-4 / h) / math.pi
    assert top == pytest.approx(math.pi**2 * h / (2 * rise**2) * math.cos(math.pi * u_up), rel=1e-12)
    assert valve_extremes(lift, theta, d, 1.0, 1.0, {2: 1.0}) == {2: (0.0, 0.0)}  # never open: at rest


def test_open_angle_of_crossings_wraps_and_handles_always_open():
    from explorer.mechanics.kinematics import open_angle

    two_pi = 2 * math.pi
    assert open_angle(np.array([1.0]), np.array([2.5]), False) == pytest.approx(1.5, abs=1e-15)
    assert open_angle(np.array([6.0]), np.array([0.5]), False) == pytest.approx(two_pi - 6.0 + 0.5, abs=1e-15)
    assert open_angle(np.array([1.0, 4.0]), np.array([2.0, 4.5]), False) == pytest.approx(1.5, abs=1e-15)
    assert open_angle(np.array([]), np.array([]), False) == 0.0
    assert open_angle(np.array([]), np.array([]), True) == two_pi


def test_the_lift_peak_is_exact_between_samples():
    """max_follower_lift_m / max_valve_lift_m are the lift's exact peak, not the largest sample: the
    oracle scene without its dwell on 97 samples peaks at the rise's end, between two samples, at
    exactly H (cycloidal rise into a harmonic return: both at rest there); spline_demo's nose
    overshoots its 10 mm station between samples (oracle: a bounded scalar maximisation of the same
    curve to 1e-15 rad). Tolerance 1e-14 relative: the peak is flat, so Brent's ~1e-15 rad root of
    L' leaves the lift within a few ulps."""
    from scipy.optimize import minimize_scalar

    from explorer.effects.lift import build_lift
    from explorer.scene.scene import load_scene

    text = SCENE.replace('dwell = "10 deg"', 'dwell = "0 deg"').replace("steps_per_revolution = 7200",
                                                                      "steps_per_revolution = 97")
    result = simulate(loads_scene(text))
    assert result.columns["follower_lift_m"].max() < H * (1 - 1e-6)  # the samples miss the peak
    assert result.summary["max_follower_lift_m"] == pytest.approx(H, rel=1e-14)
    assert result.summary["max_valve_lift_m"] == pytest.approx(RATIO * H - LASH, rel=1e-14)

    scene = load_scene(Path(__file__).parent.parent / "assets" / "scenes" / "spline_demo.toml")
    lift = build_lift(scene)
    run = simulate(scene)
    theta = np.radians(run.columns["cam_angle_deg"])
    i = int(np.argmax(lift.derivatives(theta)[0]))
    best = minimize_scalar(lambda x: -lift.derivatives(np.array([x]))[0][0], bounds=(theta[i - 1], theta[i + 1]),
                           method="bounded", options={"xatol": 1e-15})
    assert run.summary["max_follower_lift_m"] == pytest.approx(-best.fun, rel=1e-14)
    assert run.summary["max_follower_lift_m"] > lift.derivatives(theta)[0].max()
    assert run.summary["max_valve_lift_m"] == scene.follower.ratio * run.summary["max_follower_lift_m"] - scene.valve.lash
