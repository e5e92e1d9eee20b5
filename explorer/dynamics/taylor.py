"""`taylor` solver: Taylor-series stepping of the elastic linkage with a stiffness k(t).

The exact solver (exact.py) needs constant coefficients. With a stiffness that changes along the
cycle the contact equation
    M1 s'' + c s' + (k(t) + rate) s = k(t) (S(t) - lash) + c S'(t) - F0,   F0 = preload + closing + R sign(v)
still has polynomial coefficients once, over each step, the drive S is replaced by the quintic
Hermite polynomial through S, S', S'' at both ends and k by the quintic through k, k' at both ends
and the midpoint (both from the analytic drive and profile; one-sided values at the drive's
breakpoints, which are step ends). Its Taylor series in u = tau/h (h the step, a[n] = s^(n) h^n / n!) then follows exactly from
    M1 (n+2)(n+1) a[n+2] + c h (n+1) a[n+1] + h^2 (sum_j K_j a[n-j] + rate a[n]) = h^2 f[n],
    f = coefficients of k(u) (S(u) - lash) + c S'(u) - F0   (S'(u) = dS/du / h),
K_j the coefficients of k(u). Steps are at most 0.5 / rho long (rho = sqrt((kmax + rate) / M1)),
so the series converges like 0.5^n / n!: ~20 terms reach 1e-19 of the lift. The only
approximation is the interpolation of S and k, O(h^6) both (a cubic through k, k' at the ends only,
O(h^4), dominated the error on the manufactured test case: 3e-10 m at rho h = 0.5). Flight (M s'' = -W) is the same recurrence with
k = c = 0 and mass M; a valve at rest (seated, or stuck by friction) keeps s.

Events are roots of polynomials (the truncated series and the drive's Hermite polynomials), per
step: lift-off, separation, re-contact (with damping: where min(gap, k gap + c (S' - v)) rises
through 0), seat (rebound v -> -e v; Zeno chatter summed as in exact.py), velocity zero with
friction (flip or stick). A step's event function is sampled at 16 points; an interval whose ends
do not bracket a root is cleared only by the bound min(end values) - d^2/8 sup|e''| >= 0 (sup from
the coefficients), else it is subdivided; the first bracket is narrowed by bisection on the sign to
the first representable instant past the zero, so the next phase starts on its own side. The
events fire a hair (`band`, 64 eps of the lift scale) beyond their surfaces, as in reference.py.

Everything is plain-float Python over the steps (numpy only for the grid and the output).
"""

from __future__ import annotations

import math

import numpy as np

from .model import DynamicsSolution, LinkageModel
from .phases import (AFTER_CROSSING, CONTACT, FLIGHT, SEATED, STUCK, moving_events, phase_of_state, release_from_rest,
                     rest_events, rest_force, seat_rebound, seat_speed, velocity_zero)
from .series import hermite5, horner
from .tabulated import node_values

EPS = float(np.finfo(float).eps)
MAX_RHO_H = 0.5
MAX_TERMS = 40
SAMPLES = 16
MAX_DEPTH = 5  # subdivision levels of an interval the bound cannot clear (16 * 8^5 points per step)
MAX_SAME_TIME = 60


def _hermite_matrix() -> np.ndarray:
    """Inverse of the map from the coefficients of a quintic in u to (p, p') at u = 0, 1/2, 1."""
    rows = []
    for u in (0.0, 0.5, 1.0):
        rows.append([u**n for n in range(6)])
        rows.append([n * u ** (n - 1) if n else 0.0 for n in range(6)])
    return np.linalg.inv(np.array(rows))


_K_INVERSE = _hermite_matrix()


def _shift(c, u0: float, scale: float) -> list:
    """Coefficients in w of p(u0 + scale w), p given by its coefficients c in u."""
    n = len(c)
    d = list(c)
    if u0 != 0.0:  # Taylor shift (repeated synthetic division)
        for i in range(n - 1):
            for k in range(n - 2, i - 1, -1):
                d[k] += u0 * d[k + 1]
    if scale != 1.0:
        f = 1.0
        for k in range(n):
            d[k] *= f
            f *= scale
    return d


def _deriv(c) -> list:
    return [k * c[k] for k in range(1, len(c))] or [0.0]


def _mul(p, q, n_max: int) -> list:
    out = [0.0] * min(len(p) + len(q) - 1, n_max)
    for i, pi in enumerate(p):
        if pi == 0.0 or i >= n_max:
            continue
        for j in range(min(len(q), n_max - i)):
            out[i + j] += pi * q[j]
    return out


def _add(p, q, alpha: float = 1.0, beta: float = 1.0) -> list:
    n = max(len(p), len(q))
    return [(alpha * p[i] if i < len(p) else 0.0) + (beta * q[i] if i < len(q) else 0.0) for i in range(n)]


def _curv(c) -> float:
    """sup over [0, 1] of |p''| (w-scale), bounded by the coefficients."""
    acc = 0  # (a loop, not sum() of a generator: a third of the time, the same additions in order)
    for k in range(2, len(c)):
        acc += k * (k - 1) * abs(c[k])
    return acc


class _Event:
    """Fires where all components (polynomials in w) are negative: g = max(components) < 0."""

    __slots__ = ("kind", "polys", "curv")

    def __init__(self, kind: str, polys):
        self.kind = kind
        self.polys = polys
        self.curv = [_curv(p) for p in polys]

    def value(self, w: float) -> float:
        return max(horner(p, w) for p in self.polys)

    def values(self, w: float) -> list:
        return [horner(p, w) for p in self.polys]


def _first_negative(ev: _Event, w_hi: float = 1.0):
    """Earliest w in [0, w_hi] with ev.value(w) < 0 (the first representable one), or None."""
    if w_hi == 1.0:
        # cheap whole-step clearances of a component: p(w) >= p0 + sum of its negative terms on
        # [0, 1] (w^n in [0, 1]), and p >= min(p(0), p(1)) - sup|p''| / 8
        for p, m in zip(ev.polys, ev.curv):
            if p[0] + sum(x for x in p[1:] if x < 0.0) >= 0.0:
                return None
            if min(p[0], math.fsum(p)) - m / 8.0 >= 0.0:
                return None
    vals0 = ev.values(0.0)
    if max(vals0) < 0.0:
        return 0.0
    pts = [w_hi * i / SAMPLES for i in range(SAMPLES + 1)]
    return _scan(ev, pts, [vals0] + [ev.values(w) for w in pts[1:]], 0)


def _scan(ev: _Event, pts, vals, depth: int):
    for i in range(len(pts) - 1):
        a, b = pts[i], pts[i + 1]
        vb = vals[i + 1]
        if max(vb) < 0.0:
            return _bisect(ev, a, b)
        d2 = (b - a) ** 2 / 8.0
        va = vals[i]
        if any(min(x, y) - d2 * m >= 0.0 for x, y, m in zip(va, vb, ev.curv)):
            continue  # a component stays >= 0 on [a, b]: no root there
        if depth >= MAX_DEPTH:
            continue
        sub = [a + (b - a) * k / 8.0 for k in range(9)]
        sub[-1] = b
        hit = _scan(ev, sub, [va] + [ev.values(w) for w in sub[1:-1]] + [vb], depth + 1)
        if hit is not None:
            return hit
    return None


def _bisect(ev: _Event, lo: float, hi: float) -> float:
    """value(lo) >= 0 > value(hi): the first representable w with value < 0 (bisection on the
    sign, ~55 halvings: robust for the max of several polynomials, and events are few)."""
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if ev.value(mid) < 0.0:
            hi = mid
        else:
            lo = mid
    return hi



class _Solver:
    def __init__(self, model: LinkageModel, drive, t: np.ndarray, initial_state, zeno_height: float, max_events: int,
                 max_rho_h: float = MAX_RHO_H):
        self.max_rho_h = max_rho_h
        self.model = model
        self.c, self.lash = model.damping, model.lash
        self.rate, self.R = model.spring_rate, model.friction
        self.M, self.M1 = model.mass, model.oscillating_mass
        self.e = model.restitution
        self.W0 = model.seated_resistance
        self.zeno_height = zeno_height
        self.max_events = max_events
        self.initial_state = initial_state
        self._plans: dict = {}  # event rules per phase and friction sign (int keys), or per rest height
        profile = model.stiffness_profile
        self.kmax = model.stiffness if profile is None else max(model.stiffness, profile.bounds()[1])
        alpha = 0.5 * self.c / self.M1
        w2 = (self.kmax + self.rate) / self.M1
        self.wn = math.sqrt(w2)
        rho = alpha + math.sqrt(alpha * alpha - w2) if alpha * alpha > w2 else math.sqrt(w2)
        rho = max(rho, math.sqrt(self.rate / self.M))
        self._grid(drive, profile, t, rho)
        scale = float(np.abs(np.asarray(self.Dn[0])).max()) + abs(self.lash) + 1e-3
        self.band = 64 * EPS * scale
        self.tiny = 1e-21 * scale
        self.events: list[dict] = []
        nn = len(self.nodes)
        self.out_s = [0.0] * nn
        self.out_v = [0.0] * nn
        self.out_sigma = [1.0] * nn
        self.out_phase = [SEATED] * nn
        self.stats = {"method": "taylor", "nodes": nn, "steps": nn - 1, "max_rho_h": rho * max(self.h),
                      "taylor_terms_max": 0, "phases": 0, "velocity_reversals": 0, "sticks": 0, "zeno": 0,
                      "event_searches": 0, "warnings": []}

    # ------------------------------------------------------------------ grid
    def _grid(self, drive, profile, t: np.ndarray, rho: float) -> None:
        t0, t1 = float(t[0]), float(t[-1])
        hmin = float(np.min(np.diff(t)))
        tol = 1e-9 * hmin
        bps = np.asarray(drive.breakpoints(t0, t1), dtype=float).ravel()
        bps = bps[(bps > t0 + tol) & (bps < t1 - tol)]
        near = np.min(np.abs(t[:, None] - bps[None, :]), axis=0) <= tol if bps.size else np.zeros(0, bool)
        snapped = t[np.argmin(np.abs(t[:, None] - bps[None, :]), axis=0)][near] if bps.size else np.zeros(0)
        brk = np.union1d(bps[~near], snapped)
        nodes = np.union1d(t, bps[~near])
        h = np.diff(nodes)
        parts = np.maximum(1, np.ceil(rho * h / self.max_rho_h)).astype(np.int64)
        if parts.max() > 1:
            starts = np.repeat(nodes[:-1], parts)
            frac = np.arange(parts.sum()) - np.repeat(np.cumsum(parts) - parts, parts)
            inner = starts + np.repeat(h / parts, parts) * frac
            nodes = np.union1d(nodes, inner[frac > 0])
            h = np.diff(nodes)
        self.out_index = np.searchsorted(nodes, t)
        inner = np.isin(nodes, brk) & (nodes > t0) & (nodes < t1)
        i = np.nonzero(inner)[0]
        delta = 1e-7 * np.minimum(h[i - 1], h[i]) if i.size else 0.0
        right, left, k_right, k_left = node_values(drive, profile, nodes, inner, delta)
        if profile is None:  # a constant stiffness: k' = 0
            k_right = np.stack([np.full(nodes.size, self.model.stiffness), np.zeros(nodes.size)])
            k_left = k_right
        P = hermite5(h, right[:, :-1], left[:, 1:])
        # k: the quintic through k, k' at both ends and at the midpoint (the profile is smooth
        # inside a step): error ~3e-6 h^6 k^(6), against h^4 k^(4) / 384 of the cubic through the
        # ends only, which would dominate the solution's error (tests: the manufactured solution)
        Km = k_right[:, :-1] if profile is None else profile(nodes[:-1] + 0.5 * h)
        rhs = np.stack([k_right[0, :-1], k_right[1, :-1] * h, Km[0], Km[1] * h, k_left[0, 1:], k_left[1, 1:] * h])
        Kc = _K_INVERSE @ rhs
        self.nodes, self.h = nodes.tolist(), h.tolist()
        self.P, self.K = P.T.tolist(), Kc.T.tolist()
        # node values as the following step's polynomial sees them (last node: its step's end)
        Dn = np.empty((3, nodes.size))
        Dn[0, :-1], Dn[1, :-1], Dn[2, :-1] = P[0], P[1] / h, 2.0 * P[2] / h**2
        last = P[:, -1]
        Dn[0, -1] = last.sum()
        Dn[1, -1] = (np.arange(6) * last).sum() / h[-1]
        Dn[2, -1] = (np.arange(6) * np.arange(-1, 5) * last).sum() / h[-1] ** 2
        Kn = np.empty((2, nodes.size))
        Kn[0, :-1], Kn[1, :-1] = Kc[0], Kc[1] / h
        Kn[0, -1] = Kc[:, -1].sum()
        Kn[1, -1] = (np.arange(6) * Kc[:, -1]).sum() / h[-1]
        self.Dn, self.Kn = Dn, Kn

    # ------------------------------------------------------------------ step data
    def _step_polys(self, j: int, u0: float):
        """S (in w), dS/dt (in w) and k (in w) over [u0, 1] of step j, H = (1 - u0) h."""
        H = (1.0 - u0) * self.h[j]
        sc = 1.0 - u0
        S = _shift(self.P[j], u0, sc)
        k = _shift(self.K[j], u0, sc)
        Sd = [x / H for x in _deriv(S)]
        return H, S, Sd, k

    def time(self, j: int, u: float) -> float:
        if j >= len(self.h):
            return self.nodes[-1]
        return self.nodes[j] + u * self.h[j]

    def _series(self, phase: int, H: float, S, Sd, k, s: float, v: float, sigma: float) -> list:
        """Taylor coefficients a[n] of s(w) over the (sub)step."""
        a = [s, v * H]
        F0 = self.W0 + self.R * sigma
        H2 = H * H
        if phase == CONTACT:
            m, c, rate = self.M1, self.c, self.rate
            Q = list(S)
            Q[0] -= self.lash
            f = _mul(k, Q, 11)
            if c:
                f = _add(f, Sd, 1.0, c)
            f[0] -= F0
            nk = len(k)
        else:
            m, c, rate = self.M, 0.0, self.rate
            f = [-F0]
            nk = 0
        cH = c * H
        small = 0
        for n in range(MAX_TERMS - 2):
            acc = f[n] if n < len(f) else 0.0
            for jj in range(min(nk, n + 1)):
                acc -= k[jj] * a[n - jj]
            acc -= rate * a[n]
            nxt = (H2 * acc - cH * (n + 1) * a[n + 1]) / (m * (n + 2) * (n + 1))
            a.append(nxt)
            if n >= 8:
                small = small + 1 if abs(nxt) < self.tiny else 0
                if small >= 2:
                    break
        self.stats["taylor_terms_max"] = max(self.stats["taylor_terms_max"], len(a))
        return a

    # ------------------------------------------------------------------ events of a step
    def _plan(self, key, rules) -> tuple:
        """A phases.py rule set as (kind, a "max" rule?, components) per event, each component
        (quantity, its sign > 0?, the factor of its polynomial: -sign for the velocity, the
        threshold / kmax for the push), kept per phase and friction sign (or rest height): a step
        then only fills in the polynomials."""
        plan = self._plans[key] = tuple(
            (r.kind, r.comb == "max",
             tuple((q, sign > 0.0, -sign if q == "velocity" else threshold / self.kmax) for q, sign, threshold in r.comps))
            for r in rules)
        return plan

    def _moving_events(self, phase, H, S, Sd, k, a, sigma):
        """The events of phases.moving_events as polynomials in w: a component sign * quantity
        is -sign * quantity here, fired a hair (band) beyond its surface, the force scaled by
        1/kmax and the velocity's band in speed."""
        band = self.band
        V = [x / H for x in _deriv(a)]
        Q = list(S)
        Q[0] -= self.lash
        x = _add(Q, a, 1.0, -1.0)  # gap S - lash - s
        F = None
        evs = []
        key = phase if sigma > 0.0 else -1 - phase  # (an int: the cheapest key)
        plan = self._plans.get(key) or self._plan(key, moving_events(phase, bool(self.c), bool(self.R), sigma))
        for kind, split, comps in plan:
            polys = []
            for quantity, up, factor in comps:
                if quantity == "lift":
                    comp = [-y for y in a] if up else list(a)
                    comp[0] += band
                elif quantity == "gap":
                    comp = [-y for y in x] if up else list(x)
                    comp[0] += band
                elif quantity == "force":
                    if F is None:  # k gap + c (S' - v)
                        F = _mul(k, x, len(a) + 6)
                        if self.c:
                            F = _add(F, _add(Sd, V, 1.0, -1.0), 1.0, self.c)
                    kmax = self.kmax
                    comp = [-y / kmax for y in F] if up else [y / kmax for y in F]
                    comp[0] += band
                else:  # velocity
                    comp = [factor * y for y in V]
                    comp[0] += band * self.wn
                polys.append(comp)
            if split:  # a "max" rule (any component): one event per component, the earliest fires
                evs.extend(_Event(kind, [p]) for p in polys)
            else:  # the event fires where all components are < 0
                evs.append(_Event(kind, polys))
        return evs, V

    def _static_events(self, s_star: float, H, S, Sd, k):
        """The events of phases.rest_events at s_star as polynomials in w (no band: a valve at
        rest starts off its surfaces), the push scaled by 1/kmax. The gap's component is kept
        without damping too: a step where it stays >= 0 is cleared at once by the search."""
        Q = list(S)
        Q[0] -= self.lash + s_star
        P = _mul(k, Q, 11)
        if self.c:
            P = _add(P, Sd, 1.0, self.c)
        kmax = self.kmax
        evs = []
        plan = self._plans.get(("rest", s_star)) or self._plan(
            ("rest", s_star), rest_events(s_star, self.W0, self.rate, self.R, gap_check=True))
        for kind, split, comps in plan:
            polys = []
            for quantity, up, thr in comps:
                if quantity == "gap":
                    comp = [-y for y in Q] if up else list(Q)
                elif up:  # push - threshold > 0
                    comp = [-y / kmax for y in P]
                    comp[0] += thr
                else:
                    comp = [y / kmax for y in P]
                    comp[0] -= thr
                polys.append(comp)
            if split:  # a "max" rule (any component): one event per component, the earliest fires
                evs.extend(_Event(kind, [p]) for p in polys)
            else:  # the event fires where all components are < 0
                evs.append(_Event(kind, polys))
        return evs

    @staticmethod
    def _earliest(evs):
        best = None
        for ev in evs:
            w = _first_negative(ev)
            if w is not None and (best is None or w < best[0]):
                best = (w, ev.kind)
        return best

    # ------------------------------------------------------------------ main loop
    def _record(self, node: int, phase: int, s: float, v: float, sigma: float) -> None:
        self.out_phase[node] = phase
        self.out_s[node] = s
        self.out_v[node] = v
        self.out_sigma[node] = sigma

    def _drive_at(self, j: int, u: float):
        if j >= len(self.h):
            return float(self.Dn[0, -1]), float(self.Dn[1, -1]), float(self.Kn[0, -1])
        P = self.P[j]
        return horner(P, u), horner(_deriv(P), u) / self.h[j], horner(self.K[j], u)

    def _phase_at(self, s: float, v: float):
        S, S1, k = self._drive_at(0, 0.0)
        return phase_of_state(S, S1, k, self.c, self.lash, s, v, self.W0, self.rate, self.R)

    def run(self) -> None:
        n_steps = len(self.h)
        if self.initial_state is None:
            phase, s, v, sigma = SEATED, 0.0, 0.0, 1.0
        else:
            s, v = (float(x) for x in self.initial_state)
            phase, sigma = self._phase_at(s, v)
        self._record(0, phase, s, v, sigma)
        j, u0 = 0, 0.0
        same_time, last_time = 0, None
        while j < n_steps:
            H, S, Sd, k = self._step_polys(j, u0)
            if phase in (SEATED, STUCK):
                hit = self._earliest(self._static_events(s, H, S, Sd, k))
                if hit is None:
                    j, u0 = j + 1, 0.0
                    self._record(j, phase, s, 0.0, sigma)
                    continue
                w, which = hit
                u = u0 + w * (1.0 - u0)
                St, S1t, kt = horner(S, w), horner(Sd, w), horner(k, w)
                phase, sigma, lifts = release_from_rest(which, phase, St, S1t, kt, self.c, self.lash, s, self.W0, self.R)
                if lifts:
                    self._event("lift-off", j, u, 0.0)
                v = 0.0
                self.stats["phases"] += 1
            else:
                a = self._series(phase, H, S, Sd, k, s, v, sigma)
                evs, V = self._moving_events(phase, H, S, Sd, k, a, sigma)
                self.stats["event_searches"] += 1
                hit = self._earliest(evs)
                if hit is None:
                    s, v = math.fsum(a), math.fsum(V)
                    j, u0 = j + 1, 0.0
                    self._record(j, phase, s, v, sigma)
                    continue
                w, which = hit
                u = u0 + w * (1.0 - u0)
                s, v = horner(a, w), horner(V, w)
                St, S1t, kt = horner(S, w), horner(Sd, w), horner(k, w)
                phase, s, v, sigma, j, u = self._handle(which, phase, j, u, s, v, sigma, St, S1t, kt)
                self.stats["phases"] += 1
            if len(self.events) > self.max_events:
                raise RuntimeError(f"taylor solver: more than {self.max_events} events; the motion does not settle")
            t_now = self.time(j, u)
            same_time = same_time + 1 if t_now == last_time else 0
            last_time = t_now
            if same_time > MAX_SAME_TIME:
                raise RuntimeError(f"taylor solver: events repeat at t = {t_now!r} s without progress")
            if u >= 1.0:
                j, u = j + 1, 0.0
                self._record(j, phase, s, v, sigma)
            u0 = u

    def _event(self, kind: str, j: int, u: float, v: float) -> dict:
        ev = {"kind": kind, "time_s": self.time(j, u), "velocity_m_s": float(v)}
        self.events.append(ev)
        return ev

    def _handle(self, which, phase, j, u, s, v, sigma, S, S1, k):
        """The phase after the event `which` (the rules: phases.py), with this solver's bookkeeping."""
        if which in AFTER_CROSSING:
            self._event(which, j, u, v)
            return AFTER_CROSSING[which], s, v, sigma, j, u
        if which == "velocity-zero":
            self.stats["velocity_reversals"] += 1
            phase, sign = velocity_zero(phase, S, S1, k, self.c, self.lash, s, self.W0, self.rate, self.R)
            if sign is None:
                self.stats["sticks"] += 1
                return phase, s, 0.0, sigma, j, u
            return phase, s, 0.0, sign, j, u
        # seat: the event fired a hair below; the speed at s = 0 by energy
        if s < 0.0:
            m = self.M1 if phase == CONTACT else self.M
            if phase == CONTACT:
                acc = (k * (S - self.lash - s) + self.c * (S1 - v) - self.W0 - self.rate * s - self.R * sigma) / m
            else:
                acc = -(self.W0 + self.rate * s + self.R * sigma) / m
            v = seat_speed(v, s, acc)
        impact = min(v, 0.0)
        ev = self._event("seat", j, u, impact)
        if -self.e * impact <= 0.0:
            return SEATED, 0.0, 0.0, 1.0, j, u
        force = rest_force(S, S1, k, self.c, self.lash, 0.0)
        kind, rebound, _, dt = seat_rebound(impact, self.e, force, self.M, self.M1, self.W0, self.R, self.zeno_height)
        if dt is not None:  # the rest of the chatter, summed
            self.stats["zeno"] += 1
            ev["zeno_accumulation_s"] = self.time(j, u) + dt
            t_new = self.time(j, u) + dt
            while j < len(self.h) and self.nodes[j + 1] <= t_new:
                j += 1
                self._record(j, SEATED, 0.0, 0.0, 1.0)
            u = 0.0 if j >= len(self.h) else max(0.0, min((t_new - self.nodes[j]) / self.h[j], 1.0 - 1e-16))
            return SEATED, 0.0, 0.0, 1.0, j, u
        return kind, 0.0, rebound, 1.0, j, u

    # ------------------------------------------------------------------ output
    def solution(self, t: np.ndarray) -> DynamicsSolution:
        idx = self.out_index
        s = np.asarray(self.out_s)[idx]
        v = np.asarray(self.out_v)[idx]
        sigma = np.asarray(self.out_sigma)[idx]
        phase = np.asarray(self.out_phase, dtype=np.int64)[idx]
        S, S1, S2 = self.Dn[:, idx]
        k, dk = self.Kn[:, idx]
        x = S - self.lash - s
        contact = phase == CONTACT
        flight = phase == FLIGHT
        resist = self.W0 + self.rate * s + self.R * sigma
        a = np.zeros_like(s)
        jerk = np.zeros_like(s)
        a_c = (k * x + self.c * (S1 - v) - resist) / self.M1
        a[contact] = a_c[contact]
        a[flight] = -resist[flight] / self.M
        j_c = (dk * x + k * (S1 - v) + self.c * (S2 - a_c) - self.rate * v) / self.M1
        jerk[contact] = j_c[contact]
        jerk[flight] = -self.rate * v[flight] / self.M
        rest_force = np.where(x >= 0.0, np.maximum(0.0, k * x + self.c * S1), 0.0)
        force = np.where(contact, np.maximum(0.0, k * x + self.c * (S1 - v)), np.where(flight, 0.0, rest_force))
        self.stats["events"] = len(self.events)
        return DynamicsSolution(t=t, s=s, v=v, a=a, linkage_force=force, contact=force > 0.0,
                                events=tuple(self.events), stats=self.stats, jerk=jerk, phase=phase)


def solve(model: LinkageModel, drive, t: np.ndarray, initial_state: tuple[float, float] | None = None,
          zeno_height: float = 1e-12, max_events: int = 100_000, max_rho_h: float = MAX_RHO_H) -> DynamicsSolution:
    """Taylor-series solution at the output times t (sorted, strictly increasing); the valve starts
    at rest on its seat at t[0] unless initial_state = (s, v) is given.

    zeno_height: seat chatter ends (in closed form) once a rebound would rise less than this (m).
    max_events: guard against a motion that never settles (raises RuntimeError).
    max_rho_h: longest step times the fastest rate (steps of the output grid longer than that are
      split); at most 0.5 (the series' convergence); smaller refines the Hermite interpolation."""
    t = np.asarray(t, dtype=float).ravel()
    if t.size < 2 or not np.isfinite(t).all() or np.any(np.diff(t) <= 0.0):
        raise ValueError("output times must be a sorted array of at least two distinct finite times")
    if not 0.0 < max_rho_h <= MAX_RHO_H:
        raise ValueError(f"max_rho_h must be in (0, {MAX_RHO_H}]")
    solver = _Solver(model, drive, t, initial_state, zeno_height, max_events, max_rho_h)
    solver.run()
    return solver.solution(t)
