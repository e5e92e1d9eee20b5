"""Schenker's 1902 stepping scheme (explorer/dynamics/schenker1902.py).

Oracles:
- the printed formulas of the paper, typed out again here for one step with its own numbers;
- closed forms: free vibration in contact (a sinusoid), the flight parabola, residual vibration
  after a cycloidal rise A/h = |sin pi r| / (pi r |1 - r^2|);
- the scheme's amplification matrix (derived by hand in the module docstring) and the classic
  implicit linear-acceleration (Newmark gamma = 1/2, beta = 1/6) matrix;
- the converged scipy reference for a case with separation and re-contact.
"""

import math

import numpy as np
import pytest

from explorer.dynamics import schenker1902 as sch
from explorer.dynamics.model import Drive, LinkageModel
from explorer.dynamics.solvers import solve
from explorer.lift.curves import LawLift
from dynamics_cases import KGF, SCHENKER, ConstantLift, flight_case, rise_in_contact, schenker_drive


def free_vibration(h_over_tn: float, steps: int, variant="printed", deviation=(1e-4, 0.0), allow_unstable=False):
    """Contact-only oscillator about s_eq = H - W/k (W/k = 10 mm keeps contact for |dev| < 10 mm)."""
    k, m1 = 1.0e6, 1.0
    model = LinkageModel(mass=m1, oscillating_mass=m1, stiffness=k, preload=k * 0.01)
    drive = Drive(ConstantLift(0.02), 1.0, 1.0)
    tn = model.natural_period()
    t = np.arange(steps + 1) * h_over_tn * tn
    s_eq = 0.01
    sol = solve(model, drive, t, method="schenker1902", variant=variant, allow_unstable=allow_unstable,
                initial_state=(s_eq + deviation[0], deviation[1]))
    return t, sol, s_eq, 2 * math.pi / tn


def test_one_step_is_the_printed_formula():
    # Start at Schenker's point B (s = 0, v = 0, p = 0) with the roller path S rising at 0.5 m/s
    # past S0 = W/k; one step of 0.2 ms by the paper's formulas, typed out independently.
    M1, k, W = 2.6 * KGF, 1.8e6 * KGF, 385.0 * KGF
    S0 = W / k
    assert S0 == pytest.approx(0.000214, abs=5e-7)  # the paper's 385 / 1 800 000 = 0.000214 m
    lift = LawLift(height=0.02, start=0.0, rise=2.0, dwell=0.0, ret=2.0, rise_law="harmonic", return_law="harmonic")
    drive = Drive(lift, 1.0, 5.0)
    t1, dt = 0.1, 2e-4
    S1, S2 = drive(np.array([t1, t1 + dt]))[0]
    s1, v1 = S1 - S0, 0.3  # in contact, compression exactly W/k: p1 = 0
    p1 = (k / M1) * (S1 - S0 - s1)
    s2 = s1 + v1 * dt + dt**2 / 2 * (p1 + k / (3 * M1) * (S2 - S1 - v1 * dt - p1 / 2 * dt**2))
    p2 = (k / M1) * (S2 - S0 - s2)
    v2 = v1 + (p1 + p2) / 2 * dt
    model = LinkageModel(mass=2.9 * KGF, oscillating_mass=M1, stiffness=k, preload=W)
    sol = solve(model, drive, np.array([t1, t1 + dt]), method="schenker1902", initial_state=(s1, v1))
    assert sol.s[1] == pytest.approx(s2, rel=1e-14)
    assert sol.v[1] == pytest.approx(v2, rel=1e-14)
    assert sol.a[1] == pytest.approx(p2, rel=1e-10)


def test_free_vibration_converges_at_second_order():
    errors = []
    for per_period in (20, 40, 80):
        t, sol, s_eq, w = free_vibration(1.0 / per_period, 10 * per_period)  # 10 periods
        exact = s_eq + 1e-4 * np.cos(w * t)
        errors.append(np.abs(sol.s - exact).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # phase error Omega^3/24 per step -> global error ~ (Omega^2/24) * omega t: order 2 exactly
    assert np.all(np.abs(orders - 2.0) < 0.05), orders


def test_flight_parabola_is_exact_and_landing_is_seen_at_the_next_step_end():
    model, drive, (s0, v0), g, t_land = flight_case()
    t = np.linspace(0.0, 2 * t_land, 401)
    sol = solve(model, drive, t, method="schenker1902", initial_state=(s0, v0))
    flying = t < t_land
    # constant acceleration: linear acceleration is exact, errors are rounding only
    np.testing.assert_allclose(sol.s[flying], s0 + v0 * t[flying] - 0.5 * g * t[flying] ** 2, rtol=0, atol=1e-16)
    np.testing.assert_allclose(sol.a[flying], -g, rtol=1e-13)
    (seat,) = sol.events
    assert seat["kind"] == "seat"
    assert t_land <= seat["time_s"] < t_land + (t[1] - t[0])
    assert np.all(sol.s[~flying] == 0.0)


@pytest.mark.parametrize("r", [0.5, 1.5, 2.0])
def test_residual_vibration_after_a_cycloidal_rise_converges_to_the_closed_form(r):
    case = rise_in_contact("cycloidal", r)
    h, Tn = case.h, case.Tn
    errors = []
    for per_period in (40, 80, 160):
        t = np.arange(0.0, case.t_dwell + 3 * Tn, Tn / per_period)
        sol = solve(case.model, case.drive, t, method="schenker1902")
        errors.append(np.abs(case.amplitude(sol, t) - case.cycloidal_amplitude).max())
    # lift-off seen one step late costs O(h^3) of lift; the rest of the error is O(h^2)
    assert errors[-1] < 2e-4 * h
    assert errors[0] / errors[1] > 3.0 and errors[1] / errors[2] > 3.0, errors


def test_stability_limit_values():
    assert sch.stability_limit("printed") == pytest.approx(0.38985, abs=1e-5)  # sqrt(6)/(2 pi)
    assert sch.stability_limit("newmark") == pytest.approx(0.55133, abs=1e-5)  # sqrt(3)/pi
    for variant in sch.VARIANTS:
        limit = 2 * math.pi * sch.stability_limit(variant)
        below = np.abs(np.linalg.eigvals(sch.amplification_matrix(limit * (1 - 1e-6), variant))).max()
        above = np.abs(np.linalg.eigvals(sch.amplification_matrix(limit * (1 + 1e-3), variant))).max()
        assert below == pytest.approx(1.0, abs=1e-9) and above > 1.01


@pytest.mark.parametrize("variant", sch.VARIANTS)
@pytest.mark.parametrize("h_over_tn", [0.1, 0.3, 0.45, 0.6])
def test_solver_step_is_the_amplification_matrix(variant, h_over_tn):
    # Two runs of one step from unit deviations of s and of h*v give the columns of the
    # one-step map on (s - s_eq, h v); free_vibration has omega_n = 1000 rad/s.
    h = h_over_tn * 2 * math.pi / 1e3
    columns = []
    for ds, h_dv in ((1e-4, 0.0), (0.0, 1e-4)):
        t, sol, s_eq, w = free_vibration(h_over_tn, 1, variant, deviation=(ds, h_dv / h), allow_unstable=True)
        assert t[1] == pytest.approx(h)
        columns.append([(sol.s[1] - s_eq) / 1e-4, sol.v[1] * h / 1e-4])
    numeric = np.array(columns).T
    np.testing.assert_allclose(numeric, sch.amplification_matrix(2 * math.pi * h_over_tn, variant), rtol=0, atol=1e-9)


@pytest.mark.parametrize("variant", sch.VARIANTS)
def test_growth_beyond_the_limit_and_boundedness_below(variant):
    limit = sch.stability_limit(variant)
    # below: 5000 steps stay within the invariant ellipse of A (det A = 1, no numerical damping),
    # i.e. within the initial deviation times the condition number of A's eigenvectors
    t, sol, s_eq, w = free_vibration(0.98 * limit, 5000, variant, deviation=(1e-6, 0.0))
    A = sch.amplification_matrix(2 * math.pi * 0.98 * limit, variant)
    assert np.abs(sol.s - s_eq).max() < 1e-6 * np.linalg.cond(np.linalg.eig(A)[1])
    # beyond: the deviation grows by the spectral radius per step (real eigenvalues > 1 in size:
    # positive for the printed scheme, trace > 2; negative, a sawtooth, for Newmark, trace < -2).
    # 1e-9 m grown to ~1e-4 m stays far inside the 10 mm of contact: the problem stays linear.
    ratio = 1.05 * limit
    rho = np.abs(np.linalg.eigvals(sch.amplification_matrix(2 * math.pi * ratio, variant))).max()
    steps = int(math.log(1e5) / math.log(rho))
    t, sol, s_eq, w = free_vibration(ratio, steps, variant, deviation=(1e-9, 0.0), allow_unstable=True)
    dev = sol.s - s_eq
    assert rho > 1.1
    assert abs(dev[-1] / dev[-2]) == pytest.approx(rho, rel=1e-3)
    assert abs(dev[-1]) > 1e3 * 1e-9
    assert sol.contact.all() and "unstable" in sol.stats["warnings"][0]


def test_refuses_an_unstable_step_and_names_the_steps_needed():
    # The stiff linkage of the stability suite: k = 1e11 N/m on a 0.12 kg valve at 3000 rpm is
    # h/Tn = 0.8 at 3600 steps per revolution, beyond both limits.
    model = LinkageModel(mass=0.12, oscillating_mass=0.12, stiffness=1e11, preload=300.0)
    drive = Drive(ConstantLift(0.0), 1.0, 2 * math.pi * 50)
    revolution = 0.02
    assert revolution / 3600 / model.natural_period() == pytest.approx(0.8, abs=0.01)
    needed = sch.min_stable_steps(model, drive.omega)
    assert revolution / needed < sch.stability_limit() * model.natural_period() <= revolution / (needed - 1)
    with pytest.raises(sch.StabilityError, match=f"at least {needed} equal steps"):
        solve(model, drive, np.linspace(0.0, revolution, needed), method="schenker1902")
    sol = solve(model, drive, np.linspace(0.0, revolution, needed + 1), method="schenker1902")
    assert sol.stats["step_over_period"] < sch.stability_limit()
    assert needed > 3600 and sch.min_stable_steps(model, drive.omega, "newmark") > 3600


def test_schenker_gear_lift_off_flight_deceleration_and_paper_masses():
    # Lift-off is seen at the first step end where S > S0 = W/k; while separated the
    # deceleration is W/M = 385/2.9 = 133 m/s^2; with masses="paper" the contact phase where the
    # linkage force is below W uses M (Schenker's C to F), elsewhere M1.
    drive = schenker_drive(400)
    t = np.linspace(0.0, 2 * math.pi / drive.omega, 20001)
    S0 = SCHENKER.preload / SCHENKER.stiffness
    for masses in sch.MASS_RULES:
        sol = solve(SCHENKER, drive, t, method="schenker1902", masses=masses)
        kinds = [e["kind"] for e in sol.events]
        assert kinds[0] == "lift-off" and "separation" in kinds and "re-contact" in kinds
        S = drive(t)[0]
        i = int(np.searchsorted(t, sol.events[0]["time_s"]))
        assert S[i] > S0 >= S[i - 1]
        flying = ~sol.contact & (sol.s > 0)
        np.testing.assert_allclose(sol.a[flying], -385.0 / 2.9, rtol=1e-12)
        assert 385.0 / 2.9 == pytest.approx(133, abs=0.5)
        in_contact = sol.contact & (sol.s > 0)
        force = sol.linkage_force[in_contact]
        mass = np.where((masses == "paper") & (force <= SCHENKER.preload), SCHENKER.mass, SCHENKER.oscillating_mass)
        np.testing.assert_allclose(sol.a[in_contact], (force - SCHENKER.preload) / mass, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("m1_share", [1.0, 2.6 / 2.9])
def test_converges_to_the_reference_through_separation_and_re_contact(m1_share):
    # 400 rpm: lift-off, five separations and re-contacts, seat. Events are seen at step ends
    # only: where the acceleration is continuous through the event (M1 = M) that costs O(h^2)
    # and the scheme stays second order; where it jumps (Schenker's M1 < M switches the mass at
    # separation and re-contact) a late event costs O(h) in velocity, and the order drops to 1.
    model = LinkageModel(mass=SCHENKER.mass, oscillating_mass=m1_share * SCHENKER.mass,
                         stiffness=SCHENKER.stiffness, preload=SCHENKER.preload)
    drive = schenker_drive(400)
    t = np.linspace(0.0, 2 * math.pi / drive.omega, 721)
    ref = solve(model, drive, t, method="scipy", rtol=1e-12, atol=1e-15)
    errors = []
    for sub in (5, 160):  # 3600 and 115 200 steps per revolution
        sol = solve(model, drive, t, method="schenker1902", substeps=sub)
        errors.append(np.abs(sol.s - ref.s).max())
    # at closing the valve grazes the seat (seat, lift-off, seat within 0.1 ms): only the fine run
    # is asked to resolve the same sequence of events
    assert [e["kind"] for e in sol.events] == [e["kind"] for e in ref.events]
    order = math.log(errors[0] / errors[1]) / math.log(32)
    if m1_share == 1.0:
        assert order > 1.6 and errors[1] < 1e-9, errors
    else:
        assert 0.7 < order < 1.5 and errors[1] < 1e-6, errors


@pytest.mark.parametrize("damping", [20.0, 100.0])
def test_damped_linkage_recontacts_where_it_would_push_again(damping):
    """With damping the linkage lets go while still compressed (x > 0): re-contacting where the gap
    is positive would separate again every step. The scheme must find the exact solver's
    separations at any step, and come closer to it as the step shrinks."""
    from pathlib import Path

    from explorer.studies.bench import model_and_drive
    from explorer.scene.scene import load_scene

    scene = load_scene(Path(__file__).resolve().parents[1] / "assets" / "scenes" / "valve_float_demo.toml",
                       ['linkage.stiffness="5e6 N/m"', f'linkage.damping="{damping} N*s/m"'])
    model, drive = model_and_drive(scene)
    t = np.arange(3600) * (2.0 * math.pi / drive.omega / 3600)
    exact = solve(model, drive, t, method="exact")
    separations = sum(e["kind"] == "separation" for e in exact.events)
    errors = []
    for substeps in (1, 16):
        sol = solve(model, drive, t, method="schenker1902", substeps=substeps)
        assert sum(e["kind"] == "separation" for e in sol.events) == separations
        errors.append(float(np.abs(sol.s - exact.s).max()))
    assert errors[1] < errors[0] / 4.0 and errors[1] < 3e-7
