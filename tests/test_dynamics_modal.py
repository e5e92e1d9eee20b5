"""Whole-grid modal propagation (explorer/dynamics/modal.py) against long-double oracles.

Oracles, independent of the module's modal algebra: the powers exp(mu h)^n as the exponential of
the exactly summed argument in extended precision (np.longdouble, 64-bit mantissa); and the
node-to-node recurrence x[n+1] = Phi(h_n) x[n] + G[n] + g(h_n) run step by step in long double,
with Phi = exp(A h) and the constant-load response g = int_0^h exp(A tau) d tau (0, -Fc/m) from
their power series (|A| h <= 0.5: 40 terms are exact to long double). The drive forcing G is that
of a smooth quasi-static path x_qs(t), G[n] = x_qs(t_n+1) - Phi x_qs(t_n), so the states stay of
the size a real drive gives. Tolerances: the module works in double precision, so its error is a
few eps of the state's size (the largest |s| and the largest |v| + beta |s| of the run): 64 eps,
about twice the worst observed (the stiff case, 20 000 steps of 0.46 rad); a phase drift of
eps omega t (a frequency rounded to a double, or powers from a rounded argument) would exceed it
by ~5x there.
"""

import math

import numpy as np
import pytest

from explorer.dynamics import modal

LD = np.longdouble
EPS = float(np.finfo(float).eps)


def _series_exp(A: np.ndarray, h: float, terms: int = 40):
    """exp(A h) and int_0^h exp(A tau) d tau by their power series, in long double."""
    Ah = A.astype(LD) * LD(h)
    E = np.eye(2, dtype=LD)
    I = np.eye(2, dtype=LD) * LD(h)
    term = np.eye(2, dtype=LD)
    for k in range(1, terms):
        term = term @ Ah / LD(k)
        E = E + term
        I = I + term * LD(h) / LD(k + 1)
    return E, I


def _grid(h0: float, n: int, odd: dict):
    """Step lengths: mostly h0, a few odd ones (like steps ending at inserted breakpoints)."""
    h_unique = [h0]
    hidx = np.zeros(n, dtype=np.int64)
    for pos, hh in odd.items():
        h_unique.append(hh)
        hidx[pos] = len(h_unique) - 1
    h_unique = np.array(h_unique)
    h = h_unique[hidx]
    nodes = np.concatenate([[0.0], np.cumsum(h)])
    return nodes, hidx, h_unique


def _oracle_run(m, c, K, hidx, h_unique, G, j, L, s, v, Fc):
    """The recurrence from node j, in long double."""
    A = np.array([[0.0, 1.0], [-K / m, -c / m]])
    steps = {col: _series_exp(A, float(hu)) for col, hu in enumerate(h_unique)}
    b = np.array([LD(0.0), -LD(Fc) / LD(m)])
    x = np.array([LD(s), LD(v)])
    out = [x.copy()]
    for i in range(j, j + L):
        E, I = steps[int(hidx[i])]
        x = E @ x + I @ b
        if G is not None:
            x = x + G[:, i].astype(LD)
        out.append(x.copy())
    return np.array(out, dtype=LD).T  # (2, L + 1)


def _quasi_static_forcing(m, c, K, nodes, hidx, h_unique, amp=0.01, omega_drive=400.0):
    """G[n] = x_qs(t_n+1) - Phi(h_n) x_qs(t_n) for a smooth path x_qs (rounded to double)."""
    A = np.array([[0.0, 1.0], [-K / m, -c / m]])
    Es = {col: _series_exp(A, float(hu))[0] for col, hu in enumerate(h_unique)}
    t = nodes.astype(LD)
    xq = np.array([LD(amp) * np.sin(LD(omega_drive) * t), LD(amp * omega_drive) * np.cos(LD(omega_drive) * t)])
    G = np.empty((2, hidx.size), dtype=LD)
    for i in range(hidx.size):
        G[:, i] = xq[:, i + 1] - Es[int(hidx[i])] @ xq[:, i]
    return G.astype(float)


def _phi_of_step(m, c, K, hidx, h_unique):
    A = np.array([[0.0, 1.0], [-K / m, -c / m]])
    per_col = {}
    for col, hu in enumerate(h_unique):
        E, I = _series_exp(A, float(hu))
        per_col[col] = (E.astype(float), (I @ np.array([LD(0.0), LD(1.0) / LD(m)])).astype(float))

    def phi_of_step(j, L):
        cols = hidx[j:j + L]
        Phi = np.stack([per_col[int(k)][0] for k in cols], axis=-1)
        g1 = np.stack([per_col[int(k)][1] for k in cols], axis=-1)  # response to a unit load
        return Phi.tolist(), g1.tolist()

    return phi_of_step


@pytest.mark.parametrize("mu", [complex(0.0, -7071.0), complex(-350.0, -7000.0), complex(-20.0, -9.1e5), -400.0, 0.0])
@pytest.mark.parametrize("n", [1, 2, 65, 4097, 100_000])
def test_lattice_powers_are_exact_to_a_few_eps(mu, n):
    h = 4.1e-6
    U = modal._lattice(mu, h, n)
    i = np.arange(n).astype(LD)
    ref = np.exp(np.clongdouble(mu) * (i * LD(h))) if isinstance(mu, complex) else np.exp(LD(mu) * (i * LD(h)))
    # ~log2(n) roundings of exactly rounded factors; no drift with n. The oracle's own error:
    # its argument mu i h rounds to 2^-64 relative in long double (2e-14 rad at 3.7e5 rad)
    oracle = abs(mu) * h * n * float(np.finfo(LD).eps)
    assert U.shape == (n,)
    assert np.all(np.abs(U - ref) <= (8 * EPS + oracle) * np.abs(ref))


def test_step_powers_with_odd_steps_match_the_exact_products():
    mu = complex(-20.0, -9.1e5)
    nodes, hidx, h_unique = _grid(5.05e-7, 40_000, {100: 2.0e-7, 101: 3.05e-7, 20_000: 1.0e-7, 20_001: 4.05e-7})
    U = modal.step_powers(mu, hidx, h_unique)
    # tau_n = (steps of each length before n) * length, one rounding each in long double (a
    # running long-double sum of 40 000 steps would itself drift by ~1e-17 s = 1e-11 rad here)
    counts = np.zeros((h_unique.size, hidx.size + 1), dtype=np.int64)
    for col in range(h_unique.size):
        np.cumsum(hidx == col, out=counts[col, 1:])
    tau = (counts.astype(LD) * h_unique.astype(LD)[:, None]).sum(axis=0)
    ref = np.exp(np.clongdouble(mu) * tau)
    assert np.abs(U - ref).max() <= 16 * EPS * np.abs(ref).max()


CASES = {
    # (m, c, K, h0, steps): contact-like undamped, lightly damped, heavily overdamped (blocks),
    # critically damped (step loop), flight with a spring, stiff (the old drift's worst case)
    "undamped": (0.1, 0.0, 5.03e6, 4.17e-6, 3600),
    "underdamped": (0.1, 70.0, 5.03e6, 4.17e-6, 3600),
    "overdamped": (0.1, 4.25e3, 5.0e6, 4.17e-6, 3600),
    "critical": (0.1, 2.0 * math.sqrt(0.1 * 5.0e6), 5.0e6, 4.17e-6, 1200),
    "flight-spring": (0.1, 0.0, 3.0e4, 4.17e-6, 3600),
    "stiff": (0.12, 0.0, 1.0e11, 5.05e-7, 20_000),
}


@pytest.mark.parametrize("name", list(CASES))
def test_states_match_the_long_double_recurrence(name):
    m, c, K, h0, n = CASES[name]
    nodes, hidx, h_unique = _grid(h0, n, {n // 3: 0.4 * h0, n // 3 + 1: 0.6 * h0})
    G = _quasi_static_forcing(m, c, K, nodes, hidx, h_unique)
    prop = modal.Propagator(m, c, K, nodes, G, _phi_of_step(m, c, K, hidx, h_unique), hidx, h_unique)
    if name == "overdamped":
        assert prop.mode == "real" and len(prop.cuts) > 2  # several blocks
    if name == "critical":
        assert prop.mode == "loop"
    Fc = 300.0
    beta = math.sqrt(abs(K / m - (0.5 * c / m) ** 2)) or math.sqrt(K / m)
    for j, L in ((0, n), (n // 3 - 5, n - n // 3 + 5), (n - 40, 40)):
        s0, v0 = 0.004, -0.7
        SV = prop.states(j, L, s0, v0, Fc)
        ref = _oracle_run(m, c, K, hidx, h_unique, G, j, L, s0, v0, Fc)
        s_scale = float(np.abs(ref[0]).max())
        v_scale = float(np.abs(ref[1]).max()) + beta * s_scale
        assert SV.shape == (2, L + 1) and SV[0, 0] == s0 and SV[1, 0] == v0
        assert float(np.abs(SV[0] - ref[0]).max()) <= 64 * EPS * s_scale, name
        assert float(np.abs(SV[1] - ref[1]).max()) <= 64 * EPS * v_scale, name


def test_free_flight_without_spring_is_the_parabola():
    nodes, hidx, h_unique = _grid(1e-5, 500, {})
    prop = modal.Propagator(0.2, 0.0, 0.0, nodes, None, None, hidx, h_unique)
    assert prop.mode == "parabola"
    SV = prop.states(100, 300, 1e-3, 2.0, 300.0)
    tau = nodes[100:401] - nodes[100]
    g = 300.0 / 0.2
    np.testing.assert_allclose(SV[0], 1e-3 + 2.0 * tau - 0.5 * g * tau**2, rtol=0, atol=1e-17)
    np.testing.assert_allclose(SV[1], 2.0 - g * tau, rtol=0, atol=1e-15)
