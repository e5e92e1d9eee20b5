"""The `taylor` solver (Taylor series of the contact ODE with k(t), explorer/dynamics/taylor.py).

Oracles:
- the manufactured solution of tests/test_dynamics_varying.py (s(t), k(t) chosen, the drive
  derived from them; exact derivatives by jets);
- with a constant profile, the exact solver (closed forms, independent code) on valve_float_demo;
- scipy DOP853 at rtol 1e-12 (independent integrator and event logic) on the rolling lever;
- the convergence order of the interpolation (h^6);
- restitution and a very stiff linkage against the exact solver.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from explorer.studies.bench import model_and_drive
from explorer.effects.elastic import linkage_model
from explorer.dynamics import solvers
from explorer.dynamics.model import Drive, StiffnessProfile
from explorer.dynamics.solvers import solve
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

from dynamics_cases import cycloidal_groups
from test_dynamics_varying import A, M1, PRELOAD, RATE, W_S, _manufactured

SCENES = Path(__file__).resolve().parents[1] / "assets" / "scenes"
ROLLING = SCENES / "rolling_lever.toml"


def _kinds(sol):
    return [e["kind"] for e in sol.events]


def _constant_profile(model, omega):
    k = model.stiffness
    profile = StiffnessProfile(lambda th: (np.full(np.shape(th), k), np.zeros(np.shape(th))), omega)
    return replace(model, stiffness_profile=profile)


def _float_demo(*overrides):
    scene = load_scene(SCENES / "valve_float_demo.toml", ['linkage.stiffness="5e6 N/m"', *overrides])
    model, drive = model_and_drive(scene)
    t = np.arange(3600) * (2.0 * math.pi / drive.omega / 3600)
    return model, drive, t


def test_taylor_accepts_a_varying_stiffness():
    assert "taylor" in solvers.varying_stiffness()


def test_manufactured_solution_taylor():
    """s(t) = A (1 - cos w t) with k(t) = k0 (1 + 0.5 sin nu t): back to 1e-12 m (the interpolation
    error of S and k at the 0.15 / rho steps is ~1e-15 m), velocity to 1e-10 m/s; the linkage force
    and the jerk (with its k'(t) term) from the node state to 1e-9 relative (the jerk carries
    k / M1 times the velocity error)."""
    model, drive, t, exact_s = _manufactured()
    sol = solve(model, drive, t, method="taylor", initial_state=(0.0, 0.0))
    assert np.abs(sol.s - exact_s).max() < 1e-12
    assert np.abs(sol.v - A * W_S * np.sin(W_S * t)).max() < 1e-10
    assert not [e for e in sol.events if e["kind"] != "lift-off"]
    assert np.all(sol.phase == 1)  # in contact throughout
    force = M1 * A * W_S**2 * np.cos(W_S * t) + PRELOAD + RATE * exact_s
    assert np.abs(sol.linkage_force - force).max() < 1e-9 * force.max()
    jerk = -A * W_S**3 * np.sin(W_S * t)
    assert np.abs(sol.jerk - jerk).max() < 1e-8 * np.abs(jerk).max()
    acc = A * W_S**2 * np.cos(W_S * t)
    assert np.abs(sol.a - acc).max() < 1e-9 * np.abs(acc).max()


def test_manufactured_convergence_order():
    """The only error is the Hermite interpolation of S and k over a step (both through values
    and slopes at three points or more: O(h^6)). Halving the step limit rho h divides the error
    by ~64 until it reaches the rounding floor (1e-13 m)."""
    model, drive, t, _ = _manufactured()
    tt = np.linspace(0.0, t[-1], 21)
    exact = A * (1.0 - np.cos(W_S * tt))
    errors = []
    for r in (0.5, 0.25, 0.125):
        sol = solve(model, drive, tt, method="taylor", initial_state=(0.0, 0.0), max_rho_h=r)
        errors.append(float(np.abs(sol.s - exact).max()))
    assert errors[0] > 1e-13  # the coarsest step shows an interpolation error at all
    for coarse, fine in zip(errors[:-1], errors[1:]):
        assert fine < 1e-13 or coarse / fine > 40.0  # h^6: 64 (asymptotically)


@pytest.mark.parametrize("damping", [0.0, 100.0])
def test_constant_profile_reproduces_exact(damping):
    """k(t) = k: the Taylor series and the exact solver's closed forms (on the same quintic drive
    per step) agree to rounding: same events (kinds and times to 1e-12 s), lift to 1e-12 m."""
    model, drive, t = _float_demo()
    model = replace(model, damping=damping)
    ref = solve(model, drive, t, method="exact")
    sol = solve(_constant_profile(model, drive.omega), drive, t, method="taylor")
    assert _kinds(sol) == _kinds(ref)
    assert len(ref.events) >= 4
    assert max(abs(a["time_s"] - b["time_s"]) for a, b in zip(sol.events, ref.events)) < 1e-12
    assert np.abs(sol.s - ref.s).max() < 1e-12
    assert np.abs(sol.v - ref.v).max() < 1e-9
    assert np.array_equal(sol.phase, ref.phase)
    assert np.abs(sol.jerk - ref.jerk).max() < 1e-9 * np.abs(ref.jerk).max()
    assert np.abs(sol.linkage_force - ref.linkage_force).max() < 1e-9 * ref.linkage_force.max()
    # the constant-stiffness model (no profile) takes the same path
    plain = solve(model, drive, t, method="taylor")
    assert np.abs(plain.s - sol.s).max() < 1e-15


@pytest.fixture(scope="module")
def rolling_lift():
    return build_lift(load_scene(ROLLING))


@pytest.mark.parametrize("damping", [None, 300.0])
def test_rolling_lever_against_scipy(rolling_lift, damping):
    """The rolling lever's k(t) over a revolution (with damping the linkage lets go while
    compressed and re-contact is where it would push again): the same events as scipy DOP853 at
    rtol 1e-12, event times to 1e-10 s, lift to 1e-10 m (scipy's own error ~1e-12 m)."""
    overrides = [] if damping is None else [f'linkage.damping="{damping} N*s/m"']
    scene = load_scene(ROLLING, overrides)
    omega = scene.drive.omega
    model = linkage_model(scene, rolling_lift, omega)
    assert model.stiffness_profile is not None
    drive = Drive(rolling_lift, 1.0, omega)
    t = np.arange(3600) * (2.0 * math.pi / omega / 3600)
    t = t + t[int(np.argmin(drive(t)[0]))]
    ref = solve(model, drive, t, method="scipy", rtol=1e-12, atol=1e-15)
    sol = solve(model, drive, t, method="taylor")
    assert _kinds(sol) == _kinds(ref)
    assert len(ref.events) >= 3
    assert max(abs(a["time_s"] - b["time_s"]) for a, b in zip(sol.events, ref.events)) < 1e-10
    assert np.abs(sol.s - ref.s).max() < 1e-10
    assert np.abs(sol.v - ref.v).max() < 1e-7
    assert np.array_equal(sol.phase, ref.phase)
    moving = sol.phase == 1
    assert np.abs(sol.jerk - ref.jerk)[moving].max() < 1e-6 * np.abs(ref.jerk).max()


def test_restitution_chatter_terminates():
    """e = 0.7, the valve dropped from 0.5 mm with the linkage out of reach (20 mm lash): the seat
    chatter is followed until a rebound would rise less than zeno_height, the rest summed in
    closed form; the solver ends with the valve seated and agrees with the exact solver's
    chatter (26 impacts; times to 1e-9 s, lift to 1e-12 m)."""
    model, drive, t = _float_demo("seat.restitution=0.7", 'valve.lash="20 mm"')
    ref = solve(model, drive, t, method="exact", initial_state=(5e-4, 0.0))
    sol = solve(_constant_profile(model, drive.omega), drive, t, method="taylor", initial_state=(5e-4, 0.0))
    seats = [e for e in sol.events if e["kind"] == "seat"]
    assert len(seats) > 10 and sol.stats["zeno"] == 1
    assert "zeno_accumulation_s" in seats[-1]
    assert _kinds(sol) == _kinds(ref)
    assert max(abs(a["time_s"] - b["time_s"]) for a, b in zip(sol.events, ref.events)) < 1e-9
    speeds = [-e["velocity_m_s"] for e in seats]
    assert all(b < a for a, b in zip(speeds, speeds[1:]))  # each impact slower than the last
    assert np.abs(sol.s - ref.s).max() < 1e-12
    assert np.all(sol.s >= 0.0) and np.all(sol.phase[t > seats[-1]["zeno_accumulation_s"]] == 0)


def test_very_stiff_linkage_stays_finite():
    """k = 1e10 N/m: the output steps are split (3 each) so that rho h <= 0.5 and the series stays
    short and exact; the result is finite and matches the exact solver (11 events: the valve
    bounces on the stiff linkage) to 1e-12 m."""
    scene = load_scene(SCENES / "valve_float_demo.toml", ['linkage.stiffness="1e10 N/m"'])
    model, drive = model_and_drive(scene)
    t = np.arange(3600) * (2.0 * math.pi / drive.omega / 3600)
    ref = solve(model, drive, t, method="exact")
    sol = solve(_constant_profile(model, drive.omega), drive, t, method="taylor")
    assert np.all(np.isfinite(sol.s)) and np.all(np.isfinite(sol.jerk))
    assert sol.stats["max_rho_h"] <= 0.5
    assert _kinds(sol) == _kinds(ref)
    assert len(ref.events) >= 5
    assert np.abs(sol.s - ref.s).max() < 1e-12


@settings(max_examples=8, deadline=None)
@given(
    r=st.floats(0.05, 1.5),  # natural period over rise time
    spring=st.floats(0.3, 3.0),  # W0 over (M times the drive's peak deceleration)
    lash=st.one_of(st.just(0.0), st.floats(0.0, 0.3)),  # lash over lift
    zeta=st.one_of(st.just(0.0), st.floats(0.0, 5.0)),
    mu=st.one_of(st.just(0.0), st.floats(0.0, 0.2)),  # friction over W0
    amp=st.floats(0.0, 0.6), harmonic=st.integers(1, 4), phase=st.floats(0.0, 6.28),
)
def test_random_stiffness_profiles_agree_with_scipy(r, spring, lash, zeta, mu, amp, harmonic, phase):
    """k(t) = k0 (1 + amp sin(n theta + phase)) over nondimensional groups: taylor and scipy
    (independent methods) agree to 1e-8 of the lift. (Hunting by hand: 400 such draws, largest
    difference 2e-12 m; 400 constant-k draws with restitution against exact, none off.)"""
    model, drive, h = cycloidal_groups(r, spring, lash, zeta=zeta, mu=mu)
    k0, omega = model.stiffness, drive.omega
    profile = StiffnessProfile(lambda th: (k0 * (1 + amp * np.sin(harmonic * th + phase)),
                                           k0 * amp * harmonic * np.cos(harmonic * th + phase)), omega)
    model = replace(model, stiffness=profile.bounds()[1], stiffness_profile=profile)
    t = np.linspace(0.0, 2.0 * math.pi / omega, 721)[:-1]
    sol = solve(model, drive, t, method="taylor")
    ref = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14)
    assert np.all(np.isfinite(sol.s))
    assert np.abs(sol.s - ref.s).max() < 1e-8 * h
