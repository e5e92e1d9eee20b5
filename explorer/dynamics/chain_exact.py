"""The exact solver of the spring-chain model (chain.py): each phase's linear ODE solved in
closed form through the eigen-decomposition of its state matrix.

Method. A phase (linkage loaded or not, seat engaged or not) is y' = A y + B [S, S', 1] with
y = [x, x']. A is decomposed once per phase type (and speed: the model is fixed in a run) in
mass-normalised coordinates Y = [K~^(1/2) q, q'] (q = M^(1/2) x), where the undamped A is
skew-symmetric and its eigenvectors are orthogonal (well conditioned even for a 1e12 N/m seat):
y = Re(Phys z), z = Inv y, z_i' = lambda_i z_i + Gamma_i(t). Over a step of length h the drive
is the quintic Hermite polynomial through S, S', S'' at both ends (as in exact.py), so the
modal forcing is a polynomial sum_k Gamma_k u^k (u = tau/h) and the step is exact:
    z(h) = e^(lambda h) z(0) + sum_k Gamma_k h k! phi_(k+1)(lambda h)
with the phi functions of exponential integrators (series for |lambda h| < 1, their recurrence
beyond). A run of steps is the affine recurrence z_(j+1) = E_j z_j + Q_j, evaluated for a whole
window at once by a doubling scan (log2(window) passes; |E| <= 1, so no growth).

Events (separation, re-contact, lift-off, seat, coil clash) are zero crossings of functions
linear in y and the drive, g = a.y + alpha S + beta S' + g0. A step is certified free of a
crossing by bounds: g(tau) >= g(0) + g'(0) tau - M2 tau^2 / 2 from the left and the same from the
right, with M2 >= |g''| over the step from |z_i''(tau)| <= |z_i''(0)| + tau max|Gamma_i''|
(Re lambda <= 0), for all event functions of a window of steps at once. A step that is not
certified is bisected; a sign change with a certified monotone g is located by Newton's method
with the analytic slope on the closed form (started at the root of the cubic Hermite
interpolant, kept inside the bracket), to 1e-13 of the step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .chain import ChainModel, static_equilibrium
from .model import DynamicsSolution
from .series import hermite5, taylor_shift

FACT = np.array([math.factorial(k) for k in range(7)], dtype=float)
EPS = np.finfo(float).eps
WINDOW = 512  # most steps scanned at once between events
WINDOW_MIN = 16  # steps scanned at once after an event


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


def phase_modes(model: ChainModel, contact: bool, seat: bool) -> PhaseModes:
    n = model.n
    M = model.masses
    mh, ms = 1.0 / np.sqrt(M), np.sqrt(M)
    K, C = model.phase_matrices(contact, seat)
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
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K / M[:, None], -C / M[:, None]]])
    B = np.zeros((2 * n, 3))
    B[n:] = model.forcing_vectors(contact) / M[:, None]
    inv = Vi @ Ti
    # a purely imaginary pair must not drift into the right half plane by rounding
    lam = np.where(lam.real > 0.0, 1j * lam.imag, lam)
    return PhaseModes(contact, seat, lam, T @ V, inv, inv @ B, A, B)


def _sub_poly(P, a: float, b: float) -> list:
    """Coefficients of P(a + (b - a) u') in u' (P in u over its step, 0 <= a < b <= 1): a Taylor
    shift by a (synthetic division), then the scaling by (b - a)^i."""
    c = [float(x) for x in P]
    if a != 0.0:
        for i in range(5):
            for k in range(4, i - 1, -1):
                c[k] += a * c[k + 1]
    d = b - a
    if d != 1.0:
        f = 1.0
        for i in range(1, 6):
            f *= d
            c[i] *= f
    return c


class _Event:
    """g = coef . y + alpha S + beta S' + const, crossing in direction sign (+1 up, -1 down)."""

    def __init__(self, kind: str, coef: np.ndarray, alpha: float, beta: float, const: float, sign: float,
                 index: int = -1):
        self.kind, self.coef, self.alpha, self.beta, self.const = kind, coef, alpha, beta, const
        self.sign, self.index = sign, index


class ChainSolver:
    def __init__(self, model: ChainModel, drive, t: np.ndarray, max_events: int = 10_000):
        self.model, self.drive, self.max_events = model, drive, max_events
        self._modes: dict = {}
        self._tables: dict = {}
        self._ev_cache: dict = {}
        self._ev_funcs: dict = {}
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

    def _drive_poly_at(self, P: np.ndarray, hh: float, u: float) -> tuple[float, float, float, float]:
        """S, S', S'', S''' of the step polynomial at u."""
        S = S1 = S2 = S3 = 0.0
        for k in range(5, -1, -1):
            S = S * u + P[k]
        for k in range(5, 0, -1):
            S1 = S1 * u + k * P[k]
        for k in range(5, 1, -1):
            S2 = S2 * u + k * (k - 1) * P[k]
        for k in range(5, 2, -1):
            S3 = S3 * u + k * (k - 1) * (k - 2) * P[k]
        return S, S1 / hh, S2 / hh**2, S3 / hh**3

    # ------------------------------------------------------------------ phases
    def modes(self, key: tuple[bool, bool]) -> PhaseModes:
        md = self._modes.get(key)
        if md is None:
            md = self._modes[key] = phase_modes(self.model, *key)
        return md

    def tables(self, key):
        """(W (6, G, 2n), E (G, 2n)) of the phase type for each group of equal step lengths:
        z_(j+1) = E z_j + sum_k Gamma_jk W_k (once per phase type; window_tables applies them)."""
        tb = self._tables.get(key)
        if tb is None:
            md = self.modes(key)
            F = phi_functions(md.lam[None, :] * self.h_group[:, None])  # (7, G, 2n)
            W = F[1:] * (self.h_group[None, :, None] * FACT[:6, None, None])
            W = np.ascontiguousarray(W)
            tb = self._tables[key] = (W, W.real.copy(), W.imag.copy(), np.ascontiguousarray(F[0]))
        return tb

    def window_tables(self, key, j: int, L: int):
        """(E, Q) (L, 2n) of the steps j .. j+L-1 in the phase type."""
        md = self.modes(key)
        W, Wr, Wi, E0 = self.tables(key)
        P = self.P[:, j:j + L]
        h = self.h[j:j + L]
        D = np.zeros_like(P)
        D[:5] = np.arange(1, 6)[:, None] * P[1:] / h
        groups = self.group[j:j + L]
        g0 = int(groups[0])
        E = np.empty((L, md.lam.size), dtype=complex)
        Q = np.empty((L, md.lam.size), dtype=complex)
        uniform = bool(np.all(groups == g0))
        for g in ([g0] if uniform else np.unique(groups).tolist()):
            idx = slice(None) if uniform else (groups == g)
            PT = np.ascontiguousarray(P[:, idx].T)
            DT = np.ascontiguousarray(D[:, idx].T)
            # real drive coefficients times complex tables, as two real products (numpy's mixed
            # real-complex matmul takes a slow path)
            qp = (PT @ Wr[:, g]) + 1j * (PT @ Wi[:, g])
            qd = (DT @ Wr[:, g]) + 1j * (DT @ Wi[:, g])
            Q[idx] = qp * md.mB[:, 0] + qd * md.mB[:, 1] + W[0, g] * md.mB[:, 2]
            E[idx] = E0[g]
        return E, Q

    def advance(self, md: PhaseModes, z0: np.ndarray, Pc, hh: float) -> np.ndarray:
        """Modal state after hh from z0, the drive polynomial Pc (in u = tau/hh, 6 floats)."""
        if hh <= 0.0:
            return z0
        F = phi_functions(md.lam * hh)
        c = [hh * FACT[k] for k in range(6)]
        # Gamma_k = mB0 P_k + mB1 (k+1) P_(k+1) / hh + mB2 [k = 0]; z = e z0 + sum_k Gamma_k c_k phi_(k+1)
        wp = np.array([Pc[k] * c[k] for k in range(6)], dtype=complex)
        wd = np.array([(k + 1) * Pc[k + 1] / hh * c[k] for k in range(5)] + [0.0], dtype=complex)
        Fk = F[1:]
        return F[0] * z0 + md.mB[:, 0] * (wp @ Fk) + md.mB[:, 1] * (wd @ Fk) + md.mB[:, 2] * (c[0] * F[1])

    # ------------------------------------------------------------------ events
    def event_functions(self, key) -> list[_Event]:
        funcs = self._ev_funcs.get(key)
        if funcs is None:
            funcs = self._ev_funcs[key] = self._make_event_functions(key)
        return funcs

    def _make_event_functions(self, key) -> list[_Event]:
        m, n = self.model, self.n
        contact, seat = key
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
        if seat:
            ev.append(_Event("lift-off", e_s, 0.0, 0.0, 0.0, +1.0))
        else:
            ev.append(_Event("seat", e_s, 0.0, 0.0, 0.0, -1.0))
        if math.isfinite(m.clash_compression):
            for j in range(n):  # element j: x_j - x_(j+1) reaches the clash compression
                c = np.zeros(2 * n)
                c[j] = 1.0
                if j + 1 < n:
                    c[j + 1] = -1.0
                ev.append(_Event("coil-clash", c, 0.0, 0.0, -m.clash_compression, +1.0, index=j))
        return ev

    def _event_data(self, key, events):
        """(modes, rows a.Phys (E, 2n)) of the phase's event functions, once per phase type;
        their alpha, beta, const and sign as arrays in self._ev_arrays[key]."""
        cached = self._ev_cache.get(key)
        if cached is None:
            md = self.modes(key)
            rows = np.array([e.coef @ md.phys for e in events])  # (E, 2n)
            arrays = tuple(np.array([getattr(e, f) for e in events]) for f in ("alpha", "beta", "const", "sign"))
            cached = self._ev_cache[key] = (md, rows, arrays, md.mB.real.copy(), md.mB.imag.copy(), np.abs(rows),
                                            (np.abs(md.mB[:, 0]), np.abs(md.mB[:, 1])))
        return cached[0], cached[1]

    def _local(self, md, rows, events, z: np.ndarray, P: np.ndarray, hh: float, u: float):
        """g, g', |g''| at u of a step (z: modal state there): arrays over the events. Also
        z'' magnitudes for the bound."""
        S, S1, S2, S3 = self._drive_poly_at(P, hh, u)
        mB = md.mB
        gam = mB[:, 0] * S + mB[:, 1] * S1 + mB[:, 2]
        gam1 = mB[:, 0] * S1 + mB[:, 1] * S2
        gam2 = mB[:, 0] * S2 + mB[:, 1] * S3
        dz = md.lam * z + gam
        ddz = md.lam * dz + gam1
        alpha, beta, const, _ = self._ev_cache[(md.contact, md.seat)][2]
        g = (rows @ z).real + alpha * S + beta * S1 + const
        g1 = (rows @ dz).real + alpha * S1 + beta * S2
        return g, g1, np.abs(ddz), gam2

    def _bound2(self, md, rows, events, ddz_abs, hh: float, j: int):
        """M2 >= |g''| over a (sub)step of length hh from its start's |z''|."""
        alpha = np.abs([e.alpha for e in events])
        beta = np.abs([e.beta for e in events])
        S2b, S3b = self.S2b[j], self.S3b[j]
        mb = np.abs(md.mB[:, 0]) * S2b + np.abs(md.mB[:, 1]) * S3b
        return np.abs(rows) @ (ddz_abs + hh * mb) + alpha * S2b + beta * S3b

    def _bound1(self, md, i, rows, events, ddz_abs, hh: float, j: int) -> float:
        """_bound2 for event function i alone."""
        e = events[i]
        S2b, S3b = float(self.S2b[j]), float(self.S3b[j])
        arow = self._ev_cache[(md.contact, md.seat)][5][i]
        mb = self._ev_cache[(md.contact, md.seat)][6]
        return float(arow @ (ddz_abs + hh * (mb[0] * S2b + mb[1] * S3b))) + abs(e.alpha) * S2b + abs(e.beta) * S3b

    @staticmethod
    def _excluded(g0, g1a, gb, g1b, M2, hh):
        """True where g keeps its sign over [0, hh] (certified by the two parabola bounds)."""
        same = (g0 * gb > 0.0)
        s = np.sign(g0)
        a0, sa, b0, sb = s * g0, s * g1a, s * gb, -s * g1b  # distance to 0 and its slope away
        M = M2 * (1.0 + 1e-9) + 1e-300
        with np.errstate(all="ignore"):
            tl = (sa + np.sqrt(sa * sa + 2.0 * M * a0)) / M
            tr = (sb + np.sqrt(sb * sb + 2.0 * M * b0)) / M
        return same & (tl + tr > hh * (1.0 + 1e-12))

    # ------------------------------------------------------------------ the run
    def run(self, x0: np.ndarray, v0: np.ndarray, key) -> None:
        nodes, h = self.nodes, self.h
        steps = h.size
        self.z_nodes = np.empty((nodes.size, 2 * self.n), dtype=complex)
        self.key_nodes = np.empty(nodes.size, dtype=np.int8)
        md = self.modes(key)
        z = md.inv @ np.concatenate([x0, v0])
        self._store(0, z, key)
        armed = None
        window = WINDOW_MIN
        j, u = 0, 0.0  # the state z is at node j + u of its step
        while j < steps:
            events = self.event_functions(key)
            md, rows = self._event_data(key, events)
            if armed is None:
                armed = self._arm(md, rows, events, z, j, u)
            if u > 0.0:  # the rest of a step after an event
                hit = self._search_step(md, rows, events, armed, z, j, u, 1.0)
                if hit is None:
                    z = self.advance(md, z, _sub_poly(self.P[:, j], u, 1.0), (1.0 - u) * h[j])
                    j, u = j + 1, 0.0
                    self._store(j, z, key)
                    armed = self._arm(md, rows, events, z, j, 0.0, previous=armed)
                    continue
                key, z, u, armed = self._apply(hit, md, events, key, j, z, u)
                continue
            # short windows right after an event (events come in clusters: seat bounces),
            # doubling while the steps stay clear
            L = min(window, steps - j)
            E, Q = self.window_tables(key, j, L)
            Z = _affine_scan(E, Q, z)  # states at nodes j+1 .. j+L
            Zall = np.vstack([z[None, :], Z])
            ok, gb, g1b = self._window_clear(md, rows, events, Zall, j, L)
            bad = (~ok).nonzero()[0]
            done = L if bad.size == 0 else int(bad[0])
            self.z_nodes[j + 1:j + done + 1] = Zall[1:done + 1]
            self.key_nodes[j + 1:j + done + 1] = key_code(key)
            if done:
                j += done
                z = Zall[done]
                # (the functions' values at the window's last clear node, from the window)
                armed = self._armed_from(md, gb[:, done - 1], g1b[:, done - 1], float(h[j - 1]), previous=armed)
            if bad.size == 0:
                window = min(2 * window, WINDOW)
                continue
            window = WINDOW_MIN
            hit = self._search_step(md, rows, events, armed, z, j, 0.0, 1.0)
            if hit is None:
                z = Zall[done + 1]
                j += 1
                self._store(j, z, key)
                armed = self._arm(md, rows, events, z, j, 0.0, previous=armed)
                continue
            key, z, u, armed = self._apply(hit, md, events, key, j, z, 0.0)

    def _store(self, i: int, z, key) -> None:
        self.z_nodes[i] = z
        self.key_nodes[i] = key_code(key)

    def _arm(self, md, rows, events, z, j, u, previous=None):
        """An event function is armed while it is on the near side of its crossing; right after
        an event its value is a rounding away from 0 and moving out: not armed until it has
        come back (a value within rounding counts by its slope)."""
        if j >= self.h.size:
            return np.ones(len(events), bool)
        g, g1, _, _ = self._local(md, rows, events, z, self.P[:, j], self.h[j], u)
        return self._armed_from(md, g, g1, float(self.h[j]), previous)

    def _armed_from(self, md, g, g1, hstep: float, previous=None):
        sign = self._ev_cache[(md.contact, md.seat)][2][3]
        sg, sg1 = sign * g, sign * g1
        scale = np.abs(g1) * hstep + 1e-300
        tiny = np.abs(g) <= 1e-9 * scale
        armed = (sg < 0.0) | (tiny & (sg1 < 0.0))
        if previous is not None:
            armed = armed | previous & (sg < 0.0)
        return armed

    def _window_clear(self, md, rows, events, Zall, j, L):
        """Per step of the window: certified free of any crossing of an armed function (and of
        the return of an unarmed one)."""
        h = self.h[j:j + L]
        # drive at the step starts and ends (from the step polynomials)
        Pw = self.P[:, j:j + L]
        k = np.arange(6)[:, None]
        S0, S10, S20 = Pw[0], Pw[1] / h, 2.0 * Pw[2] / h**2
        S1e = (k * Pw).sum(0) / h
        S2e = (k * (k - 1) * Pw).sum(0) / h**2
        Se = Pw.sum(0)
        Za, Zb = Zall[:-1], Zall[1:]
        alpha, beta, const, _ = (x[:, None] for x in self._ev_cache[(md.contact, md.seat)][2])
        lam, mB = md.lam, md.mB
        gam_a = mB[:, 0][None] * S0[:, None] + mB[:, 1][None] * S10[:, None] + mB[:, 2][None]
        gam_b = mB[:, 0][None] * Se[:, None] + mB[:, 1][None] * S1e[:, None] + mB[:, 2][None]
        gam1_a = mB[:, 0][None] * S10[:, None] + mB[:, 1][None] * S20[:, None]
        dza = lam * Za + gam_a
        dzb = lam * Zb + gam_b
        ddza = lam * dza + gam1_a
        ga = (rows @ Za.T).real + alpha * S0 + beta * S10 + const
        gb = (rows @ Zb.T).real + alpha * Se + beta * S1e + const
        g1a = (rows @ dza.T).real + alpha * S10 + beta * S20
        g1b = (rows @ dzb.T).real + alpha * S1e + beta * S2e
        S2b, S3b = self.S2b[j:j + L], self.S3b[j:j + L]
        mb = np.abs(mB[:, 0])[None] * S2b[:, None] + np.abs(mB[:, 1])[None] * S3b[:, None]
        M2 = np.abs(rows) @ (np.abs(ddza) + h[:, None] * mb).T + np.abs(alpha) * S2b + np.abs(beta) * S3b
        # a step is clear when no function can change sign in it (an unarmed one that has come
        # back is armed at the next node by _arm)
        return np.all(self._excluded(ga, g1a, gb, g1b, M2, h[None, :]), axis=0), gb, g1b

    def _search_step(self, md, rows, events, armed, z, j, u0, u1):
        """The first crossing of an armed function in (u0, u1] of step j: (u, event index) or None.
        Unarmed functions arm where they cross back."""
        hj = float(self.h[j])
        P = self.P[:, j]
        armed_local = armed.copy()

        cache = {u0: z}

        def state(u):  # the closed form at u, shared by the event functions
            zz = cache.get(u)
            if zz is None:
                zz = cache[u] = self.advance(md, z, _sub_poly(P, u0, u), (u - u0) * hj)
            return zz

        gcache = {}

        def gvals(u, zz):  # g, g', |z''| at u: all event functions at once, shared
            r = gcache.get(u)
            if r is None:
                r = gcache[u] = self._local(md, rows, events, zz, P, hj, u)
            return r

        # all functions at once over the whole interval first: only those not certified free of a
        # sign change go through the search
        ga, g1a, ddza, _ = gvals(u0, z)
        gb, g1b, _, _ = gvals(u1, state(u1))
        M2 = self._bound2(md, rows, events, ddza, (u1 - u0) * hj, j)
        free = self._excluded(ga, g1a, gb, g1b, M2, (u1 - u0) * hj)
        roots = []
        for i, e in enumerate(events):
            if free[i]:
                continue
            r = self._first_crossing(i, e, armed_local[i], u0, u1, z, state, gvals, md, rows, events, hj, j)
            if r is not None:
                roots.append((r, i))
        if not roots:
            return None
        return min(roots)

    def _first_crossing(self, i, e, armed, u0, u1, z0, state, gvals, md, rows, events, hj, j):
        """First u in (u0, u1] where event i crosses in its direction while armed."""
        stack = [(u0, z0, u1, None)]
        while stack:
            a, za, b, zb = stack.pop()
            if zb is None:
                zb = state(b)
            ga, g1a, ddza, _ = gvals(a, za)
            gb, g1b, _, _ = gvals(b, zb)
            ga, g1a, gb, g1b = ga[i] * e.sign, g1a[i] * e.sign, gb[i] * e.sign, g1b[i] * e.sign
            M2 = self._bound1(md, i, rows, events, ddza, (b - a) * hj, j)
            width = (b - a) * hj
            if not armed:
                if ga >= 0.0 and gb > 0.0 and _excluded1(ga, g1a, gb, g1b, M2, width):
                    continue
            elif ga < 0.0 and gb < 0.0 and _excluded1(ga, g1a, gb, g1b, M2, width):
                continue
            if (ga < 0.0) != (gb < 0.0) and (abs(g1a) - M2 * width > 0.0) and g1a * g1b > 0.0:
                if not armed and gb < 0.0:
                    # one monotone crossing back to the near side: armed from there on, and no
                    # crossing out again in this interval
                    armed = True
                    continue
                # one monotone crossing: locate it on the closed form, from the root of the
                # cubic Hermite interpolant of g (values and slopes at both ends)
                r = _newton_bracketed(lambda u: tuple(x[i] * e.sign for x in gvals(u, state(u))[:2]),
                                      a, b, ga, gb, hj, _hermite_root(a, b, ga, gb, g1a * hj, g1b * hj))
                if armed and gb > 0.0:
                    return r
                if not armed and gb < 0.0:
                    armed = True
                    # continue after the arming point: the rest of the interval
                    rest = min(r + 1e-15, b)
                    if rest < b:
                        stack.append((rest, state(rest), b, zb))
                    continue
                continue
            if width < 1e-15 * max(1.0, abs(float(self.nodes[j]))):
                if armed and gb > 0.0:
                    return b
                continue
            mid = 0.5 * (a + b)
            zm = state(mid)
            stack.append((mid, zm, b, zb))  # right half later
            stack.append((a, za, mid, zm))  # left half first
        return None

    def _apply(self, hit, md, events, key, j, z0, u0):
        """The event `hit` = (u, function index) in step j (state z0 at u0): record it, switch
        the phase, and return (phase, modal state, u, armed flags)."""
        u, i = hit
        e = events[i]
        hj = float(self.h[j])
        z = self.advance(md, z0, _sub_poly(self.P[:, j], u0, u), (u - u0) * hj)
        y = (md.phys @ z).real
        item = {"kind": e.kind, "time_s": float(self.nodes[j]) + u * hj}
        if e.kind == "seat":
            item["velocity_m_s"] = float(y[self.n])
        if e.kind == "coil-clash":
            item["element"] = e.index
        self.events.append(item)
        if len(self.events) > self.max_events:
            raise RuntimeError(f"more than {self.max_events} events in one run")
        contact, seat = key
        contact = {"separation": False, "re-contact": True}.get(e.kind, contact)
        seat = {"lift-off": False, "seat": True}.get(e.kind, seat)
        new = (contact, seat)
        if new == key:  # a clash: that function waits until it has come back
            armed = self._arm(md, self._event_data(key, events)[1], events, z, j, u)
            armed[i] = False
            return key, z, u, armed
        return new, self.modes(new).inv @ y, u, None


def _excluded1(g0: float, g1a: float, gb: float, g1b: float, M2: float, hh: float) -> bool:
    """ChainSolver._excluded for one function, in plain floats."""
    if not g0 * gb > 0.0:
        return False
    sgn = 1.0 if g0 > 0.0 else -1.0
    a0, sa, b0, sb = sgn * g0, sgn * g1a, sgn * gb, -sgn * g1b
    M = M2 * (1.0 + 1e-9) + 1e-300
    tl = (sa + math.sqrt(sa * sa + 2.0 * M * a0)) / M
    tr = (sb + math.sqrt(sb * sb + 2.0 * M * b0)) / M
    return tl + tr > hh * (1.0 + 1e-12)


def _hermite_root(a: float, b: float, fa: float, fb: float, da: float, db: float) -> float:
    """The root in (a, b) of the cubic through f and df/du at both ends (f(a), f(b) of opposite
    signs): a start for Newton on the closed form, within O((b - a)^4) of the root."""
    w = b - a
    # in x = (u - a) / w: p(x) = fa h00 + w da h10 + fb h01 + w db h11
    c0, c1 = fa, w * da
    c2 = 3.0 * (fb - fa) - w * (2.0 * da + db)
    c3 = 2.0 * (fa - fb) + w * (da + db)
    lo, hi = 0.0, 1.0
    x = fa / (fa - fb)
    for _ in range(8):
        p = ((c3 * x + c2) * x + c1) * x + c0
        if (p < 0.0) == (fa < 0.0):
            lo = x
        else:
            hi = x
        dp = (3.0 * c3 * x + 2.0 * c2) * x + c1
        xn = x - p / dp if dp != 0.0 else 0.5 * (lo + hi)
        if not lo < xn < hi:
            xn = 0.5 * (lo + hi)
        if abs(xn - x) < 1e-15:
            break
        x = xn
    return a + w * x


def _newton_bracketed(fg, a: float, b: float, fa: float, fb: float, h: float, start: float | None = None) -> float:
    """The root of a monotone f in [a, b] (f(a), f(b) of opposite signs): Newton steps with the
    analytic slope (f, df/dt) = fg(u), u = t/h, kept inside the shrinking bracket (bisection when
    a step leaves it), to a bracket of a few ulp."""
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    u = start if start is not None and a < start < b else a + (b - a) * fa / (fa - fb)
    for _ in range(100):
        f, df = fg(u)
        if f == 0.0:
            return u
        if (f < 0.0) == (fa < 0.0):
            a, fa = u, f
        else:
            b, fb = u, f
        if b - a <= 4.0 * EPS * max(abs(a), abs(b), 1e-300):
            break
        step = f / (df * h) if df != 0.0 else math.inf
        un = u - step
        if not a < un < b:
            un = 0.5 * (a + b)
        if abs(un - u) <= 1e-13:
            # converged: u is a fraction of the step, 1e-13 of it is far below the times' rounding
            # of events (~1e-18 s at these steps), and g's own rounding stops Newton there
            return un
        u = un
    return b if (fb > 0.0) else a


def _affine_scan(E: np.ndarray, Q: np.ndarray, z0: np.ndarray) -> np.ndarray:
    """z_(j+1) = E_j z_j + Q_j for a window (L, m): all z_1..z_L (doubling scan)."""
    A = E.copy()
    X = Q.copy()
    L = E.shape[0]
    d = 1
    while d < L:
        X[d:] = X[d:] + A[d:] * X[:-d]
        A[d:] = A[d:] * A[:-d]
        d *= 2
    return X + A * z0[None, :]


@dataclass(frozen=True)
class ChainSolution(DynamicsSolution):
    coils: np.ndarray | None = None  # (N, T) m, coil displacements u_1 (retainer side) .. u_N
    coil_velocities: np.ndarray | None = None  # (N, T) m/s
    retainer_force: np.ndarray | None = None  # N, the spring's force on the retainer (dynamic)
    seat_force: np.ndarray | None = None  # N, the seat's force on the valve (Kelvin-Voigt)


def start_state(model: ChainModel, drive, t0: float):
    """(x0, v0, phase key): at rest in static equilibrium with the drive at t0."""
    D = np.asarray(drive(np.array([t0])), dtype=float)[:, 0]
    x, contact, seat = static_equilibrium(model, float(D[0]), float(D[1]))
    return x, np.zeros_like(x), (contact, seat)


# phase types (linkage loaded, seat engaged) by their code 2 * contact + seat
KEYS = ((False, False), (False, True), (True, False), (True, True))


def key_code(key) -> int:
    return 2 * int(key[0]) + int(key[1])


def chain_outputs(model: ChainModel, drive, t: np.ndarray, y: np.ndarray, codes: np.ndarray, events, stats,
                  modes, D: np.ndarray | None = None) -> ChainSolution:
    """The solution's columns from the physical states y (2n, T) and the phase code of each
    sample (key_code); D: the drive (3+, T) at t when the caller has it."""
    n = model.n
    if D is None:
        D = np.asarray(drive(t), dtype=float)
    codes = np.asarray(codes)
    contact = codes >= 2
    seat = (codes % 2) == 1
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
    phase = np.where(seat, 0, np.where(contact, 1, 2))
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
