"""The `exact` solver (explorer/dynamics/exact.py) against closed forms and the scipy reference.

Every case has an independent oracle: the damped oscillator's solution, the parabola of free
flight, the instants where a drive that stops dead lets the valve separate and catches it again,
the residual vibration after cycloidal and 3-4-5 rises (NOTES.md), geometric seat bounces and
their accumulation time, the Coulomb oscillator that loses 2R/K of amplitude per half cycle, and
solve_ivp (DOP853, rtol 1e-12) where no closed form exists. The solver's own error is rounding:
tolerances are ~1e-13 m on lifts of a few mm unless stated.
"""

import math

import numpy as np
import pytest

from explorer.dynamics.model import PHASE_CODES, Drive, LinkageModel
from explorer.dynamics.solvers import solve
from explorer.lift.curves import LawLift
from dynamics_cases import (KGF, REF, BumpLift, ConstantLift, flight_case, friction_apex, revolution,
                            rise_in_contact, stopping_drive)


def schenker_like(k_factor: float = 1.0, rpm: float = 240.0, friction_kgf: float = 35.0, restitution: float = 0.0):
    """Schenker's Fig. 4 numbers (kgf, technical mass units) on an analytic 160 deg harmonic flank."""
    g = KGF
    lift = LawLift(height=0.0206, start=math.radians(20), rise=math.radians(80), dwell=0.0,
                   ret=math.radians(80), rise_law="harmonic", return_law="harmonic")
    model = LinkageModel(mass=2.9 * g, oscillating_mass=2.6 * g, stiffness=k_factor * 1.8e6 * g, lash=0.6e-3,
                         preload=260 * g, friction=friction_kgf * g, closing_load=90 * g, restitution=restitution)
    return model, Drive(lift, 1.0, rpm * math.pi / 30.0)


@pytest.mark.parametrize("zeta", [0.0, 0.05, 1.0, 3.0])
def test_contact_free_vibration_matches_the_damped_oscillator(zeta):
    # M1 s'' + c s' + k s = k H - W: s - s_eq is the free damped oscillator (under-, critically
    # and over-damped: three different code paths of the modal recurrence)
    k, m1, W, H = 2.0e6, 0.5, 2.0e4, 0.02
    c = 2.0 * zeta * math.sqrt(k * m1)
    model = LinkageModel(mass=0.8, oscillating_mass=m1, stiffness=k, damping=c, preload=W)
    drive = Drive(ConstantLift(H), 1.0, 50.0)
    s_eq, w0, al = H - W / k, math.sqrt(k / m1), c / (2 * m1)
    x0, v0 = 1.0e-3, 0.3  # amplitude < W/k = 10 mm: contact is never lost
    t = np.linspace(0.0, 0.05, 2001)  # ~80 periods
    sol = solve(model, drive, t, initial_state=(s_eq + x0, v0))
    # x, x', x'', x''' of the closed form by complex exponentials (roots of m r^2 + c r + k)
    if zeta == 1.0:  # critical: (x0 + (v0 + al x0) t) e^(-al t)
        B = v0 + al * x0
        e = np.exp(-al * t)
        x = (x0 + B * t) * e
        derivs = [x]
        poly = [x0, B]  # d/dt of (p0 + p1 t) e^(-al t) = (p1 - al p0 - al p1 t) e^(-al t)
        for _ in range(3):
            poly = [poly[1] - al * poly[0], -al * poly[1]]
            derivs.append((poly[0] + poly[1] * t) * e)
    else:
        r1, r2 = np.roots([m1, c, k])
        A = (v0 - r2 * x0) / (r1 - r2)
        B = x0 - A
        derivs = [np.real(A * r1**n * np.exp(r1 * t) + B * r2**n * np.exp(r2 * t)) for n in range(4)]
    scale = 1e-3
    # rounding of the carried state: ~n eps |s| = 2000 * 2.2e-16 * 0.01 m = 4e-15 m
    assert np.abs(sol.s - s_eq - derivs[0]).max() < 1e-13
    assert np.abs(sol.v - derivs[1]).max() < 1e-12 * w0 * scale
    assert np.abs(sol.a - derivs[2]).max() < 1e-11 * w0**2 * scale
    assert np.abs(sol.jerk - derivs[3]).max() < 1e-10 * w0**3 * scale
    assert sol.contact.all() and sol.events == ()
    assert np.all(sol.phase == PHASE_CODES["contact"])
    np.testing.assert_allclose(sol.linkage_force, k * (H - sol.s) - c * sol.v, rtol=1e-12, atol=1e-9)


def test_flight_is_a_parabola_and_the_landing_time_its_root():
    model, drive, (s0, v0), g, t_land = flight_case()
    t = np.linspace(0.0, 2 * t_land, 1001)
    sol = solve(model, drive, t, initial_state=(s0, v0))
    flying = t < t_land
    np.testing.assert_allclose(sol.s[flying], s0 + v0 * t[flying] - 0.5 * g * t[flying] ** 2, rtol=0, atol=1e-15)
    np.testing.assert_allclose(sol.a[flying], -g, rtol=1e-13)
    # the output at t_land itself lies on the event to within rounding of the time
    assert np.abs(sol.s[~flying]).max() < 1e-16
    assert np.all(sol.s[t > t_land * (1 + 1e-12)] == 0.0) and np.all(sol.v[t > t_land * (1 + 1e-12)] == 0.0)
    # with zero lash and the drive at 0 the gap closes at the landing too: the seat decides
    assert [e["kind"] for e in sol.events] == ["seat"]
    assert sol.events[0]["time_s"] == pytest.approx(t_land, rel=1e-14)
    assert sol.events[0]["velocity_m_s"] == pytest.approx(v0 - g * t_land, rel=1e-13)


def test_drive_stopping_dead_gives_closed_form_separation_and_re_contact():
    # the drive stops dead; separation, flight and re-contact in closed form (see stopping_drive)
    case = stopping_drive()
    t, t1, t_sep, t_re = case.t, case.t1, case.t_sep, case.t_re
    sol = solve(case.model, case.drive, t, initial_state=case.start)
    assert [e["kind"] for e in sol.events[:2]] == ["separation", "re-contact"]
    assert sol.events[0]["time_s"] == pytest.approx(t_sep, abs=1e-15)
    assert sol.events[1]["time_s"] == pytest.approx(t_re, abs=2e-15)
    flying = (t > t_sep) & (t < t_re)
    # rounding of the carried state over 4000 steps: ~n eps |s| = 5e-15 m on s = 6 mm
    np.testing.assert_allclose(sol.s[flying], case.flight(t[flying]), rtol=0, atol=5e-15)
    assert not sol.contact[flying].any() and np.all(sol.phase[flying] == PHASE_CODES["flight"])
    before = (t > t1) & (t < t_sep)
    np.testing.assert_allclose(sol.s[before], case.oscillation(t[before]), rtol=0, atol=5e-15)


def _residual_amplitude(rise_law: str, r: float):
    """Amplitude of the free vibration after a rise of duration r Tn (see rise_in_contact)."""
    case = rise_in_contact(rise_law, r)
    t = np.linspace(0.0, case.t_dwell + 3 * case.Tn, 3001)
    sol = solve(case.model, case.drive, t)
    return case.amplitude(sol, t), case, sol


@pytest.mark.parametrize("r", [0.5, 1.0, 1.5, 2.0, 2.7])
def test_residual_vibration_after_a_cycloidal_rise(r):
    amplitude, case, sol = _residual_amplitude("cycloidal", r)
    assert np.abs(amplitude - case.cycloidal_amplitude).max() < 1e-14  # h = 2 mm
    assert [e["kind"] for e in sol.events] == ["lift-off"]


@pytest.mark.parametrize("r", [0.7, 1.3, 2.2])
def test_residual_vibration_after_a_345_rise(r):
    amplitude, case, _ = _residual_amplitude("polynomial-345", r)
    lam = 2 * math.pi * r
    expected = case.h * 120 * abs((12 - lam**2) * math.sin(lam / 2) - 6 * lam * math.cos(lam / 2)) / lam**5
    assert np.abs(amplitude - expected).max() < 1e-14


def test_restitution_bounces_are_geometric_and_end_at_the_accumulation_time():
    M, W, e = 0.1, 100.0, 0.8
    model = LinkageModel(mass=M, oscillating_mass=M, stiffness=1e6, preload=W, restitution=e)
    drive = Drive(ConstantLift(0.0), 1.0, 10.0)
    g, v0 = W / M, 1.0
    t_inf = 2 * v0 / g / (1 - e)  # sum of all flight times
    t = np.linspace(0.0, 1.5 * t_inf, 3001)
    zeno_height = 1e-12
    sol = solve(model, drive, t, initial_state=(0.0, v0), zeno_height=zeno_height)
    seats = [ev for ev in sol.events if ev["kind"] == "seat"]
    speeds = np.array([-ev["velocity_m_s"] for ev in seats])
    # event times to ~eps t: speeds to ~1e-15 m/s (a rebound of 5e-5 m/s: relative 1e-11)
    np.testing.assert_allclose(speeds, v0 * e ** np.arange(len(speeds)), rtol=1e-12, atol=1e-14)
    # chatter is followed while a rebound rises more than zeno_height, then summed in closed form
    assert (e * speeds[-1]) ** 2 / (2 * g) <= zeno_height < (e * speeds[-2]) ** 2 / (2 * g)
    assert seats[-1]["zeno_accumulation_s"] == pytest.approx(t_inf, rel=1e-13)
    assert np.all(sol.s[t > t_inf] == 0.0) and np.all(sol.s >= 0.0)
    assert sol.stats["zeno"] == 1
    lost = 0.5 * M * v0**2  # everything the valve had is lost at the seat, bit by bit
    assert sol.stats["impact_energy_loss_J"] == pytest.approx(lost, rel=1e-12)


def test_coulomb_friction_in_contact_loses_2R_over_K_per_half_cycle_and_sticks():
    k, m1, W, H, R = 1e6, 0.2, 5e3, 0.02, 300.0
    model = LinkageModel(mass=m1, oscillating_mass=m1, stiffness=k, preload=W, friction=R)
    drive = Drive(ConstantLift(H), 1.0, 50.0)
    s_eq, w = H - W / k, math.sqrt(k / m1)
    A0 = 1.1e-3
    t = np.linspace(0.0, 0.02, 4001)
    sol = solve(model, drive, t, initial_state=(s_eq + A0, 0.0))
    # half cycle n: centred at s_eq -+ R/K, amplitude A0 - (2n - 1) R/K about that centre
    n = 0
    while A0 - 2 * (n + 1) * R / k >= -R / k and abs(A0 - 2 * n * R / k) > R / k:
        n += 1
    rest = (A0 - 2 * n * R / k) * (-1) ** n
    half = math.pi / w
    assert sol.stats["velocity_reversals"] == n and sol.stats["sticks"] == 1
    # s = 15 mm: 1e-15 m is a few ulp of the carried state
    np.testing.assert_allclose(sol.s[t > n * half + 1e-9], s_eq + rest, rtol=0, atol=1e-15)
    first = t < half
    centre = s_eq + R / k  # moving down, friction acts up
    np.testing.assert_allclose(sol.s[first], centre + (A0 - R / k) * np.cos(w * t[first]), rtol=0, atol=1e-15)


@pytest.mark.parametrize("preload", [30.0, 80.0])
def test_coulomb_friction_at_the_flight_apex_sticks_or_slips(preload):
    case = friction_apex(preload)
    t = np.linspace(0.0, 4 * case.t_top, 2001)
    sol = solve(case.model, case.drive, t, initial_state=case.start)
    after = t > case.t_top
    if case.sticks:
        np.testing.assert_allclose(sol.s[after], case.top, rtol=1e-15)
        assert np.all(sol.v[after] == 0.0) and np.all(sol.phase[after] == PHASE_CODES["stuck"])
    else:
        np.testing.assert_allclose(sol.s[after], case.fall(t[after]), rtol=0, atol=1e-16)


def test_a_narrow_bump_between_two_output_times_is_caught():
    # A valve drifting up in flight meets a bump of the drive 0.4 ms wide while the output times
    # are 10 ms apart: a re-contact and a separation inside one step. The events must be found.
    # The solver splits steps to 2/omega_n = 0.2 ms, so the quintic interpolation of this bump
    # is coarse (~1e-8 s on the instants); with outputs 10 us apart it agrees with solve_ivp
    # (step bounded by Tn/4) to rounding.
    M, W = 0.1, 1e-3
    model = LinkageModel(mass=M, oscillating_mass=M, stiffness=1e7, preload=W)
    drive = Drive(BumpLift(height=0.02, centre=1.0, width=2e-4), 1.0, 1.0)
    coarse = solve(model, drive, np.linspace(0.5, 1.5, 101), initial_state=(0.011, 0.0))
    t_fine = np.linspace(0.5, 1.5, 100001)
    fine = solve(model, drive, t_fine, initial_state=(0.011, 0.0))
    ref = solve(model, drive, t_fine, initial_state=(0.011, 0.0), **REF)
    kinds = ["re-contact", "separation"]
    assert [e["kind"] for e in coarse.events] == [e["kind"] for e in fine.events] == [e["kind"] for e in ref.events] == kinds
    for a, b, c in zip(coarse.events, fine.events, ref.events):
        assert a["time_s"] == pytest.approx(c["time_s"], abs=1e-7)
        assert b["time_s"] == pytest.approx(c["time_s"], abs=1e-12)
        assert b["velocity_m_s"] == pytest.approx(c["velocity_m_s"], abs=1e-9)
    # the kicked valve flies off to ~43 m (W = 1 mN): compare relative to the lift
    np.testing.assert_allclose(fine.s, ref.s, rtol=1e-10, atol=1e-12)
    # coarse: the bump spans two internal steps; its quintic pieces give the kick to ~1e-4
    np.testing.assert_allclose(coarse.s, fine.s[::1000], rtol=1e-3, atol=1e-9)


def test_default_resolution_is_within_1e8_of_converged_references():
    # Schenker-like scene with a chain of separations and re-contacts: 3600 steps against the
    # same solver at 100x the steps, and against solve_ivp at rtol 1e-12
    model, drive = schenker_like()
    t = revolution(drive, 3600)
    sol = solve(model, drive, t)
    kinds = [e["kind"] for e in sol.events]
    assert kinds[0] == "lift-off" and kinds[-1] == "seat" and kinds.count("separation") >= 5
    assert kinds.count("separation") == kinds.count("re-contact")
    fine = solve(model, drive, revolution(drive, 360_000))
    assert np.abs(sol.s - fine.s[::100]).max() < 1e-11
    ref = solve(model, drive, t, **REF)
    assert [e["kind"] for e in ref.events] == kinds
    assert np.abs(sol.s - ref.s).max() < 1e-9  # scipy's own error at rtol 1e-12 dominates
    for a, b in zip(sol.events, fine.events):  # lift error 1e-13 m over relative speeds ~0.1 m/s
        assert a["time_s"] == pytest.approx(b["time_s"], abs=1e-10)


def test_a_jump_of_the_drive_acceleration_between_output_times_is_a_step_end():
    # harmonic rise and return without dwell: S'' jumps at start, top and end, none of them on
    # the output grid (start 20.05 deg with 1 deg outputs); a fine run is the oracle
    lift = LawLift(height=0.01, start=math.radians(20.05), rise=math.radians(60.3), dwell=0.0,
                   ret=math.radians(60.3), rise_law="harmonic", return_law="harmonic")
    model = LinkageModel(mass=0.1, oscillating_mass=0.1, stiffness=5e5, lash=1e-4, preload=300.0, spring_rate=2e4)
    drive = Drive(lift, 1.0, 300.0)
    coarse = solve(model, drive, revolution(drive, 360))
    fine = solve(model, drive, revolution(drive, 36000))
    assert np.abs(coarse.s - fine.s[::100]).max() < 1e-10
    assert [e["kind"] for e in coarse.events] == [e["kind"] for e in fine.events]


def test_output_times_must_be_sorted_but_may_repeat():
    model, drive = schenker_like()
    with pytest.raises(ValueError):
        solve(model, drive, np.array([0.0, 0.2, 0.1]))
    t = revolution(drive, 360)
    once = solve(model, drive, t)
    twice = solve(model, drive, np.repeat(t, 2))
    np.testing.assert_array_equal(twice.s[::2], once.s)
    np.testing.assert_array_equal(twice.s[1::2], once.s)
