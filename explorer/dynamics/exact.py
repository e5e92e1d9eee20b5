"""`exact` solver (the default): piecewise-exact stepping of the elastic valve linkage.

Its parts: exact_steps.py (a phase's ODE over a step: Taylor tables, forcing, one step's
expansion), exact_events.py (event functions, bounds, root polish), modal.py (the propagator
over many steps), phases.py (what happens at an event, shared with taylor), series.py (Hermite
and Taylor helpers); this module: the grid, the solver loop and the output.

Each moving phase is a linear ODE with constant coefficients,
    m s'' + c s' + K s = kc (S(t) - lash) + cc S'(t) - F0,
  contact: m = M1, c = damping, K = k + rate, kc = k, cc = c, F0 = preload + closing + R sign(v)
  flight:  m = M,  c = 0,       K = rate,     kc = cc = 0,  F0 = the same
and a valve at rest (seated, or stuck by friction) has s = const. Over every step the drive S is
replaced by the quintic Hermite polynomial through S, S', S'' at both ends (taken from the analytic
drive; steps end at the drive's breakpoints, so jumps of S'' fall on step ends). With polynomial
forcing the response over a step is known in closed form; it is carried as its Taylor series in
the step variable u = tau/h, whose coefficients follow exactly from the ODE,
    m (n+2)(n+1) a[n+2] + c h (n+1) a[n+1] + K h^2 a[n] = h^2 f[n]        (a[n] = s^(n) h^n / n!),
i.e. the matrix exponential of the augmented system (the "phi functions" of exponential
integrators) as a power series. Steps are at most 0.5 / rho long (rho: the phase's fastest rate,
the natural frequency), so 9-17 terms reach 1e-19 and no digits are lost to the cancellation
between particular and homogeneous solution that the textbook closed form suffers when
omega_n h is small. Longer steps (very stiff linkages) are split. There is no stability limit
and no tuning knob: the only error is the interpolation of S, O(h^6) (a drive feature narrower
than the output step, e.g. a bump, is seen only through that interpolation).

From step to step the state follows x[i+1] = Phi(h) x[i] + g[i]. In modal coordinates
(s, (v + alpha s)/beta) Phi is a damped rotation for any step length, so this recurrence is
solved in closed form for the whole grid at once (modal.py): the powers of the eigenvalue and the
cumulative sums of the drive's forcing are computed once per phase kind, and a phase is then a
few vector operations on slices, whatever its length (no Python loop over steps, no per-phase
cumulative sum). The module needs numpy only (fast to import).

Cost (issue 4's speed target): a solve is a fixed part -- the drive at the nodes, the step
polynomials, per phase kind the modal powers and the sums of the drive's forcing as far as its
phases reach -- plus, per phase, one window of vector operations (states, event values, bounds:
~20 numpy calls) and two single steps in plain Python (the phase's first partial step, where the
event that began it sits on its zero, and the step where the next event lies). Everything at the
scale of one step is plain-float Python: numpy's overhead on tiny arrays would dominate. At the
default 3600 steps per revolution the time is mostly that overhead, not arithmetic (a tenth of
the steps saves only 10-25 %): ~0.9 ms for a revolution with 3 events, ~1.3 ms with 11, and
0.25-0.35 ms more right after unrelated work has evicted the caches (benchmarks/bench_dynamics.py
measures that way, alternating with scipy).

Events are roots of the closed forms, per step:
  seated -> lift-off    linkage force k (S - lash) + c S' exceeds preload + closing + friction
  contact -> separation linkage force k (S - lash - s) + c (S' - v) falls to 0
  flight -> re-contact  gap S - lash - s closes (with damping: and the force would be positive)
  any -> seat           s = 0 moving down: rebound v -> -e v
  velocity zero         (only with friction) the friction force flips, or the valve sticks
No crossing inside a step is missed. A step is cleared only by a rigorous bound: the event
function e is at most the larger end value plus h^2/8 sup e''. sup e'' is bounded first for a
whole window of steps from node values and the ODE (cheap), then for the steps this does not
clear from each one's own left-node values, and for the few left from the step's own Taylor
coefficients (values and slopes at both ends and a signed bound of e''). Steps still not
cleared are sampled at 8 points, recursively, and the first sign change is polished to machine
precision (Newton steps from the secant point inside the bracket, or the Illinois variant of
regula falsi), returning the first representable instant past the zero so that the next phase
starts on its own side. At a phase start the function that began it sits on its
zero: its leading Taylor terms against the positive part of the rest clear an initial stretch
analytically (e(w) <= w^k (e_k + sum max(e_n, 0) w^(n-k))).

Chattering seat impacts (e > 0) are followed until the next bounce would rise less than
`zeno_height`; the remaining infinitely many bounces are summed as a geometric series (durations
2 v e^n / A, A the net deceleration on the seat) and the valve stays seated from that
accumulation instant on.

Output: s, v, a, jerk (the closed-form third derivative within the phase), linkage force and
phase at the requested times; the valve starts at rest on its seat at t[0] unless
initial_state = (s, v) is given.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .exact_events import (BOUND_WEIGHTS, Event, coeff_list, coefficients, combine, combine_cleared, combine_cleared1,
                           combine_excluded, combine_hits, deriv, deriv_list, excluded, excluded1, excluded_range,
                           excluded_steps, illinois, lincomb_into, positive_at, rising_range, root_rising, shift_list,
                           start_clearance, start_coeffs)
from .exact_steps import LinearPhase, StepTables, drive_response, expand_step, step_tables, taylor_terms
from .modal import Propagator
from .model import DynamicsSolution, LinkageModel
from .phases import (AFTER_CROSSING, CONTACT, FLIGHT, SEATED, STUCK, phase_of_state, release_from_rest, rest_force,
                     seat_rebound, velocity_zero)
from .series import hermite5, horner, taylor_shift, taylor_shift1

EPS = float(np.finfo(float).eps)
MAX_RHO_H = 0.5  # longest step times the fastest rate: short, well-conditioned series; cheap chunk bounds
MAX_DEPTH = 6  # refinement levels of the event search (8 sub-intervals each: 4e-6 of a step)
SUBDIVISIONS = 8
MAX_SAME_TIME = 60  # events at one instant before the phase logic is declared looping
_MAX = np.maximum.reduce  # the ufunc itself: ndarray.max adds a Python layer per call


class _Solver:
    def __init__(self, model: LinkageModel, drive, t: np.ndarray, initial_state, zeno_height: float,
                 max_events: int, chunk: int, hmin: float):
        self.model = model
        self.k, self.c, self.lash = model.stiffness, model.damping, model.lash
        self.rate, self.R = model.spring_rate, model.friction
        self.M, self.M1 = model.mass, model.oscillating_mass
        self.e = model.restitution
        self.W0 = model.seated_resistance
        self.zeno_height = zeno_height
        self.max_events = max_events
        self.chunk = chunk
        self.lins = {
            CONTACT: LinearPhase(self.M1, self.c, self.k + self.rate, self.k, self.c),
            FLIGHT: LinearPhase(self.M, 0.0, self.rate, 0.0, 0.0),
        }
        rho = max(lin.rho for lin in self.lins.values())
        self._build_grid(drive, t, rho, hmin)
        h_max = self.h_max
        self.n_terms = taylor_terms(rho * h_max)
        self._tabs: dict = {}  # step tables per phase kind, built on first use
        self.props: dict = {}
        self._setups: dict = {}
        self._static_cache: dict = {}
        self._last_length: dict = {}  # steps of the last moving phase of each kind
        nn = self.nodes.size
        out = np.empty((3, nn))
        out[:2] = np.nan
        out[2] = 1.0
        self.out_s, self.out_v, self.out_sigma = out  # (sigma: friction sign of moving nodes)
        self.out_phase = np.empty(nn, dtype=np.int8)
        self.out_phase[:] = -1
        self.events: list[dict] = []
        self.stats = {
            "method": "exact", "nodes": int(nn), "steps": int(nn - 1), "taylor_terms": self.n_terms,
            "max_rho_h": rho * h_max, "phases": 0, "detail_searches": 0, "velocity_reversals": 0,
            "sticks": 0, "zeno": 0, "impact_energy_loss_J": 0.0, "mass_switch_energy_J": 0.0,
            "warnings": [],
        }
        self.initial_state = initial_state

    # ---------------------------------------------------------------- grid and drive data
    def _build_grid(self, drive, t: np.ndarray, rho: float, hmin: float) -> None:
        t0, t1 = float(t[0]), float(t[-1])
        tol = 1e-9 * hmin
        n = t.size
        # drive breakpoints: a node within tol of one becomes a breakpoint node, the others are
        # inserted as nodes (a few per revolution: plain Python, then one insertion)
        brk_set, new = set(), []
        bps = [b for b in np.asarray(drive.breakpoints(t0, t1), dtype=float).ravel().tolist() if t0 <= b <= t1]
        if bps:
            for b, i in zip(bps, t.searchsorted(bps).tolist()):
                i = min(max(i, 1), n - 1)
                if b - float(t[i - 1]) <= tol:
                    brk_set.add(i - 1)
                elif float(t[i]) - b <= tol:
                    brk_set.add(i)
                else:
                    new.append(b)
        inserted: list[int] = []  # final indices of the inserted nodes
        if new:
            new = sorted(set(new))
            new = [b for k, b in enumerate(new) if k == 0 or b - new[k - 1] > tol]
            pos = t.searchsorted(new).tolist()  # insertion points (no node within tol)
            inserted = [p + k for k, p in enumerate(pos)]
            nodes = np.empty(n + len(new))
            prev = 0
            for k, (p, b) in enumerate(zip(pos, new)):
                nodes[prev + k:p + k] = t[prev:p]
                nodes[p + k] = b
                prev = p
            nodes[prev + len(new):] = t[prev:]
            brk = sorted({i + sum(1 for p in pos if p <= i) for i in brk_set} | set(inserted))
        else:
            nodes = t.copy()
            brk = sorted(brk_set)
        is_out = np.empty(nodes.size, bool)
        is_out[:] = True
        is_out[inserted] = False
        h = nodes[1:] - nodes[:-1]
        h_max = float(_MAX(h))
        # split steps longer than MAX_RHO_H / rho (stiff linkages)
        if rho * h_max / MAX_RHO_H > 1.0:
            brk_mask = np.zeros(nodes.size, bool)
            brk_mask[brk] = True
            parts = np.maximum(1, np.ceil(rho * h / MAX_RHO_H)).astype(np.int64)
            starts = np.repeat(nodes[:-1], parts)
            frac = np.arange(parts.sum()) - np.repeat(np.cumsum(parts) - parts, parts)
            inner = starts + np.repeat(h / parts, parts) * frac
            keep = frac > 0
            nodes = np.concatenate([nodes, inner[keep]])
            is_out = np.concatenate([is_out, np.zeros(int(keep.sum()), bool)])
            brk_mask = np.concatenate([brk_mask, np.zeros(int(keep.sum()), bool)])
            order = np.argsort(nodes, kind="stable")
            nodes, is_out, brk_mask = nodes[order], is_out[order], brk_mask[order]
            brk = brk_mask.nonzero()[0].tolist()
            h = nodes[1:] - nodes[:-1]
            h_max = float(_MAX(h))
        self.nodes, self.is_out = nodes, is_out
        self.h = h
        nn = nodes.size
        # one-sided drive data at breakpoint nodes: evaluated a hair inside and moved back by Taylor
        nb = len(brk)
        if nb:
            hl = [float(h[i - 1]) if i > 0 else math.inf for i in brk]
            hr = [float(h[i]) if i < nn - 1 else math.inf for i in brk]
            d = [1e-7 * min(a, b) for a, b in zip(hl, hr)]
            tb = nodes[brk]
            dd = np.array(d)
            D = np.asarray(drive(np.concatenate([nodes, tb + dd, tb - dd])), dtype=float)
            right = D[:3, :nn]
            left = right.copy()
            if nb <= 32:  # a few breakpoints: plain Python (numpy's overhead on tiny arrays)
                Dr, Dl = D[:, nn:nn + nb].T.tolist(), D[:, nn + nb:].T.tolist()
                right[:, brk] = np.array([taylor_shift1(r, -di)[:3] for di, r in zip(d, Dr)]).T
                left[:, brk] = np.array([taylor_shift1(l, di)[:3] for di, l in zip(d, Dl)]).T
            else:
                right[:, brk] = taylor_shift(D[:, nn:nn + nb], -dd)[:3]
                left[:, brk] = taylor_shift(D[:, nn + nb:], dd)[:3]
        else:
            right = left = np.asarray(drive(nodes), dtype=float)
        P = self.P = hermite5(h, right[:, :-1], left[:, 1:])  # (6, steps)
        self.PT = P.T  # rows: one step's polynomial
        # drive at the nodes as the following step sees it (the last node: the end of its step):
        # S, S', S'' of the step polynomials, so node values match the step expansions
        inv = 1.0 / h
        inv2 = inv * inv
        Dn = self.Dn = np.empty((3, nn))
        Dn[0, :-1] = P[0]
        np.multiply(P[1], inv, out=Dn[1, :-1])
        np.multiply(P[2], 2.0 * inv2, out=Dn[2, :-1])
        last = P[:, -1].tolist()
        Dn[0, -1] = math.fsum(last)
        Dn[1, -1] = sum(k * c for k, c in enumerate(last)) * float(inv[-1])
        Dn[2, -1] = sum(k * (k - 1) * c for k, c in enumerate(last)) * float(inv2[-1])
        # per step: bounds of |S1|, |S2|, |S3| (derivatives) over the step (from the polynomial)
        Sb = self.Sb = BOUND_WEIGHTS @ np.abs(P)
        Sb[0] *= inv
        Sb[1] *= inv2
        inv2 *= inv
        Sb[2] *= inv2
        self._group_steps(h, h_max)

    def _group_steps(self, h: np.ndarray, h_max: float) -> None:
        """Steps of (nearly) equal length share their tables: equal up to 1e-11 relative or up to
        the rounding of the node times (a few ulp of t: a uniform grid of 10^5 steps differs by
        ~1e-10 relative from step to step). The sorted lengths are chained while consecutive
        ones differ by at most tol; the tables take a group's mean length (summed in sorted
        order): a time warp of the drive by at most those roundings (~1e-18 s), no error of
        the state. Sets h_unique (group lengths), hidx (group of each step), base_col (the
        most common group), odd (the steps of the other groups) and uniform (one group)."""
        nodes = self.nodes
        tol = max(1e-11 * h_max, 8.0 * EPS * max(abs(float(nodes[0])), abs(float(nodes[-1]))))
        self.h_max = h_max
        self.uniform = float(np.minimum.reduce(h)) >= h_max - tol
        # the scan bounds a window's longest step by the grid's when the most common steps are
        # the longest (a uniform grid with drive breakpoints inserted): the same bound then
        self.window_h_is_max = self.uniform
        if self.uniform:
            self.h_unique = np.array([np.add.reduce(h) / h.size])  # (h.mean())
            self.hidx = np.zeros(h.size, dtype=np.int64)
            self.base_col = 0
            self.odd = np.zeros(0, dtype=np.int64)
            return
        hs = h.copy()
        hs.sort()  # (equal lengths are equal floats: no need of a stable argsort)
        starts = (hs[1:] - hs[:-1] > tol).nonzero()[0] + 1
        bounds = [0] + starts.tolist() + [h.size]
        means = []
        for a, b in zip(bounds[:-1], bounds[1:]):
            if b - a > 32:
                total = float(hs[a:b].cumsum()[-1])  # sequential, as a running sum
            else:
                total = 0.0
                for x in hs[a:b].tolist():
                    total += x
            means.append(total / (b - a))
        self.h_unique = np.array(means)
        counts = [b - a for a, b in zip(bounds[:-1], bounds[1:])]
        base = self.base_col = max(range(len(counts)), key=counts.__getitem__)  # the most common length
        self.window_h_is_max = base == len(counts) - 1
        # the steps outside the base group's range, and their groups (searched among the few)
        lo, hi = float(hs[bounds[base]]), float(hs[bounds[base + 1] - 1])
        odd = self.odd = ((h < lo) | (h > hi)).nonzero()[0]
        self.hidx = np.empty(h.size, dtype=np.intp)
        self.hidx[:] = base
        self.hidx[odd] = hs[starts].searchsorted(h[odd], side="right")  # group starts at or below

    @property
    def dP(self) -> np.ndarray:
        """Scaled coefficients of dS/dt per step (built on first use)."""
        dP = self.__dict__.get("_dP")
        if dP is None:
            dP = self._dP = deriv(self.P, self.h)
        return dP

    def time(self, j: int, u: float) -> float:
        if j >= self.h.size:
            return float(self.nodes[-1])
        return float(self.nodes[j]) + u * float(self.h[j])

    # ---------------------------------------------------------------- event functions
    def _moving_events(self, kind: int, sigma: float) -> list[Event]:
        k, c, lash = self.k, self.c, self.lash
        events = [Event("seat", ((0.0, 0.0, 0.0, -1.0, 0.0),))]
        if kind == CONTACT:
            events.append(Event("separation", ((-k, -c, k * lash, k, c),)))
        else:
            gap = (k, 0.0, -k * lash, -k, 0.0)
            if c > 0.0:
                events.append(Event("re-contact", (gap, (k, c, -k * lash, -k, -c)), "min"))
            else:
                events.append(Event("re-contact", (gap,)))
        if self.R > 0.0:
            events.append(Event("velocity-zero", ((0.0, 0.0, 0.0, 0.0, -sigma),)))
        return events

    def _moving_setup(self, kind: int, sigma: float):
        """The events of a moving phase and, for scanning windows of nodes: their components as
        rows (aP, bP, const, l0, l1), per event its rows and combination, the drive's part of
        every row at all nodes (aP S + bP S' + const), the rows' state coefficients (l0, l1), and
        the drive's part of the phase's force kc S + cc S' at all nodes (for the acceleration).
        Cached per phase kind and friction sign: a window then costs one small matrix product."""
        key = (kind, sigma)
        hit = self._setups.get(key)
        if hit is None:
            events = self._moving_events(kind, sigma)
            rows, groups = [], []
            for ev in events:
                groups.append((list(range(len(rows), len(rows) + len(ev.comps))), ev.comb))
                rows.extend(ev.comps)
            D0, D1 = self.Dn[0], self.Dn[1]
            # the drive parts do not depend on the friction sign (only the velocity row's state
            # coefficient does): shared between both signs
            other = self._setups.get((kind, -sigma))
            if other is not None and len(other[1]) == len(rows):
                Ed, Fd = other[3], other[5]
            else:
                Ed = []  # (row, drive part at all nodes, or a constant): rows without one skipped
                for r, (aP, bP, const, _, _) in enumerate(rows):
                    if aP or bP:
                        part = np.empty(D0.size)
                        lincomb_into(part, ((aP, D0), (bP, D1)), const)
                        Ed.append((r, part))
                    elif const:
                        Ed.append((r, const))
                lin = self.lins[kind]
                Fd = np.empty(D0.size)
                lincomb_into(Fd, ((lin.kc, D0), (lin.cc, D1)), 0.0)
            Cs = np.array([[l0, l1] for _, _, _, l0, l1 in rows])
            simple = all(comb == "one" for _, comb in groups)
            absrows = [(abs(aP), abs(bP), abs(l0), abs(l1)) for aP, bP, _, l0, l1 in rows]  # for sag bounds
            hit = self._setups[key] = (events, rows, groups, Ed, Cs, Fd, simple, absrows)
        return hit

    def _static_events(self, s_star: float) -> list[Event]:
        k, c = self.k, self.c
        off = -k * (self.lash + s_star)
        thr_up = self.W0 + self.rate * s_star + self.R
        events = []
        if c > 0.0:
            events.append(Event("up", ((k, c, off - thr_up, 0.0, 0.0), (k, 0.0, off, 0.0, 0.0)), "min"))
        else:
            events.append(Event("up", ((k, 0.0, off - thr_up, 0.0, 0.0),)))
        thr_dn = self.W0 + self.rate * s_star - self.R
        if s_star > 0.0 and thr_dn > 0.0:
            if c > 0.0:
                events.append(Event("down", ((-k, -c, thr_dn - off, 0.0, 0.0), (-k, 0.0, -off, 0.0, 0.0)), "max"))
            else:
                events.append(Event("down", ((-k, 0.0, thr_dn - off, 0.0, 0.0),)))
        return events

    # ---------------------------------------------------------------- root search in one step
    def _earliest(self, events, coeff_sets, zero_flags, t_abs: float, h_loc: float):
        """Earliest event over one step: (kind, w) or None. coeff_sets: per event, its components'
        coefficient vectors over w in [0, 1]."""
        best = None
        for ev, Es, zero in zip(events, coeff_sets, zero_flags):
            lists = Es
            w_lo = 0.0
            if zero:
                # starting on its zero: most often it leaves it downwards and the plain test for
                # the whole step suffices; otherwise clear the start analytically, test the rest
                if len(lists) == 1:
                    if excluded1(lists[0]):
                        continue
                else:
                    ex = [excluded1(e) for e in lists]
                    if (any(ex) if ev.comb == "min" else all(ex)):
                        continue
                clear = [start_clearance(e) if e[0] == 0.0 else 0.0 for e in lists]
                w_lo = max(clear) if ev.comb == "min" else min(clear)
                if w_lo >= 1.0:
                    continue
            e = lists[0]
            if len(lists) == 1:
                e_lo, e_hi = (e[0] if w_lo == 0.0 else horner(e, w_lo)), sum(e)
                # (a sign change from one end to the other needs no exclusion test)
                if not e_lo <= 0.0 < e_hi and (
                        excluded1(e, e_hi) if w_lo == 0.0 else excluded_range(e, w_lo, 1.0)):
                    continue
            else:
                ex = [excluded1(e) if w_lo == 0.0 else excluded_range(e, w_lo, 1.0) for e in lists]
                if (any(ex) if ev.comb == "min" else all(ex)):
                    continue
            if (ev.comb == "one" and e_lo <= 0.0 < e_hi
                    and rising_range(e, w_lo, 1.0)):  # one simple crossing: polish it directly
                self.stats["newton_roots"] = self.stats.get("newton_roots", 0) + 1
                w = root_rising(e, w_lo, 1.0, max(0.5 * math.ulp(abs(t_abs)) / h_loc, 1e-300), e_lo, e_hi)
            elif positive_at(lists, ev.comb, w_lo):  # already > 0 where the search would begin
                w = w_lo
            else:
                w = self._first_root(Es, ev.comb, w_lo, t_abs, h_loc)
            if w is None:
                continue
            # the seat is rigid: when the valve lands in the same instant as another event
            # (zero lash on the base circle: gap and lift close together) the seat decides
            tie = best is not None and abs(w - best[1]) <= 1e-9 * max(w, 1e-300) + 64.0 * EPS
            if best is None or w < best[1] and not (tie and best[0] == "seat") or tie and ev.kind == "seat":
                best = (ev.kind, w)
        return best

    def _first_root(self, Es, comb, w_lo: float, t_abs: float, h_loc: float):
        """First w in [w_lo, 1] where the combined function becomes > 0, or None."""
        self.stats["detail_searches"] += 1
        pts = np.linspace(w_lo, 1.0, SUBDIVISIONS + 1)
        xtol = max(0.5 * math.ulp(abs(t_abs)) / h_loc, 1e-300) if h_loc > 0 else 1e-300
        E = np.array(Es)  # (components, N+1)
        return self._search(E, comb, pts, 0, xtol)

    def _search(self, E, comb, pts, depth, xtol):
        nc, nr = E.shape
        powers = pts[:, None] ** np.arange(nr)
        n = np.arange(nr, dtype=float)
        vals = (powers @ E.T).T  # (nc, K)
        ders = (powers[:, :-1] @ (E[:, 1:] * n[1:]).T).T
        cv = combine(vals, comb)
        w2 = E[:, 2:] * (n[2:] * (n[2:] - 1.0))  # (nc, nr-2)
        pa, pb = powers[:-1, :nr - 2], powers[1:, :nr - 2]
        D = pts[1:] - pts[:-1]
        ex = np.array([
            excluded(vals[c, :-1], ders[c, :-1], vals[c, 1:], ders[c, 1:],
                      np.maximum(pa * w2[c], pb * w2[c]).sum(axis=1), D)
            for c in range(nc)
        ])
        ex = combine_excluded(ex, comb)
        for i in np.nonzero(~ex)[0]:
            lo, hi = float(pts[i]), float(pts[i + 1])
            if cv[i] > 0.0:
                return lo
            if cv[i + 1] > 0.0:
                if depth < MAX_DEPTH and not self._monotone(E, comb, lo, hi, ders[:, i]):
                    r = self._search(E, comb, np.linspace(lo, hi, SUBDIVISIONS + 1), depth + 1, xtol)
                    if r is not None:
                        return r
                return self._brent(E, comb, lo, hi, xtol)
            if depth < MAX_DEPTH:
                r = self._search(E, comb, np.linspace(lo, hi, SUBDIVISIONS + 1), depth + 1, xtol)
                if r is not None:
                    return r
        return None

    @staticmethod
    def _monotone(E, comb, lo, hi, d_lo) -> bool:
        """e' > 0 on [lo, hi] for a single-component function (then its root there is unique)."""
        if comb != "one":
            return False
        e = E[0]
        n = np.arange(2, e.size, dtype=float)
        w = n * (n - 1.0) * e[2:]
        B2lo = np.minimum(w * lo ** (n - 2.0), w * hi ** (n - 2.0)).sum()
        return float(d_lo[0]) + min(0.0, B2lo) * (hi - lo) > 0.0

    @staticmethod
    def _brent(E, comb, lo, hi, xtol):
        cs = [list(map(float, e)) for e in E]
        if comb == "one":
            c0 = cs[0]

            def f(x):
                return horner(c0, x)
        elif comb == "min":

            def f(x):
                return min(horner(c, x) for c in cs)
        else:

            def f(x):
                return max(horner(c, x) for c in cs)
        flo = f(lo)
        if flo > 0.0:
            return lo
        if flo == 0.0:  # leave the zero: bisect on the sign for the first point where f > 0
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi:
                    break
                if f(mid) > 0.0:
                    hi = mid
                else:
                    lo = mid
            return hi
        return illinois(f, lo, hi, flo, f(hi), xtol)

    # ---------------------------------------------------------------- recording
    def _record_static(self, j0: int, j1: int, s_star: float, phase: int) -> None:
        """Nodes j0..j1-1 at rest at s_star."""
        if j1 <= j0:
            return
        self.out_s[j0:j1] = s_star
        self.out_v[j0:j1] = 0.0
        self.out_phase[j0:j1] = phase

    def _record_moving(self, kind: int, j0: int, S, V, sigma: float) -> None:
        """Nodes j0.. moving with the states S (and V, at least as long). Acceleration, jerk and
        linkage force follow from the phase ODE at the end (solution), for the output nodes only."""
        n = len(S)
        if n == 0:
            return
        sl = slice(j0, j0 + n)
        self.out_s[sl] = S
        self.out_v[sl] = V[:n]
        self.out_phase[sl] = kind
        self.out_sigma[sl] = sigma

    # ---------------------------------------------------------------- phases
    def _static_setup(self, s_star: float):
        """Events of a valve at rest at s_star, per event its component rows, and the steps of
        the whole grid that the bound max(e_i, e_i+1) + h^2/8 sup|e''| <= 0 does not clear (with
        the per-row exclusions). A resting valve's event functions depend on the drive only, so
        this is computed once per rest height (cached; all seated phases share it)."""
        hit = self._static_cache.get(s_star)
        if hit is None:
            events = self._static_events(s_star)
            rows, groups = [], []
            for ev in events:
                groups.append((list(range(len(rows), len(rows) + len(ev.comps))), ev.comb))
                rows.extend(ev.comps)
            D0, D1 = self.Dn[0], self.Dn[1]
            h2 = self.h * self.h / 8.0
            ex = np.empty((len(rows), self.h.size), dtype=bool)
            E = np.empty(self.nodes.size)
            for r, (aP, bP, const, _, _) in enumerate(rows):
                lincomb_into(E, ((aP, D0), (bP, D1)), const)
                sag = abs(aP) * self.Sb[1] + abs(bP) * self.Sb[2] if bP else abs(aP) * self.Sb[1]
                np.less_equal(np.maximum(E[:-1], E[1:]) + h2 * sag, 0.0, out=ex[r])
            cand = (~combine_cleared(ex, groups)).nonzero()[0]
            hit = self._static_cache[s_star] = (events, groups, ex, cand)
        return hit

    def _run_static(self, j: int, u0: float, s_star: float, phase: int):
        """Valve at rest at s_star from (j, u0). Returns (kind, j, u) of the release, or None."""
        nsteps = self.h.size
        if self.W0 + self.rate * s_star + self.R < 0.0:
            return "up", j, u0  # the loads alone push the valve open: no rest
        if j >= nsteps:
            self._record_static(j, nsteps + 1, s_star, phase)
            return None
        events, groups, ex, cand = self._static_setup(s_star)
        # first (possibly partial) step
        P = shift_list(self.PT[j], u0)
        h_loc = (1.0 - u0) * float(self.h[j])
        dP = deriv_list(P, h_loc) if self.c else None  # (S' enters the events with damping only)
        sets, zeros = [], []
        for ev in events:
            Es, zero = start_coeffs(ev.comps, ev.comb, P, dP, None, None, s_star, 0.0)
            zeros.append(zero)
            sets.append(Es)
        best = self._earliest(events, sets, zeros, self.time(j, u0), h_loc)
        if u0 == 0.0:
            self._record_static(j, j + 1, s_star, phase)
        if best is not None:
            return best[0], j, u0 + best[1] * (1.0 - u0)
        j += 1
        # the steps not cleared by the bound, in order, searched one by one (converted a few at
        # a time: the list can hold every step of the lift)
        k0 = int(cand.searchsorted(j))
        for i in itertools.chain.from_iterable(cand[k:k + 16].tolist() for k in range(k0, cand.size, 16)):
            h_i = float(self.h[i])
            P = self.PT[i].tolist()
            dP = deriv_list(P, h_i) if self.c else None
            check, col = [], []
            for ev, (rr, comb) in zip(events, groups):
                if not combine_cleared1(ex[rr, i].tolist(), comb):
                    check.append(ev)
                    col.append([coeff_list(cp, P, dP, None, None) for cp in ev.comps])
            best = self._earliest(check, col, [False] * len(check), self.time(i, 0.0), h_i)
            if best is not None:
                self._record_static(j, i + (1 if best[1] > 0.0 else 0), s_star, phase)
                return best[0], i, best[1]
        self._record_static(j, nsteps + 1, s_star, phase)
        return None

    def tab(self, kind: int) -> StepTables:
        """The step tables of a phase kind (built on first use: a flight needs none unless its
        events must be searched in many steps at once)."""
        tab = self._tabs.get(kind)
        if tab is None:
            tab = self._tabs[kind] = step_tables(self.lins[kind], self.h_unique, self.n_terms)
        return tab

    def _forcing(self, kind: int):
        """G(a, b) -> (2, b - a): s and v at the end of the steps a..b-1 from rest under the
        drive's forcing kc S + cc S' alone. Steps of the most common length by their table (one
        matrix product for the whole grid); the few others (ends at inserted breakpoints) by
        their own expansion, in Python when first asked for, so that no table is built for them."""
        lin = self.lins[kind]
        odd = self.odd
        if odd.size > 64:  # a non-uniform grid: every table, vectorised
            WP = self.tab(kind).WP
            G = WP[:, :, self.base_col] @ self.P
            G[:, odd] = np.einsum("knm,nm->km", WP[:, :, self.hidx[odd]], self.P[:, odd])
            return lambda a, b: G[:, a:b]
        hb = float(self.h_unique[self.base_col])
        if kind in self._tabs:
            WP = self._tabs[kind].WP[:, :, self.base_col]
        else:
            WP = drive_response(lin, hb, self.n_terms)
        G = WP @ self.P
        if not odd.size:
            return lambda a, b: G[:, a:b]
        pending = set(odd.tolist())  # odd steps not expanded yet
        N = self.n_terms

        def forcing(a: int, b: int) -> np.ndarray:
            if pending:
                for m in odd[odd.searchsorted(a):odd.searchsorted(b)].tolist():
                    if m in pending:
                        pending.discard(m)
                        hu = float(self.h_unique[self.hidx[m]])
                        e = expand_step(lin, self.PT[m].tolist(), hu, 0.0, 0.0, 0.0, N)
                        G[0, m] = sum(e)
                        G[1, m] = sum([k * x for k, x in enumerate(e)]) / hu
            return G[:, a:b]

        return forcing

    def _prop(self, kind: int) -> Propagator:
        """The closed-form propagator of a phase kind over the whole grid (built on first use)."""
        prop = self.props.get(kind)
        if prop is None:
            lin = self.lins[kind]
            G = None
            if lin.kc or lin.cc:  # the drive's forcing over every step, (s, v) response from rest
                G = self._forcing(kind)

            def phi_of_step(j: int, L: int):
                tab = self.tab(kind)
                cols = self.hidx[j:j + L]
                return tab.Phi[:, :, cols].tolist(), tab.g1[:, cols].tolist()

            prop = self.props[kind] = Propagator(lin.m, lin.c, lin.K, self.nodes, G, phi_of_step, self.hidx,
                                                 self.h_unique, self.base_col)
        return prop

    def _run_moving(self, kind: int, j: int, u0: float, s: float, v: float, sigma: float, release: bool = False):
        """Valve moving (contact or flight) from (j, u0) with state (s, v) and friction sign sigma.
        release: the valve starts from rest, pushed in the direction sigma.
        Returns (event kind, j, u, s, v) or None at the end of the grid."""
        lin = self.lins[kind]
        Fc = lin.kc * self.lash + self.W0 + self.R * sigma
        setup = self._moving_setup(kind, sigma)
        events = setup[0]
        nsteps = self.h.size
        N = self.n_terms
        if j >= nsteps:
            self._record_moving(kind, nsteps, [s], [v], sigma)
            return None
        # first (possibly partial) step: event functions may start on their zero here
        P = shift_list(self.PT[j], u0)
        h_loc = (1.0 - u0) * float(self.h[j])
        a = expand_step(lin, P, h_loc, s, v, Fc, N)
        if release:
            # the release instant was found where the net force just passed zero in the direction
            # sigma; recomputed here it may differ by rounding (~1e-16 of its terms) and start the
            # valve the wrong way. Such a residual is removed from this first step's forcing.
            f0 = 2.0 * lin.m * a[2] / (h_loc * h_loc)
            terms = abs(lin.kc * P[0]) + abs(lin.cc * P[1] / h_loc) + abs(Fc) + abs(lin.K * s)
            if sigma * f0 < 0.0 and abs(f0) <= 1e-12 * terms:
                a = expand_step(lin, P, h_loc, s, v, Fc + f0, N)
        da = deriv_list(a, h_loc)
        dP = deriv_list(P, h_loc) if self.c else None  # (S' enters the events with damping only)
        sets, zeros = [], []
        for ev in events:
            Es, zero = start_coeffs(ev.comps, ev.comb, P, dP, a, da, s, v)
            zeros.append(zero)
            sets.append(Es)
        best = self._earliest(events, sets, zeros, self.time(j, u0), h_loc)
        if u0 == 0.0:
            self._record_moving(kind, j, [s], [v], sigma)
        if best is not None:
            w = best[1]
            return best[0], j, u0 + w * (1.0 - u0), horner(a, w), horner(da, w)
        s, v = math.fsum(a), math.fsum(da)
        j += 1
        prop = self._prop(kind)
        # first window: twice the last phase of this kind (a window costs in proportion to its
        # length; most phases are short), then 8x as long until an event is found
        L = max(self.chunk, 2 * self._last_length.get(kind, 0))
        j_start = j
        while j < nsteps:
            L = min(nsteps - j, L)
            SV = prop.states(j, L, s, v, Fc)  # nodes j..j+L
            S, V = SV
            found, n_done = self._scan_window(kind, lin, j, L, SV, Fc, setup)
            if found is not None:
                which, i, w, s_ev, v_ev = found
                self._last_length[kind] = j + i - j_start
                self._record_moving(kind, j, S[:i + (1 if w > 0.0 else 0)], V, sigma)
                return which, j + i, w, s_ev, v_ev
            self._record_moving(kind, j, S[:n_done], V, sigma)
            s, v = float(S[n_done]), float(V[n_done])
            j += n_done
            L = 8 * L
        self._record_moving(kind, nsteps, [s], [v], sigma)
        return None

    def _scan_window(self, kind, lin, j: int, L: int, SV, Fc: float, setup):
        """The first event in the steps j..j+L-1, given the node states SV = (s, v) at j..j+L.
        Returns ((kind, i, w, s, v), i) for an event in step j+i at w, or (None, n): the
        first n steps are clear of events.

        Event values at all nodes at once; a function > 0 at a node ends the search there (the
        event lies at the latest in the step before). Steps before it are cleared by the bound
        max(e_i, e_i+1) + h^2/8 sup|e2| <= 0, sup|e2| from window bounds of |S2|, |S3|, |a|,
        |jerk| (from the node maxima and the ODE: a = a_node + int jerk, jerk = (f' - c a - K v)/m).
        The few steps not cleared are expanded and searched one by one."""
        events, rows, groups, Ed, Cs, Fd, simple, absrows = setup
        S, V = SV
        E = Cs @ SV
        for r, part in Ed:
            E[r] += part[j:j + L + 1] if isinstance(part, np.ndarray) else part
        if simple:  # every event one row: the largest row decides where one turns > 0
            top = _MAX(E[:, 1:], axis=0) if len(rows) > 1 else E[0, 1:]
            first = int((top > 0.0).argmax())
            last = first + 1 if top[first] > 0.0 else L
        else:
            hit = combine_hits(E[:, 1:] > 0.0, groups)
            first = int(hit.argmax())
            last = first + 1 if hit[first] else L
        n = last
        m, c, K = lin.m, lin.c, lin.K
        H = self.h_max if self.window_h_is_max else float(_MAX(self.h[j:j + n]))
        q = H * (c + K * H) / m
        if q < 0.5:
            S1b, S2b, S3b = _MAX(self.Sb[:, j:j + n], axis=1).tolist()
            Sw, Vw = S[:n], V[:n]
            Vn = float(_MAX(np.abs(Vw)))
            if lin.kc or lin.cc:
                A = Fd[j:j + n] - Fc - K * Sw
            else:  # no drive forcing (flight): -A m = Fc + K s (the same magnitudes)
                A = K * Sw
                A += Fc
            if c:
                A -= c * Vw
            An = float(_MAX(np.abs(A))) / m
            F1 = lin.kc * S1b + lin.cc * S2b
            Ahat = (An + H * (F1 + K * Vn) / m) / (1.0 - q)
            Jhat = (F1 + c * Ahat + K * (Vn + H * Ahat)) / m
            H8 = H * H / 8.0
            xs = (H8 * S2b, H8 * S3b, H8 * Ahat, H8 * Jhat)
            sag = np.array([a0 * xs[0] + a1 * xs[1] + a2 * xs[2] + a3 * xs[3] for a0, a1, a2, a3 in absrows])
            Mx = np.maximum(E[:, :n], E[:, 1:n + 1])
            Mx += sag[:, None]
            if simple:  # a step is cleared when every row's bound is <= 0
                cand = (_MAX(Mx, axis=0) > 0.0).nonzero()[0] if len(rows) > 1 else (Mx[0] > 0.0).nonzero()[0]
            else:
                cand = (~combine_cleared(Mx <= 0.0, groups)).nonzero()[0]
            if cand.size > 1:
                # the window's maxima are loose where a function starts near its zero (a phase
                # begun by an event): the same bound with each step's own left-node values (a
                # few steps: plain Python)
                steps = j + cand
                Vc, Ac = np.abs(V[cand]).tolist(), np.abs(A[cand]).tolist()
                S1c, S2c, S3c = self.Sb[:, steps].tolist()
                Ea, Eb = E[:, cand].tolist(), E[:, cand + 1].tolist()
                kc, cc, q1 = lin.kc, lin.cc, 1.0 - q
                keep, flags = [], {}
                for t, i in enumerate(cand.tolist()):
                    Vi = Vc[t]
                    F1i = kc * S1c[t] + cc * S2c[t] if kc else 0.0
                    Ai = (Ac[t] / m + H * (F1i + K * Vi) / m) / q1
                    Ji = (F1i + c * Ai + K * (Vi + H * Ai)) / m
                    x0, x1, x2, x3 = S2c[t], S3c[t], Ai, Ji
                    col = [(Ea[r][t] if Ea[r][t] > Eb[r][t] else Eb[r][t])
                           + H8 * (a0 * x0 + a1 * x1 + a2 * x2 + a3 * x3) <= 0.0
                           for r, (a0, a1, a2, a3) in enumerate(absrows)]
                    cleared = all(col) if simple else all(
                        col[rr[0]] if len(rr) == 1 else combine_cleared1([col[r] for r in rr], cb)
                        for rr, cb in groups)
                    if not cleared:
                        keep.append(i)
                        flags[i] = col
                cand = np.array(keep, dtype=np.intp)
            else:
                flags = None
        else:
            Mx = flags = None
            cand = np.arange(n)
        if 0 < cand.size <= 4:  # the usual case near an event: expand those steps in Python
            N = self.n_terms
            for i in cand.tolist():
                h_i = float(self.h[j + i])
                P = self.PT[j + i].tolist()
                a = expand_step(lin, P, h_i, float(S[i]), float(V[i]), Fc, N)
                da, dP = deriv_list(a, h_i), (deriv_list(P, h_i) if self.c else None)
                if Mx is None:
                    check = events
                    col = [[coeff_list(cp, P, dP, a, da) for cp in ev.comps] for ev in events]
                else:  # only the events the window bound did not clear in this step
                    check, col = [], []
                    exi = flags[i] if flags else [x <= 0.0 for x in Mx[:, i].tolist()]
                    for ev, (rr, comb) in zip(events, groups):
                        cleared = exi[rr[0]] if len(rr) == 1 else combine_cleared1([exi[r] for r in rr], comb)
                        if not cleared:
                            check.append(ev)
                            col.append([coeff_list(cp, P, dP, a, da) for cp in ev.comps])
                best = self._earliest(check, col, [False] * len(check), self.time(j + i, 0.0), h_i)
                if best is not None:
                    w = best[1]
                    return (best[0], i, w, horner(a, w), horner(da, w)), i
        elif cand.size:
            tab = self.tab(kind)
            N = self.n_terms
            steps = j + cand
            cols = self.hidx[steps]
            P = self.P[:, steps]
            hc = self.h[steps]
            a = (tab.A[:, cols] * S[cand] + tab.B[:, cols] * V[cand]
                 + np.einsum("nku,ku->nu", tab.R[:, :, cols], P) - Fc * tab.C1[:, cols])
            da = deriv(a, hc)
            dP = self.dP[:, steps]
            sets = [[coefficients(cp, P, dP, a, da, N + 1) for cp in ev.comps] for ev in events]
            if cand.size > 32:  # many (stiff linkage): the exact per-step test vectorized first
                still = np.zeros(cand.size, bool)
                for ev, Es in zip(events, sets):
                    still |= ~combine_excluded(np.array([excluded_steps(e) for e in Es]), ev.comb)
                order = np.nonzero(still)[0]
            else:  # few: _earliest tests each step in plain Python
                order = range(cand.size)
            for i_c in order:
                i = int(cand[i_c])
                col = [[e[:, i_c].tolist() for e in Es] for Es in sets]
                best = self._earliest(events, col, [False] * len(events), self.time(j + i, 0.0), float(hc[i_c]))
                if best is not None:
                    w = best[1]
                    return (best[0], i, w, horner(a[:, i_c], w), horner(da[:, i_c], w)), i
        return None, n

    # ---------------------------------------------------------------- helpers at an instant
    def _drive_at(self, j: int, u: float):
        """S, S' of the step polynomial at (j, u) (the last node: its left value)."""
        if j >= self.h.size:
            return float(self.Dn[0, -1]), float(self.Dn[1, -1])
        P = self.PT[j].tolist()
        return horner(P, u), horner(deriv_list(P, float(self.h[j])), u)

    def _advance(self, j: int, u: float, dt: float, s_star: float):
        """Position dt later; nodes passed on the way are recorded seated at s_star."""
        t_new = self.time(j, u) + dt
        j0 = j
        while j < self.h.size and self.nodes[j + 1] <= t_new:
            j += 1
        start = j0 + (1 if u > 0.0 else 0)
        if j >= self.h.size:
            self._record_static(start, j, s_star, SEATED)
            return j, 0.0
        u_new = max(0.0, min((t_new - self.nodes[j]) / self.h[j], 1.0 - 1e-16))
        self._record_static(start, j + (1 if u_new > 0.0 else 0), s_star, SEATED)
        return j, u_new

    def _event(self, kind: str, j: int, u: float, v: float | None = None, **extra) -> None:
        ev = {"kind": kind, "time_s": self.time(j, u)}
        if v is not None:
            ev["velocity_m_s"] = float(v)
        ev.update(extra)
        self.events.append(ev)

    # ---------------------------------------------------------------- main loop
    def run(self) -> None:
        if self.initial_state is None:
            phase, s, v, sigma = SEATED, 0.0, 0.0, 1.0
        else:
            s, v = (float(x) for x in self.initial_state)
            phase, sigma = self._phase_at(0, 0.0, s, v)
        j, u = 0, 0.0
        release = self.initial_state is not None and v == 0.0
        same_time, last_time = 0, None
        while True:
            self.stats["phases"] += 1
            if len(self.events) > self.max_events:
                raise RuntimeError(f"exact solver: more than {self.max_events} events; the motion does not settle")
            if phase in (SEATED, STUCK):
                res = self._run_static(j, u, s, phase)
                if res is None:
                    break
                which, j, u = res
                if j < self.h.size and u >= 1.0:
                    j, u = j + 1, 0.0
                S, S1 = self._drive_at(j, u)
                phase, sigma, lifts = release_from_rest(which, phase, S, S1, self.k, self.c, self.lash, s, self.W0, self.R)
                if lifts:
                    self._event("lift-off", j, u, 0.0)
                v = 0.0
                release = True
            else:
                res = self._run_moving(phase, j, u, s, v, sigma, release)
                release = False
                if res is None:
                    break
                which, j, u, s, v = res
                if j < self.h.size and u >= 1.0:
                    j, u = j + 1, 0.0
                phase, s, v, sigma, j, u = self._handle(which, phase, j, u, s, v, sigma)
            t_now = self.time(j, u)
            same_time = same_time + 1 if t_now == last_time else 0
            last_time = t_now
            if same_time > MAX_SAME_TIME:
                raise RuntimeError(f"exact solver: events repeat at t = {t_now!r} s without progress")

    def _phase_at(self, j: int, u: float, s: float, v: float):
        """Phase and friction sign of a valve given at (s, v)."""
        S, S1 = self._drive_at(j, u)
        return phase_of_state(S, S1, self.k, self.c, self.lash, s, v, self.W0, self.rate, self.R)

    def _handle(self, which: str, phase: int, j: int, u: float, s: float, v: float, sigma: float):
        """The phase after the event `which` (the rules: phases.py), with this solver's bookkeeping."""
        m_phase = self.M1 if phase == CONTACT else self.M
        if which in AFTER_CROSSING:
            self._event(which, j, u, v)
            switch = 0.5 * (self.M - self.M1) * v * v
            self.stats["mass_switch_energy_J"] += switch if which == "separation" else -switch
            return AFTER_CROSSING[which], s, v, sigma, j, u
        S, S1 = self._drive_at(j, u)  # (the mass switches above need no drive)
        if which == "velocity-zero":
            self.stats["velocity_reversals"] += 1
            phase, sign = velocity_zero(phase, S, S1, self.k, self.c, self.lash, s, self.W0, self.rate, self.R)
            if sign is None:
                self.stats["sticks"] += 1
                return phase, s, 0.0, sigma, j, u
            return phase, s, 0.0, sign, j, u
        # seat impact
        impact = min(v, 0.0)
        self._event("seat", j, u, impact)
        self.stats["impact_energy_loss_J"] += 0.5 * m_phase * (1.0 - self.e * self.e) * impact * impact
        if -self.e * impact <= 0.0:
            return SEATED, 0.0, 0.0, 1.0, j, u
        force = rest_force(S, S1, self.k, self.c, self.lash, 0.0)
        kind, rebound, m_rest, dt = seat_rebound(impact, self.e, force, self.M, self.M1, self.W0, self.R,
                                                 self.zeno_height)
        if dt is not None:  # the rest of the chatter, summed
            self.stats["zeno"] += 1
            self.stats["impact_energy_loss_J"] += 0.5 * m_rest * rebound * rebound
            self.events[-1]["zeno_accumulation_s"] = self.time(j, u) + dt
            j, u = self._advance(j, u, dt, 0.0)
            return SEATED, 0.0, 0.0, 1.0, j, u
        return kind, 0.0, rebound, 1.0, j, u

    def solution(self, t_req: np.ndarray, inverse) -> DynamicsSolution:
        """The results at the output times (inverse: node of each output time, None: one each)."""
        s, v, phase = self.out_s, self.out_v, self.out_phase
        D0, D1, D2 = self.Dn
        # acceleration and jerk from the phase ODEs (exact: the closed form's derivatives), with
        # each node's coefficients looked up by its phase code (at rest: a = jerk = 0); computed
        # in place in the looked-up rows (the formulas' order of operations kept)
        table = np.zeros((8, 4))
        table[1] = 1.0  # m
        table[7] = 1.0  # linkage force kept (0 in flight)
        for code, lin in self.lins.items():
            table[:7, code] = (1.0, lin.m, lin.c, lin.K, lin.kc, lin.cc, lin.kc * self.lash + self.W0)
        table[7, FLIGHT] = 0.0
        moving, m, c, K, kc, cc, Fc, keep = table.take(phase, axis=1)
        if self.R:
            Fc += self.R * self.out_sigma
        acc = kc * D0  # (kc D0 + cc D1 - Fc - c v - K s) / m * moving
        if self.c:
            acc += cc * D1
            acc -= Fc
            acc -= np.multiply(c, v, out=Fc)
        else:
            acc -= Fc
        acc -= np.multiply(K, s, out=Fc)
        acc /= m
        acc *= moving
        jerk = np.multiply(kc, D1, out=kc)  # (kc D1 + cc D2 - c a - K v) / m * moving
        if self.c:
            jerk += np.multiply(cc, D2, out=cc)
            jerk -= np.multiply(c, acc, out=c)
        jerk -= np.multiply(K, v, out=K)
        jerk /= m
        jerk *= moving
        # linkage force: in contact the stretched linkage; at rest the static force; in flight 0
        x = D0 - self.lash
        x -= s
        if self.c:
            kx = self.k * x
            contact_force = np.maximum(0.0, kx + self.c * (D1 - v))
            rest_force = np.where(x >= 0.0, np.maximum(0.0, kx + self.c * D1), 0.0)
            force = np.where(phase == CONTACT, contact_force, np.where(moving > 0.0, 0.0, rest_force))
        else:  # undamped: contact and rest alike max(0, k x) (k x < 0 exactly where x < 0)
            x *= self.k
            force = np.maximum(x, 0.0, out=x)
            force *= keep
        self.stats["events"] = len(self.events)
        if inverse is None and self.is_out.all():  # the output times are the nodes
            pick = slice(None)
        else:
            out = self.is_out.nonzero()[0]
            pick = out if inverse is None else out[inverse]
        force = force[pick]
        return DynamicsSolution(
            t=t_req, s=s[pick], v=v[pick], a=acc[pick], linkage_force=force,
            contact=force > 0.0, events=tuple(self.events), stats=self.stats,
            jerk=jerk[pick], phase=phase[pick].astype(np.int64),
        )


def solve(
    model: LinkageModel,
    drive,
    t: np.ndarray,
    initial_state: tuple[float, float] | None = None,
    zeno_height: float = 1e-12,
    max_events: int = 100_000,
    chunk: int = 512,
) -> DynamicsSolution:
    """Piecewise-exact solution at the output times t (sorted).

    initial_state: (s, v) at t[0]; default: at rest on the seat.
    zeno_height: seat chatter ends (in closed form) once a rebound would rise less than this (m).
    max_events: guard against a motion that never settles (raises RuntimeError).
    chunk: fewest steps propagated and scanned at once at the start of a moving phase (then twice
      the last phase of its kind, growing 8x while no event is found).
    """
    t_req = np.asarray(t, dtype=float).ravel()
    steps = t_req[1:] - t_req[:-1]
    hmin = float(np.minimum.reduce(steps)) if steps.size else 0.0
    if t_req.size == 0 or hmin < 0.0 or not np.isfinite(t_req).all():
        raise ValueError("output times must be a non-empty, sorted array of finite numbers")
    if t_req.size > 1 and hmin > 0.0:  # strictly increasing: the nodes themselves
        t_nodes, inverse = t_req, None
    else:
        t_nodes, inverse = np.unique(t_req, return_inverse=True)
        inverse = inverse.ravel()
        if t_nodes.size == 1:  # one instant: the state itself
            t_nodes = np.array([t_nodes[0], t_nodes[0] + 1e-9])
            inverse = np.zeros(t_req.size, dtype=np.int64)
        hmin = float(np.minimum.reduce(t_nodes[1:] - t_nodes[:-1]))
    solver = _Solver(model, drive, t_nodes, initial_state, zeno_height, max_events, chunk, hmin)
    solver.run()
    return solver.solution(t_req, inverse)
