"""The `scipy` reference solver (explorer/dynamics/reference.py) against closed forms.

Every case is small and hand-built so that its motion is known exactly:
- contact-only free vibration of the linear oscillator (a sinusoid);
- free flight under constant deceleration (a parabola) and the seat landing time;
- a drive that stops dead: contact oscillation, separation at a closed-form instant, a parabolic
  flight and re-contact at a closed-form instant (M1 in contact and M in flight);
- residual vibration after a cycloidal rise: A/h = |sin pi r| / (pi r |1 - r^2|);
- restitution: geometric bounces that end before their accumulation time;
- Coulomb friction: a valve that sticks at its apex, or falls with reduced deceleration.
At rtol 1e-12 DOP853 is accurate to ~1e-13 m on these; tolerances below leave a factor ~10-100.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from explorer.dynamics.model import PHASE_CODES, Drive, LinkageModel
from explorer.dynamics.solvers import solve
from explorer.lift.curves import LawLift
from dynamics_cases import (REF, SCHENKER, BumpLift, ConstantLift, flight_case, friction_apex, rise_in_contact,
                            schenker_drive, stopping_drive)


def test_free_vibration_in_contact_is_the_exact_sinusoid():
    # M1 s'' = k (H - s) - W: oscillation about s_eq = H - W/k with omega = sqrt(k/M1).
    k, m1, W, H = 2.0e6, 0.5, 2.0e4, 0.02
    model = LinkageModel(mass=0.8, oscillating_mass=m1, stiffness=k, preload=W)
    drive = Drive(ConstantLift(H), 1.0, 50.0)
    s_eq, w = H - W / k, math.sqrt(k / m1)
    s0, v0 = s_eq + 1.0e-3, 0.3  # amplitude ~1.1 mm < W/k = 10 mm: contact is never lost
    t = np.linspace(0.0, 0.0125, 501)  # ~ 20 periods
    sol = solve(model, drive, t, initial_state=(s0, v0), **REF)
    exact = s_eq + (s0 - s_eq) * np.cos(w * t) + v0 / w * np.sin(w * t)
    vel = -(s0 - s_eq) * w * np.sin(w * t) + v0 * np.cos(w * t)
    assert np.abs(sol.s - exact).max() < 1e-12  # 20 periods at rtol 1e-12: phase drift ~1e-13 m
    assert np.abs(sol.v - vel).max() < 1e-8
    assert np.abs(sol.a + w * w * (sol.s - s_eq)).max() < 1e-4 * w * w * 1e-3
    assert sol.contact.all() and sol.events == () and np.all(sol.phase == PHASE_CODES["contact"])
    np.testing.assert_allclose(sol.linkage_force, k * (H - sol.s), rtol=1e-12)
    np.testing.assert_allclose(sol.jerk, -w * w * sol.v, rtol=1e-12, atol=1e-9)  # j = -omega^2 v


def test_flight_is_a_parabola_and_the_landing_time_is_its_root():
    model, drive, (s0, v0), g, t_land = flight_case()
    t = np.linspace(0.0, 2 * t_land, 1001)
    sol = solve(model, drive, t, initial_state=(s0, v0), **REF)
    flying = t < t_land
    np.testing.assert_allclose(sol.s[flying], s0 + v0 * t[flying] - 0.5 * g * t[flying] ** 2, rtol=0, atol=1e-15)
    np.testing.assert_allclose(sol.a[flying], -g, rtol=1e-14)
    assert np.abs(sol.s[~flying]).max() < 1e-15 and np.all(sol.v[t > t_land + 1e-9] == 0.0)  # e = 0: stays down
    assert [e["kind"] for e in sol.events] == ["seat"]
    assert np.all(sol.phase[flying] == PHASE_CODES["flight"]) and np.all(sol.phase[t > t_land * (1 + 1e-12)] == PHASE_CODES["seated"])
    assert sol.events[0]["time_s"] == pytest.approx(t_land, rel=1e-13)
    assert sol.events[0]["velocity_m_s"] == pytest.approx(v0 - g * t_land, rel=1e-12)


def test_drive_stopping_dead_gives_closed_form_separation_and_re_contact():
    # the drive stops dead; separation, flight and re-contact in closed form (see stopping_drive)
    case = stopping_drive()
    t, t1, t_sep, t_re = case.t, case.t1, case.t_sep, case.t_re
    sol = solve(case.model, case.drive, t, initial_state=case.start, **REF)
    kinds = [e["kind"] for e in sol.events]
    assert kinds[:2] == ["separation", "re-contact"]
    assert sol.events[0]["time_s"] == pytest.approx(t_sep, abs=1e-13)
    assert sol.events[1]["time_s"] == pytest.approx(t_re, abs=1e-13)
    flying = (t > t_sep) & (t < t_re)
    np.testing.assert_allclose(sol.s[flying], case.flight(t[flying]), rtol=0, atol=1e-13)
    assert not sol.contact[flying].any() and np.all(sol.linkage_force[flying] == 0.0)
    before = (t > t1) & (t < t_sep)
    np.testing.assert_allclose(sol.s[before], case.oscillation(t[before]), rtol=0, atol=1e-13)


@pytest.mark.parametrize("r", [0.5, 1.0, 1.5, 2.0, 2.7])
def test_residual_vibration_after_a_cycloidal_rise(r):
    # Kept in contact (W = k*base holds the valve on its seat exactly until the rise begins),
    # y = s - L obeys M1 y'' + k y = -M1 L'': after a cycloidal rise of duration r Tn the free
    # vibration has amplitude A = h |sin pi r| / (pi r |1 - r^2|) (zero at integer r >= 2).
    case = rise_in_contact("cycloidal", r)
    t = np.linspace(0.0, case.t_dwell + 3 * case.Tn, 3001)
    sol = solve(case.model, case.drive, t, **REF)
    assert sol.events[0]["kind"] == "lift-off"
    # the cycloid starts as u^3: below u ~ 3e-6 of the rise the lift vanishes next to `base` in
    # floating point, so the computed lift-off may lag the start of the rise by that much
    assert sol.events[0]["time_s"] == pytest.approx(case.t_start, abs=1e-5 * r * case.Tn)
    assert np.abs(case.amplitude(sol, t) - case.cycloidal_amplitude).max() < 1e-12  # h = 2 mm: ~5e-10 relative
    assert sol.contact[t > case.t_dwell].all()


def test_restitution_bounces_are_geometric_and_end_before_accumulation():
    M, W, e = 0.1, 100.0, 0.8
    model = LinkageModel(mass=M, oscillating_mass=M, stiffness=1e6, preload=W, restitution=e)
    drive = Drive(ConstantLift(0.0), 1.0, 10.0)
    g, v0 = W / M, 1.0
    t_first = 2 * v0 / g
    t_inf = t_first + 2 * e * v0 / (g * (1 - e))  # sum of all flight times
    t = np.linspace(0.0, 1.5 * t_inf, 3001)
    sol = solve(model, drive, t, initial_state=(0.0, v0), **REF)
    seats = [ev for ev in sol.events if ev["kind"] == "seat"]
    speeds = np.array([-ev["velocity_m_s"] for ev in seats])
    # rebounds end once one would rise less than 1e-12 m: e|v| < sqrt(2 g 1e-12) = 4.5e-5 m/s,
    # after 1 + log(4.5e-5)/log(0.8) = 45 impacts
    assert len(seats) == 45
    # event location to ~1e-16 s relative: impact speeds exact to ~1e-12 m/s
    np.testing.assert_allclose(speeds, v0 * e ** np.arange(len(speeds)), rtol=1e-9)
    assert seats[0]["time_s"] == pytest.approx(t_first, rel=1e-12)
    assert seats[-1]["time_s"] < t_inf
    assert np.all(sol.s[t > t_inf] == 0.0)
    assert np.all(sol.s >= 0.0)


@pytest.mark.parametrize("preload", [30.0, 80.0])
def test_coulomb_friction_sticks_or_slips_at_the_apex(preload):
    # sticks at the apex when W <= mu, else falls with deceleration (W - mu)/M (friction_apex)
    case = friction_apex(preload)
    t = np.linspace(0.0, 4 * case.t_top, 2001)
    sol = solve(case.model, case.drive, t, initial_state=case.start, **REF)
    after = t > case.t_top
    if case.sticks:
        np.testing.assert_allclose(sol.s[after], case.top, rtol=1e-13)
        assert np.all(sol.v[after] == 0.0) and np.all(sol.phase[after] == PHASE_CODES["stuck"])
    else:
        np.testing.assert_allclose(sol.s[after], case.fall(t[after]), rtol=0, atol=1e-14)


@pytest.mark.parametrize("method", ["RK45", "Radau", "LSODA"])
def test_other_methods_agree_with_dop853(method):
    case = stopping_drive()  # separation and re-contact
    model, drive, start = case.model, case.drive, case.start
    t = np.linspace(0.0, 0.008, 801)
    ref = solve(model, drive, t, initial_state=start, **REF)
    other = solve(model, drive, t, initial_state=start, method="scipy", scipy_method=method, rtol=1e-10, atol=1e-14)
    # rtol 1e-10 on a 6 mm lift through separation and re-contact: ~1e-9 m, LSODA/Radau a bit worse
    assert np.abs(other.s - ref.s).max() < 1e-7
    assert [e["kind"] for e in other.events] == [e["kind"] for e in ref.events]
    assert other.stats["method"] == method and other.stats["nfev"] > 0


def test_bounded_step_catches_a_short_re_contact_that_free_steps_jump_over():
    # A valve drifting in flight sees a narrow smooth bump of the drive (no breakpoints) pass
    # under it. With free step sizes (a parabola is integrated exactly, so steps grow without
    # limit) the solver steps over the bump and the sign-change test misses both crossings;
    # with max_step = Tn/4 (0.16 ms, the bump is above the valve for ~0.5 ms) it sees them.
    M, W = 0.1, 1e-3
    model = LinkageModel(mass=M, oscillating_mass=M, stiffness=1e7, preload=W)
    drive = Drive(BumpLift(height=0.02, centre=1.0, width=2e-4), 1.0, 1.0)
    t = np.linspace(0.95, 1.05, 101)
    bounded = solve(model, drive, t, initial_state=(0.011, 0.0), **REF)
    free = solve(model, drive, t, initial_state=(0.011, 0.0), max_step_fraction=1e9, **REF)
    assert "re-contact" in [e["kind"] for e in bounded.events]
    assert [e["kind"] for e in free.events] == []
    assert bounded.stats["max_step_s"] == pytest.approx(0.25 * model.natural_period())


@pytest.mark.parametrize(
    "case",
    [
        dict(law="harmonic", rpm=400, model=dict(mass=28.44, oscillating_mass=25.5, stiffness=1.765e7, preload=3775.6)),
        dict(law="cycloidal", rpm=6000, model=dict(mass=0.12, oscillating_mass=0.1, stiffness=2e6, damping=20.0, lash=3e-4,
                                                    preload=250.0, spring_rate=25e3, friction=15.0, closing_load=20.0)),
        dict(law="polynomial-345", rpm=7000, model=dict(mass=0.12, oscillating_mass=0.1, stiffness=2e6, lash=3e-4,
                                                         preload=250.0, spring_rate=25e3, closing_load=20.0, restitution=0.7)),
    ],
    ids=["schenker-400rpm", "damped-friction-6000rpm", "bouncing-7000rpm"],
)
def test_agrees_with_the_exact_solver(case):
    # Two independent methods (adaptive Runge-Kutta with event location vs closed-form steps
    # with root-finding) on one revolution with lift-off, separation, re-contact and seat:
    # at rtol 1e-12 they agree to ~1e-13 m; 1e-9 m is the promise of a converged reference.
    model = LinkageModel(**case["model"])
    lift = LawLift(height=0.0103 if case["rpm"] > 1000 else 0.0206, start=0.35, rise=1.22, dwell=0.0, ret=1.22,
                   rise_law=case["law"], return_law=case["law"])
    drive = Drive(lift, 1.0, 2 * math.pi * case["rpm"] / 60)
    t = np.arange(3600) * (2 * math.pi / drive.omega) / 3600
    ref = solve(model, drive, t, **REF)
    exact = solve(model, drive, t, method="exact")
    kinds = {e["kind"] for e in ref.events}
    assert {"lift-off", "separation", "seat"} <= kinds
    assert np.abs(ref.s - exact.s).max() < 1e-9
    assert np.abs(ref.v - exact.v).max() < 1e-6
    # events pair up to 1e-9 s; exact may also report a re-contact in the same instant as a
    # seat landing at zero lash (gap and lift close together), where the reference lets the seat decide
    def matched(event, others):
        return any(o["kind"] == event["kind"] and abs(o["time_s"] - event["time_s"]) < 1e-9 for o in others)

    assert all(matched(e, exact.events) for e in ref.events)
    seats = [e["time_s"] for e in ref.events if e["kind"] == "seat"]
    for e in exact.events:
        if not matched(e, ref.events):
            assert e["kind"] == "re-contact" and min(abs(e["time_s"] - ts) for ts in seats) < 1e-9


def test_watching_event_extrema_finds_a_short_flight_inside_one_step():
    # Schenker's gear (M = 2.9, M1 = 2.6, k = 1.8e6, W = 385 in technical units) on a harmonic
    # cam at 400 rpm: near 0.0603 s the valve leaves the linkage for 0.3 ms (a gap of 2 um).
    # DOP853 at rtol 1e-10 steps ~1 ms there; plain sign-change detection sees the separation
    # force positive at both ends of the step and misses the flight (and its 6 um aftermath);
    # watching the force's minimum finds it.
    model, drive = SCHENKER, schenker_drive(400)
    t = np.linspace(0.0, 2 * math.pi / drive.omega, 3601)
    ref = solve(model, drive, t, **REF)
    watched = solve(model, drive, t, method="scipy", rtol=1e-10, atol=1e-13)
    plain = solve(model, drive, t, method="scipy", rtol=1e-10, atol=1e-13, watch_extrema=False)
    short = [e["time_s"] for e in ref.events if e["kind"] == "separation" and 0.060 < e["time_s"] < 0.061]
    assert len(short) == 1
    assert watched.stats["double_crossings"] >= 1
    assert [e["kind"] for e in watched.events] == [e["kind"] for e in ref.events]
    assert np.abs(watched.s - ref.s).max() < 1e-10
    assert not any(abs(e["time_s"] - short[0]) < 1e-6 for e in plain.events)
    assert np.abs(plain.s - ref.s).max() > 1e-6


@pytest.mark.parametrize("damping", [20.0, 100.0])
def test_damped_linkage_recontacts_after_separating_while_compressed(damping):
    """With damping the linkage lets go while still compressed (k x + c (S' - v) = 0 at x > 0): the
    re-contact must be found where the linkage would push again, not where the gap closes (it is
    open already). scipy and the exact solver, two independent methods, agree on every event and
    to 1e-10 m (both converged far below that)."""
    from explorer.studies.bench import model_and_drive
    from explorer.scene.scene import load_scene

    scene = load_scene(Path(__file__).resolve().parents[1] / "assets" / "scenes" / "valve_float_demo.toml",
                       ['linkage.stiffness="5e6 N/m"', f'linkage.damping="{damping} N*s/m"'])
    model, drive = model_and_drive(scene)
    t = np.arange(3600) * (2.0 * math.pi / drive.omega / 3600)
    exact = solve(model, drive, t, method="exact")
    ref = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14)
    kinds = [e["kind"] for e in exact.events]
    assert kinds.count("re-contact") >= 2
    assert [e["kind"] for e in ref.events] == kinds
    assert np.abs(exact.s - ref.s).max() < 1e-10
