"""The exact solver of the spring-chain model (chain.py): each phase's linear ODE solved in
closed form through the eigen-decomposition of its state matrix.

Method. A phase (linkage loaded or not, seat engaged or not, the valve moving up or down with
its friction, or held by it) is y' = A y + B [S, S', 1] with
y = [x, x']. A is decomposed once per phase type (and speed: the model is fixed in a run) in
mass-normalised coordinates Y = [K~^(1/2) q, q'] (q = M^(1/2) x), where the undamped A is
skew-symmetric and its eigenvectors are orthogonal (well conditioned even for a 1e12 N/m seat):
y = Re(Phys z), z = Inv y, z_i' = lambda_i z_i + Gamma_i(t). Over a step of length h the drive
is the quintic Hermite polynomial through S, S', S'' at both ends (as in exact.py), so the
modal forcing is a polynomial sum_k Gamma_k u^k (u = tau/h) and the step is exact:
    z(h) = e^(lambda h) z(0) + sum_k Gamma_k h k! phi_(k+1)(lambda h)
with the phi functions of exponential integrators (series for |lambda h| < 1, their recurrence
beyond). A run of steps is the affine recurrence z_(j+1) = E_j z_j + Q_j (|E| <= 1, so no
growth), E and the phi tables once per phase type and step length.

Events (separation, re-contact, lift-off, seat, coil clash; with friction the valve's velocity
reaching 0 and the held valve's release) are zero crossings of functions
linear in y and the drive, g = a.y + alpha S + beta S' + g0. A step is certified free of a
crossing by bounds: g(tau) >= g(0) + g'(0) tau - M2 tau^2 / 2 from the left and the same from the
right, with M2 >= |g''| over the step from |z_i''(tau)| <= |z_i''(0)| + tau max|Gamma_i''|
(Re lambda <= 0), for all event functions at each step. A step that is not certified is
bisected; a sign change with a certified monotone g is located by Newton's method with the
analytic slope on the closed form (started at the root of the cubic Hermite interpolant, kept
inside the bracket), to 1e-13 of the step.

Cost. The recurrence, the certification and the event search are loops over a few dozen modes
compiled with numba (chain_kernels.py, cached on disk): the recurrence runs from one event to the
first step that is not certified, the search of that step runs whole in one call. This module
keeps the per-phase-type set-up (eigen-decomposition, phi tables, event functions) and the
events' bookkeeping in numpy and Python: a few dozen calls per revolution, not per step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import chain_kernels as kernels
from .chain import ChainModel, static_equilibrium
from .model import Drive, DynamicsSolution
from .series import hermite5, taylor_shift

FACT = np.array([math.factorial(k) for k in range(7)], dtype=float)
EPS = np.finfo(float).eps


# phi_j(x) = sum_n x^n / (n + j)!, j = 1..6, as x^n (n < 24) times this table: 1/(24+j)! < 1e-24
_PHI_SERIES = np.array([[1.0 / math.factorial(n + j) for j in range(1, 7)] for n in range(24)])


def phi_functions(x: np.ndarray) -> np.ndarray:
    """(7, *x.shape): phi_0 = e^x, phi_j(x) = sum_n x^n / (n + j)!  (complex x). Below |x| = 1
    the series (24 terms: the next is below 1e-24), beyond it the recurrence
    phi_j = (phi_(j-1) - 1/(j-1)!) / x, which loses nothing there."""
    x = np.asarray(x, dtype=complex)
    shape = x.shape
    x = x.ravel()
    out = np.empty((7, x.size), dtype=complex)
    e = out[0] = np.exp(x)
    small = np.abs(x) < 1.0
    n_small = int(np.count_nonzero(small))
    if n_small < x.size:
        xs = np.where(small, 1.0, x)
        f = e
        for j in range(1, 7):
            f = (f - _INV_FACT[j - 1]) / xs
            out[j] = f
    if n_small:
        xm = x if n_small == x.size else x[small]
        powers = np.empty((xm.size, 24), dtype=complex)
        powers[:, 0] = 1.0
        powers[:, 1:] = xm[:, None]
        np.cumprod(powers, axis=1, out=powers)
        vals = (powers @ _PHI_SERIES_C).T  # (6, m)
        if n_small == x.size:
            out[1:] = vals
        else:
            out[1:, small] = vals
    return out.reshape((7,) + shape)


_INV_FACT = [1.0 / math.factorial(k) for k in range(8)]
_PHI_SERIES_C = _PHI_SERIES.astype(complex)


@dataclass(frozen=True)
class PhaseModes:
    contact: bool
    seat: bool
    lam: np.ndarray  # (2n,) eigenvalues
    phys: np.ndarray  # (2n, 2n): y = Re(phys @ z)
    inv: np.ndarray  # (2n, 2n): z = inv @ y
    mB: np.ndarray  # (2n, 3): modal forcing per unit S, S', 1
    A: np.ndarray  # (2n, 2n) physical state matrix
    B: np.ndarray  # (2n, 3)
    mode: int = 1  # the valve moving up (+1: friction -R) or down (-1), or held by friction (0)


def _decompose(M: np.ndarray, K: np.ndarray, C: np.ndarray):
    """(lam, phys, inv) of y' = A y (y = [x, x'], M x'' + C x' + K x = 0, K positive definite) in
    mass-normalised coordinates Y = [K~^(1/2) q, q'] (q = M^(1/2) x), where the undamped A is
    skew-symmetric and its eigenvectors orthogonal: y = phys @ z, z = inv @ y."""
    n = M.size
    mh, ms = 1.0 / np.sqrt(M), np.sqrt(M)
    Kt = mh[:, None] * K * mh[None, :]
    Ct = mh[:, None] * C * mh[None, :]
    w2, Q = np.linalg.eigh(0.5 * (Kt + Kt.T))
    w = np.sqrt(w2)
    Sq = (Q * w) @ Q.T
    Sqi = (Q / w) @ Q.T
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


def phase_modes(model: ChainModel, contact: bool, seat: bool, mode: int = 1) -> PhaseModes:
    """The phase type's state matrix and its decomposition. mode +1/-1: the valve moves (its
    friction -mode R in the forcing). mode 0: the valve is held by friction at its height s*
    (v = 0) while the coils move: s and v are states of eigenvalue 0, the coils' motion about
    their static shape with the valve at s* is decomposed as the chain with both ends held."""
    n = model.n
    M = model.masses
    K, C = model.phase_matrices(contact, seat)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K / M[:, None], -C / M[:, None]]])
    B = np.zeros((2 * n, 3))
    if mode != 0:
        lam, phys, inv = _decompose(M, K, C)
        B[n:] = model.forcing_vectors(contact, float(mode)) / M[:, None]
        return PhaseModes(contact, seat, lam, phys, inv, inv @ B, A, B, mode)
    # held valve: the rows of s and v are 0 (s' = 0, v' = 0: s stays s*, v stays 0); the coils
    # u = G s + w with G the static shape (K_cc G = -K_c0), w the chain with held ends
    A[0] = 0.0
    A[n] = 0.0
    A[:, n] = 0.0  # v = 0: its damping couplings do not act (and e_v is then a mode of eigenvalue 0)
    m = n - 1
    cs = np.r_[1:n, n + 1:2 * n]  # the coils' rows of y
    z = np.zeros((2 * n, 2 * n), dtype=complex)
    phys = z.copy()
    inv = z.copy()
    lam = np.zeros(2 * n, dtype=complex)
    if m:
        lc, pc, ic = _decompose(M[1:], K[1:, 1:], C[1:, 1:])
        G = -np.linalg.solve(K[1:, 1:], K[1:, 0])
        lam[:2 * m] = lc
        phys[np.ix_(cs, np.arange(2 * m))] = pc
        inv[np.ix_(np.arange(2 * m), cs)] = ic
        # y_u = G s + w: the s column of phys adds G; z_w = ic [u - G s; u']
        phys[1:n, 2 * m] = G
        inv[:2 * m, 0] = -ic[:, :m] @ G
    phys[0, 2 * m] = phys[n, 2 * m + 1] = 1.0
    inv[2 * m, 0] = inv[2 * m + 1, n] = 1.0
    return PhaseModes(contact, seat, lam, phys, inv, np.zeros((2 * n, 3), dtype=complex), A, B, 0)


class _Event:
    """g = coef . y + alpha S + beta S' + const, crossing in direction sign (+1 up, -1 down)."""

    def __init__(self, kind: str, coef: np.ndarray, alpha: float, beta: float, const: float, sign: float,
                 index: int = -1):
        self.kind, self.coef, self.alpha, self.beta, self.const = kind, coef, alpha, beta, const
        self.sign, self.index = sign, index


@dataclass(frozen=True)
class _PhaseData:
    """What the compiled loops need of one phase type, as contiguous arrays (built once)."""
    modes: PhaseModes
    events: tuple
    mB: np.ndarray  # (3, 2n) complex: modal forcing per unit S, S', 1
    rows: np.ndarray  # (E, 2n) complex: event function e = Re(rows[e] . z) + ...
    absrows: np.ndarray  # (E, 2n)
    absmB: np.ndarray  # (2, 2n): |mB| of S and S' (the bound of the forcing's second derivative)
    ev: np.ndarray  # (4, E): alpha, beta, const, sign of each event function
    W: np.ndarray  # (6, G, 2n) complex: hh k! phi_(k+1)(lambda hh) per group of equal steps
    E0: np.ndarray  # (G, 2n) complex: e^(lambda hh)


class ChainSolver:
    def __init__(self, model: ChainModel, drive, t: np.ndarray, max_events: int = 10_000):
        self.model, self.drive, self.max_events = model, drive, max_events
        self._modes: dict = {}
        self._data: dict = {}
        self._build_grid(drive, t)
        self.events: list[dict] = []
        self.n = model.n

    # ------------------------------------------------------------------ grid and drive
    def _build_grid(self, drive, t: np.ndarray) -> None:
        t0, t1 = float(t[0]), float(t[-1])
        h0 = float(np.min(np.diff(t))) if t.size > 1 else 1.0
        tol = 1e-9 * h0
        bps = [b for b in np.asarray(drive.breakpoints(t0, t1), dtype=float).tolist() if t0 < b < t1]
        near = [b for b in bps if np.min(np.abs(t - b)) <= tol]
        new = [b for b in bps if b not in near]
        nodes = np.union1d(t, np.array(new)) if new else t.copy()
        brk = sorted({int(np.argmin(np.abs(nodes - b))) for b in bps})
        self.nodes = nodes
        self.is_out = np.ones(nodes.size, bool)
        if new:
            self.is_out[np.searchsorted(nodes, np.array(new))] = False
        h = self.h = np.diff(nodes)
        D = self.D_nodes = np.asarray(drive(nodes), dtype=float)
        right, left = D[:3].copy(), D[:3].copy()
        if brk:
            nb = np.array(brk)
            hl = np.where(nb > 0, h[np.maximum(nb - 1, 0)], np.inf)
            hr = np.where(nb < h.size, h[np.minimum(nb, h.size - 1)], np.inf)
            d = 1e-7 * np.minimum(hl, hr)
            tb = nodes[nb]
            Dr = np.asarray(drive(tb + d), dtype=float)
            Dl = np.asarray(drive(tb - d), dtype=float)
            right[:, nb] = taylor_shift(Dr, -d)[:3]
            left[:, nb] = taylor_shift(Dl, d)[:3]
        self.P = hermite5(h, right[:, :-1], left[:, 1:])  # (6, steps)
        k = np.arange(6)[:, None]
        # |S''| and |S'''| over each step, bounded by the polynomial's coefficients
        self.S2b = (k * (k - 1) * np.abs(self.P)).sum(0) / h**2
        self.S3b = (k * (k - 1) * (k - 2) * np.abs(self.P)).sum(0) / h**3
        # the compiled loops read a step's polynomial as a column: one contiguous copy per step
        self.PT = np.ascontiguousarray(self.P.T)
        # steps of (nearly) equal length share one set of phi functions: a time warp of the
        # drive by the roundings of the node times (exact.py does the same)
        tolh = max(1e-11 * float(h.max()), 8.0 * EPS * max(abs(t0), abs(t1)))
        order = np.argsort(h, kind="stable")
        hs = h[order]
        starts = np.concatenate([[0], (np.diff(hs) > tolh).nonzero()[0] + 1, [h.size]])
        self.group = np.empty(h.size, dtype=np.intp)
        means = []
        for g, (a, b) in enumerate(zip(starts[:-1], starts[1:])):
            self.group[order[a:b]] = g
            means.append(float(hs[a:b].sum()) / (b - a))
        self.h_group = np.array(means)

    # ------------------------------------------------------------------ phases
    def modes(self, key: tuple[bool, bool, int]) -> PhaseModes:
        md = self._modes.get(key)
        if md is None:
            md = self._modes[key] = phase_modes(self.model, *key)
        return md

    def data(self, key) -> _PhaseData:
        """The phase type's arrays for the compiled loops (once per phase type and run)."""
        pd = self._data.get(key)
        if pd is None:
            md = self.modes(key)
            events = tuple(self._make_event_functions(key))
            rows = np.ascontiguousarray(np.array([e.coef @ md.phys for e in events]))  # (E, 2n)
            ev = np.array([[getattr(e, f) for e in events] for f in ("alpha", "beta", "const", "sign")])
            F = phi_functions(md.lam[None, :] * self.h_group[:, None])  # (7, G, 2n)
            W = np.ascontiguousarray(F[1:] * (self.h_group[None, :, None] * FACT[:6, None, None]))
            mB = np.ascontiguousarray(md.mB.T)
            pd = self._data[key] = _PhaseData(md, events, mB, rows, np.abs(rows), np.abs(mB[:2]), ev, W,
                                              np.ascontiguousarray(F[0]))
        return pd

    # ------------------------------------------------------------------ events
    def _make_event_functions(self, key) -> list[_Event]:
        m, n = self.model, self.n
        contact, seat, mode = key
        ev = []
        e_s = np.zeros(2 * n)
        e_s[0] = 1.0
        e_v = np.zeros(2 * n)
        e_v[n] = 1.0
        if contact:  # linkage force k (S - lash - s) + c (S' - v) falls to 0
            ev.append(_Event("separation", -m.stiffness * e_s - m.damping * e_v, m.stiffness, m.damping,
                             -m.stiffness * m.lash, -1.0))
        else:  # the gap S - lash - s closes
            ev.append(_Event("re-contact", -e_s, 1.0, 0.0, -m.lash, +1.0))
        if mode == 0:
            # held by friction: released when the net force leaves the band [-R, R] (the seat's
            # state cannot change while the valve stands)
            coef, alpha, beta, const = m.net_force_row(contact, seat)
            ev.append(_Event("release", coef, alpha, beta, const - m.friction, +1.0, index=+1))
            ev.append(_Event("release", coef, alpha, beta, const + m.friction, -1.0, index=-1))
        elif seat:
            ev.append(_Event("lift-off", e_s, 0.0, 0.0, 0.0, +1.0))
        else:
            ev.append(_Event("seat", e_s, 0.0, 0.0, 0.0, -1.0))
        if mode != 0 and m.friction > 0.0:  # the velocity reaches 0: the valve sticks or turns
            ev.append(_Event("velocity-zero", -mode * e_v, 0.0, 0.0, 0.0, +1.0))
        if math.isfinite(m.clash_compression):
            for j in range(n):  # element j: x_j - x_(j+1) reaches the clash compression
                c = np.zeros(2 * n)
                c[j] = 1.0
                if j + 1 < n:
                    c[j + 1] = -1.0
                ev.append(_Event("coil-clash", c, 0.0, 0.0, -m.clash_compression, +1.0, index=j))
        return ev

    def _arm(self, pd: _PhaseData, z, j: int, u: float, previous=None) -> np.ndarray:
        """An event function is armed while it is on the near side of its crossing; right after
        an event its value is a rounding away from 0 and moving out: not armed until it has
        come back (a value within rounding counts by its slope)."""
        if j >= self.h.size:
            return np.ones(len(pd.events), bool)
        out = np.empty(len(pd.events), bool)
        kernels.arm(pd.modes.lam, pd.mB, pd.rows, pd.ev, z, self.PT[j], float(self.h[j]), u,
                    _NONE if previous is None else previous, out)
        return out

    def _search(self, pd: _PhaseData, armed, z, j: int, u0: float):
        """The first crossing of an armed function in (u0, 1] of step j: (u, index) or None."""
        u, i = kernels.search_step(pd.modes.lam, pd.mB, pd.rows, pd.absrows, pd.absmB, pd.ev, armed, z, self.PT[j],
                                   float(self.h[j]), float(self.S2b[j]), float(self.S3b[j]), float(self.nodes[j]),
                                   u0, 1.0)
        return None if i < 0 else (u, i)

    # ------------------------------------------------------------------ the run
    def run(self, x0: np.ndarray, v0: np.ndarray, key) -> None:
        nodes, h = self.nodes, self.h
        steps = h.size
        self.z_nodes = np.empty((nodes.size, 2 * self.n), dtype=complex)
        self.key_nodes = np.empty(nodes.size, dtype=np.int8)
        pd = self.data(key)
        z = pd.modes.inv @ np.concatenate([x0, v0])
        self._store(0, z, key)
        armed = None
        j, u = 0, 0.0  # the state z is at node j + u of its step
        while j < steps:
            pd = self.data(key)
            lam = pd.modes.lam
            if armed is None:
                armed = self._arm(pd, z, j, u)
            if u > 0.0:  # the rest of a step after an event
                hit = self._search(pd, armed, z, j, u)
                if hit is None:
                    z = kernels.advance_to(lam, pd.mB, z, self.PT[j], u, 1.0, float(h[j]))
                    j, u = j + 1, 0.0
                    self._store(j, z, key)
                    armed = self._arm(pd, z, j, 0.0, previous=armed)
                    continue
                key, z, u, armed = self._apply(hit, pd, key, j, z, u)
                continue
            # step on while every step is certified free of events (the compiled recurrence)
            done, zend = kernels.scan(j, z, steps, lam, pd.mB, pd.rows, pd.absrows, pd.absmB, pd.ev, pd.W, pd.E0,
                                      self.group, self.P, h, self.S2b, self.S3b, self.z_nodes, armed)
            if done:
                self.key_nodes[j + 1:j + done + 1] = key_code(key)
                j += done
                z = self.z_nodes[j]
            if j >= steps:
                break
            hit = self._search(pd, armed, z, j, 0.0)
            if hit is None:
                z = zend
                j += 1
                self._store(j, z, key)
                armed = self._arm(pd, z, j, 0.0, previous=armed)
                continue
            key, z, u, armed = self._apply(hit, pd, key, j, z, 0.0)

    def _store(self, i: int, z, key) -> None:
        self.z_nodes[i] = z
        self.key_nodes[i] = key_code(key)

    def _apply(self, hit, pd: _PhaseData, key, j, z0, u0):
        """The event `hit` = (u, function index) in step j (state z0 at u0): record it, switch
        the phase, and return (phase, modal state, u, armed flags)."""
        u, i = hit
        e = pd.events[i]
        hj = float(self.h[j])
        z = kernels.advance_to(pd.modes.lam, pd.mB, z0, self.PT[j], u0, u, hj)
        y = (pd.modes.phys @ z).real
        kind = e.kind
        contact, seat, mode = key
        if kind == "velocity-zero":
            S, S1, _, _ = kernels.drive_at(self.PT[j], hj, u)
            kind, mode = stick_or_turn(self.model, y, S, S1, contact, seat)
            y[self.n] = 0.0  # (a rounding away from 0)
        elif kind == "release":
            mode = e.index
        item = {"kind": kind, "time_s": float(self.nodes[j]) + u * hj}
        if kind == "seat":
            item["velocity_m_s"] = float(y[self.n])
        if kind == "coil-clash":
            item["element"] = e.index
        self.events.append(item)
        if len(self.events) > self.max_events:
            raise RuntimeError(f"more than {self.max_events} events in one run")
        contact = {"separation": False, "re-contact": True}.get(kind, contact)
        seat = {"lift-off": False, "seat": True}.get(kind, seat)
        new = (contact, seat, mode)
        if new == key:  # a clash: that function waits until it has come back
            armed = self._arm(pd, z, j, u)
            armed[i] = False
            return key, z, u, armed
        pd_new = self.data(new)
        z = pd_new.modes.inv @ y
        if kind in ("release", "turn"):
            # the valve starts from v = 0 with an acceleration that may be a rounding of 0 (the net
            # force has just left the band): its velocity-zero function waits until the valve has
            # moved in its direction, or a rounding would read as a stop at once
            armed = self._arm(pd_new, z, j, u)
            armed[[e.kind == "velocity-zero" for e in pd_new.events]] = False
            return new, z, u, armed
        return new, z, u, None


_NONE = np.zeros(0, bool)  # "no previous flags" for the compiled arm

@dataclass(frozen=True)
class ChainSolution(DynamicsSolution):
    coils: np.ndarray | None = None  # (N, T) m, coil displacements u_1 (retainer side) .. u_N
    coil_velocities: np.ndarray | None = None  # (N, T) m/s
    retainer_force: np.ndarray | None = None  # N, the spring's force on the retainer (dynamic)
    seat_force: np.ndarray | None = None  # N, the seat's force on the valve (Kelvin-Voigt)


def start_state(model: ChainModel, drive, t0: float):
    """(x0, v0, phase key): at rest in static equilibrium with the drive at t0 (with friction
    held there: the net force, 0, is within the band)."""
    D = np.asarray(drive(np.array([t0])), dtype=float)[:, 0]
    x, contact, seat = static_equilibrium(model, float(D[0]), float(D[1]))
    return x, np.zeros_like(x), (contact, seat, 0 if model.friction > 0.0 else 1)


def stick_or_turn(model: ChainModel, y: np.ndarray, S: float, S1: float, contact: bool, seat: bool):
    """The valve's velocity has reached 0 (with friction R): ("stick", 0) when the net force is
    within [-R, R], else ("turn", its sign), as phases.velocity_zero for the massless valve."""
    coef, alpha, beta, const = model.net_force_row(contact, seat)
    yy = y.copy()
    yy[model.n] = 0.0
    net = float(coef @ yy) + alpha * S + beta * S1 + const
    if abs(net) <= model.friction:
        return "stick", 0
    return "turn", (1 if net > 0.0 else -1)


# phase types (linkage loaded, seat engaged, valve mode) by their code: 2 * contact + seat +
# 4 * (0 moving up or without friction, 1 moving down, 2 held by friction)
MODE_INDEX = {1: 0, -1: 1, 0: 2}
KEYS = tuple((c, s, m) for m in (1, -1, 0) for c in (False, True) for s in (False, True))


def key_code(key) -> int:
    return 2 * int(key[0]) + int(key[1]) + 4 * MODE_INDEX[key[2]]


def chain_outputs(model: ChainModel, drive, t: np.ndarray, y: np.ndarray, codes: np.ndarray, events, stats,
                  modes, D: np.ndarray | None = None) -> ChainSolution:
    """The solution's columns from the physical states y (2n, T) and the phase code of each
    sample (key_code); D: the drive (3+, T) at t when the caller has it."""
    n = model.n
    if D is None:
        D = np.asarray(drive(t), dtype=float)
    codes = np.asarray(codes)
    contact = (codes % 4) >= 2
    seat = (codes % 2) == 1
    held = codes >= 8
    yd = np.empty_like(y)
    ydd = np.empty_like(y)
    for code in np.unique(codes).tolist():
        idx = codes == code
        A, B = modes(KEYS[code])
        u = np.array([D[0, idx], D[1, idx], np.ones(int(idx.sum()))])
        u1 = np.array([D[1, idx], D[2, idx], np.zeros(int(idx.sum()))])
        yd[:, idx] = A @ y[:, idx] + B @ u
        ydd[:, idx] = A @ yd[:, idx] + B @ u1
    s, v = y[0], y[n]
    force = np.where(contact, model.stiffness * (D[0] - model.lash - s) + model.damping * (D[1] - v), 0.0)
    force = np.maximum(force, 0.0)
    # PHASE_CODES of the massless model: seated, contact, flight, stuck (held above the seat)
    phase = np.where(seat, 0, np.where(held, 3, np.where(contact, 1, 2)))
    seat_force = np.where(seat, -model.seat_stiffness * s - model.seat_damping * v, 0.0)
    return ChainSolution(
        t=t, s=s, v=v, a=yd[n], linkage_force=force, contact=contact, events=tuple(events), stats=stats,
        jerk=ydd[n], phase=phase, coils=y[1:n], coil_velocities=y[n + 1:],
        retainer_force=model.retainer_force(y[:n], y[n:]), seat_force=seat_force,
    )


def solve(model: ChainModel, drive, t: np.ndarray, initial_state=None, max_events: int = 10_000) -> ChainSolution:
    """The chain model over the times t, from rest in static equilibrium at t[0] (or from
    initial_state = (x0, v0, (contact, seat)))."""
    t = np.asarray(t, dtype=float)
    solver = ChainSolver(model, drive, t, max_events=max_events)
    x0, v0, key = initial_state if initial_state is not None else start_state(model, drive, float(t[0]))
    solver.run(np.asarray(x0, float), np.asarray(v0, float), key)
    out = solver.is_out
    zs = solver.z_nodes[out]
    codes = solver.key_nodes[out]
    y = np.empty((2 * model.n, zs.shape[0]))
    for code in np.unique(codes).tolist():
        idx = codes == code
        y[:, idx] = (solver.modes(KEYS[code]).phys @ zs[idx].T).real
    stats = {"steps": int(solver.h.size), "events": len(solver.events), "phase_types": len(solver._modes)}
    return chain_outputs(model, drive, t, y, codes, solver.events, stats,
                         lambda key: (solver.modes(key).A, solver.modes(key).B), D=solver.D_nodes[:, out])


class _CosineLift:
    """L(theta) = a (1 - cos theta): a smooth lift for warm(), no joints."""

    def __init__(self, a: float):
        self.a = a

    def derivatives(self, theta):
        c, s = np.cos(theta), np.sin(theta)
        return np.stack([self.a * (1.0 - c), self.a * s, self.a * c, -self.a * s])

    def breakpoints(self):
        return np.zeros(0)


def warm() -> int:
    """Compile (or load from numba's disk cache) every kernel the solver calls: one revolution of
    a 2-element chain with lift-off, seat, separation and a coil clash. For the install step
    (`python -c "from explorer.dynamics.chain_exact import warm; warm()"`), so that the first run
    does not pay numba's compilation (~10 s). Returns the kinds of its events."""
    model = ChainModel(valve_mass=0.08, spring_mass=0.04, elements=2, spring_rate=30e3, preload=200.0,
                       stiffness=3e6, seat_stiffness=2e8, damping=8.0, seat_damping=400.0, damping_ratio=0.02,
                       clash_compression=2e-3)
    omega = 600.0
    sol = solve(model, Drive(_CosineLift(4e-3), 1.0, omega), np.linspace(0.0, 2.0 * math.pi / omega, 721))
    return [e["kind"] for e in sol.events]


if __name__ == "__main__":
    print(f"chain kernels ready ({len(warm())} events in the warm-up run)")
