"""The valve train of lumped masses and the hydraulic lash adjuster (issue #25): dynamics/train.py,
dynamics/hla.py, solved by chain_exact's piecewise-exact solver and chain_reference's scipy run.

Oracles: closed-form 2-DOF frequencies, the fixed-free chain's eigenvalues, a vanishing mass, the
spring-chain model itself (a train of one element, bit for bit), the energy balance, the adjuster's
leak-down in closed form and by Poiseuille, the eccentric annulus by quadrature, the refill against
the orifice law, and scipy DOP853 on the same model."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from explorer.dynamics import chain_exact, chain_reference
from explorer.dynamics.chain import ChainModel
from explorer.dynamics.hla import HLA, LeakdownRig
from explorer.dynamics.model import Drive
from explorer.dynamics.phase_system import decompose_free
from explorer.dynamics.train import Joint, Part, TrainModel
from explorer.effects.lift import build_lift
from explorer import load_scene
from explorer.scene.builtin import scenes_dir


def _drive(rpm: float) -> Drive:
    return Drive(build_lift(load_scene(scenes_dir() / "spring_surge.toml")), 1.0, rpm * math.pi / 30.0)


def _grid(rpm: float, steps: int = 3600) -> np.ndarray:
    return np.linspace(0.0, 60.0 / rpm, steps + 1)


def _valve(**changes) -> ChainModel:
    base = dict(valve_mass=0.08, spring_mass=0.045, elements=0, spring_rate=30.6e3, preload=220.0, stiffness=3e6,
                seat_stiffness=2e8, damping=8.0, lash=0.25e-3, closing_load=15.0, seat_damping=400.0,
                damping_ratio=0.02)
    base.update(changes)
    return ChainModel(**base)


def _finger(rpm_float: bool = True, **hla_changes) -> TrainModel:
    """An end-pivot roller finger on an adjuster (valve-referred: ratio 1.7, lever 0.7)."""
    valve = ChainModel(valve_mass=0.05, spring_mass=0.0, elements=0, spring_rate=40e3, preload=250.0,
                       stiffness=1.5e8, seat_stiffness=2e8, damping=50.0, seat_damping=400.0)
    h = dict(plunger_mass=0.012, plunger_diameter=12e-3, clearance=6e-6, leak_length=8e-3, viscosity=0.01,
             chamber_volume=2e-7, supply_pressure=0.3e6, aeration=0.02, check_diameter=1.0e-3,
             refill_pressure_drop=0.05e6, spring_rate=5e3, spring_preload=15.0, lever=0.7, travel=1e-3)
    h.update(hla_changes)
    return TrainModel(valve, (Part("finger", 0.02),), (Joint("cam", 3.5e7, 30.0), Joint("pad", 1.5e8, 50.0)), HLA(**h))


class _Flat:
    """A lift of zero: the drive of the leak-down tester (the rig ignores it)."""

    def derivatives(self, theta):
        return np.zeros((4, np.size(theta)))

    def breakpoints(self):
        return np.zeros(0)


# -- natural frequencies ---------------------------------------------------------------------------

@pytest.mark.parametrize("spring_rate", [30.6e3, 0.0])
def test_two_masses_natural_frequencies_closed_form(spring_rate):
    # lifter m1 on the cam through k1, valve m2 on the lifter through k2, the valve spring k_s:
    # det(K - w^2 M) = m1 m2 w^4 - (m1 (k2 + k_s) + m2 (k1 + k2)) w^2 + (k1 + k2)(k2 + k_s) - k2^2 = 0
    m1, m2, k1, k2 = 0.05, 0.08, 2e7, 5e6
    tr = TrainModel(_valve(valve_mass=m2, spring_mass=0.0, spring_rate=spring_rate, damping=0.0, seat_damping=0.0),
                    (Part("lifter", m1),), (Joint("cam", k1), Joint("stem", k2, one_sided=False)))
    a, b = m1 * m2, m1 * (k2 + spring_rate) + m2 * (k1 + k2)
    c = (k1 + k2) * (k2 + spring_rate) - k2 * k2
    w2 = np.sort([(b - math.sqrt(b * b - 4 * a * c)) / (2 * a), (b + math.sqrt(b * b - 4 * a * c)) / (2 * a)])
    key = tr.running_key()
    np.testing.assert_allclose(tr.natural_frequencies(key), np.sqrt(w2) / (2 * math.pi), rtol=1e-12)
    # the solver's decomposition of that (undamped) phase: eigenvalues +-i w
    lam = tr.phase_modes(key).lam
    assert np.max(np.abs(lam.real)) < 1e-9 * np.max(np.abs(lam))
    np.testing.assert_allclose(np.sort(lam.imag[lam.imag > 0]), np.sqrt(w2), rtol=1e-12)


def test_n_masses_against_the_tridiagonal_system():
    # ten equal masses m in a row through equal springs k, the first on the cam, the valve free
    # (no spring, off its seat): the fixed-free chain, w_j = 2 sqrt(k/m) sin((2j - 1) pi / (2 (2n + 1)))
    n, m, k = 10, 0.03, 4e7
    tr = TrainModel(_valve(valve_mass=m, spring_mass=0.0, spring_rate=0.0, damping=0.0, seat_damping=0.0),
                    tuple(Part(f"p{i}", m) for i in range(n - 1)),
                    (Joint("cam", k),) + tuple(Joint(f"j{i}", k, one_sided=False) for i in range(n - 1)))
    j = np.arange(1, n + 1)
    closed = 2 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi / (2 * (2 * n + 1)))
    T = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    T[-1, -1] = 1.0
    np.testing.assert_allclose(np.sqrt(np.linalg.eigvalsh(T * k / m)), closed, rtol=1e-12)
    lam = tr.phase_modes(tr.running_key()).lam
    np.testing.assert_allclose(np.sort(lam.imag[lam.imag > 0]), closed, rtol=1e-11)


# -- the model without parts, and parts that vanish -----------------------------------------------

@pytest.mark.parametrize("rpm, changes", [
    (3000, {}), (3000, {"elements": 8, "damping_ratio": 0.02}),
    (3000, {"elements": 8, "clash_compression": 0.94e-3}), (3000, {"elements": 4, "friction": 20.0}),
    (3900, {"elements": 32, "clash_compression": 0.5e-3}),
])
def test_a_train_of_one_element_is_the_chain_model_bit_for_bit(rpm, changes):
    m = _valve(spring_mass=0.045, **changes)
    tr = TrainModel(m, (), (Joint("cam", m.stiffness, m.damping, m.lash),))
    a = chain_exact.solve(m, _drive(rpm), _grid(rpm))
    b = chain_exact.solve(tr, _drive(rpm), _grid(rpm))
    for name in ("s", "v", "a", "jerk", "coils", "coil_velocities", "retainer_force", "seat_force", "linkage_force",
                 "contact", "phase"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert [(e["kind"], e["time_s"]) for e in a.events] == [(e["kind"], e["time_s"]) for e in b.events]
    assert len(a.events) > 10


def test_a_vanishing_part_recovers_the_train_without_it():
    # a lifter of mass eps between the cam (k_a, one-sided, with the lash) and the valve (k_b):
    # as eps -> 0 the valve moves as on one linkage of k_a k_b / (k_a + k_b). Undamped joints and
    # seat (a massless node between two dampers is another model). The difference falls in
    # proportion to eps (measured 6.8e-8, 4.8e-9, 4.1e-10 m at 1e-7, 1e-8, 1e-9 kg); at 1e-10 kg it
    # is below 1e-10 m
    rpm = 3000
    ka, kb = 9e6, 4.5e6
    base = _valve(stiffness=ka * kb / (ka + kb), damping=0.0, seat_damping=0.0, spring_mass=0.0)
    drive, t = _drive(rpm), _grid(rpm)
    ref = chain_exact.solve(base, drive, t)
    diffs = []
    for eps in (1e-7, 1e-8, 1e-9, 1e-10):
        tr = TrainModel(base, (Part("lifter", eps),), (Joint("cam", ka, 0.0, base.lash), Joint("stem", kb, one_sided=False)))
        sol = chain_exact.solve(tr, drive, t)
        diffs.append(float(np.max(np.abs(sol.s - ref.s))))
    assert diffs[-1] < 1e-10, diffs
    assert diffs[0] > diffs[1] > diffs[2] > diffs[3], diffs


def test_energy_balance_over_a_revolution_without_damping():
    # a lifter and a rocker, undamped joints (the cam one-sided, the pad one-sided), an undamped
    # massless spring; only the seat damps. The change of the train's energy (kinetic, closed
    # joints, spring, seat) equals the work of the cam's force on the drive's motion and of the
    # constant loads minus the seat damper's loss, and minus the energy (c v)^2 / (2 k) the seat
    # keeps where it lets go (its force 0, still compressed by c v / k: the massless seat's own,
    # its damper takes it as it relaxes; 0.02 J at this 7 m/s rebound, 1 % of the energy turned
    # over). Trapezoid rule on 144 000 steps (the seat damper's power c v^2 jumps at each seat
    # impact and release: first order there, measured 1.5e-3, 7.9e-4, 2.3e-4 of the energy turned
    # over on 36 000, 72 000, 144 000 steps; 8.5e-3 without the seat's released energy); bound 1e-3
    rpm = 4200
    tr = TrainModel(_valve(damping=0.0, spring_mass=0.0, lash=0.0),
                    (Part("lifter", 0.04), Part("rocker", 0.03)),
                    (Joint("cam", 4e7, 0.0, 0.2e-3), Joint("pushrod", 2e7, 0.0, one_sided=False), Joint("pad", 5e7)))
    t = _grid(rpm, 144000)
    drive = _drive(rpm)
    sol = chain_exact.solve(tr, drive, t)
    kinds = {(e["kind"], e.get("contact")) for e in sol.events}
    assert ("separation", "cam") in kinds and ("seat", None) in kinds
    D = drive(t)
    c = tr.chain
    E = 0.5 * c.masses[0] * sol.v**2 + 0.5 * c.spring_rate * sol.s**2
    E += 0.5 * (tr.parts[0].mass * sol.part_velocities[0]**2 + tr.parts[1].mass * sol.part_velocities[1]**2)
    for j, jt in enumerate(tr.all_joints):
        f = sol.joint_forces[jt.name]
        E += np.where(sol.joint_closed[jt.name], 0.5 * f * f / jt.stiffness, 0.0)
    seat = sol.phase == 0
    E += np.where(seat, 0.5 * c.seat_stiffness * sol.s**2, 0.0)
    power = (sol.joint_forces["cam"] * D[1] - (c.preload + c.closing_load) * sol.v
             - np.where(seat, c.seat_damping * sol.v**2, 0.0))
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(t))])
    for e in sol.events:
        if e["kind"] == "lift-off":
            work[t > e["time_s"]] -= 0.5 * (c.seat_damping * e["velocity_m_s"]) ** 2 / c.seat_stiffness
    scale = np.max(np.abs(E - E[0]))
    assert np.max(np.abs(E - E[0] - work)) < 1e-3 * scale, np.max(np.abs(E - E[0] - work)) / scale


def test_free_flying_group_is_decomposed_exactly():
    # a pushrod train with both ends of the lifter-and-pushrod open: they fly as one body (a
    # double eigenvalue 0); the decomposition's rows invert its columns and the modes are
    # those of the state matrix, the group's position driven by its velocity (X' = V)
    tr = TrainModel(_valve(spring_mass=0.0), (Part("lifter", 0.05), Part("pushrod", 0.03), Part("rocker", 0.04)),
                    (Joint("cam", 2e8, 50.0), Joint("lp", 5e7, 20.0, one_sided=False), Joint("top", 3e7, 20.0),
                     Joint("pad", 1e8, 30.0, one_sided=False)))
    key = ((False, False), False, 1, None)
    assert tr.free_groups(key) == ((tr.chain.n, tr.chain.n + 1),)
    md = tr.phase_modes(key)
    assert len(md.rigid) == 1
    X, V = md.rigid[0]
    assert md.lam[X] == 0.0 and md.lam[V] == 0.0
    np.testing.assert_allclose(md.inv @ md.phys, np.eye(md.lam.size), atol=1e-12)
    J = np.diag(md.lam)
    J[X, V] = 1.0
    np.testing.assert_allclose(md.inv @ md.A @ md.phys, J, atol=1e-9 * np.max(np.abs(md.lam)))


# -- the hydraulic lash adjuster ---------------------------------------------------------------------

def _hla(**changes) -> HLA:
    base = dict(plunger_mass=0.012, plunger_diameter=12e-3, clearance=6e-6, leak_length=8e-3, viscosity=0.01,
                chamber_volume=2e-7, supply_pressure=0.3e6, spring_rate=50.0, spring_preload=15.0)
    base.update(changes)
    return HLA(**base)


def test_leakdown_against_the_closed_form_and_poiseuille():
    # a 500 N weight on the plunger, the check valve shut: the travel is the closed form of the
    # linear system (x_inf + V e^(Lambda t) V^-1 (x0 - x_inf), the 3x3 state matrix's eigen-
    # decomposition: measured 4e-15 m; scipy's expm of A t loses 3e-10 m there, ||A t|| ~ 1e5); after
    # the oil column's ring-down the plunger sinks at the Poiseuille rate
    # p' = G_l (P - P_s) / (A + cap k_s / A), P = (W - F_0 - k_s p) / A, G_l = pi d c^3 / (12 mu L)
    h = _hla()
    W = 500.0
    rig = LeakdownRig(h, W)
    t = np.linspace(0.0, 2.0, 2001)
    sol = chain_exact.solve(rig, Drive(_Flat(), 1.0, 1.0), t)
    assert sol.events == ()
    A = rig.phase_modes(False).A
    b = rig.forcing(False)[:, 2]
    x0 = np.array([0.0, 0.0, h.supply_pressure])
    xinf = -np.linalg.solve(A, b)
    lam, V = np.linalg.eig(A)
    c0 = np.linalg.solve(V, x0 - xinf)
    ref = np.array([(xinf + V @ (np.exp(lam * tt) * c0)).real for tt in t]).T
    assert np.max(np.abs(sol.plunger - ref[0])) < 1e-13
    assert np.max(np.abs(sol.chamber_pressure - ref[2])) < 1e-6 * W / h.area
    p = sol.plunger[-1]
    assert h.leak_conductance == pytest.approx(math.pi * 12e-3 * (6e-6)**3 / (12 * 0.01 * 8e-3), rel=1e-15)
    rate = h.leak_conductance * ((W - h.spring_preload - h.spring_rate * p) / h.area - h.supply_pressure) / (
        h.area + h.capacitance * h.spring_rate / h.area)
    assert sol.plunger_velocity[-1] == pytest.approx(rate, rel=1e-12)
    # without the spring's travel and the oil's compressibility: the textbook leak-down rate
    assert sol.plunger_velocity[-1] == pytest.approx(h.leakdown_velocity(W), rel=1e-3)


def test_eccentricity_factor_is_the_annulus_integral():
    # plane Poiseuille flow through the local gap h = c (1 + e cos t) round the bore:
    # q = (d/2) dp / (12 mu L) int h^3 dt = pi d c^3 dp (1 + 1.5 e^2) / (12 mu L)
    for e in (0.0, 0.3, 0.8):
        h = _hla(eccentricity=e)
        t = np.linspace(0.0, 2.0 * math.pi, 20001)
        gap3 = (h.clearance * (1.0 + e * np.cos(t)))**3
        integral = np.sum(0.5 * (gap3[1:] + gap3[:-1]) * np.diff(t))
        q = 0.5 * h.plunger_diameter * integral / (12.0 * h.viscosity * h.leak_length)
        assert h.leak_conductance == pytest.approx(q, rel=1e-12)


def test_refill_against_the_orifice_formula():
    # the plunger pulled out by a constant force (a negative load): the chamber falls below the
    # supply, the check valve opens, and the plunger settles to the speed at which the refill
    # (and the leak, both ways) feeds the growing chamber. With the load set so that the pressure
    # drop is the refill law's reference dp_ref, the refill flow equals the orifice formula
    # C_d A_o sqrt(2 dp / rho) there (elsewhere the linear law gives G_r dp / orifice(dp) =
    # sqrt(dp / dp_ref) times it: twice at 4 dp_ref, half at dp_ref / 4)
    dp = 0.05e6
    h = _hla(refill_pressure_drop=dp, spring_rate=1e-3, check_diameter=0.3e-3)
    load = h.spring_preload + h.area * (h.supply_pressure - dp)  # A P = load - F_0 at P = P_s - dp
    rig = LeakdownRig(h, load)
    t = np.linspace(0.0, 0.05, 2001)
    sol = chain_exact.solve(rig, Drive(_Flat(), 1.0, 1.0), t)
    assert [e["kind"] for e in sol.events] == ["check-valve-open"]
    assert sol.check_open[-1]
    P = sol.chamber_pressure[-1]
    # at rest in force: A P = load - F_0 - k_s p (the feeble spring's travel moves it by 1e-8)
    assert P == pytest.approx((load - h.spring_preload - h.spring_rate * sol.plunger[-1]) / h.area, rel=1e-10)
    assert P == pytest.approx(h.supply_pressure - dp, rel=1e-7)
    Q = -h.area * sol.plunger_velocity[-1]  # the chamber grows by this
    refill = Q - h.leak_conductance * (h.supply_pressure - P)
    assert refill == pytest.approx(h.refill_conductance * (h.check_threshold - P), rel=1e-9)
    assert refill == pytest.approx(h.orifice_flow(dp), rel=1e-6)
    assert h.refill_flow(dp) == pytest.approx(h.orifice_flow(dp), rel=1e-15)
    assert h.refill_flow(4 * dp) == pytest.approx(2 * h.orifice_flow(4 * dp), rel=1e-15)
    for x in (0.01, 0.25, 3.0, 100.0):
        assert h.refill_flow(x * dp) == pytest.approx(math.sqrt(x) * h.orifice_flow(x * dp), rel=1e-14)


def test_aerated_oil_secant_modulus():
    # no air: the oil's modulus. With air fraction X at the supply pressure: the mixture's volume
    # change from p_s to p_r is the oil's (p_r - p_s)/beta and the air's isothermal p V = const
    h = _hla()
    assert h.effective_bulk_modulus == h.bulk_modulus
    X = 0.02
    ha = _hla(aeration=X)
    ps, pr = ha.supply_pressure + 101325.0, ha.reference_pressure + 101325.0
    dV = (1 - X) * (pr - ps) / ha.bulk_modulus + X * (1.0 - ps / pr)
    assert ha.effective_bulk_modulus == pytest.approx((pr - ps) / dV, rel=1e-14)
    assert ha.effective_bulk_modulus < 0.3 * h.bulk_modulus


def test_secant_modulus_against_the_scenes_peak():
    # the secant is the chord of the mixture's pressure-volume curve: a chamber compressed
    # linearly from p_s by beta_e loses, at p_r, the volume the curve loses (oil (1 - X) dp /
    # beta_l, air X (1 - p_s/p_r), isothermal) -- 1e-12 rel, round-off. The figures the docstring
    # quotes for finger_hla_pumpup (2 % air, 3 bar) run with the default reference_pressure,
    # 10 MPa (peak 5.687 MPa in its summary then, what made the scene set 5.7 MPa): 380 MPa to
    # the default 10 MPa, 243 MPa to the peak; oil columns A^2 beta / V; tangent moduli
    # 1 / ((1 - X)/beta_l + X p_s/p^2), 20 MPa at the supply, 1.1 GPa at the peak (1e-3: quoted
    # to 2-3 digits)
    h = replace(load_scene(scenes_dir() / "finger_hla_pumpup.toml").hla.hla, reference_pressure=10e6)
    atm, X, bl = 101_325.0, 0.02, 1.5e9
    ps = h.supply_pressure
    assert (X, bl, ps, h.polytropic_index) == (h.aeration, h.bulk_modulus, 0.3e6, 1.0)

    def chord(p):
        return (1 - X) * (p - ps) / bl + X * (1 - (ps + atm) / (p + atm))

    for pr in (1e6, 5.687e6, 10e6, 50e6):
        hp = replace(h, reference_pressure=pr)
        assert hp.capacitance * (pr - ps) / hp.chamber_volume == pytest.approx(chord(pr), rel=1e-12)
    peak = replace(h, reference_pressure=5.687e6)
    assert h.effective_bulk_modulus == pytest.approx(380e6, rel=1e-3)
    assert peak.effective_bulk_modulus == pytest.approx(243.4e6, rel=1e-3)
    assert h.oil_stiffness == pytest.approx(24.3e6, rel=1e-3)
    assert peak.oil_stiffness == pytest.approx(15.57e6, rel=1e-3)
    tr = TrainModel.from_scene(load_scene(scenes_dir() / "finger_hla_pumpup.toml"))
    for hh, lowest in ((h, 2528.4), (peak, 2256.3)):  # the train's lowest running mode, Hz
        tt = replace(tr, hla=hh)
        assert tt.natural_frequencies(tt.running_key())[0] == pytest.approx(lowest, rel=1e-4)

    def tangent(p):
        return 1.0 / ((1 - X) / bl + X * (ps + atm) / (p + atm) ** 2)

    assert tangent(ps) == pytest.approx(19.8e6, rel=1e-3) and tangent(5.687e6) == pytest.approx(1.12e9, rel=1e-3)


# -- against scipy --------------------------------------------------------------------------------

def _compare(tr, rpm, steps=3600, atol_s=1e-9):
    drive, t = _drive(rpm), _grid(rpm, steps)
    ex = chain_exact.solve(tr, drive, t)
    ref = chain_reference.solve(tr, drive, t, rtol=1e-11, atol=1e-14)
    assert [(e["kind"], e.get("contact")) for e in ex.events] == [(e["kind"], e.get("contact")) for e in ref.events]
    np.testing.assert_allclose([e["time_s"] for e in ex.events], [e["time_s"] for e in ref.events], atol=1e-9)
    assert np.max(np.abs(ex.s - ref.s)) < atol_s
    assert np.max(np.abs(ex.parts - ref.parts)) < atol_s
    return ex, ref


def test_finger_on_an_adjuster_matches_scipy_with_two_contacts_and_the_check_valve():
    # the finger floats at 5300 rpm: the cam contact opens and closes, the pad on the valve tip
    # opens and closes, the adjuster's check valve opens and shuts; the valve lift and the parts
    # within 1e-9 m of scipy DOP853 at rtol 1e-11, the plunger and the chamber pressure too
    ex, ref = _compare(_finger(), 5300)
    kinds = {(e["kind"], e.get("contact")) for e in ex.events}
    assert {("separation", "cam"), ("separation", "pad"), ("check-valve-open", None),
            ("check-valve-close", None)} <= kinds
    assert np.max(np.abs(ex.plunger - ref.plunger)) < 1e-9
    # measured: the lift 2.6e-14 m, the plunger 3.3e-14 m, the pressure 3e-10 of its peak, events 1e-13 s
    assert np.max(np.abs(ex.chamber_pressure - ref.chamber_pressure)) < 1e-6 * np.max(np.abs(ex.chamber_pressure))


def test_stiff_pushrod_ten_masses_high_speed_stays_finite_and_matches_scipy():
    # nine parts and the valve, a 1e10 N/m pushrod, 12 000 rpm: no stability limit (closed forms)
    parts = tuple(Part(f"p{i}", 0.01 + 0.002 * i) for i in range(9))
    joints = (Joint("cam", 1e8, 40.0),) + tuple(
        Joint(f"j{i}", 1e10 if i == 3 else 5e7, 20.0, one_sided=False) for i in range(9))
    tr = TrainModel(_valve(spring_mass=0.0, lash=0.0), parts, joints)
    ex, _ = _compare(tr, 12000, steps=1800)
    assert np.all(np.isfinite(ex.s)) and np.all(np.isfinite(ex.parts))


def test_pushrod_train_rattling_in_its_lash_matches_scipy():
    # the pushrod scene's lifter and rocker (the pushrod in series with the rocker's cup) with the
    # lash at the valve tip: after the valve seats, the lifter and the rocker rattle in the lash --
    # the cam contact, the rocker's cup and the pad open and close, parts fly free of both
    # neighbours (their rigid-body modes) -- 56 events, every one as scipy finds it; measured
    # 4.8e-13 m over the revolution
    scene = load_scene(scenes_dir() / "pushrod_train.toml")
    els = scene.linkage.elements
    series = 1.0 / (1.0 / els[1].stiffness + 1.0 / els[2].stiffness)
    tr = TrainModel.from_scene(scene.with_changes(linkage=replace(
        scene.linkage, elements=(els[0], replace(els[2], stiffness=series)))))
    rpm = 2000
    drive = Drive(build_lift(scene), scene.follower.ratio, rpm * math.pi / 30.0)
    t = _grid(rpm)
    ex = chain_exact.solve(tr, drive, t)
    ref = chain_reference.solve(tr, drive, t, rtol=1e-11, atol=1e-14)
    assert [(e["kind"], e.get("contact")) for e in ex.events] == [(e["kind"], e.get("contact")) for e in ref.events]
    contacts = {e.get("contact") for e in ex.events if e["kind"] == "separation"}
    assert contacts == {"cam", "rocker", "valve"}
    np.testing.assert_allclose([e["time_s"] for e in ex.events], [e["time_s"] for e in ref.events], atol=1e-9)
    assert np.max(np.abs(ex.s - ref.s)) < 1e-9
    assert np.max(np.abs(ex.parts - ref.parts)) < 1e-9


def test_parts_with_the_spring_as_a_chain_match_scipy():
    # issue #25 item 1, "the spring's chain where the scene asks for it": a lifter and a rocker on
    # a valve whose spring is 8 coil masses that clash; the cam contact (with its lash) opens and
    # closes -- the exact solver against scipy DOP853 at rtol 1e-11 on the same model, 48 events;
    # measured 4.9e-12 m in the lift and the coils. (With the pad one-sided as well the parts
    # rattle in the lash after the valve seats, ~100 events at grazing contacts that amplify
    # scipy's own error: 1.7e-5, 4.2e-6, 1.3e-7, 2.5e-9 m at rtol 1e-10 ... 1e-13, converging on
    # the exact solution; test_pushrod_train_rattling_in_its_lash_matches_scipy is a rattling case
    # that stays well conditioned)
    tr = TrainModel(_valve(elements=8, stiffness=5e7, lash=0.0, clash_compression=0.94e-3),
                    (Part("lifter", 0.04), Part("rocker", 0.03)),
                    (Joint("cam", 4e7, 30.0, 0.1e-3), Joint("pushrod", 2e7, 20.0, one_sided=False),
                     Joint("pad", 5e7, 20.0, one_sided=False)))
    ex, ref = _compare(tr, 4200)
    kinds = {e["kind"] for e in ex.events}
    assert {"separation", "re-contact", "coil-clash", "seat"} <= kinds
    assert np.max(np.abs(ex.coils - ref.coils)) < 1e-9
