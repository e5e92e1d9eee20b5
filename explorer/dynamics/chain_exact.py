"""The exact solver of piecewise-linear models: the spring chain (chain.py, through ChainPhases)
and the valve train of parts with its lash adjuster (train.py), any PhaseSystem
(phase_system.py): each phase's linear ODE solved in closed form through the eigen-decomposition
of its state matrix.

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

Events (separation, re-contact, lift-off and seat -- the seat's force falling to 0, the lift
falling through 0 or the seat's force turning positive below it --, coil clash; with friction the
valve's velocity reaching 0 and the held valve's release) are zero crossings of functions
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
from .chain_modes import chain_phase_modes
from .model import Drive, DynamicsSolution
from .phase_system import Event, PhaseModes, Transition, decompose, held_modes, reduce_pairs, state_matrix
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


def _decompose(M: np.ndarray, K: np.ndarray, C: np.ndarray):
    """(lam, phys, inv) of the chain's phase (phase_system.decompose without first-order states)."""
    return decompose(M, K, C)


# from this many coil elements on, a moving phase is decomposed from the chain's structure
# (chain_modes.py: O(n^2)) rather than by the dense eig (O(n^3)); below it the dense one, which is
# as fast there (measured: 8 elements 0.3 vs 0.6 ms, 16: 0.5 vs 1.5 ms, 64: 14-24 vs 2 ms per phase type)
STRUCTURED_FROM = 24


def phase_modes(model: ChainModel, contact: bool, seat: bool, mode: int = 1) -> PhaseModes:
    """The phase type's state matrix and its decomposition. mode +1/-1: the valve moves (its
    friction -mode R in the forcing). mode 0: the valve is held by friction at its height s*
    (v = 0) while the coils move: s and v are states of eigenvalue 0, the coils' motion about
    their static shape with the valve at s* is decomposed as the chain with both ends held."""
    n = model.n
    M = model.masses
    K, C = model.phase_matrices(contact, seat)
    key = (contact, seat, mode)
    if mode != 0:
        A = state_matrix(M, K, C)
        B = np.zeros((2 * n, 3))
        structured = chain_phase_modes(model, contact, seat) if model.elements >= STRUCTURED_FROM else None
        lam, phys, inv = structured if structured is not None else _decompose(M, K, C)
        B[n:] = model.forcing_vectors(contact, float(mode)) / M[:, None]
        return PhaseModes(key, lam, phys, inv, inv @ B, A, B, mode)
    # held valve: its forcing acts on the valve's rows only, which are held (B = 0)
    return held_modes(key, M, K, C, np.zeros((2 * n, 3)), 0)


class ChainPhases:
    """The spring-chain model (chain.py) as a PhaseSystem (phase_system.py): phase types
    (linkage loaded, seat engaged, valve mode), keyed (contact, seat, mode)."""

    def __init__(self, model: ChainModel):
        self.model = model
        self.n = model.n
        self.size = 2 * model.n
        self.velocity_index = model.n
        # a long chain: half the modes (conjugate pairs) and the outputs' rows only (a short one
        # keeps the arithmetic its results were made with: golden scenes)
        self.reduce_pairs = model.elements >= STRUCTURED_FROM

    def phase_modes(self, key) -> PhaseModes:
        return phase_modes(self.model, *key)

    def event_functions(self, key) -> list[Event]:
        m, n = self.model, self.n
        contact, seat, mode = key
        ev = []
        e_s = np.zeros(2 * n)
        e_s[0] = 1.0
        e_v = np.zeros(2 * n)
        e_v[n] = 1.0
        if contact:  # linkage force k (S - lash - s) + c (S' - v) falls to 0
            ev.append(Event("separation", -m.stiffness * e_s - m.damping * e_v, m.stiffness, m.damping,
                            -m.stiffness * m.lash, -1.0))
        else:  # the gap S - lash - s closes
            ev.append(Event("re-contact", -e_s, 1.0, 0.0, -m.lash, +1.0, guard=True))
        if mode == 0:
            # held by friction: released when the net force leaves the band [-R, R] (the seat's
            # state cannot change while the valve stands)
            coef, alpha, beta, const = m.net_force_row(contact, seat)
            ev.append(Event("release", coef, alpha, beta, const - m.friction, +1.0, index=+1))
            ev.append(Event("release", coef, alpha, beta, const + m.friction, -1.0, index=-1))
        else:
            ev.extend(seat_events(m, 2 * n, n, seat))
        if mode != 0 and m.friction > 0.0:  # the velocity reaches 0: the valve sticks or turns
            ev.append(Event("velocity-zero", -mode * e_v, 0.0, 0.0, 0.0, +1.0))
        if math.isfinite(m.clash_compression):
            for j in range(n):  # element j: x_j - x_(j+1) reaches the clash compression
                c = np.zeros(2 * n)
                c[j] = 1.0
                if j + 1 < n:
                    c[j + 1] = -1.0
                ev.append(Event("coil-clash", c, 0.0, 0.0, -m.clash_compression, +1.0, index=j, grouped=True))
        return ev

    def apply_event(self, key, e: Event, y: np.ndarray, S: float, S1: float) -> Transition:
        kind = e.kind
        contact, seat, mode = key
        if kind == "seat-force":
            if not seat_closes(y):
                return Transition(None, key, y)
            kind = "seat"
        if kind == "velocity-zero":
            kind, mode = stick_or_turn(self.model, y, S, S1, contact, seat)
            y[self.n] = 0.0  # (a rounding away from 0)
        elif kind == "release":
            mode = e.index
        item = {"kind": kind}
        if kind in ("seat", "lift-off"):  # the impact speed; the speed the valve leaves with
            item["velocity_m_s"] = float(y[self.n])
        if kind == "coil-clash":
            item["element"] = e.index
        contact = {"separation": False, "re-contact": True}.get(kind, contact)
        seat = {"lift-off": False, "seat": True}.get(kind, seat)
        # the valve starts from v = 0 with an acceleration that may be a rounding of 0 (the net
        # force has just left the band): its velocity-zero function waits until the valve has
        # moved in its direction, or a rounding would read as a stop at once
        disarm = ("velocity-zero",) if kind in ("release", "turn") else ()
        return Transition(item, (contact, seat, mode), y, disarm)

    def start_state(self, drive, t0: float):
        x0, v0, key = start_state(self.model, drive, t0)
        return np.concatenate([x0, v0]), key

    def outputs(self, t, y, keys, codes, events, stats, matrices, D):
        return chain_outputs(self.model, None, t, y, codes, events, stats, matrices, D=D, keys=keys,
                             rows_only=self.reduce_pairs)


@dataclass(frozen=True)
class _PhaseData:
    """What the compiled loops need of one phase type, as contiguous arrays (built once)."""
    modes: PhaseModes
    events: tuple
    mB: np.ndarray  # (3, N) complex: modal forcing per unit S, S', 1
    rows: np.ndarray  # (E, N) complex: event function e = Re(rows[e] . z) + ...
    absrows: np.ndarray  # (E, N)
    absmB: np.ndarray  # (2, N): |mB| of S and S' (the bound of the forcing's second derivative)
    ev: np.ndarray  # (4, E): alpha, beta, const, sign of each event function
    W: np.ndarray  # (6, G, N) complex: hh k! phi_(k+1)(lambda hh) per group of equal steps
    E0: np.ndarray  # (G, N) complex: e^(lambda hh)
    gs: int  # the grouped functions (certified together) are those from gs on
    colmax: np.ndarray  # (N,): max over the grouped functions of |rows[e, i]|


class PhaseSolver:
    """The event loop over the steps of the output grid for any PhaseSystem (phase_system.py):
    the spring chain (ChainPhases) and the valve train (train.TrainModel)."""

    def __init__(self, system, drive, t: np.ndarray, max_events: int = 10_000):
        self.system, self.drive, self.max_events = system, drive, max_events
        self._modes: dict = {}
        self._data: dict = {}
        self._build_grid(drive, t)
        self.events: list[dict] = []
        self.keys: list = []  # the phase types met, numbered in that order (key_nodes holds the numbers)
        self._codes: dict = {}

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
    def modes(self, key) -> PhaseModes:
        md = self._modes.get(key)
        if md is None:
            md = self.system.phase_modes(key)
            if getattr(self.system, "reduce_pairs", False):
                md = reduce_pairs(md)
            self._modes[key] = md
        return md

    def data(self, key) -> _PhaseData:
        """The phase type's arrays for the compiled loops (once per phase type and run)."""
        pd = self._data.get(key)
        if pd is None:
            md = self.modes(key)
            events = tuple(self.system.event_functions(key))
            rows = np.ascontiguousarray(np.array([e.coef @ md.phys for e in events]))  # (E, N)
            ev = np.array([[getattr(e, f) for e in events] for f in ("alpha", "beta", "const", "sign")])
            F = phi_functions(md.lam[None, :] * self.h_group[:, None])  # (7, G, N)
            W = np.ascontiguousarray(F[1:] * (self.h_group[None, :, None] * FACT[:6, None, None]))
            mB = np.ascontiguousarray(md.mB.T)
            grouped = [e.grouped for e in events]
            gs = grouped.index(True) if any(grouped) else len(events)
            if not all(grouped[gs:]) or any(e.alpha or e.beta for e in events[gs:]):
                raise ValueError("grouped event functions must come last and depend on the state alone")
            absrows = np.abs(rows)
            colmax = absrows[gs:].max(axis=0) if gs < len(events) else np.zeros(md.lam.size)
            pd = self._data[key] = _PhaseData(md, events, mB, rows, absrows, np.abs(mB[:2]), ev, W,
                                              np.ascontiguousarray(F[0]), gs, np.ascontiguousarray(colmax))
        return pd

    def code(self, key) -> int:
        c = self._codes.get(key)
        if c is None:
            c = self._codes[key] = len(self.keys)
            self.keys.append(key)
        return c

    # ------------------------------------------------------------------ events
    @staticmethod
    def _forcing(pd: _PhaseData, z) -> np.ndarray:
        """The modal forcing of this phase from the state z: the phase type's, with each free
        group's velocity V as the constant forcing of its position X (X' = V; V is constant
        while the phase lasts, so any state of it gives the same)."""
        if not pd.modes.rigid:
            return pd.mB
        mB = pd.mB.copy()
        for a, b in pd.modes.rigid:
            mB[2, a] = z[b]
        return mB

    def _arm(self, pd: _PhaseData, z, j: int, u: float, previous=None) -> np.ndarray:
        """An event function is armed while it is on the near side of its crossing; right after
        an event its value is a rounding away from 0 and moving out: not armed until it has
        come back (a value within rounding counts by its slope)."""
        if j >= self.h.size:
            return np.ones(len(pd.events), bool)
        out = np.empty(len(pd.events), bool)
        kernels.arm(pd.modes.lam, self._forcing(pd, z), pd.rows, pd.ev, z, self.PT[j], float(self.h[j]), u,
                    _NONE if previous is None else previous, out)
        return out

    def _search(self, pd: _PhaseData, armed, z, j: int, u0: float):
        """The first crossing of an armed function in (u0, 1] of step j: (u, index) or None."""
        u, i = kernels.search_step(pd.modes.lam, self._forcing(pd, z), pd.rows, pd.absrows, pd.absmB, pd.ev, armed, z,
                                   self.PT[j], float(self.h[j]), float(self.S2b[j]), float(self.S3b[j]),
                                   float(self.nodes[j]), u0, 1.0)
        return None if i < 0 else (u, i)

    # ------------------------------------------------------------------ the run
    def run(self, y0: np.ndarray, key) -> None:
        nodes, h = self.nodes, self.h
        steps = h.size
        self.z_nodes = np.empty((nodes.size, self.system.size), dtype=complex)
        self.key_nodes = np.empty(nodes.size, dtype=np.int16)
        pd = self.data(key)
        z = pd.modes.inv @ y0
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
                    z = kernels.advance_to(lam, self._forcing(pd, z), z, self.PT[j], u, 1.0, float(h[j]))
                    j, u = j + 1, 0.0
                    self._store(j, z, key)
                    armed = self._arm(pd, z, j, 0.0, previous=armed)
                    continue
                key, z, u, armed = self._apply(hit, pd, key, j, z, u)
                continue
            # step on while every step is certified free of events (the compiled recurrence)
            done, zend = kernels.scan(j, z, steps, lam, self._forcing(pd, z), pd.rows, pd.absrows, pd.absmB, pd.ev,
                                      pd.W, pd.E0,
                                      self.group, self.P, h, self.S2b, self.S3b, self.z_nodes, armed, pd.gs,
                                      pd.colmax)
            if done:
                self.key_nodes[j + 1:j + done + 1] = self.code(key)
                j += done
                z = self.z_nodes[j, :lam.size]
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
        self.z_nodes[i, :z.size] = z
        self.key_nodes[i] = self.code(key)

    def _apply(self, hit, pd: _PhaseData, key, j, z0, u0):
        """The event `hit` = (u, function index) in step j (state z0 at u0): record it, switch
        the phase, and return (phase, modal state, u, armed flags)."""
        u, i = hit
        e = pd.events[i]
        hj = float(self.h[j])
        z = kernels.advance_to(pd.modes.lam, self._forcing(pd, z0), z0, self.PT[j], u0, u, hj)
        y = (pd.modes.phys @ z).real
        S, S1, _, _ = kernels.drive_at(self.PT[j], hj, u)
        tr = self.system.apply_event(key, e, y, S, S1)
        if tr.record is not None:
            item = {"kind": tr.record["kind"], "time_s": float(self.nodes[j]) + u * hj}
            item.update((k, v) for k, v in tr.record.items() if k != "kind")
            self.events.append(item)
            if len(self.events) > self.max_events:
                raise RuntimeError(f"more than {self.max_events} events in one run")
        new = tr.key
        if new == key:  # a clash: that function waits until it has come back
            armed = self._arm(pd, z, j, u)
            armed[i] = False
            return key, z, u, armed
        pd_new = self.data(new)
        z = pd_new.modes.inv @ tr.y
        if tr.disarm:
            armed = self._arm(pd_new, z, j, u)
            armed[[e.kind in tr.disarm for e in pd_new.events]] = False
            return new, z, u, armed
        return new, z, u, None


ChainSolver = PhaseSolver  # (its name when it ran the spring chain only)


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


def seat_events(model: ChainModel, size: int, n: int, seat: bool) -> list[Event]:
    """The elastic seat's event functions for a moving valve (lift s = y[0], velocity v = y[n], a
    state of `size`), as the train's one-sided joints open and close (train.py): the seat carries
    F = -k_seat s - c_seat v only while F >= 0 (it cannot pull).
    Engaged: "lift-off" where F falls to 0 -- below s = 0 (s = -c v / k) when the valve leaves
    with a damped seat; for an undamped one F = -k s falls to 0 where s rises through 0, and the
    function is the lift row itself (the arithmetic the undamped seat's results were made with).
    Open: "seat" where s falls through 0, and with damping "seat-force" where the force it would
    carry turns positive: the valve released below its seat (s < 0) and slowing down closes it
    again there, before it could turn round below s = 0 and fly through it (seat_closes: above the
    seat that crossing is the damper's pull on a valve still in the air, and nothing happens). Both
    are guards: the scipy reference restarts at their turning points (the apex; the force's least
    value), or a hop or a dip of F below 0 shorter than its step (a valve released at 8 mm/s is
    back on its seat 1.4 us later) would go unseen."""
    e_s = np.zeros(size)
    e_s[0] = 1.0
    k, c = model.seat_stiffness, model.seat_damping
    if c > 0.0:
        force = np.zeros(size)
        force[0], force[n] = -k, -c
    if seat:
        if c > 0.0:
            return [Event("lift-off", force, 0.0, 0.0, 0.0, -1.0)]
        return [Event("lift-off", e_s, 0.0, 0.0, 0.0, +1.0)]
    ev = [Event("seat", e_s, 0.0, 0.0, 0.0, -1.0, guard=True)]
    if c > 0.0:
        ev.append(Event("seat-force", force, 0.0, 0.0, 0.0, +1.0, guard=True))
    return ev


def seat_closes(y: np.ndarray) -> bool:
    """At a "seat-force" crossing (the open seat's force -k s - c v turning positive): True where
    the valve is on or below its seat (s <= 0: the seat closes with F = 0), False above it (the
    gap is open: no contact)."""
    return bool(y[0] <= 0.0)


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


def valve_derivatives(y, codes, keys, modes, D, row: int, rows_only: bool = False):
    """(y', y'') of state row `row` (a velocity: the acceleration and the jerk) from the phase ODE,
    y' = A y + B u, y'' = A y' + B u' (u = [S, S', 1]). rows_only: from A's row and A^2's row
    alone, O(N T) (long chains); else the whole y' (the arithmetic the short chain's results
    were made with)."""
    if not rows_only:
        yd = np.empty_like(y)
        ydd = np.empty_like(y)
    acc = np.empty(y.shape[1])
    jerk = np.empty(y.shape[1])
    for code in np.unique(codes).tolist():
        idx = codes == code
        A, B = modes(keys[code])
        u = np.array([D[0, idx], D[1, idx], np.ones(int(idx.sum()))])
        u1 = np.array([D[1, idx], D[2, idx], np.zeros(int(idx.sum()))])
        if rows_only:
            a_row, b_row = A[row], B[row]
            acc[idx] = a_row @ y[:, idx] + b_row @ u
            jerk[idx] = (a_row @ A) @ y[:, idx] + (a_row @ B) @ u + b_row @ u1
        else:
            yd[:, idx] = A @ y[:, idx] + B @ u
            ydd[:, idx] = A @ yd[:, idx] + B @ u1
    if not rows_only:
        return yd[row], ydd[row]
    return acc, jerk


def chain_outputs(model: ChainModel, drive, t: np.ndarray, y: np.ndarray, codes: np.ndarray, events, stats,
                  modes, D: np.ndarray | None = None, keys=KEYS, rows_only: bool = False) -> ChainSolution:
    """The solution's columns from the physical states y (2n, T) and the phase of each sample,
    keys[codes[i]] (default: key_code's numbering); modes(key) -> (A, B); D: the drive (3+, T)
    at t when the caller has it; rows_only: valve_derivatives'."""
    n = model.n
    if D is None:
        D = np.asarray(drive(t), dtype=float)
    codes = np.asarray(codes)
    table = np.array([[k[0], k[1], k[2] == 0] for k in keys], dtype=bool).reshape(-1, 3)
    contact, seat, held = table[codes, 0], table[codes, 1], table[codes, 2]
    acc, jerk = valve_derivatives(y, codes, keys, modes, D, n, rows_only)
    s, v = y[0], y[n]
    force = np.where(contact, model.stiffness * (D[0] - model.lash - s) + model.damping * (D[1] - v), 0.0)
    force = np.maximum(force, 0.0)
    # PHASE_CODES of the massless model: seated, contact, flight, stuck (held above the seat)
    phase = np.where(seat, 0, np.where(held, 3, np.where(contact, 1, 2)))
    seat_force = np.where(seat, -model.seat_stiffness * s - model.seat_damping * v, 0.0)
    return ChainSolution(
        t=t, s=s, v=v, a=acc, linkage_force=force, contact=contact, events=tuple(events), stats=stats,
        jerk=jerk, phase=phase, coils=y[1:n], coil_velocities=y[n + 1:],
        retainer_force=model.retainer_force(y[:n], y[n:]), seat_force=seat_force,
    )


def as_system(model):
    """The PhaseSystem of a model: a ChainModel wrapped (ChainPhases), any other taken as it is."""
    return ChainPhases(model) if isinstance(model, ChainModel) else model


def run_states(system, drive, t: np.ndarray, y0: np.ndarray, key, max_events: int = 10_000):
    """Run the solver: (solver, physical states (N, T) at t, the phase code of each sample)."""
    solver = PhaseSolver(system, drive, t, max_events=max_events)
    solver.run(np.asarray(y0, float), key)
    out = solver.is_out
    zs = solver.z_nodes[out]
    codes = solver.key_nodes[out]
    if getattr(system, "reduce_pairs", False):
        # Re(phys z) as one real product of the modal states' (re, im) pairs (a view of the
        # complex array) with [Re phys', -Im phys'] interleaved: half the arithmetic of the complex
        # product; phase by phase over the nodes (a phase's nodes follow each other: no copies)
        zf = solver.z_nodes.view(np.float64)
        every = solver.key_nodes
        yT = np.empty((every.size, system.size))
        mats: dict = {}
        cuts = np.flatnonzero(np.diff(every)) + 1
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, every.size]):
            code = int(every[a])
            P = mats.get(code)
            if P is None:
                phys = solver.modes(solver.keys[code]).phys
                P = mats[code] = np.empty((2 * phys.shape[1], system.size))
                P[0::2] = phys.real.T
                P[1::2] = -phys.imag.T
            np.matmul(zf[a:b, :P.shape[0]], P, out=yT[a:b])
        return solver, (yT if bool(np.all(out)) else yT[out]).T, codes
    y = np.empty((system.size, zs.shape[0]))
    for code in np.unique(codes).tolist():
        idx = codes == code
        y[:, idx] = (solver.modes(solver.keys[code]).phys @ zs[idx].T).real
    return solver, y, codes


def solve(model, drive, t: np.ndarray, initial_state=None, max_events: int = 10_000):
    """The model (a ChainModel, or a PhaseSystem such as train.TrainModel) over the times t, from
    rest in static equilibrium at t[0], or from initial_state: (x0, v0, key) for the chain,
    (y0, key) for a PhaseSystem."""
    t = np.asarray(t, dtype=float)
    system = as_system(model)
    if initial_state is None:
        y0, key = system.start_state(drive, float(t[0]))
    elif isinstance(model, ChainModel):
        x0, v0, key = initial_state
        y0 = np.concatenate([np.asarray(x0, float), np.asarray(v0, float)])
    else:
        y0, key = initial_state
    solver, y, codes = run_states(system, drive, t, y0, key, max_events)
    out = solver.is_out
    stats = {"steps": int(solver.h.size), "events": len(solver.events), "phase_types": len(solver._modes)}
    return system.outputs(t, y, solver.keys, codes, solver.events, stats,
                          lambda key: (solver.modes(key).A, solver.modes(key).B), solver.D_nodes[:, out])


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
    # the long chains' root finder (chain_modes.py), on a one-mode problem
    kernels.aberth(np.array([1j]), np.array([2j]), np.array([0.1]), 1.0, 0.1, 1.0, 4)
    return [e["kind"] for e in sol.events]


if __name__ == "__main__":
    print(f"chain kernels ready ({len(warm())} events in the warm-up run)")
