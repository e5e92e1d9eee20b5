"""A linkage stiffness that changes along the cycle (the rolling lever's k(t)).

Oracles:
- a manufactured solution: choose the valve motion s(t) and k(t), derive the drive S(t) that the
  contact equation M1 s'' = k(t) (S - lash - s) - W(s) demands (derivatives exact by jets), and
  check that the solvers give back s(t), its linkage force and its jerk;
- a constant profile must reproduce the constant-stiffness solution;
- the tabulated drive (Hermite tables) against the analytic evaluation on the real gear;
- the rolling lever's dk/dtheta against central differences of k itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

from explorer.effects.elastic import linkage_model
from explorer.dynamics.model import Drive, LinkageModel, StiffnessProfile
from explorer.dynamics.solvers import solve
from explorer.core.errors import InputError
from explorer.gears import jet as J
from explorer.gears.jet import Jet
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

SCENES = Path(__file__).resolve().parents[1] / "assets" / "scenes"
ROLLING = SCENES / "rolling_lever.toml"

# manufactured case: s = A (1 - cos w t) for t in [0, 0.8 * 2 pi / w] (the valve stays above the
# seat and in contact: M1 s'' + W(s) > 0 with the preload below), k = k0 (1 + 0.5 sin(nu t))
A, W_S, K0, NU = 0.004, 150.0, 4.0e6, 900.0
M1, PRELOAD, RATE, LASH = 0.5, 300.0, 2.0e4, 1.0e-4
MODEL = LinkageModel(mass=M1, oscillating_mass=M1, stiffness=1.5 * K0, lash=LASH, preload=PRELOAD, spring_rate=RATE)


def _motion(t):
    tj = Jet.variable(np.asarray(t, dtype=float))
    s = A * (1.0 - J.cos(W_S * tj))
    k = K0 * (1.0 + 0.5 * J.sin(NU * tj))
    return tj, s, k


def _stiffness(theta):  # omega = 1: theta is the time
    _, _, k = _motion(theta)
    return k.c[0], k.c[1]


@dataclass(frozen=True)
class _ManufacturedLift:
    """S(t) = s + lash + (M1 s'' + preload + rate s) / k(t), with its derivatives exact (jets;
    s'' as a jet is the shifted jet of s, known to one order less, so it is written out)."""

    def derivatives(self, theta):
        tj, s, k = _motion(theta)
        s2 = A * W_S**2 * J.cos(W_S * tj)  # s'' as a jet of its own (exact to third order)
        S = s + LASH + (M1 * s2 + PRELOAD + RATE * s) / k
        return S.c

    def breakpoints(self):
        return np.array([])


def _manufactured():
    profile = StiffnessProfile(_stiffness, 1.0)
    model = replace(MODEL, stiffness=profile.bounds()[1], stiffness_profile=profile)
    drive = Drive(_ManufacturedLift(), 1.0, 1.0)
    t = np.linspace(0.0, 0.8 * 2.0 * math.pi / W_S, 801)
    exact_s = A * (1.0 - np.cos(W_S * t))
    return model, drive, t, exact_s


def test_manufactured_solution_scipy():
    """scipy (tabulated drive and k) gives back s(t) = A (1 - cos w t): error far below 1e-9 m at
    rtol 1e-11 (the integrator's tolerance times the lift, plus the table error ~1e-16)."""
    model, drive, t, exact_s = _manufactured()
    # the valve starts at rest on the seat and the drive already pushes: it lifts at t = 0
    sol = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14, initial_state=(0.0, 0.0))
    assert np.abs(sol.s - exact_s).max() < 1e-10
    assert not [e for e in sol.events if e["kind"] != "lift-off"]  # in contact throughout
    # linkage force = M1 s'' + W(s) and the jerk = s''' (with its k'(t) term)
    force = M1 * A * W_S**2 * np.cos(W_S * t) + PRELOAD + RATE * exact_s
    assert np.abs(sol.linkage_force - force).max() < 1e-6 * force.max()
    jerk = -A * W_S**3 * np.sin(W_S * t)
    assert np.abs(sol.jerk - jerk).max() < 1e-6 * np.abs(jerk).max()


def test_manufactured_solution_scipy_analytic_drive():
    """The same with one analytic evaluation per instant (tabulate=0): the tables change nothing."""
    model, drive, t, exact_s = _manufactured()
    t = t[:200]
    tab = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14, initial_state=(0.0, 0.0))
    ana = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14, initial_state=(0.0, 0.0), tabulate=0)
    assert np.abs(tab.s - ana.s).max() < 1e-13
    assert np.abs(ana.s - exact_s[:200]).max() < 1e-10


def test_manufactured_solution_schenker1902_converges_at_second_order():
    """The 1902 scheme with k at the step end: the error falls ~4x per halving of the step (its
    order for smooth contact motion) and reaches the exact motion."""
    model, drive, t, exact_s = _manufactured()
    errors = []
    for sub in (1, 2, 4):
        sol = solve(model, drive, t, method="schenker1902", substeps=sub, initial_state=(0.0, 0.0))
        errors.append(float(np.abs(sol.s - exact_s).max()))
    assert errors[-1] < 1e-7
    assert errors[0] / errors[1] > 3.0 and errors[1] / errors[2] > 3.0


def test_exact_solver_refuses_a_varying_stiffness():
    model, drive, t, _ = _manufactured()
    with pytest.raises(ValueError, match="constant linkage stiffness"):
        solve(model, drive, t, method="exact")


def test_constant_profile_reproduces_constant_stiffness():
    """k(t) = k everywhere: the varying-stiffness path (tables, cache.k) equals the constant one."""
    scene = load_scene(SCENES / "valve_float_demo.toml", ['linkage.stiffness="5e6 N/m"'])
    from explorer.studies.bench import model_and_drive

    model, drive = model_and_drive(scene)
    k = model.stiffness
    profile = StiffnessProfile(lambda th: (np.full(np.shape(th), k), np.zeros(np.shape(th))), drive.omega)
    varying = replace(model, stiffness_profile=profile)
    t = np.arange(3600) * (2.0 * math.pi / drive.omega / 3600)
    a = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14)
    b = solve(varying, drive, t, method="scipy", rtol=1e-11, atol=1e-14)
    assert [e["kind"] for e in a.events] == [e["kind"] for e in b.events]
    assert np.abs(a.s - b.s).max() < 1e-11  # two runs of rtol 1e-11 on a 9 mm lift
    c = solve(varying, drive, t, method="schenker1902")
    d = solve(model, drive, t, method="schenker1902")
    assert np.array_equal(c.s, d.s)  # the same arithmetic


def test_series_profile():
    """In series with a constant: 1/k = 1/k1 + 1/k2 and k' = k^2 k1'/k1^2."""
    k1 = (lambda th: (3e6 + 1e6 * np.sin(th), 1e6 * np.cos(th)))
    p = StiffnessProfile(k1, 2.0, series=5e6)
    t = np.linspace(0.0, 3.0, 7)
    k, dk = p(t)
    a = 3e6 + 1e6 * np.sin(2.0 * t)
    expected = 1.0 / (1.0 / a + 1.0 / 5e6)
    assert np.allclose(k, expected, rtol=1e-14)
    h = 1e-6
    fd = (p(t + h)[0] - p(t - h)[0]) / (2 * h)
    assert np.allclose(dk, fd, rtol=1e-7)  # central difference: truncation ~h^2 k''', rounding ~eps k / h


@pytest.fixture(scope="module")
def rolling():
    scene = load_scene(ROLLING)
    lift = build_lift(scene)
    return scene, lift


def test_rolling_lever_stiffness_derivative(rolling):
    """d k / d theta of the rolling lever (lever, rod, series) against central differences of k,
    where the faces roll (w > 0), to 1e-7 of the largest k (truncation h^2 k'''/6 ~ 1e-12, rounding
    eps k / h ~ 1e-10 with h = 1e-6 rad)."""
    _, lift = rolling
    gear = lift.gear
    theta = np.linspace(0.0, 2.0 * math.pi, 721)
    k = gear.stiffness(theta, with_derivative=True)
    rolling_now = gear.rolling_swing(theta).c[0] > 1e-4
    h = 1e-6
    plus, minus = gear.stiffness(theta + h), gear.stiffness(theta - h)
    for part in ("lever", "rod", "total"):
        fd = (plus[part] - minus[part]) / (2 * h)
        scale = np.abs(k[part][rolling_now]).max()
        assert np.abs(fd - k[f"d_{part}"])[rolling_now].max() < 1e-7 * scale
    assert np.all(np.isfinite(k["total"])) and np.all(np.isfinite(k["d_total"]))
    # before pick-up the faces do not touch: frozen at the meeting point
    apart = gear.rolling_swing(theta).c[0] <= 0.0
    assert np.ptp(k["total"][apart]) < 1e-9 * k["total"].max()
    assert np.all(k["d_total"][apart] == 0.0)


def test_rolling_lever_tables_match_analytic_drive(rolling):
    """Across the pick-up impact (13 events in 40 ms), scipy with the Hermite tables and with one
    analytic evaluation per instant agree to 1e-13 m: the tables cost no accuracy."""
    scene, lift = rolling
    omega = scene.drive.omega
    model = linkage_model(scene, lift, omega)
    drive = Drive(lift, 1.0, omega)
    pick = min(lift.breakpoints()) / omega
    t = pick - 0.002 + np.arange(120) * (2.0 * math.pi / omega / 3600)
    tab = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14)
    ana = solve(model, drive, t, method="scipy", rtol=1e-11, atol=1e-14, tabulate=0)
    assert [e["kind"] for e in tab.events] == [e["kind"] for e in ana.events]
    assert len(tab.events) >= 3
    assert np.abs(tab.s - ana.s).max() < 1e-13


def test_rolling_lever_elastic_uses_the_varying_stiffness(rolling):
    """The scene's elastic effect runs with k(t): its range spans the gear's (pick-up stiffer than
    full lift, Schenker's point), and the motion differs from either constant bound by far more
    than the solver's error."""
    from explorer.effects.pipeline import simulate

    scene, lift = rolling
    result = simulate(scene)
    stats = result.summary["elastic_solver"]
    k = lift.gear.stiffness(np.linspace(0, 2 * math.pi, 721))["total"]
    series = scene.linkage.stiffness
    chain = 1.0 / (1.0 / k + 1.0 / series)
    assert stats["stiffness_min_N_m"] == pytest.approx(chain.min(), rel=1e-3)
    assert stats["stiffness_max_N_m"] == pytest.approx(chain.max(), rel=1e-3)
    assert stats["stiffness_max_N_m"] > 2.0 * stats["stiffness_min_N_m"]
    model = linkage_model(scene, lift, scene.drive.omega)
    drive = Drive(lift, 1.0, scene.drive.omega)
    t = np.arange(3600) * (2.0 * math.pi / scene.drive.omega / 3600)
    varying = solve(model, drive, t, method="scipy")
    for k_const in model.stiffness_profile.bounds():
        const = solve(replace(model, stiffness=k_const, stiffness_profile=None), drive, t, method="exact")
        assert np.abs(const.s - varying.s).max() > 1e-5


def test_scene_refuses_exact_with_rolling_stiffness():
    with pytest.raises(InputError) as info:
        load_scene(ROLLING, ['solver.method="exact"'])
    assert info.value.key == "solver.method"
    assert "constant" in str(info.value)


def test_bench_measures_the_solvers_that_take_k_of_t(rolling, tmp_path):
    """`explorer bench` on the rolling lever: taylor takes the exact solver's place (rows, the
    cross-check against the scipy reference, the speed ratio), each measured against the other
    kind of method; the 1902 scheme converges with the steps."""
    from explorer.studies.bench import run_bench

    scene, _ = rolling
    rep = run_bench(scene, quick=True, repeats=1, differentiation=False)
    assert rep.check_method == "taylor" and rep.ratio is not None and rep.ratio.method == "taylor"
    assert {r.method for r in rep.runs} == {"taylor", "schenker1902", "scipy"}
    assert rep.reference_check_m < 1e-12  # taylor and scipy rtol 1e-12, independent methods
    taylor = [r for r in rep.runs if r.method == "taylor"]
    assert all(r.max_error_m < 1e-12 and r.events == len(rep.reference_events) for r in taylor)
    sch = sorted((r for r in rep.runs if r.method == "schenker1902"), key=lambda r: r.steps)
    assert sch[-1].max_error_m < sch[0].max_error_m / 10.0
    assert "exact replaced by taylor" in rep.table() and "taylor" in rep.ratio.text()


def test_damped_varying_stiffness_scipy_and_schenker1902_agree(rolling):
    """k(t) with damping (300 N s/m): the linkage lets go while compressed, so both solvers must
    find re-contact where it would push again (scipy's event uses k(t) and its slope k'(t)); two
    independent methods agree on the events and, the 1902 scheme refined, to 1e-7 m."""
    scene, lift = rolling
    scene = load_scene(ROLLING, ['linkage.damping="300 N*s/m"'])
    omega = scene.drive.omega
    model = linkage_model(scene, lift, omega)
    drive = Drive(lift, 1.0, omega)
    t = np.arange(3600) * (2.0 * math.pi / omega / 3600)
    t = t + t[int(np.argmin(drive(t)[0]))]
    ref = solve(model, drive, t, method="scipy", rtol=1e-12, atol=1e-15)
    kinds = [e["kind"] for e in ref.events]
    assert "re-contact" in kinds
    fine = solve(model, drive, t, method="schenker1902", substeps=16)
    assert [e["kind"] for e in fine.events] == kinds
    assert np.abs(fine.s - ref.s).max() < 1e-7


def test_rod_stiffness_against_a_stretched_rod(rolling):
    """k_rod / (ds/dl)^2 by statics: lengthen the eccentric rod by +-dl at a fixed shaft angle and
    see how far the valve moves (a central difference of the geometry itself, not of k): ds/dl."""
    _, lift = rolling
    gear = lift.gear
    theta = np.array([1.6, 2.2, 3.0, 3.6])
    theta = theta[gear.rolling_swing(theta).c[0] > 0.0]
    assert theta.size >= 3
    dl = 1e-7
    moved = []
    for sign in (1.0, -1.0):
        drive = replace(gear.drive, rod=gear.drive.rod + sign * dl)
        moved.append(replace(gear, drive=drive).virtual_lift(theta).c[0])
    ds_dl = (moved[0] - moved[1]) / (2.0 * dl)
    k = gear.stiffness(theta)
    assert np.allclose(k["rod"], gear.rod_stiffness / ds_dl**2, rtol=1e-6)
