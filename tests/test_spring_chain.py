"""The valve spring as a body (issue #15): the chain model, its exact solver and the scene keys.

Oracles: the chain's eigenfrequencies in closed form and their convergence to the continuous
spring's; the scipy reference on the same model; the massless model as the spring's mass goes
to 0; the energy balance over a revolution; the phi functions against their integral."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explorer import load_scene, loads_scene, simulate
from explorer.dynamics import chain_reference
from explorer.dynamics.chain import ChainModel, chain_frequencies, continuous_frequencies
from explorer.dynamics.chain_exact import phase_modes, phi_functions, solve
from explorer.dynamics.chain_kernels import phi_into
from explorer.dynamics.model import Drive, LinkageModel
from explorer.dynamics.solvers import solve as solve_massless
from explorer.core.errors import InputError
from explorer.effects.lift import build_lift
from explorer.scene.builtin import scenes_dir

SCENE = scenes_dir() / "spring_surge.toml"


def _model(**changes) -> ChainModel:
    base = dict(valve_mass=0.08, spring_mass=0.045, elements=8, spring_rate=30.6e3, preload=220.0, stiffness=3e6,
                seat_stiffness=2e8, damping=8.0, lash=0.25e-3, closing_load=15.0, seat_damping=400.0,
                damping_ratio=0.02)
    base.update(changes)
    return ChainModel(**base)


def _drive(rpm: float) -> Drive:
    scene = load_scene(SCENE)
    return Drive(build_lift(scene), 1.0, rpm * math.pi / 30.0)


def _grid(rpm: float, steps: int = 3600) -> np.ndarray:
    return np.linspace(0.0, 60.0 / rpm, steps + 1)


# -- the chain's modes -----------------------------------------------------------------------

@pytest.mark.parametrize("N", [1, 4, 8, 31])
def test_chain_eigenfrequencies_closed_form(N):
    # the coils with both ends held: eigh of the model's matrices against
    # omega_j = 2 sqrt(k_e/m_e) sin(j pi / (2 (N+1))); eigh is backward stable: 1e-12 relative
    m = _model(elements=N)
    w, _ = m.coil_modes
    np.testing.assert_allclose(np.sort(w), chain_frequencies(N, m.spring_rate, m.spring_mass), rtol=1e-12)


def test_chain_frequencies_converge_to_continuous_spring_at_second_order():
    # f_j(N) -> (j/2) sqrt(k/m_s); with the half-element ends the error falls as 1/N^2:
    # the closed form gives f1(N)/f1 = sin(x)/x, x = pi/(2(N+1)), error ~ x^2/6
    k, ms = 30e3, 0.05
    f_inf = continuous_frequencies(3, k, ms)
    errs, Ns = [], (8, 16, 32, 64)
    for N in Ns:
        f = chain_frequencies(N, k, ms)[:3] / (2 * math.pi)
        errs.append(np.abs(f / f_inf - 1.0))
        x = np.arange(1, 4) * math.pi / (2 * (N + 1))
        assert np.all(errs[-1] <= x * x / 6 * (1 + 1e-9))  # 1 - sin(x)/x <= x^2/6
    orders = [math.log(errs[i][0] / errs[i + 1][0]) / math.log((Ns[i + 1] + 1) / (Ns[i] + 1)) for i in range(3)]
    assert all(1.99 < p < 2.01 for p in orders), orders


def test_spring_damping_is_modal_ratio():
    # each held-ends mode has exactly the ratio zeta: the undamped shape diagonalises C
    m = _model(damping_ratio=0.05)
    w, Phi = m.coil_modes
    C = m.spring_damping_matrix[1:, 1:]
    modal = Phi.T @ C @ Phi
    np.testing.assert_allclose(np.diag(modal), 2 * 0.05 * w, rtol=1e-9)
    assert np.max(np.abs(modal - np.diag(np.diag(modal)))) < 1e-9 * np.max(np.abs(modal))
    # and the quasi-static compression (u_j = s r_j) is not damped
    r = 1.0 - np.arange(0, m.n) / (m.n)
    assert np.max(np.abs(m.spring_damping_matrix @ r)) < 1e-9 * np.max(np.abs(m.spring_damping_matrix))


def test_phi_functions_against_their_integral():
    # phi_j(x) = int_0^1 e^((1-s) x) s^(j-1)/(j-1)! ds, Gauss-Legendre with 60 nodes (exact to
    # rounding for these |x| <= 30 on [0, 1]); the series/recurrence switch at |x| = 1 included
    xs = np.array([1e-8j, 0.3 + 0.2j, -0.99j, 1.01j, 2.5j, -4.0 + 3.0j, -30.0 + 1.0j, 0.999])
    nodes, weights = np.polynomial.legendre.leggauss(60)
    s, w = 0.5 * (nodes + 1.0), 0.5 * weights
    F = phi_functions(xs)
    # the compiled copy the solver's inner loops use (chain_kernels.py), same oracle
    Fc = np.empty((7, xs.size), dtype=complex)
    phi_into(xs.astype(complex), Fc)
    for j in range(1, 7):
        ref = (np.exp(np.outer(xs, 1.0 - s)) * s ** (j - 1) / math.factorial(j - 1)) @ w
        np.testing.assert_allclose(F[j], ref, rtol=1e-13, atol=1e-16)
        np.testing.assert_allclose(Fc[j], ref, rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(Fc[0], np.exp(xs), rtol=1e-15)


def test_warm_up_run_reaches_every_kernel():
    # the install step's warm-up (chain_exact.warm) must call each compiled kernel once: the
    # scan between events, the search and the arming (at lift-off, seat, separation, clash)
    from explorer.dynamics.chain_exact import warm

    kinds = warm()
    assert {"lift-off", "seat", "separation", "coil-clash"} <= set(kinds)


def test_undamped_phase_eigenvalues_are_imaginary_and_match_eigh():
    m = _model(damping=0.0, seat_damping=0.0, damping_ratio=0.0)
    md = phase_modes(m, True, False)
    K, _ = m.phase_matrices(True, False)
    w = np.sqrt(np.linalg.eigvalsh(K / np.sqrt(m.masses)[:, None] / np.sqrt(m.masses)[None, :]))
    assert np.max(np.abs(md.lam.real)) < 1e-9 * np.max(w)
    np.testing.assert_allclose(np.sort(np.abs(md.lam.imag))[::2], w, rtol=1e-10)


# -- the exact solver against its oracles ------------------------------------------------------

@pytest.mark.parametrize("rpm, N, changes", [
    (3000, 8, {}), (2300, 4, {}), (5000, 1, {}),
    # coil clash events (the same-phase event that disarms its function until it comes back)
    (3000, 8, {"clash_compression": 0.94e-3}),
])
def test_exact_matches_scipy_reference(rpm, N, changes):
    # same model, same events; scipy DOP853 rtol 1e-10 atol 1e-13 is good to ~1e-11 m here
    m = _model(elements=N, **changes)
    drive, t = _drive(rpm), _grid(rpm)
    ex = solve(m, drive, t)
    ref = chain_reference.solve(m, drive, t)
    assert [e["kind"] for e in ex.events] == [e["kind"] for e in ref.events]
    np.testing.assert_allclose([e["time_s"] for e in ex.events], [e["time_s"] for e in ref.events], atol=1e-9)
    assert np.max(np.abs(ex.s - ref.s)) < 5e-11
    assert np.max(np.abs(ex.coils - ref.coils)) < 5e-11
    assert np.max(np.abs(ex.retainer_force - ref.retainer_force)) < 1e-5


def test_light_spring_recovers_the_massless_model():
    # the spring's mass -> 0: the valve of mass M = valve + m_e/2 (-> valve) on a massless spring.
    # The difference falls in proportion to m_s; at m_s = 1e-9 kg it is below 1e-10 m. The seat:
    # 1e13 N/m stands for the rigid seat (compression W0/k ~ 2e-11 m); the
    # comparison runs over the lift, up to the first seat contact. (A damped Kelvin-Voigt seat holds
    # the valve back as it leaves: 4e-10 m with critical damping, so the seat here is undamped)
    rpm = 2000
    drive, t = _drive(rpm), _grid(rpm)
    M = 0.08
    base = LinkageModel(mass=M, oscillating_mass=M, stiffness=3e6, damping=0.0, lash=0.25e-3, preload=220.0,
                        spring_rate=30.6e3, closing_load=15.0, restitution=0.0)
    ref = solve_massless(base, drive, t)
    seat_at = min(e["time_s"] for e in ref.events if e["kind"] == "seat")
    window = t < seat_at - 1e-4
    diffs = []
    for ms in (1e-6, 1e-7, 1e-8, 1e-9):
        m = _model(valve_mass=M - 0.5 * ms / 9, spring_mass=ms, elements=8, damping=0.0, damping_ratio=0.0,
                   seat_stiffness=1e13, seat_damping=0.0)
        ch = solve(m, drive, t)
        diffs.append(np.max(np.abs(ch.s - ref.s)[window]))
    assert diffs[-1] < 1e-10, diffs
    assert diffs[0] > diffs[1] > diffs[2] > diffs[3]


@pytest.mark.parametrize("rpm, N, R", [(3000, 8, 20.0), (2300, 4, 40.0)])
def test_friction_matches_scipy_reference(rpm, N, R):
    # Coulomb friction R on the valve: the valve sticks where its velocity reaches 0 with the net
    # force within [-R, R] (its coils go on moving), turns otherwise, and is released when the
    # net force leaves the band. scipy with the same rules (velocity-zero and release functions):
    # the same events in the same order, the motion within 5e-11 m (measured 2.1e-12, 1.6e-12)
    m = _model(elements=N, friction=R)
    drive, t = _drive(rpm), _grid(rpm)
    ex = solve(m, drive, t)
    ref = chain_reference.solve(m, drive, t)
    kinds = [e["kind"] for e in ex.events]
    assert kinds == [e["kind"] for e in ref.events]
    assert {"stick", "release", "turn"} <= set(kinds)
    np.testing.assert_allclose([e["time_s"] for e in ex.events], [e["time_s"] for e in ref.events], atol=1e-9)
    assert np.max(np.abs(ex.s - ref.s)) < 5e-11
    assert np.max(np.abs(ex.coils - ref.coils)) < 5e-11
    # held by friction, from each stick to its release, the valve does not move at all
    # (the run starts held: its first stop is a release)
    stops = [e["time_s"] for e in ex.events if e["kind"] in ("stick", "release")]
    assert [e["kind"] for e in ex.events if e["kind"] in ("stick", "release")][:2] == ["release", "stick"]
    held = 0
    for a, b in zip(stops[1::2], stops[2::2]):
        inside = (t > a) & (t < b)
        held += int(inside.sum())
        assert np.all(ex.s[inside] == ex.s[inside][0]) and np.all(ex.v[inside] == 0.0)
    assert held > 10


def test_light_spring_with_friction_recovers_the_massless_model():
    # as test_light_spring_recovers_the_massless_model, with friction R = 20 N on both: from a
    # state on the lift flank (the massless run's, the coils on their quasi-static shape) to the
    # first seat; the valve turns 7 times (in contact over the nose and in flight) in both.
    # Difference proportional to m_s: measured 9.6e-9 .. 9.6e-12 m for 1e-6 .. 1e-9 kg
    rpm, M, R = 2000, 0.08, 20.0
    drive, t = _drive(rpm), _grid(rpm)
    base = LinkageModel(mass=M, oscillating_mass=M, stiffness=3e6, damping=0.0, lash=0.25e-3, preload=220.0,
                        spring_rate=30.6e3, closing_load=15.0, restitution=0.0, friction=R)
    full = solve_massless(base, drive, t)
    i0 = int(np.argmax((full.s > 1e-3) & full.contact))
    ts = t[i0:]
    ref = solve_massless(base, drive, ts, initial_state=(float(full.s[i0]), float(full.v[i0])))
    seat_at = min(e["time_s"] for e in ref.events if e["kind"] == "seat")
    window = ts < seat_at - 1e-4
    r = 1.0 - np.arange(9) / 9  # the quasi-static shape of the coils
    diffs = []
    for ms in (1e-6, 1e-7, 1e-8, 1e-9):
        m = _model(valve_mass=M - 0.5 * ms / 9, spring_mass=ms, elements=8, damping=0.0, damping_ratio=0.0,
                   seat_stiffness=1e13, seat_damping=0.0, friction=R)
        ch = solve(m, drive, ts, initial_state=(ref.s[0] * r, ref.v[0] * r, (True, False, 1)))
        turns = [e for e in ch.events if e["kind"] == "turn" and e["time_s"] < seat_at]
        assert len(turns) == ref.stats["velocity_reversals"] == 7
        diffs.append(np.max(np.abs(ch.s - ref.s)[window]))
    assert diffs[-1] < 1e-10, diffs
    assert diffs[0] > diffs[1] > diffs[2] > diffs[3]


def _released_seat_energy(events, t: np.ndarray, k: float, c: float) -> np.ndarray:
    """At each time t, the sum of (c v)^2 / (2 k) over the lift-offs before it (v: their speed)."""
    out = np.zeros(t.size)
    for e in events:
        if e["kind"] == "lift-off":
            out[t > e["time_s"]] += 0.5 * (c * e["velocity_m_s"]) ** 2 / k
    return out


def test_energy_balance_over_a_revolution():
    # undamped chain and linkage, seat damping only: the change of the valve-and-spring energy
    # (kinetic + chain + seat spring) equals the work of the linkage force and the constant loads
    # on the valve minus the seat damper's loss. The seat lets go where its force falls to 0, still
    # compressed by c v / k: the energy (c v)^2 / (2 k) left in its spring is the massless seat's
    # own, which its damper takes as it relaxes (k x + c x' = 0), v the lift-off's recorded speed.
    # Trapezoid rule on a 36 000-step grid: at each of the ~20 seat impacts the damper's force c v
    # jumps (Kelvin-Voigt seat), a first-order error of the quadrature there; bound 1e-3 of the
    # energy turned over (measured 1.5e-4; 8.1e-4 without the seat's released energy)
    rpm = 3000
    m = _model(damping=0.0, damping_ratio=0.0)
    t = _grid(rpm, 36000)
    sol = solve(m, _drive(rpm), t)
    x = np.vstack([sol.s, sol.coils])
    v = np.vstack([sol.v, sol.coil_velocities])
    K = m.spring_stiffness_matrix
    seat = sol.phase == 0
    E = (0.5 * np.einsum("i,it->t", m.masses, v * v) + 0.5 * np.einsum("it,ij,jt->t", x, K, x)
         + np.where(seat, 0.5 * m.seat_stiffness * sol.s**2, 0.0))
    power = (sol.linkage_force - m.preload - m.closing_load) * sol.v - np.where(seat, m.seat_damping * sol.v**2, 0.0)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(t))])
    work -= _released_seat_energy(sol.events, t, m.seat_stiffness, m.seat_damping)
    scale = np.max(np.abs(E - E[0]))
    assert np.max(np.abs(E - E[0] - work)) < 1e-3 * scale, np.max(np.abs(E - E[0] - work)) / scale


def test_first_separation_converges_with_elements():
    # the first separation angle during the lift as N grows: Richardson on N = 8, 16, 32 gives
    # the order; the half-element lumping makes it second order (the frequencies' order).
    # Measured: 61.035, 61.131, 61.158 (64: 61.165) deg, orders 1.83 and 1.92 (N = 16, 32, 64)
    rpm = 3900
    drive, t = _drive(rpm), _grid(rpm)
    angles = []
    for N in (8, 16, 32):
        sol = solve(_model(elements=N, damping_ratio=0.0), drive, t)
        sep = [e["time_s"] for e in sol.events if e["kind"] == "separation"]
        angles.append(math.degrees(sep[0] * rpm * math.pi / 30.0))
    d1, d2 = angles[0] - angles[1], angles[1] - angles[2]
    order = math.log2(abs(d1 / d2))
    assert 1.7 < order < 2.2, (angles, order)


def test_stiff_seat_many_elements_high_speed_stays_finite_and_matches_reference():
    # k_seat = 1e12 N/m, 64 elements, 12 000 rpm: no stability limit (closed forms), the same
    # motion as scipy (whose steps the fastest mode bounds)
    rpm = 12000
    m = _model(elements=64, seat_stiffness=1e12, seat_damping=2 * math.sqrt(1e12 * 0.08) * 0.5)
    drive, t = _drive(rpm), _grid(rpm, 1800)
    ex = solve(m, drive, t)
    assert np.all(np.isfinite(ex.s)) and np.all(np.isfinite(ex.coils))
    ref = chain_reference.solve(m, drive, t)
    assert [e["kind"] for e in ex.events] == [e["kind"] for e in ref.events]
    assert np.max(np.abs(ex.s - ref.s)) < 1e-9


# -- scene keys and the effect -----------------------------------------------------------------

def _scene_text(spring: str, seat: str = 'stiffness = "200 N/um"\ndamping = "400 N*s/m"', extra: str = "") -> str:
    return f"""
effects = ["elastic"]
[drive]
rpm = 2300
[lift]
law = "polynomial-345"
height = "9.25 mm"
start = "30 deg"
rise = "75 deg"
dwell = "10 deg"
return = "75 deg"
[valve]
mass = "0.08 kg"
lash = "0.25 mm"
[spring]
{spring}
[linkage]
stiffness = "3 kN/mm"
[seat]
{seat}
{extra}
"""


GEOMETRY = ('preload = "220 N"\nwire_diameter = "4 mm"\ncoil_diameter = "24 mm"\nactive_coils = 6\n'
            'shear_modulus = "79300 MPa"\ndensity = "7850 kg/m**3"\nelements = 8\n')


def test_wire_geometry_gives_rate_and_mass():
    scene = loads_scene(_scene_text(GEOMETRY))
    d, D, n, G, rho = 4e-3, 24e-3, 6.0, 79.3e9, 7850.0
    assert scene.spring.rate == pytest.approx(G * d**4 / (8 * D**3 * n), rel=1e-14)
    assert scene.spring.mass == pytest.approx(rho * math.pi**2 * d * d * D * n / 4, rel=1e-14)


def test_rate_disagreeing_with_geometry_names_both_keys():
    with pytest.raises(InputError) as exc:
        loads_scene(_scene_text(GEOMETRY + 'rate = "32 N/mm"\n'))
    text = str(exc.value)
    assert "spring.rate" in text and "shear_modulus" in text and "%" in text
    loads_scene(_scene_text(GEOMETRY + 'rate = "30.7 N/mm"\n'))  # within 1 %


@pytest.mark.parametrize("spring, seat, key", [
    ('preload = "220 N"\nrate = "30 N/mm"\nelements = 8\n', None, "spring.elements"),
    ('preload = "220 N"\nrate = "30 N/mm"\nmass = "40 g"\nelements = 8\n', "restitution = 0.2", "seat.stiffness"),
    ('preload = "220 N"\nrate = "30 N/mm"\nwire_diameter = "4 mm"\n', None, "spring.coil_diameter"),
    ('preload = "220 N"\nrate = "30 N/mm"\nmass = "40 g"\nelements = 8.5\n', None, "spring.elements"),
])
def test_chain_input_errors(spring, seat, key):
    with pytest.raises(InputError) as exc:
        loads_scene(_scene_text(spring, seat) if seat else _scene_text(spring))
    assert key in str(exc.value) and "\n" not in str(exc.value)


def test_oscillating_mass_with_a_chain_is_an_error():
    # Schenker's M1 removes the spring's share from the mass under the linkage; with the spring as
    # masses that share is the coils' own motion: an M1 as well would count it twice
    text = _scene_text('preload = "220 N"\nrate = "30 N/mm"\nmass = "40 g"\nelements = 8\n')
    text = text.replace('mass = "0.08 kg"', 'mass = "0.08 kg"\noscillating_mass = "0.07 kg"')
    with pytest.raises(InputError) as exc:
        loads_scene(text)
    assert "valve.oscillating_mass" in str(exc.value) and "\n" not in str(exc.value)


def test_friction_with_a_chain_in_the_elastic_effect():
    # loads.friction reaches the chain: the valve sticks on its seat and after it, and the summary
    # counts the stops; the seat's stick/release rounds are the scipy-tested ones above
    scene = loads_scene(_scene_text(GEOMETRY, extra='[loads]\nfriction = "20 N"\n'))
    result = simulate(scene)
    counts = result.summary["elastic_event_counts"]
    assert counts["stick"] >= 1 and counts["release"] >= 1
    assert "friction 20 N" in result.summary["elastic_model"]
    assert result.summary["elastic_max_valve_lift_m"] > 8e-3


def test_static_lift_reaching_solid_height_is_an_error():
    spring = GEOMETRY + 'free_length = "50 mm"\nsolid_height = "34 mm"\n'  # travel 50 - 7.2 - 34 = 8.8 mm < 9
    scene = loads_scene(_scene_text(spring))
    with pytest.raises(InputError) as exc:
        simulate(scene)
    assert "spring.solid_height" in str(exc.value)


def test_coil_clash_is_an_event_with_a_warning():
    # travel to solid 9.1 mm: the static lift (9 mm) stays clear, the surge does not
    spring = GEOMETRY + 'free_length = "50 mm"\nsolid_height = "33.6 mm"\n'
    scene = loads_scene(_scene_text(spring).replace("rpm = 2300", "rpm = 3000"))
    result = simulate(scene)
    kinds = [e["kind"] for e in result.events]
    assert "coil-clash" in kinds
    assert any("coil clash" in w for w in result.warnings)


def test_surge_scene_separates_below_the_rigid_float_speed():
    result = simulate(load_scene(SCENE))
    s = result.summary
    assert s["spring_elements"] == 8
    assert s["surge_amplitude_N"] > 10.0
    # the valve leaves the cam on the lift flank (before the nose at 67.5 + ... deg), far below the
    # rigid train's jump speed of the forces effect (3886 rpm: its mass is the valve and a third of
    # the spring, which the scene models as masses; tests/test_rigid_mass.py)
    assert s["first_separation_deg"] is not None and 60.0 < s["first_separation_deg"] < 105.0
    assert s["jump_speed_rpm"] > 1.45 * s["rpm"]
    f1 = s["spring_modal_frequencies_Hz"][0]
    # the closed form of the chain, and the continuous spring within the 1/N^2 lumping error
    assert f1 == pytest.approx(0.5 * math.sqrt(30.6e3 / 0.0446) * math.sin(math.pi / 18) / (math.pi / 18), rel=2e-3)
    for name in ("spring_force_retainer_N", "spring_force_static_N", "coil_1_displacement_m", "coil_8_displacement_m"):
        assert name in result.columns


def test_schenker_gear_surge_model_against_his_mass_split():
    # SEEDS.md section 3: Schenker lumps the spring's share 0.3 of M = 2.9 into the free flight
    # and leaves it out (M1 = 2.6) under the linkage. The chain model with his valve (2.6) and his
    # spring (Gf = 8 kgf, whose third is his 0.27 ~ 0.3), 16 masses, against his split on the same
    # gear (friction off in both, the comparison is of the masses; a rate of 2 kgf/mm, since a chain needs
    # one; his rigid seat as 1e9 N/m). The fast linkage oscillation (132 Hz) is far above the
    # spring's first mode (25 Hz), so the coils barely follow it: his M1 is the right mass there,
    # and the two models separate at the same cam angles. Measured: first three separations
    # 0.5, 0.5, 1.4 deg apart, lift within 0.52 mm of 20 mm
    import tomllib

    from explorer.scene.scene import apply_overrides, scene_from_dict

    path = scenes_dir() / "schenker1902_fig2.toml"
    base = ['loads.friction="0 kgf"', 'spring.rate="2 kgf/mm"']
    split = simulate(load_scene(path, base))
    data = apply_overrides(tomllib.loads(path.read_text()),
                           base + ['valve.mass="2.6 kgf*s**2/m"', 'spring.mass="8 kg"', "spring.elements=16"], str(path))
    del data["valve"]["oscillating_mass"]
    data["seat"] = {"stiffness": "1e9 N/m", "damping": "2e5 N*s/m"}
    chain = simulate(scene_from_dict(data, str(path)))
    f1 = chain.summary["spring_modal_frequencies_Hz"][0]
    assert f1 == pytest.approx(0.5 * math.sqrt(2 * 9.80665e3 / 8.0), rel=0.01)  # continuous spring, 1/N^2 error

    def separations(result):
        return [e["cam_angle_deg"] for e in result.events if e.get("effect") == "elastic" and e["kind"] == "separation"]

    a, b = separations(split)[:3], separations(chain)[:3]
    assert len(a) == len(b) == 3
    assert np.max(np.abs(np.array(a) - np.array(b))) < 2.0, (a, b)
    assert np.max(np.abs(split.columns["valve_lift_m"] - chain.columns["valve_lift_m"])) < 1e-3


def test_viewer_and_recording_move_the_coils_with_the_surge(tmp_path):
    # the drawn spring: each coil node's wire point is moved by magnification x (u_j - s r_j);
    # the recording: one point per coil per step under the spring's frame, at the same surge
    from explorer.view import parts as meshes
    from explorer.view.rerun.recording import with_parts, write_recordings
    from explorer.view.rerun.read import read_rrd

    scene = load_scene(SCENE, ["solver.steps_per_revolution=720"])
    result = simulate(scene)
    lay = meshes.layout(scene, result)
    w = meshes.spring_surge(result, 10.0)
    u1 = result.columns["coil_1_displacement_m"]
    s = result.columns["valve_lift_m"]
    np.testing.assert_allclose(w[:, 0], 10.0 * (u1 - s * 8 / 9), rtol=1e-12, atol=1e-15)
    i = int(np.argmax(np.abs(w).max(axis=1)))
    plain = meshes.spring_vertices(lay, 0.05)
    moved = meshes.spring_vertices(lay, 0.05, surge=w[i])
    assert np.max(np.abs(moved[:, 2] - plain[:, 2])) == pytest.approx(np.max(np.abs(w[i])), rel=0.05)
    np.testing.assert_array_equal(moved[:, :2], plain[:, :2])  # only along the axis
    out = tmp_path / "surge.rrd"
    write_recordings(out, [with_parts("surge", result)])
    run = read_rrd(out)[0]
    coils = run.temporal["/parts/spring/coils"]
    positions = coils["Points3D:positions"]
    assert len(positions) == 720 and len(positions[0]) == 8
    sz = meshes.spring_axial_scale(scene, result, lay=lay)
    z = np.array([[p[2] for p in row] for row in positions])
    # the surge of coil 1, back from the recorded height (float32 in the file: 1e-6 m)
    z_rest = z + meshes.spring_surge(result)[:, :] / sz[:, None]
    assert np.max(np.abs(z_rest - z_rest[0])) < 1e-6


def test_the_modes_exciting_orders_are_the_drives_acceleration_harmonics():
    # the cam orders around each spring mode carry the drive's acceleration harmonics in m/s^2
    # ((k omega)^2 times the displacement's FFT amplitude: a mode excited through its base feels m
    # times the base's acceleration). Oracle: the FFT of the kinematics' analytic acceleration
    # column (follower_accel_m_s2 x ratio), a different signal; 1e-3 rel: that column's 3-4-5
    # acceleration has kinks (its jerk jumps), whose sampled harmonics alias by ~3e-4 here
    scene = load_scene(scenes_dir() / "spring_surge.toml")
    r = simulate(scene)
    accel = r.columns["follower_accel_m_s2"] * scene.follower.ratio
    harmonics = np.abs(np.fft.rfft(accel)) * 2.0 / accel.size
    seen = 0
    for mode in r.summary["spring_modes_cam_orders"]:
        for order, amplitude in mode["exciting_accel_m_s2"].items():
            assert amplitude == pytest.approx(harmonics[int(order)], rel=1e-3)
            seen += 1
    assert seen == 6
