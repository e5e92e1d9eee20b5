"""Part of the `exact` solver (exact.py): one phase at a time. A valve at rest (seated, or stuck
by friction) keeps its height until a release event; a moving valve (contact or flight) is carried
over windows of steps by the closed-form propagator (modal.py) and each window is scanned for its
first event (rigorous bounds clear most steps; the rest are searched by exact_events.py). The
event found ends the phase; what happens then is exact.py's (with phases.py's rules).

PhaseStepper holds the model's constants, the grid (exact_grid.py), the per-kind tables and
propagators (built on first use) and the node records; exact._Solver adds the event loop."""

from __future__ import annotations

import itertools
import math

import numpy as np

from .exact_events import (Event, coeff_list, coefficients, combine_cleared, combine_cleared1, combine_excluded,
                           combine_hits, deriv, deriv_list, earliest, event_of, excluded_steps, lincomb_into,
                           shift_list, start_coeffs)
from .exact_grid import build_grid
from .exact_steps import LinearPhase, StepTables, drive_response, expand_step, step_tables, taylor_terms
from .modal import Propagator
from .model import LinkageModel
from .phases import CONTACT, FLIGHT, moving_events, rest_events
from .series import horner

_MAX = np.maximum.reduce  # the ufunc itself: ndarray.max adds a Python layer per call
RELEASE_RESIDUAL = 1e-12  # a release's net force below this fraction of its terms is rounding
MAX_BOUND_Q = 0.5  # the step bound's q = H (c + K H) / m: its series for |a| converges below 1 (margin: 0.5)


class PhaseStepper:
    def __init__(self, model: LinkageModel, drive, t: np.ndarray, chunk: int, hmin: float):
        self.model = model
        self.k, self.c, self.lash = model.stiffness, model.damping, model.lash
        self.rate, self.R = model.spring_rate, model.friction
        self.M, self.M1 = model.mass, model.oscillating_mass
        self.e = model.restitution
        self.W0 = model.seated_resistance
        self.chunk = chunk
        self.lins = {
            CONTACT: LinearPhase(self.M1, self.c, self.k + self.rate, self.k, self.c),
            FLIGHT: LinearPhase(self.M, 0.0, self.rate, 0.0, 0.0),
        }
        rho = max(lin.rho for lin in self.lins.values())
        g = self.grid = build_grid(drive, t, rho, hmin)
        # the grid's arrays as attributes: read in every phase and window
        self.nodes, self.is_out, self.h, self.P, self.PT, self.Dn, self.Sb = g.nodes, g.is_out, g.h, g.P, g.PT, g.Dn, g.Sb
        h_max = self.h_max = g.h_max
        self.window_h_is_max = g.window_h_is_max
        self.h_unique, self.hidx, self.base_col, self.odd = g.h_unique, g.hidx, g.base_col, g.odd
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
        self.stats = {
            "method": "exact", "nodes": int(nn), "steps": int(nn - 1), "taylor_terms": self.n_terms,
            "max_rho_h": rho * h_max, "phases": 0, "detail_searches": 0, "velocity_reversals": 0,
            "sticks": 0, "zeno": 0, "impact_energy_loss_J": 0.0, "mass_switch_energy_J": 0.0,
            "warnings": [],
        }

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
        rules = moving_events(kind, self.c > 0.0, self.R > 0.0, sigma)
        return [event_of(rule, self.k, self.c, self.lash) for rule in rules]

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
        rules = rest_events(s_star, self.W0, self.rate, self.R, gap_check=self.c > 0.0)
        return [event_of(rule, self.k, self.c, self.lash, s_star) for rule in rules]

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
        best = earliest(events, sets, zeros, self.time(j, u0), h_loc, self.stats)
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
            best = earliest(check, col, [False] * len(check), self.time(i, 0.0), h_i, self.stats)
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
            if sigma * f0 < 0.0 and abs(f0) <= RELEASE_RESIDUAL * terms:
                a = expand_step(lin, P, h_loc, s, v, Fc + f0, N)
        da = deriv_list(a, h_loc)
        dP = deriv_list(P, h_loc) if self.c else None  # (S' enters the events with damping only)
        sets, zeros = [], []
        for ev in events:
            Es, zero = start_coeffs(ev.comps, ev.comb, P, dP, a, da, s, v)
            zeros.append(zero)
            sets.append(Es)
        best = earliest(events, sets, zeros, self.time(j, u0), h_loc, self.stats)
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
        if q < MAX_BOUND_Q:
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
                best = earliest(check, col, [False] * len(check), self.time(j + i, 0.0), h_i, self.stats)
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
            else:  # few: earliest() tests each step in plain Python
                order = range(cand.size)
            for i_c in order:
                i = int(cand[i_c])
                col = [[e[:, i_c].tolist() for e in Es] for Es in sets]
                best = earliest(events, col, [False] * len(events), self.time(j + i, 0.0), float(hc[i_c]), self.stats)
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
