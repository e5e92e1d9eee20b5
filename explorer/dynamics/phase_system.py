"""What the piecewise-exact solver of linear phases (chain_exact.py) needs of a model: its
phase types, each a linear ODE with constant coefficients, their decompositions, their event
functions and what happens at each event.

A model that the solver takes is a PhaseSystem (the Protocol below, numbered contract). Two
implement it: the valve with its spring as a chain of masses (chain.py, through
chain_exact.ChainPhases) and the valve train of lumped masses with one-sided contacts and a
hydraulic lash adjuster (train.py). The state is y = [x, x', w]: n displacements of the lumped
masses, their velocities and r first-order states (a chamber's pressure); a phase type is
    M x'' + C x' + K x + H w = F [S, S', 1]          (n rows)
    Cap w'                    = H' x' - G w + F_w [S, S', 1]   (r rows)
with M diagonal and positive, K symmetric positive definite, C and G symmetric positive
semi-definite and Cap diagonal positive (a chamber's V / bulk modulus): the mechanical part a
mass-spring-damper system, the first-order part a compressible volume whose pressure w pushes on
the masses through H and whose volume the masses' velocities change through H' (the same H: the
power p A v is exchanged without loss), with leaks G. In the energy coordinates
    Y = [K~^(1/2) q, q', Cap^(1/2) w],   q = M^(1/2) x,   K~ = M^(-1/2) K M^(-1/2)
the undamped, leak-free part of the state matrix is skew-symmetric, so its eigenvectors are
orthogonal and the decomposition is well conditioned however stiff a seat or an oil column is
(decompose()).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np


@dataclass(frozen=True)
class PhaseModes:
    """A phase type's state matrix and its eigen-decomposition: y' = A y + B [S, S', 1];
    y = Re(phys @ z), z = inv @ y, z_i' = lam_i z_i + (mB @ [S, S', 1])_i."""

    key: Any
    lam: np.ndarray  # (N,) eigenvalues
    phys: np.ndarray  # (N, N)
    inv: np.ndarray  # (N, N)
    mB: np.ndarray  # (N, 3): modal forcing per unit S, S', 1
    A: np.ndarray  # (N, N) physical state matrix
    B: np.ndarray  # (N, 3)
    mode: int = 1  # the valve moving up (+1), down (-1), or held by friction (0)
    # (X, V) mode indices of each group of masses flying free (decompose_free): X' = V, V' = 0
    rigid: tuple = ()


class Event:
    """An event function g = coef . y + alpha S + beta S' + const, crossing in direction sign
    (+1 up, -1 down); index tells functions of one kind apart (a contact, a coil element, the
    direction of a release). grouped: a function of the state alone (alpha = beta = 0) that the
    solver may certify together with the other grouped ones (coil clashes: one bound for all);
    the grouped functions of a phase come last. guard: a re-engagement (a seat, a contact closing)
    whose short excursions the scipy reference splits at its turning points (chain_reference.py)."""

    def __init__(self, kind: str, coef: np.ndarray, alpha: float, beta: float, const: float, sign: float,
                 index: int = -1, grouped: bool = False, guard: bool = False):
        self.kind, self.coef, self.alpha, self.beta, self.const = kind, coef, alpha, beta, const
        self.sign, self.index, self.grouped, self.guard = sign, index, grouped, guard


@dataclass(frozen=True)
class Transition:
    """What an event does (PhaseSystem.apply_event): the record of the event (kind, and what
    else it reports; None: a crossing that changes nothing and is not an event, such as a
    contact's force turning positive while its gap is open), the phase type after it, the state after it (the same but for a rounding
    put right, such as a velocity set to 0 where it was reached), and the kinds of functions of
    the new phase that wait until they have come back to their near side (they sit on their zero)."""

    record: dict | None
    key: Any
    y: np.ndarray
    disarm: tuple[str, ...] = ()


class PhaseSystem(Protocol):
    """The contract of a model that chain_exact's solver runs (and chain_reference's scipy run):
    1. `size`: the state's length N = 2 n + r; `velocity_index`: the row of y whose velocity a
       seat event reports (the valve's).
    2. `phase_modes(key) -> PhaseModes`: the phase type's A, B and eigen-decomposition; the same
       arrays for the same key (the solver caches them per run).
    3. `event_functions(key) -> list[Event]`: the phase's event functions, grouped ones last.
    4. `apply_event(key, event, y, S, S1) -> Transition` at an event of `event`'s kind.
    5. `start_state(drive, t0) -> (y0, key)`: at rest in static equilibrium with the drive at t0.
    6. `outputs(t, y, keys, codes, events, stats, matrices, D)`: the solution's columns from the
       physical states y (N, T) and each sample's phase (keys[codes[i]]); matrices(key) -> (A, B).
    7. optional `reduce_pairs` (bool): the solver carries one mode of each conjugate pair
       (reduce_pairs() below) and projects the states with real products.
    Keys are hashable; the solver numbers them in the order it meets them."""

    size: int
    velocity_index: int

    def phase_modes(self, key) -> PhaseModes: ...

    def event_functions(self, key) -> list[Event]: ...

    def apply_event(self, key, event: Event, y: np.ndarray, S: float, S1: float) -> Transition: ...

    def start_state(self, drive, t0: float) -> tuple[np.ndarray, Any]: ...

    def outputs(self, t, y, keys, codes, events, stats, matrices, D): ...


def decompose(M: np.ndarray, K: np.ndarray, C: np.ndarray, H: np.ndarray | None = None,
              cap: np.ndarray | None = None, G: np.ndarray | None = None):
    """(lam, phys, inv) of y' = A y (y = [x, x', w], M x'' + C x' + K x + H w = 0,
    cap w' = H' x' - G w; K positive definite) in the energy coordinates
    Y = [K~^(1/2) q, q', cap^(1/2) w] (q = M^(1/2) x), where the undamped, leak-free A is
    skew-symmetric and its eigenvectors orthogonal: y = phys @ z, z = inv @ y. Without
    first-order states (H None) the valve-and-spring chain's decomposition as it always was."""
    n = M.size
    mh, ms = 1.0 / np.sqrt(M), np.sqrt(M)
    Kt = mh[:, None] * K * mh[None, :]
    Ct = mh[:, None] * C * mh[None, :]
    w2, Q = np.linalg.eigh(0.5 * (Kt + Kt.T))
    w = np.sqrt(w2)
    Sq = (Q * w) @ Q.T
    Sqi = (Q / w) @ Q.T
    if H is None or H.shape[1] == 0:
        AY = np.block([[np.zeros((n, n)), Sq], [-Sq, -Ct]])
        lam, V = np.linalg.eig(AY)
        Vi = np.linalg.inv(V)
        T = np.zeros((2 * n, 2 * n))
        T[:n, :n] = mh[:, None] * Sqi
        T[n:, n:] = np.diag(mh)
        Ti = np.zeros((2 * n, 2 * n))
        Ti[:n, :n] = Sq * ms[None, :]
        Ti[n:, n:] = np.diag(ms)
        # a purely imaginary pair must not drift into the right half plane by rounding
        lam = np.where(lam.real > 0.0, 1j * lam.imag, lam)
        return lam, T @ V, Vi @ Ti
    r = H.shape[1]
    ch, cs = 1.0 / np.sqrt(cap), np.sqrt(cap)
    Hc = mh[:, None] * H * ch[None, :]
    Gt = ch[:, None] * G * ch[None, :]
    N = 2 * n + r
    AY = np.zeros((N, N))
    AY[:n, n:2 * n] = Sq
    AY[n:2 * n, :n] = -Sq
    AY[n:2 * n, n:2 * n] = -Ct
    AY[n:2 * n, 2 * n:] = -Hc
    AY[2 * n:, n:2 * n] = Hc.T
    AY[2 * n:, 2 * n:] = -Gt
    lam, V = np.linalg.eig(AY)
    Vi = np.linalg.inv(V)
    T = np.zeros((N, N))
    T[:n, :n] = mh[:, None] * Sqi
    T[n:2 * n, n:2 * n] = np.diag(mh)
    T[2 * n:, 2 * n:] = np.diag(ch)
    Ti = np.zeros((N, N))
    Ti[:n, :n] = Sq * ms[None, :]
    Ti[n:2 * n, n:2 * n] = np.diag(ms)
    Ti[2 * n:, 2 * n:] = np.diag(cs)
    lam = np.where(lam.real > 0.0, 1j * lam.imag, lam)
    return lam, T @ V, Vi @ Ti


def decompose_free(M, K, C, H=None, cap=None, G=None, groups=()):
    """decompose() of a phase in which groups of masses fly free (no spring, damper or drive ties
    them to the rest: K phi = C phi = 0 for phi = 1 on the group, H' phi = 0), returning
    (lam, phys, inv, rigid): each group's rigid-body motion is a double eigenvalue 0 with a
    Jordan block (X' = V, V' = 0: nothing acts on the group as a whole), which no eigenvector
    basis holds. It is decomposed with each group held by a spring kappa (M phi)(M phi)' of
    frequency below every other (it changes that mode alone: the others are M-orthogonal to phi),
    and that pair of modes is then replaced by the exact ones, the group's position X and velocity
    V (lambda = 0; columns [phi; 0], [0; phi]; rows phi' M / (phi' M phi) on x and on x'). rigid:
    the (X, V) mode indices of each group; the solver adds V as X's constant forcing in each
    phase it enters (chain_exact: X(t) = X0 + V t exactly)."""
    if not groups:
        lam, phys, inv = decompose(M, K, C, H, cap, G)
        return lam, phys, inv, ()
    n = M.size
    mh = 1.0 / np.sqrt(M)
    free = np.ones(n, bool)
    for g in groups:
        free[np.asarray(g)] = False
    Kt = mh[:, None] * K * mh[None, :]
    w2 = np.linalg.eigvalsh(0.5 * (Kt + Kt.T))
    floor = float(np.min(w2[w2 > 1e-9 * np.max(w2)]))
    Kr = K.copy()
    phis = []
    for i, g in enumerate(groups):
        phi = np.zeros(n)
        phi[np.asarray(g)] = 1.0
        Mphi = M * phi
        mg = float(phi @ Mphi)
        w2g = floor * 0.37 / (i + 1)  # below every other mode, distinct for each group
        Kr = Kr + (w2g / mg) * np.outer(Mphi, Mphi)
        phis.append((phi, Mphi, mg))
    lam, phys, inv = decompose(M, Kr, C, H, cap, G)
    lam = lam.copy()
    phys = phys.copy()
    inv = inv.copy()
    rigid = []
    taken: set = set()
    for phi, Mphi, mg in phis:
        share = np.abs(Mphi @ phys[:n]) / np.max(np.abs(phys), axis=0)
        share[list(taken)] = -1.0
        a, b = np.argsort(share)[-2:]
        taken.update((a, b))
        lam[a] = lam[b] = 0.0
        phys[:, a] = 0.0
        phys[:, b] = 0.0
        phys[:n, a] = phi
        phys[n:2 * n, b] = phi
        inv[a] = 0.0
        inv[b] = 0.0
        inv[a, :n] = Mphi / mg
        inv[b, n:2 * n] = Mphi / mg
        rigid.append((int(a), int(b)))
    # the other modes exactly free of the rigid ones (they are, to the rounding of the temporary
    # spring's modes): their rows annihilate the rigid columns, their columns the rigid rows
    R = np.array([i for pair in rigid for i in pair])
    O = np.setdiff1d(np.arange(lam.size), R)
    inv[O] -= (inv[O] @ phys[:, R]) @ inv[R]
    phys[:, O] -= phys[:, R] @ (inv[R] @ phys[:, O])
    return lam, phys, inv, tuple(rigid)


def state_matrix(M, K, C, H=None, cap=None, G=None) -> np.ndarray:
    """A of y' = A y + B u for y = [x, x', w] (the physical state matrix)."""
    n = M.size
    if H is None or H.shape[1] == 0:
        return np.block([[np.zeros((n, n)), np.eye(n)], [-K / M[:, None], -C / M[:, None]]])
    r = H.shape[1]
    N = 2 * n + r
    A = np.zeros((N, N))
    A[:n, n:2 * n] = np.eye(n)
    A[n:2 * n, :n] = -K / M[:, None]
    A[n:2 * n, n:2 * n] = -C / M[:, None]
    A[n:2 * n, 2 * n:] = -H / M[:, None]
    A[2 * n:, n:2 * n] = H.T / cap[:, None]
    A[2 * n:, 2 * n:] = -G / cap[:, None]
    return A


def held_modes(key, M, K, C, B: np.ndarray, held: int, H=None, cap=None, G=None, groups=()) -> PhaseModes:
    """The phase with mass `held` held at rest (a valve stuck by friction): its position and
    velocity rows are 0 (it stays where it is, v = 0); the other masses move about their static
    shape with it there, u = G_s s + w, K_rr G_s = -K_r,held, and w (with the first-order states)
    is the system without the held mass. B: the forcing of the free phase; its held rows are
    dropped."""
    n = M.size
    r = 0 if H is None else H.shape[1]
    N = 2 * n + r
    A = state_matrix(M, K, C, H, cap, G)
    A[held] = 0.0
    A[n + held] = 0.0
    A[:, n + held] = 0.0  # v = 0: its damping couplings do not act
    Bh = B.copy()
    Bh[held] = 0.0
    Bh[n + held] = 0.0
    rest = np.array([i for i in range(n) if i != held], dtype=int)
    m = rest.size
    # the rows of y that the rest's decomposition covers: its positions, velocities, first-order states
    rows = np.r_[rest, n + rest, 2 * n + np.arange(r)]
    lam = np.zeros(N, dtype=complex)
    phys = np.zeros((N, N), dtype=complex)
    inv = np.zeros((N, N), dtype=complex)
    k = 2 * m + r
    rigid: tuple = ()
    if k:
        Hr = None if H is None else H[rest]
        where = {int(i): j for j, i in enumerate(rest)}  # index in the rest of each free mass
        lc, pc, ic, rg = decompose_free(M[rest], K[np.ix_(rest, rest)], C[np.ix_(rest, rest)], Hr, cap, G,
                                        [[where[int(i)] for i in g] for g in groups])
        rigid = rg
        Gs = -np.linalg.solve(K[np.ix_(rest, rest)], K[rest, held])
        lam[:k] = lc
        phys[np.ix_(rows, np.arange(k))] = pc
        inv[np.ix_(np.arange(k), rows)] = ic
        phys[rest, k] = Gs  # the rest's positions follow the held mass's through their static shape
        inv[:k, held] = -ic[:, :m] @ Gs
    phys[held, k] = phys[n + held, k + 1] = 1.0
    inv[k, held] = inv[k + 1, n + held] = 1.0
    mB = inv @ Bh if np.any(Bh) else np.zeros((N, 3), dtype=complex)
    for a, b in rigid:
        mB[a] = mB[b] = 0.0
    return PhaseModes(key, lam, phys, inv, mB, A, Bh, 0, rigid)


def reduce_pairs(md: PhaseModes) -> PhaseModes:
    """The same phase carried by half its modes: a real state's complex modes come in conjugate
    pairs (lambda, conj lambda) whose modal states stay conjugate, so y = Re(phys z) = Re(2 phys_i
    z_i) over one of each pair (plus the real modes once). The solver then steps, bounds and
    searches half as many modes; the event rows and bounds made from the doubled columns are the
    same sums. Unchanged (md itself) when the eigenvalues are not in exact conjugate pairs."""
    lam = md.lam
    upper = np.flatnonzero(lam.imag > 0.0)
    lower = np.flatnonzero(lam.imag < 0.0)
    real = np.flatnonzero(lam.imag == 0.0)
    if upper.size != lower.size:
        return md
    order_u = upper[np.lexsort((lam[upper].real, lam[upper].imag))]
    order_l = lower[np.lexsort((lam[lower].real, -lam[lower].imag))]
    if not np.array_equal(lam[order_u], lam[order_l].conj()):
        return md
    keep = np.concatenate([order_u, real])
    factor = np.concatenate([np.full(order_u.size, 2.0), np.ones(real.size)])
    where = {int(i): j for j, i in enumerate(keep)}
    rigid = tuple((where[a], where[b]) for a, b in md.rigid)
    return PhaseModes(md.key, lam[keep], md.phys[:, keep] * factor[None, :], md.inv[keep], md.mB[keep], md.A, md.B,
                      md.mode, rigid)
