"""The eigen-decomposition of a long spring chain's phases from its structure (issue #27, item 6).

The dense decomposition (phase_system.decompose: numpy's eig of the 2n x 2n state matrix and its
inverse) costs O(n^3) with a large constant: 7-9 ms per phase type at 64 elements on one core,
more than the rest of a revolution. The chain's structure gives the same modes for O(n^2) plus two
matrix products:

Coordinates xi = (s, eta): the valve's lift and the coils' motion about their quasi-static shape,
u = r s + Phi eta (r_j = 1 - j/(N+1), the static shape; Phi the chain's modes with both ends held,
mass-normalised, in closed form: Phi_jk = sqrt(2/((N+1) m_e)) sin(j k pi/(N+1)), omega_k =
2 sqrt(k_e/m_e) sin(k pi/(2(N+1)))). The static shape makes the stiffness block-diagonal (the
valve sees the spring's rate, the coils their held-ends modes: K = diag(k_0, omega_k^2)), the
spring's modal damping is diagonal by its definition (chain.py: C = diag(c_0, 2 zeta omega_k)), and
the mass matrix is an arrowhead: [[m_s, b'], [b, I]] with m_s = M_valve + m_e r.r, b = m_e Phi' r.
A mode (lambda, xi) with s = 1 then has eta_k = -lambda^2 b_k / d_k(lambda), d_k = lambda^2 +
2 zeta omega_k lambda + omega_k^2, and lambda is a root of the secular function
    f(lambda) = m_s lambda^2 + c_0 lambda + k_0 - lambda^4 sum_k b_k^2 / d_k(lambda),
k_0 and c_0 the valve's stiffness and damping of the phase (rate, + linkage, + seat).

Roots: started at the undamped ones, i omega with omega^2 the eigenvalues of the symmetric
tridiagonal M^(-1/2) K M^(-1/2) (scipy's eigh_tridiagonal, O(n^2)), shifted by their first-order
damping, and found all together by
Aberth's iteration on the characteristic polynomial P = f prod_k d_k (Newton's correction P/P',
each root repelled from the others' approximations so that no two converge to the same root;
O(n N) per iteration, cubic convergence from these starts). Near a coil mode f has a pole and a
root close to it: each root's correction is computed from g = d_k f with its nearest pole removed
and d_k factored as (lambda - p_k)(lambda - conj p_k), so nothing cancels there. Certified before use: every root finite, of its own (pairwise
distinct by 1e-9 of its size), a root (|g| within 1e-10 of the size of its terms and of its slope
times lambda: what rounding lambda moves it by), none
overdamped (a conjugate pair); 2n distinct roots of f are all of the 2n eigenvalues. When a check
fails the caller falls back to the dense decomposition.

Inverse without inversion: the problem is symmetric (M, C, K), so the eigenvectors are orthogonal
under the linearisation [[C, M], [M, 0]]: with a_i = xi_i' (2 lambda_i M + C) xi_i, the rows of the
inverse are (1/a_i) [xi_i' C + lambda_i xi_i' M, xi_i' M] (Tisseur and Meerbergen, The quadratic
eigenvalue problem, SIAM Review 43 (2001), section 3.5); no O(n^3) inversion and no loss to the
conditioning of the eigenvector matrix. The modes are then mapped back to x = (s, u) with R and
R^(-1) = [[1, 0], [-Phi' m_e r, Phi' m_e]] (Phi' m_e Phi = I).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

MAX_ITERATIONS = 100


def _local(lam, ms, c0, k0, b2, p, nearest):
    """For each root lam_i (upper half plane): g_i = d_k f and g_i' with k = nearest[i] its nearest
    coil pole (f's pole there removed: no cancellation near it), the other poles' sum of
    d_l'/d_l (P'/P = g'/g + that, P = f prod_l d_l the characteristic polynomial), the size of
    g's terms, and every d_l(lam_i) = (lam_i - p_l)(lam_i - conj p_l), factored: exact near its roots."""
    L = lam[:, None]
    a, c = L - p[None, :], L - p.conj()[None, :]
    D = a * c
    dD = a + c
    R = np.arange(lam.size)
    q = b2[None, :] / D
    q[R, nearest] = 0.0
    S = q.sum(axis=1)
    S1 = (q * dD / D).sum(axis=1)
    rest = dD / D
    rest[R, nearest] = 0.0
    l2 = lam * lam
    fk = ms * l2 + c0 * lam + k0 - l2 * l2 * S
    dfk = 2.0 * ms * lam + c0 - 4.0 * l2 * lam * S + l2 * l2 * S1
    dk, ddk, bk = D[R, nearest], dD[R, nearest], b2[nearest]
    g = dk * fk - l2 * l2 * bk
    dg = ddk * fk + dk * dfk - 4.0 * l2 * lam * bk
    size = (np.abs(dk) * (ms * np.abs(l2) + abs(c0) * np.abs(lam) + abs(k0) + np.abs(l2) ** 2 * np.abs(q).sum(axis=1))
            + np.abs(l2) ** 2 * bk)
    return g, dg, rest.sum(axis=1), size, D


def _real_times(a, b, left: bool = True):
    """a @ b with one real factor (the left one if left, else the right), as real products."""
    if left:
        return a @ b.real + 1j * (a @ b.imag)
    return a.real @ b + 1j * (a.imag @ b)


@lru_cache(maxsize=8)
def _held_modes(N: int) -> np.ndarray:
    """Phi (N, N) without its mass factor: sin(j k pi / (N + 1)) (read-only)."""
    j = np.arange(1, N + 1)
    out = np.sin(np.outer(j, j) * (math.pi / (N + 1)))
    out.flags.writeable = False
    return out


def chain_phase_modes(model, contact: bool, seat: bool):
    """(lam, phys, inv) of a moving phase of a ChainModel (the same as phase_system.decompose's, up
    to rounding and the order and scaling of the modes), or None when the roots fail a check."""
    from scipy.linalg import eigh_tridiagonal

    N = model.elements
    n = N + 1
    if N < 1:
        return None
    me, ke = model.element_mass, model.element_stiffness
    j = np.arange(1, N + 1)
    Phi = math.sqrt(2.0 / ((N + 1) * me)) * _held_modes(N)
    w = 2.0 * math.sqrt(ke / me) * np.sin(j * math.pi / (2.0 * (N + 1)))
    zeta = model.damping_ratio
    cw = 2.0 * zeta * w
    # the coil modes' poles, damped: d_k = lambda^2 + 2 zeta w_k lambda + w_k^2 = (lambda - p_k)(lambda - conj p_k)
    p = w * (-zeta + 1j * math.sqrt(max(1.0 - zeta * zeta, 0.0)))
    r = 1.0 - j / (N + 1)
    M = model.masses
    ms = float(M[0] + me * (r @ r))
    b = me * (Phi.T @ r)
    b2 = b * b
    k0 = model.spring_rate + (model.stiffness if contact else 0.0) + (model.seat_stiffness if seat else 0.0)
    c0 = (model.damping if contact else 0.0) + (model.seat_damping if seat else 0.0)
    # the undamped roots: the phase's K~ = M^(-1/2) K M^(-1/2) is tridiagonal
    K, _ = model.phase_matrices(contact, seat)
    mh = 1.0 / np.sqrt(M)
    om2 = eigh_tridiagonal(np.diag(K) * mh * mh, np.diag(K, 1) * mh[:-1] * mh[1:], eigvals_only=True)
    if not np.all(om2 > 0.0):
        return None
    om = np.sqrt(om2)
    # first-order damping shift of each undamped mode xi0 = (1, eta0): -xi0'C xi0 / (2 xi0'M xi0)
    # (eta0_k = om^2 b_k / (w_k^2 - om^2), real); a root right at a coil mode takes its damping
    with np.errstate(divide="ignore", invalid="ignore"):
        eta0 = (om * om)[:, None] * b[None, :] / ((w * w)[None, :] - (om * om)[:, None])
        shift = -(c0 + (cw[None, :] * eta0 * eta0).sum(axis=1)) / (
            2.0 * (ms + 2.0 * eta0 @ b + (eta0 * eta0).sum(axis=1)))
    near = np.argmin(np.abs(om[:, None] - w[None, :]), axis=1)
    shift = np.where(np.isfinite(shift), shift, p.real[near])
    lam = shift + 1j * om
    # Aberth's iteration for the n roots in the upper half plane (their conjugates are the other n):
    # Newton's correction N = P/P' of each, repelled from the others' (all 2n) approximations
    # (compiled: chain_kernels.aberth; the same formulas as _local's)
    from .chain_kernels import aberth  # numba: compiled kernels load on first use

    lam = np.ascontiguousarray(lam)
    if aberth(lam, p, b2, ms, c0, k0, MAX_ITERATIONS) > MAX_ITERATIONS:
        return None
    nearest = np.argmin(np.abs(lam[:, None] - p[None, :]), axis=1)
    g, dg, _, size, D = _local(lam, ms, c0, k0, b2, p, nearest)
    # a root to within what rounding lam moves g by (its terms' size and its slope times lam's rounding)
    if not (np.all(np.isfinite(lam)) and np.all(np.abs(g) <= 1e-10 * (size + np.abs(dg * lam)))):
        return None
    if not np.all(lam.imag > 1e-6 * np.abs(lam)):  # an overdamped pair: not a conjugate pair
        return None
    gap = np.abs(lam[:, None] - lam[None, :]) + np.diag(np.full(n, np.inf))
    if not np.all(gap >= 1e-9 * np.maximum(np.abs(lam)[:, None], np.abs(lam)[None, :])):
        return None
    # eigenvectors (s = 1: eta_k = -lambda^2 b_k / d_k) and the rows of the inverse, in xi = (s, eta)
    L = lam[:, None]
    eta = -(L * L) * b[None, :] / D  # (n roots, N)
    Mx_s = ms + eta @ b  # (M xi)_s
    Mx_e = b[None, :] + eta  # (M xi)_eta
    a = 2.0 * lam * (Mx_s + eta @ b + (eta * eta).sum(axis=1)) + c0 + (cw[None, :] * eta * eta).sum(axis=1)
    rho_s = (c0 + lam * Mx_s) / a
    rho_e = (cw[None, :] * eta + L * Mx_e) / a[:, None]
    sig_s = Mx_s / a
    sig_e = Mx_e / a[:, None]
    # back to x = (s, u): columns x = (1, r + Phi eta); rows through R^(-1)
    # (Phi real: the products of the real and imaginary parts, half the work of complex ones)
    X = np.empty((n, n), dtype=complex)
    X[0] = 1.0
    X[1:] = r[:, None] + _real_times(Phi, eta.T)
    phys_u = np.empty((2 * n, n), dtype=complex)
    phys_u[:n] = X
    phys_u[n:] = X * lam[None, :]
    inv_u = np.empty((n, 2 * n), dtype=complex)
    inv_u[:, 0] = rho_s - rho_e @ b
    inv_u[:, 1:n] = me * _real_times(rho_e, Phi.T, left=False)
    inv_u[:, n] = sig_s - sig_e @ b
    inv_u[:, n + 1:] = me * _real_times(sig_e, Phi.T, left=False)
    # scale each mode to a largest component of 1 (the inverse's row by the inverse factor)
    scale = np.max(np.abs(phys_u), axis=0)
    phys_u /= scale[None, :]
    inv_u *= scale[:, None]
    # the conjugate pairs interleaved, as numpy's eig returns them
    lam_full = np.empty(2 * n, dtype=complex)
    lam_full[0::2], lam_full[1::2] = lam, lam.conj()
    phys = np.empty((2 * n, 2 * n), dtype=complex)
    phys[:, 0::2], phys[:, 1::2] = phys_u, phys_u.conj()
    inv = np.empty((2 * n, 2 * n), dtype=complex)
    inv[0::2], inv[1::2] = inv_u, inv_u.conj()
    return lam_full, phys, inv
