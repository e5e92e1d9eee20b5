"""The `exact` solver compiled (numba): the same model, closed forms and events as exact.py, for the
batch engine of sweeps (explorer/studies/sweep_kernel.py). Only the sweep engine imports this module
(numba costs ~0.4 s to import; `import explorer` must not pay it).

What is the same as exact.py (read its docstring for the method): the grid (exact_grid.build_grid,
called in Python and passed in as arrays), the drive over a step (the quintic Hermite through S, S',
S'' at both ends), a step's response as the Taylor series of the phase ODE (the same recursion,
steps split to rho h <= 0.5 by the grid), the event functions (phases.py's rules, exact_events'
rows aP S + bP S' + const + l0 s + l1 v, combined by min/max), the rigorous clearing of a step
(max of the end values + h^2/8 sup|e''|, sup|e''| from the ODE's bounds of |a| and |jerk|, then
the step's own Taylor coefficients), the search in a step that is not cleared (start clearance,
Newton in a proven rising bracket, 8-point subdivision to depth 6 with the coefficient bounds,
Illinois), what happens at an event (phases.py's rules written again in compiled form: lift-off,
separation, re-contact, seat with restitution and the chatter's closed-form Zeno tail, velocity
zero with Coulomb friction, stick and release).

What differs: the node states are carried step by step by the one-step propagator
x[i+1] = Phi(h) x[i] + W_P P[i] - Fc g1 (the unit responses' end values; the tables of exact_steps
for each step length), not by modal.py's closed form over a window. Both are the exact solution of
the same step ODE; they differ by rounding (~1e-16 relative per step, a few 1e-15 over a revolution:
tests/test_sweep_kernel.py holds every row to simulate's within 1e-12 m and 1e-12 s).
The steps are cleared in groups before the per-step bound: a seated valve's BLOCK steps by its
push row's bound over the block, a moving valve's WINDOW steps (their states propagated first)
by each event's rows bounded over the window from the ranges of S, S1, s, v at its nodes; each
term of those bounds is at least the per-step bound's, so they change which steps are looked at,
never the states or the events (tests/test_sweep_kernel.py).

The LinkageModel without stiffness_profile only (constant coefficients): `supports(model)`.

`python -m explorer.dynamics.exact_kernel --warm` compiles (and caches next to this module) every
compiled function once: `make` runs it at install, so the first sweep does not compile.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .exact_grid import build_grid
from .exact_steps import LinearPhase, taylor_terms
from .free_vibration import free_amplitude
from .model import DynamicsSolution, LinkageModel
from .phases import CONTACT, FLIGHT, SEATED, STUCK

EPS = float(np.finfo(float).eps)
ZERO_START = 1e-11  # exact_events.ZERO_START
MAX_DEPTH = 6  # exact_events.MAX_DEPTH
SUBDIVISIONS = 8
MAX_SAME_TIME = 60  # exact.MAX_SAME_TIME
MAX_RHO_H = 0.5
BLOCK = 8  # steps a seated valve's bound clears at once (small: a seated stretch starts anywhere, and
# its bound fails near the lift-off; 8 measured faster than 16 and 64)
WINDOW = 16  # steps a moving valve's window bound clears at once (~1/10 of the steps between events)

# event codes (records): the first four are model.EVENT_KINDS in order
LIFT_OFF, SEPARATION, RECONTACT, SEAT, VZERO, UP, DOWN = 0, 1, 2, 3, 4, 5, 6
EVENT_NAMES = ("lift-off", "separation", "re-contact", "seat")
ONE, MIN, MAX = 0, 1, 2  # how an event's components combine
# kernel status
OK, TOO_MANY_EVENTS, NO_PROGRESS = 0, 1, 2

_free_amplitude = njit(cache=True)(free_amplitude)  # the elastic effect's residual amplitude, compiled

_INV_PAIR = np.array([1.0 / ((n + 1) * (n + 2)) for n in range(64)])


def supports(model) -> bool:
    """The kernel solves this model: constant coefficients (no stiffness profile)."""
    return getattr(model, "stiffness_profile", None) is None


# ---------------------------------------------------------------- small polynomial helpers
@njit(cache=True)
def _horner(c, n, x):
    acc = 0.0
    for i in range(n - 1, -1, -1):
        acc = acc * x + c[i]
    return acc


@njit(cache=True)
def _plain_sum(c, n):
    acc = 0.0
    for i in range(n):
        acc += c[i]
    return acc


@njit(cache=True)
def _fsum(c, n):
    """Compensated (Neumaier) sum: math.fsum's role in exact.py (a moving phase's first step)."""
    s = 0.0
    comp = 0.0
    for i in range(n):
        x = c[i]
        t = s + x
        if abs(s) >= abs(x):
            comp += (s - t) + x
        else:
            comp += (x - t) + s
        s = t
    return s + comp


@njit(cache=True)
def _deriv_into(c, n, h, out):
    inv = 1.0 / h
    for k in range(1, n):
        out[k - 1] = k * c[k] * inv
    out[n - 1] = 0.0


@njit(cache=True)
def _shift_into(P, u0, out):
    """exact_events.shift_list: coefficients in w of P(u0 + (1 - u0) w)."""
    p0, p1, p2, p3, p4, p5 = P[0], P[1], P[2], P[3], P[4], P[5]
    if u0 == 0.0:
        out[0], out[1], out[2], out[3], out[4], out[5] = p0, p1, p2, p3, p4, p5
        return
    u = u0
    l1 = 1.0 - u0
    l2 = l1 * l1
    l3 = l2 * l1
    l4 = l3 * l1
    out[0] = ((((p5 * u + p4) * u + p3) * u + p2) * u + p1) * u + p0
    out[1] = ((((5.0 * p5 * u + 4.0 * p4) * u + 3.0 * p3) * u + 2.0 * p2) * u + p1) * l1
    out[2] = (((10.0 * p5 * u + 6.0 * p4) * u + 3.0 * p3) * u + p2) * l2
    out[3] = ((10.0 * p5 * u + 4.0 * p4) * u + p3) * l3
    out[4] = (5.0 * p5 * u + p4) * l4
    out[5] = p5 * (l4 * l1)


@njit(cache=True)
def _expand(m, c, K, kc, cc, P, h, s, v, Fc, N, a, f):
    """exact_steps.expand_step: scaled Taylor coefficients a[0..N] of s over one step from (s, v)."""
    h2m = h * h / m
    beta = K * h2m
    for n in range(f.size):
        f[n] = 0.0
    if cc != 0.0:
        ch = cc / h
        for n in range(5):
            f[n] = (kc * P[n] + ch * (n + 1) * P[n + 1]) * h2m
        f[5] = kc * P[5] * h2m
    else:
        for n in range(6):
            f[n] = kc * P[n] * h2m
    f[0] -= Fc * h2m
    a[0] = s
    a[1] = v * h
    a0 = s
    a1 = v * h
    if c != 0.0:
        alpha = c * h / m
        for n in range(N - 1):
            nxt = (f[n] - alpha * (n + 1) * a1 - beta * a0) * _INV_PAIR[n]
            a0 = a1
            a1 = nxt
            a[n + 2] = a1
    else:
        for n in range(N - 1):
            nxt = (f[n] - beta * a0) * _INV_PAIR[n]
            a0 = a1
            a1 = nxt
            a[n + 2] = a1


@njit(cache=True)
def _step_tables(m, c, K, kc, cc, h_unique, N):
    """Per step length: Phi (end value and slope of the responses to s0 = 1 and v0 = 1), g1 (to a
    unit constant forcing) and W_P (to the drive P = u^k): exact_steps' tables at u = 1, in the
    columns [Phi00 Phi01 Phi10 Phi11 g0 g1 W0_0..5 W1_0..5]."""
    U = h_unique.size
    out = np.zeros((U, 18))
    a = np.zeros(N + 1)
    f = np.zeros(6)
    for u in range(U):
        hu = h_unique[u]
        h2 = hu * hu
        ch = c * hu
        Kh2 = K * h2
        for b in range(9):
            for n in range(N + 1):
                a[n] = 0.0
            for n in range(6):
                f[n] = 0.0
            if b == 0:
                a[0] = 1.0
            elif b == 1:
                a[1] = hu
            elif b == 2:
                f[0] = 1.0
            else:
                k = b - 3
                f[k] += kc
                if k >= 1:
                    f[k - 1] += cc * k / hu
            for n in range(N - 1):
                rhs = -ch * (n + 1) * a[n + 1] - Kh2 * a[n]
                if n < 6:
                    rhs = rhs + h2 * f[n]
                a[n + 2] = rhs / (m * (n + 1) * (n + 2))
            end = 0.0
            slope = 0.0
            for n in range(N + 1):
                end += a[n]
                slope += n * a[n]
            slope /= hu
            if b == 0:
                out[u, 0] = end
                out[u, 2] = slope
            elif b == 1:
                out[u, 1] = end
                out[u, 3] = slope
            elif b == 2:
                out[u, 4] = end
                out[u, 5] = slope
            else:
                out[u, 6 + b - 3] = end
                out[u, 12 + b - 3] = slope
    return out


# ---------------------------------------------------------------- bounds and roots (exact_events.py)
@njit(cache=True)
def _qmax1(d, B, D):
    val = max(d * D + 0.5 * B * D * D, 0.0)
    if B < 0.0 and 0.0 < -d / B < D:
        val = max(val, -0.5 * d * d / B)
    return val


@njit(cache=True)
def _excluded(Ea, Da, Eb, Db, B2, D):
    if max(Ea, Eb) + max(B2, 0.0) * D * D / 8.0 <= 0.0:
        return True
    return min(Ea + _qmax1(Da, B2, D), Eb + _qmax1(-Db, B2, D)) <= 0.0


@njit(cache=True)
def _excluded1(e, n, Eb):
    Ea = e[0]
    B2 = 2.0 * e[2]
    for i in range(3, n):
        en = e[i]
        if en > 0.0:
            B2 += i * (i - 1.0) * en
    if (Ea if Ea > Eb else Eb) + (0.125 * B2 if B2 > 0.0 else 0.0) <= 0.0:
        return True
    Db = 0.0
    for i in range(n):
        Db += i * e[i]
    return min(Ea + _qmax1(e[1], B2, 1.0), Eb + _qmax1(-Db, B2, 1.0)) <= 0.0


@njit(cache=True)
def _excluded_range(e, n, lo, hi):
    Ea = 0.0
    Da = 0.0
    Eb = 0.0
    Db = 0.0
    B2 = 0.0
    plo = 1.0
    phi = 1.0
    for i in range(n):
        if i >= 2:
            B2 += i * (i - 1.0) * max(e[i] * plo, e[i] * phi)
            plo *= lo
            phi *= hi
    for i in range(n - 1, -1, -1):
        Ea = Ea * lo + e[i]
        Eb = Eb * hi + e[i]
    for i in range(n - 1, 0, -1):
        Da = Da * lo + i * e[i]
        Db = Db * hi + i * e[i]
    D = hi - lo
    if max(Ea, Eb) + max(B2, 0.0) * D * D / 8.0 <= 0.0:
        return True
    return min(Ea + _qmax1(Da, B2, D), Eb + _qmax1(-Db, B2, D)) <= 0.0


@njit(cache=True)
def _rising_range(e, n, lo, hi):
    if lo == 0.0:
        B2lo = 2.0 * e[2]
        phi = hi
        for i in range(3, n):
            en = e[i] * phi
            if en < 0.0:
                B2lo += i * (i - 1.0) * en
            phi *= hi
        return e[1] + (B2lo if B2lo < 0.0 else 0.0) * hi > 0.0
    d = 0.0
    for i in range(n - 1, 0, -1):
        d = d * lo + i * e[i]
    B2lo = 0.0
    plo = 1.0
    phi = 1.0
    for i in range(2, n):
        B2lo += i * (i - 1.0) * min(e[i] * plo, e[i] * phi)
        plo *= lo
        phi *= hi
    return d + min(0.0, B2lo) * (hi - lo) > 0.0


@njit(cache=True)
def _root_rising(e, n, lo, hi, xtol, flo, fhi):
    x = lo
    if fhi > flo:
        x = lo - flo * (hi - lo) / (fhi - flo)
        if not (lo <= x < hi):
            x = lo
    for _ in range(100):
        fx = e[n - 1]
        dx = 0.0
        for i in range(n - 2, -1, -1):
            dx = dx * x + fx
            fx = fx * x + e[i]
        if fx > 0.0:
            hi = x
        else:
            lo = x
        tol = xtol + 4.0 * EPS * hi
        if hi - lo <= tol:
            break
        x_new = x - fx / dx if dx > 0.0 else 0.5 * (lo + hi)
        if abs(x_new - x) < tol:
            x_new += tol if fx <= 0.0 else -tol
        if not (lo < x_new < hi):
            x_new = 0.5 * (lo + hi)
        x = x_new
    return hi


@njit(cache=True)
def _combined(E, r0, nr, comb, n, x):
    val = _horner(E[r0], n, x)
    for r in range(r0 + 1, r0 + nr):
        y = _horner(E[r], n, x)
        if comb == MIN:
            val = min(val, y)
        else:
            val = max(val, y)
    return val


@njit(cache=True)
def _illinois(E, r0, nr, comb, n, lo, hi, flo, fhi, xtol):
    side = 0
    for _ in range(200):
        if hi - lo <= xtol + 4.0 * EPS * abs(hi):
            break
        x = hi - fhi * (hi - lo) / (fhi - flo) if fhi != flo else 0.5 * (lo + hi)
        if not (lo < x < hi):
            x = 0.5 * (lo + hi)
        fx = _combined(E, r0, nr, comb, n, x)
        if fx > 0.0:
            hi = x
            fhi = fx
            if side == 1:
                flo *= 0.5
            side = 1
        else:
            lo = x
            flo = fx
            if side == -1:
                fhi *= 0.5
            side = -1
    return hi


@njit(cache=True)
def _brent(E, r0, nr, comb, n, lo, hi, xtol):
    flo = _combined(E, r0, nr, comb, n, lo)
    if flo > 0.0:
        return lo
    if flo == 0.0:
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if mid <= lo or mid >= hi:
                break
            if _combined(E, r0, nr, comb, n, mid) > 0.0:
                hi = mid
            else:
                lo = mid
        return hi
    return _illinois(E, r0, nr, comb, n, lo, hi, flo, _combined(E, r0, nr, comb, n, hi), xtol)


@njit(cache=True)
def _positive_at(E, r0, nr, comb, n, w):
    best = 0.0
    for r in range(r0, r0 + nr):
        val = 0.0
        mag = 0.0
        for i in range(n - 1, -1, -1):
            val = val * w + E[r, i]
            mag = mag * w + abs(E[r, i])
        if not (abs(val) > 1e-12 * mag):
            return False
        if r == r0:
            best = val
        elif comb == MIN:
            best = min(best, val)
        else:
            best = max(best, val)
    return best > 0.0


@njit(cache=True)
def _start_clearance(e, n):
    big = 0.0
    for i in range(n):
        big = max(big, abs(e[i]))
    k = -1
    for i in range(n):
        if abs(e[i]) > 1e-9 * big:
            k = i
            break
    if k < 0 or e[k] > 0.0:
        return 0.0

    def phi(w):
        acc = 0.0
        for i in range(n - 1, k, -1):
            acc = acc * w + max(e[i], 0.0)
        return e[k] + w * acc

    if phi(1.0) < 0.0:
        return 1.0
    lo = 0.0
    hi = 1.0
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        if phi(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def _monotone(E, r0, nr, comb, n, lo, hi, d_lo):
    if comb != ONE:
        return False
    B2lo = 0.0
    for i in range(2, n):
        w = i * (i - 1.0) * E[r0, i]
        B2lo += min(w * lo ** (i - 2.0), w * hi ** (i - 2.0))
    return d_lo + min(0.0, B2lo) * (hi - lo) > 0.0


@njit(cache=True)
def _value_slope(e, n, x):
    fx = e[n - 1]
    dx = 0.0
    for i in range(n - 2, -1, -1):
        dx = dx * x + fx
        fx = fx * x + e[i]
    return fx, dx


@njit(cache=True)
def _piece(a, b, p):
    """Ends of the p-th of SUBDIVISIONS pieces of [a, b]."""
    lo = a + (b - a) * p / SUBDIVISIONS
    hi = b if p + 1 == SUBDIVISIONS else a + (b - a) * (p + 1) / SUBDIVISIONS
    return lo, hi


@njit(cache=True)
def _search(E, r0, nr, comb, n, a, b, xtol):
    """exact_events._first_root/_search: the first w in [a, b] where the combined function turns
    > 0, or -1.0. Each level splits an interval into SUBDIVISIONS pieces; a piece is skipped when
    the coefficient bound excludes a zero there, else refined (to MAX_DEPTH levels) and polished.
    The recursion of exact_events._search with an explicit stack (numba's cache does not keep
    recursive functions)."""
    sa = np.empty(MAX_DEPTH + 1)
    sb = np.empty(MAX_DEPTH + 1)
    sp = np.zeros(MAX_DEPTH + 1, dtype=np.int64)
    sbrent = np.zeros(MAX_DEPTH + 1, dtype=np.bool_)
    d = 0
    sa[0] = a
    sb[0] = b
    sp[0] = 0
    while d >= 0:
        if sp[d] >= SUBDIVISIONS:  # this level found nothing
            d -= 1
            if d >= 0 and sbrent[d]:  # its interval brackets a crossing: polish it
                return _brent(E, r0, nr, comb, n, sa[d + 1], sb[d + 1], xtol)
            continue
        lo, hi = _piece(sa[d], sb[d], sp[d])
        sp[d] += 1
        sbrent[d] = False
        ex_all = True
        ex_any = False
        cv0 = 0.0
        cv1 = 0.0
        d_lo = 0.0
        for r in range(nr):
            f0, d0 = _value_slope(E[r0 + r], n, lo)
            f1, d1 = _value_slope(E[r0 + r], n, hi)
            B2 = 0.0
            for i in range(2, n):
                w2 = E[r0 + r, i] * (i * (i - 1.0))
                B2 += max(lo ** (i - 2) * w2, hi ** (i - 2) * w2)
            ex = _excluded(f0, d0, f1, d1, B2, hi - lo)
            ex_all = ex_all and ex
            ex_any = ex_any or ex
            if r == 0:
                cv0, cv1, d_lo = f0, f1, d0
            elif comb == MIN:
                cv0, cv1 = min(cv0, f0), min(cv1, f1)
            else:
                cv0, cv1 = max(cv0, f0), max(cv1, f1)
        if (ex_any if comb == MIN else ex_all):
            continue
        if cv0 > 0.0:
            return lo
        if cv1 > 0.0:
            if d < MAX_DEPTH and not _monotone(E, r0, nr, comb, n, lo, hi, d_lo):
                sbrent[d] = True
                d += 1
                sa[d], sb[d], sp[d] = lo, hi, 0
                continue
            return _brent(E, r0, nr, comb, n, lo, hi, xtol)
        if d < MAX_DEPTH:
            d += 1
            sa[d], sb[d], sp[d] = lo, hi, 0
    return -1.0


@njit(cache=True)
def _earliest(E, n, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros, t_abs, h_loc):
    """exact_events.earliest: the first event of a step (E: each row's coefficients over w in
    [0, 1]; check: the events to search). Returns (kind, w), kind -1: none."""
    best_kind = -1
    best_w = 0.0
    for q in range(n_ev):
        if not check[q]:
            continue
        r0 = ev_r0[q]
        nr = ev_nr[q]
        comb = ev_comb[q]
        w_lo = 0.0
        if zeros[q]:
            ex_all = True
            ex_any = False
            for r in range(r0, r0 + nr):
                ex = _excluded1(E[r], n, _plain_sum(E[r], n))
                ex_all = ex_all and ex
                ex_any = ex_any or ex
            if (ex_any if comb == MIN else ex_all):
                continue
            first = True
            for r in range(r0, r0 + nr):
                cl = _start_clearance(E[r], n) if E[r, 0] == 0.0 else 0.0
                if first:
                    w_lo = cl
                    first = False
                elif comb == MIN:
                    w_lo = max(w_lo, cl)
                else:
                    w_lo = min(w_lo, cl)
            if w_lo >= 1.0:
                continue
        e_lo = 0.0
        e_hi = 0.0
        if nr == 1:
            e = E[r0]
            e_lo = e[0] if w_lo == 0.0 else _horner(e, n, w_lo)
            e_hi = _plain_sum(e, n)
            if not (e_lo <= 0.0 < e_hi):
                if (_excluded1(e, n, e_hi) if w_lo == 0.0 else _excluded_range(e, n, w_lo, 1.0)):
                    continue
        else:
            ex_all = True
            ex_any = False
            for r in range(r0, r0 + nr):
                ex = _excluded1(E[r], n, _plain_sum(E[r], n)) if w_lo == 0.0 else _excluded_range(E[r], n, w_lo, 1.0)
                ex_all = ex_all and ex
                ex_any = ex_any or ex
            if (ex_any if comb == MIN else ex_all):
                continue
        xtol = max(0.5 * _ulp(abs(t_abs)) / h_loc, 1e-300) if h_loc > 0.0 else 1e-300
        if comb == ONE and e_lo <= 0.0 < e_hi and _rising_range(E[r0], n, w_lo, 1.0):
            w = _root_rising(E[r0], n, w_lo, 1.0, xtol, e_lo, e_hi)
        elif _positive_at(E, r0, nr, comb, n, w_lo):
            w = w_lo
        else:
            w = _search(E, r0, nr, comb, n, w_lo, 1.0, xtol)
            if w < 0.0:
                continue
        kind = ev_kind[q]
        if best_kind < 0:
            best_kind = kind
            best_w = w
            continue
        tie = abs(w - best_w) <= 1e-9 * max(w, 1e-300) + 64.0 * EPS
        if (w < best_w and not (tie and best_kind == SEAT)) or (tie and kind == SEAT):
            best_kind = kind
            best_w = w
    return best_kind, best_w


@njit(cache=True)
def _ulp(x):
    return np.nextafter(x, np.inf) - x


# ---------------------------------------------------------------- event tables (phases.py's rules)
@njit(cache=True)
def _moving_table(kind, k, c, lash, R, sigma, rows, ev_kind, ev_r0, ev_nr, ev_comb):
    """phases.moving_events as rows (aP, bP, const, l0, l1) (exact_events.event_of)."""
    n_ev = 0
    nrow = 0
    if kind == CONTACT:  # separation: -force
        rows[0, 0], rows[0, 1], rows[0, 2], rows[0, 3], rows[0, 4] = -k, -c, k * lash, k, c
        ev_kind[0], ev_r0[0], ev_nr[0], ev_comb[0] = SEPARATION, 0, 1, ONE
        nrow = 1
    elif c > 0.0:  # re-contact: min(gap, force)
        rows[0, 0], rows[0, 1], rows[0, 2], rows[0, 3], rows[0, 4] = k, 0.0, -k * lash, -k, 0.0
        rows[1, 0], rows[1, 1], rows[1, 2], rows[1, 3], rows[1, 4] = k, c, -k * lash, -k, -c
        ev_kind[0], ev_r0[0], ev_nr[0], ev_comb[0] = RECONTACT, 0, 2, MIN
        nrow = 2
    else:
        rows[0, 0], rows[0, 1], rows[0, 2], rows[0, 3], rows[0, 4] = k, 0.0, -k * lash, -k, 0.0
        ev_kind[0], ev_r0[0], ev_nr[0], ev_comb[0] = RECONTACT, 0, 1, ONE
        nrow = 1
    n_ev = 1
    rows[nrow, 0], rows[nrow, 1], rows[nrow, 2], rows[nrow, 3], rows[nrow, 4] = 0.0, 0.0, 0.0, -1.0, 0.0
    ev_kind[1], ev_r0[1], ev_nr[1], ev_comb[1] = SEAT, nrow, 1, ONE
    nrow += 1
    n_ev = 2
    if R > 0.0:
        rows[nrow, 0], rows[nrow, 1], rows[nrow, 2], rows[nrow, 3], rows[nrow, 4] = 0.0, 0.0, 0.0, 0.0, -sigma
        ev_kind[2], ev_r0[2], ev_nr[2], ev_comb[2] = VZERO, nrow, 1, ONE
        nrow += 1
        n_ev = 3
    return n_ev, nrow


@njit(cache=True)
def _static_table(s_star, k, c, lash, W0, rate, R, rows, ev_kind, ev_r0, ev_nr, ev_comb):
    """phases.rest_events (gap_check with damping) as rows."""
    nrow = 0
    thr_up = W0 + rate * s_star + R
    if c > 0.0:
        rows[0, 0], rows[0, 1], rows[0, 2], rows[0, 3], rows[0, 4] = k, 0.0, -k * (lash + s_star), 0.0, 0.0
        nrow = 1
    rows[nrow, 0], rows[nrow, 1], rows[nrow, 2], rows[nrow, 3], rows[nrow, 4] = (
        k, c, -k * (lash + s_star) - thr_up, 0.0, 0.0)
    nrow += 1
    ev_kind[0], ev_r0[0], ev_nr[0], ev_comb[0] = UP, 0, nrow, (MIN if nrow > 1 else ONE)
    n_ev = 1
    thr_dn = W0 + rate * s_star - R
    if s_star > 0.0 and thr_dn > 0.0:
        r0 = nrow
        if c > 0.0:
            rows[nrow, 0], rows[nrow, 1], rows[nrow, 2], rows[nrow, 3], rows[nrow, 4] = (
                -k, 0.0, k * (lash + s_star), 0.0, 0.0)
            nrow += 1
        rows[nrow, 0], rows[nrow, 1], rows[nrow, 2], rows[nrow, 3], rows[nrow, 4] = (
            -k, -c, k * (lash + s_star) + thr_dn, 0.0, 0.0)
        nrow += 1
        ev_kind[1], ev_r0[1], ev_nr[1], ev_comb[1] = DOWN, r0, nrow - r0, (MAX if nrow - r0 > 1 else ONE)
        n_ev = 2
    return n_ev, nrow


@njit(cache=True)
def _coeffs(rows, nrow, P, dP, a, da, n, E, start, s0, v0, zr):
    """exact_events.coeff_list of every row over a step (a, da None at rest: n = 6 then);
    start: exact_events.start_coeffs (components on their zero up to rounding set to 0; zr[r])."""
    for r in range(nrow):
        aP, bP, const, l0, l1 = rows[r, 0], rows[r, 1], rows[r, 2], rows[r, 3], rows[r, 4]
        for i in range(n):
            E[r, i] = l0 * a[i] + l1 * da[i]
        for i in range(6):
            E[r, i] += aP * P[i] + bP * dP[i]
        E[r, 0] += const
        zr[r] = False
        if start:
            scale = abs(aP * P[0]) + abs(const)
            if bP != 0.0:
                scale += abs(bP * dP[0])
            if l0 != 0.0:
                scale += abs(l0 * s0)
            if l1 != 0.0:
                scale += abs(l1 * v0)
            if abs(E[r, 0]) <= ZERO_START * scale:
                E[r, 0] = 0.0
                zr[r] = True


@njit(cache=True)
def _zero_flags(E, zr, ev_r0, ev_nr, ev_comb, n_ev, zeros):
    for q in range(n_ev):
        r0 = ev_r0[q]
        nr = ev_nr[q]
        anyz = False
        for r in range(r0, r0 + nr):
            anyz = anyz or zr[r]
        if nr == 1:
            zeros[q] = anyz
        else:
            st = E[r0, 0]
            for r in range(r0 + 1, r0 + nr):
                st = min(st, E[r, 0]) if ev_comb[q] == MIN else max(st, E[r, 0])
            zeros[q] = anyz and st == 0.0


# ---------------------------------------------------------------- the solver
@njit(cache=True)
def _span(x, lo, hi):
    """The range of x y for y in [lo, hi]."""
    p = x * lo
    q = x * hi
    return min(p, q), max(p, q)


@njit(cache=True)
def _step(tabs, kind, g, PTq, Fc, s, v):
    """The state one step later: x1 = Phi x + (drive part - Fc g). The drive's and the constant
    force's part does not depend on the state: summed first, so that the chain carried from step
    to step (s, v -> s1, v1) is one multiply and two adds long, not nine operations (the adds are
    not reassociated for us: no fastmath)."""
    ds = -Fc * tabs[kind, g, 4]
    dv = -Fc * tabs[kind, g, 5]
    for p in range(6):
        ds += tabs[kind, g, 6 + p] * PTq[p]
        dv += tabs[kind, g, 12 + p] * PTq[p]
    return (tabs[kind, g, 0] * s + tabs[kind, g, 1] * v) + ds, (tabs[kind, g, 2] * s + tabs[kind, g, 3] * v) + dv


@njit(cache=True)
def _window_clear(S_lo, S_hi, D_lo, D_hi, b1, b2, b3, s_lo, s_hi, v_lo, v_hi, m, c, K, kc, cc, Fc, inv_m, H, inv1q,
                  H8, rows, ev_r0, ev_nr, ev_comb, n_ev, clear_row):
    """Every event of a moving phase cleared over a window of steps: each row's bound
    max e + H^2/8 sup|e''| <= 0 with the largest e from the ranges of S, S1 (D) at the window's nodes
    and of the states s, v there, and sup|e''| from the per-step bound's |a| and |jerk| bounds
    (exact_phase._scan_window) taken over the same ranges and the largest |S'|, |S''|, |S'''| (b1,
    b2, b3) and step (H, 1 / (1 - q), H^2/8): each term is at least the per-step bound's of every
    step of the window. The rows combine into events as in the per-step clearing."""
    V = max(abs(v_lo), abs(v_hi))
    # |kc S + cc S1 - Fc - K s - c v| at any node of the window
    lo, hi = _span(kc, S_lo, S_hi)
    x_lo, x_hi = _span(cc, D_lo, D_hi)
    lo += x_lo
    hi += x_hi
    x_lo, x_hi = _span(-K, s_lo, s_hi)
    lo += x_lo
    hi += x_hi
    x_lo, x_hi = _span(-c, v_lo, v_hi)
    lo += x_lo - Fc
    hi += x_hi - Fc
    Ac = max(abs(lo), abs(hi))
    F1 = abs(kc) * b1 + abs(cc) * b2
    A = (Ac + H * (F1 + abs(K) * V)) * inv_m * inv1q
    J = (F1 + abs(c) * A + abs(K) * (V + H * A)) * inv_m
    for r in range(4):
        a_, b_, k_, l_, m_ = rows[r, 0], rows[r, 1], rows[r, 2], rows[r, 3], rows[r, 4]
        top = k_ + _span(a_, S_lo, S_hi)[1] + _span(b_, D_lo, D_hi)[1] + _span(l_, s_lo, s_hi)[1] \
            + _span(m_, v_lo, v_hi)[1]
        clear_row[r] = top + H8 * (abs(a_) * b2 + abs(b_) * b3 + abs(l_) * A + abs(m_) * J) <= 0.0
    for q in range(n_ev):
        cl = clear_row[ev_r0[q]]
        for r in range(ev_r0[q] + 1, ev_r0[q] + ev_nr[q]):
            cl = (cl or clear_row[r]) if ev_comb[q] == MIN else (cl and clear_row[r])
        if not cl:
            return False
    return True


@njit(cache=True)
def _grow(ev, n):
    if n < ev.shape[0]:
        return ev
    new = np.full((2 * ev.shape[0], 4), np.nan)
    new[:ev.shape[0]] = ev
    return new


@njit(cache=True)
def _time(nodes, h, ns, j, u):
    if j >= ns:
        return nodes[ns]
    return nodes[j] + u * h[j]


@njit(cache=True)
def _drive_at(PT, Dn, h, ns, j, u, tmp):
    if j >= ns:
        return Dn[0, ns], Dn[1, ns]
    P = PT[j]
    _deriv_into(P, 6, h[j], tmp)
    return _horner(P, 6, u), _horner(tmp, 6, u)


@njit(cache=True)
def grid_bounds(h, Dn, Sb):
    """What the block and window bounds read of a grid, computed once per grid (a sweep's runs
    share it; solve_nodes scales it to its speed sw1, each entry by a positive factor, under which
    the largest value stays the largest):
    blk (per BLOCK steps, the seated valve's block clearance): the largest S and S1 at its nodes
    and the largest h^2/8 |S2| and h^2/8 |S3| over its steps (at the speed sw1: times 1, sw1, 1,
    sw1, for h in time is h in angle / sw1);
    win (per WINDOW steps, the moving valve's window bound): the smallest and largest S and S1 at
    its nodes and the largest bounds of |S1|, |S2|, |S3| over its steps (times 1, 1, sw1, sw1,
    sw1, sw1^2, sw1^3)."""
    ns = h.size
    nb = ns // BLOCK
    blk = np.full((4, max(nb, 1)), -np.inf)
    for bk in range(nb):
        for i in range(bk * BLOCK, bk * BLOCK + BLOCK + 1):
            blk[0, bk] = max(blk[0, bk], Dn[0, i])
            blk[1, bk] = max(blk[1, bk], Dn[1, i])
        for i in range(bk * BLOCK, bk * BLOCK + BLOCK):
            hh = h[i] * h[i] / 8.0
            blk[2, bk] = max(blk[2, bk], hh * Sb[1, i])
            blk[3, bk] = max(blk[3, bk], hh * Sb[2, i])
    nw = ns // WINDOW
    win = np.empty((7, max(nw, 1)))
    for wb in range(nw):
        i = wb * WINDOW
        s_lo = s_hi = Dn[0, i]
        d_lo = d_hi = Dn[1, i]
        for q in range(i + 1, i + WINDOW + 1):
            s_lo = min(s_lo, Dn[0, q])
            s_hi = max(s_hi, Dn[0, q])
            d_lo = min(d_lo, Dn[1, q])
            d_hi = max(d_hi, Dn[1, q])
        b1 = b2 = b3 = 0.0
        for q in range(i, i + WINDOW):
            b1 = max(b1, Sb[0, q])
            b2 = max(b2, Sb[1, q])
            b3 = max(b3, Sb[2, q])
        win[0, wb], win[1, wb], win[2, wb], win[3, wb] = s_lo, s_hi, d_lo, d_hi
        win[4, wb], win[5, wb], win[6, wb] = b1, b2, b3
    return blk, win


@njit(cache=True)
def solve_nodes(nodes, h, PT, Dn, Sb, sw1, hidx, h_unique, M, M1, k, c, lash, W0, rate, R, e, zeno_height, max_events,
                N, blk, win):
    """The node records (s, v, friction sign, phase code) and the events (rows: code, time,
    velocity, Zeno accumulation time or NaN) of one run over the grid (exact_grid.build_grid's
    nodes, h, P.T, Dn, hidx, h_unique; Sb its bounds of the drive's first three derivatives per
    step, times sw1, sw1^2, sw1^3: a grid in cam angle at the speed sw1), starting at rest on the
    seat; and a status (OK, or TOO_MANY_EVENTS / NO_PROGRESS: exact.py's RuntimeErrors).
    blk, win: grid_bounds of the grid at the speed 1."""
    ns = h.size
    nn = ns + 1
    U = h_unique.size
    sw2 = sw1 * sw1
    sw3 = sw2 * sw1
    grp_H = np.empty(U)
    grp_q = np.empty(U)
    grp_inv1q = np.empty(U)
    grp_H8 = np.empty(U)
    out_s = np.full(nn, np.nan)
    out_v = np.full(nn, np.nan)
    out_sigma = np.ones(nn)
    out_phase = np.full(nn, -1, dtype=np.int8)
    ev = np.full((16, 4), np.nan)
    n_events = 0
    # per phase kind: m, c, K, kc, cc (exact.py's LinearPhase) and the one-step tables
    lin = np.empty((3, 5))
    lin[CONTACT, 0], lin[CONTACT, 1], lin[CONTACT, 2], lin[CONTACT, 3], lin[CONTACT, 4] = M1, c, k + rate, k, c
    lin[FLIGHT, 0], lin[FLIGHT, 1], lin[FLIGHT, 2], lin[FLIGHT, 3], lin[FLIGHT, 4] = M, 0.0, rate, 0.0, 0.0
    tabs = np.zeros((3, h_unique.size, 18))
    tabs[CONTACT] = _step_tables(M1, c, k + rate, k, c, h_unique, N)
    tabs[FLIGHT] = _step_tables(M, 0.0, rate, 0.0, 0.0, h_unique, N)
    NC = N + 1
    a = np.zeros(NC)
    da = np.zeros(NC)
    f = np.zeros(max(6, NC))
    Pw = np.zeros(6)
    dP = np.zeros(6)
    tmp = np.zeros(6)
    zero6 = np.zeros(NC)
    rows = np.zeros((4, 5))
    E = np.zeros((4, NC))
    zr = np.zeros(4, dtype=np.bool_)
    ev_kind = np.zeros(4, dtype=np.int64)
    ev_r0 = np.zeros(4, dtype=np.int64)
    ev_nr = np.zeros(4, dtype=np.int64)
    ev_comb = np.zeros(4, dtype=np.int64)
    zeros = np.zeros(4, dtype=np.bool_)
    check = np.zeros(4, dtype=np.bool_)
    clear_row = np.zeros(4, dtype=np.bool_)
    E1 = np.zeros(4)

    phase = SEATED
    s = 0.0
    v = 0.0
    sigma = 1.0
    j = 0
    u = 0.0
    release = False
    same_time = 0
    last_time = np.nan
    status = OK
    n_detail = 0  # steps searched in detail (the bound did not clear them)
    while True:
        if n_events > max_events:
            status = TOO_MANY_EVENTS
            break
        which = -1
        if phase == SEATED or phase == STUCK:
            # ------------------------------------------------ at rest (exact_phase._run_static)
            s_star = s
            found = False
            if W0 + rate * s_star + R < 0.0:
                which = UP
                found = True
            elif j >= ns:
                for q in range(j, nn):
                    out_s[q] = s_star
                    out_v[q] = 0.0
                    out_phase[q] = phase
            else:
                n_ev, nrow = _static_table(s_star, k, c, lash, W0, rate, R, rows, ev_kind, ev_r0, ev_nr, ev_comb)
                u0 = u
                _shift_into(PT[j], u0, Pw)
                h_loc = (1.0 - u0) * h[j]
                _deriv_into(Pw, 6, h_loc, dP)
                _coeffs(rows, nrow, Pw, dP, zero6, zero6, 6, E, True, s_star, 0.0, zr)
                _zero_flags(E, zr, ev_r0, ev_nr, ev_comb, n_ev, zeros)
                for q in range(n_ev):
                    check[q] = True
                kind_b, w = _earliest(E, 6, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros,
                                      _time(nodes, h, ns, j, u0), h_loc)
                if u0 == 0.0:
                    out_s[j] = s_star
                    out_v[j] = 0.0
                    out_phase[j] = phase
                if kind_b >= 0:
                    which = kind_b
                    u = u0 + w * (1.0 - u0)
                    found = True
                else:
                    for q in range(n_ev):
                        zeros[q] = False
                    # the rows as scalars (padded to 4 with a row that is always -1): the loop
                    # below is straight-line code on registers
                    for r in range(nrow, 4):
                        rows[r, 0], rows[r, 1], rows[r, 2], rows[r, 3], rows[r, 4] = 0.0, 0.0, -1.0, 0.0, 0.0
                    a0_, b0_, k0_ = rows[0, 0], rows[0, 1], rows[0, 2]
                    a1_, b1_, k1_ = rows[1, 0], rows[1, 1], rows[1, 2]
                    a2_, b2_, k2_ = rows[2, 0], rows[2, 1], rows[2, 2]
                    a3_, b3_, k3_ = rows[3, 0], rows[3, 1], rows[3, 2]
                    i = j + 1
                    e0a = e0b = e0c = e0d = -1.0
                    if i < nn:
                        D0, D1 = Dn[0, i], Dn[1, i]
                        e0a = a0_ * D0 + b0_ * D1 + k0_
                        e0b = a1_ * D0 + b1_ * D1 + k1_
                        e0c = a2_ * D0 + b2_ * D1 + k2_
                        e0d = a3_ * D0 + b3_ * D1 + k3_
                    # a valve held only by the "up" event (no "down"): whole blocks of steps are
                    # cleared at once by the push row's bound over the block (the drive's largest
                    # S and S1 at its nodes, plus the largest sag k h^2/8 |S2| + c h^2/8 |S3|)
                    ap_, bp_, kp_ = rows[nrow - 1, 0], rows[nrow - 1, 1], rows[nrow - 1, 2]
                    blocks_ok = n_ev == 1 and ap_ >= 0.0 and bp_ >= 0.0
                    while i < ns:
                        if blocks_ok and i % BLOCK == 0 and i + BLOCK <= ns:
                            bk = i // BLOCK
                            if ap_ * (blk[0, bk] + blk[2, bk]) + bp_ * ((blk[1, bk] + blk[3, bk]) * sw1) + kp_ <= 0.0:
                                for q in range(i, i + BLOCK):
                                    out_s[q] = s_star
                                    out_v[q] = 0.0
                                    out_phase[q] = phase
                                i += BLOCK
                                if i < nn:
                                    D0, D1 = Dn[0, i], Dn[1, i]
                                    e0a = a0_ * D0 + b0_ * D1 + k0_
                                    e0b = a1_ * D0 + b1_ * D1 + k1_
                                    e0c = a2_ * D0 + b2_ * D1 + k2_
                                    e0d = a3_ * D0 + b3_ * D1 + k3_
                                continue
                        out_s[i] = s_star
                        out_v[i] = 0.0
                        out_phase[i] = phase
                        h_i = h[i]
                        b2 = Sb[1, i] * sw2
                        b3 = Sb[2, i] * sw3
                        H8 = h_i * h_i / 8.0
                        D0, D1 = Dn[0, i + 1], Dn[1, i + 1]
                        e1a = a0_ * D0 + b0_ * D1 + k0_
                        e1b = a1_ * D0 + b1_ * D1 + k1_
                        e1c = a2_ * D0 + b2_ * D1 + k2_
                        e1d = a3_ * D0 + b3_ * D1 + k3_
                        ca = max(e0a, e1a) + H8 * (abs(a0_) * b2 + abs(b0_) * b3) <= 0.0
                        cb = max(e0b, e1b) + H8 * (abs(a1_) * b2 + abs(b1_) * b3) <= 0.0
                        cc = max(e0c, e1c) + H8 * (abs(a2_) * b2 + abs(b2_) * b3) <= 0.0
                        cd = max(e0d, e1d) + H8 * (abs(a3_) * b2 + abs(b3_) * b3) <= 0.0
                        e0a, e0b, e0c, e0d = e1a, e1b, e1c, e1d
                        any_open = False
                        if not (ca and cb and cc and cd):
                            clear_row[0], clear_row[1], clear_row[2], clear_row[3] = ca, cb, cc, cd
                            for q in range(n_ev):
                                cl = clear_row[ev_r0[q]]
                                for r in range(ev_r0[q] + 1, ev_r0[q] + ev_nr[q]):
                                    cl = (cl or clear_row[r]) if ev_comb[q] == MIN else (cl and clear_row[r])
                                check[q] = not cl
                                any_open = any_open or check[q]
                        if any_open:
                            n_detail += 1
                            _deriv_into(PT[i], 6, h_i, dP)
                            _coeffs(rows, nrow, PT[i], dP, zero6, zero6, 6, E, False, 0.0, 0.0, zr)
                            kind_b, w = _earliest(E, 6, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros,
                                                  nodes[i], h_i)
                            if kind_b >= 0:  # (at w = 0 the next phase records node i again)
                                which = kind_b
                                j = i
                                u = w
                                found = True
                                break
                        i += 1
                    if not found:
                        for q in range(j + 1, nn):
                            out_s[q] = s_star
                            out_v[q] = 0.0
                            out_phase[q] = phase
            if not found:
                break
            if j < ns and u >= 1.0:
                j += 1
                u = 0.0
            S, S1 = _drive_at(PT, Dn, h, ns, j, u, tmp)
            # phases.release_from_rest
            x = S - lash - s
            pushes = x >= 0.0 and k * x + c * S1 > 0.0
            seated = phase == SEATED
            if which == UP and seated and not pushes and c * S1 > 0.0 and W0 + R > 0.0:
                pushes = True
            sigma = 1.0 if which == UP else -1.0
            if which == UP and seated:
                ev = _grow(ev, n_events)
                ev[n_events, 0] = LIFT_OFF
                ev[n_events, 1] = _time(nodes, h, ns, j, u)
                ev[n_events, 2] = 0.0
                n_events += 1
            phase = CONTACT if pushes else FLIGHT
            v = 0.0
            release = True
        else:
            # ------------------------------------------------ moving (exact_phase._run_moving)
            kind = phase
            m_, c_, K_, kc_, cc_ = lin[kind, 0], lin[kind, 1], lin[kind, 2], lin[kind, 3], lin[kind, 4]
            Fc = kc_ * lash + W0 + R * sigma
            n_ev, nrow = _moving_table(kind, k, c, lash, R, sigma, rows, ev_kind, ev_r0, ev_nr, ev_comb)
            found = False
            if j >= ns:
                out_s[ns] = s
                out_v[ns] = v
                out_phase[ns] = kind
                out_sigma[ns] = sigma
                break
            u0 = u
            _shift_into(PT[j], u0, Pw)
            h_loc = (1.0 - u0) * h[j]
            _expand(m_, c_, K_, kc_, cc_, Pw, h_loc, s, v, Fc, N, a, f)
            if release:
                f0 = 2.0 * m_ * a[2] / (h_loc * h_loc)
                terms = abs(kc_ * Pw[0]) + abs(cc_ * Pw[1] / h_loc) + abs(Fc) + abs(K_ * s)
                if sigma * f0 < 0.0 and abs(f0) <= 1e-12 * terms:
                    _expand(m_, c_, K_, kc_, cc_, Pw, h_loc, s, v, Fc + f0, N, a, f)
            release = False
            _deriv_into(a, NC, h_loc, da)
            _deriv_into(Pw, 6, h_loc, dP)
            _coeffs(rows, nrow, Pw, dP, a, da, NC, E, True, s, v, zr)
            _zero_flags(E, zr, ev_r0, ev_nr, ev_comb, n_ev, zeros)
            for q in range(n_ev):
                check[q] = True
            kind_b, w = _earliest(E, NC, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros,
                                  _time(nodes, h, ns, j, u0), h_loc)
            if u0 == 0.0:
                out_s[j] = s
                out_v[j] = v
                out_phase[j] = kind
                out_sigma[j] = sigma
            if kind_b >= 0:
                which = kind_b
                u = u0 + w * (1.0 - u0)
                s = _horner(a, NC, w)
                v = _horner(da, NC, w)
                found = True
            else:
                s = _fsum(a, NC)
                v = _fsum(da, NC)
                for q in range(n_ev):
                    zeros[q] = False
                # per step length: a bound of the steps (a hair above the group's length: the
                # lengths of a group differ by rounding), the bound's q = H (c + K H) / m and
                # 1 / (1 - q), H^2 / 8
                for gi in range(U):
                    Hq = h_unique[gi] * (1.0 + 1e-9)
                    grp_H[gi] = Hq
                    grp_q[gi] = Hq * (c_ + K_ * Hq) / m_
                    grp_inv1q[gi] = 1.0 / (1.0 - grp_q[gi])
                    grp_H8[gi] = Hq * Hq / 8.0
                inv_m = 1.0 / m_
                # the window bound's step: the largest of the groups (q, 1 / (1 - q) and H^2/8 grow
                # with H); no window bound where a group's per-step bound does not apply (q >= 0.5)
                wH = wq = wi1q = wH8 = 0.0
                for gi in range(U):
                    wH = max(wH, grp_H[gi])
                    wq = max(wq, grp_q[gi])
                    wi1q = max(wi1q, grp_inv1q[gi])
                    wH8 = max(wH8, grp_H8[gi])
                win_ok = wq < 0.5
                # the rows as scalars (padded to 4 with a row that is always -1): the loop below is
                # straight-line code on registers
                for r in range(nrow, 4):
                    rows[r, 0], rows[r, 1], rows[r, 2], rows[r, 3], rows[r, 4] = 0.0, 0.0, -1.0, 0.0, 0.0
                a0_, b0_, k0_, l0_, m0_ = rows[0, 0], rows[0, 1], rows[0, 2], rows[0, 3], rows[0, 4]
                a1_, b1_, k1_, l1_, m1_ = rows[1, 0], rows[1, 1], rows[1, 2], rows[1, 3], rows[1, 4]
                a2_, b2_, k2_, l2_, m2_ = rows[2, 0], rows[2, 1], rows[2, 2], rows[2, 3], rows[2, 4]
                a3_, b3_, k3_, l3_, m3_ = rows[3, 0], rows[3, 1], rows[3, 2], rows[3, 3], rows[3, 4]
                i = j + 1
                S0 = 0.0
                S10 = 0.0
                if i < nn:
                    S0, S10 = Dn[0, i], Dn[1, i]
                e0a = a0_ * S0 + b0_ * S10 + k0_ + l0_ * s + m0_ * v
                e0b = a1_ * S0 + b1_ * S10 + k1_ + l1_ * s + m1_ * v
                e0c = a2_ * S0 + b2_ * S10 + k2_ + l2_ * s + m2_ * v
                e0d = a3_ * S0 + b3_ * S10 + k3_ + l3_ * s + m3_ * v
                while i < ns:
                    if win_ok and i % WINDOW == 0 and i + WINDOW <= ns:
                        # the window bound: the states of WINDOW steps propagated first (the same
                        # operations as below: the same states), then every event cleared at once
                        # by a bound of its rows over the whole window -- the largest value from the
                        # ranges of S, S1, s, v at its nodes plus H^2/8 times a bound of |e''| from
                        # the largest |S'|, |S''|, |S'''| and the ranges of the state (each term at
                        # least the per-step bound's, so a window cleared has every step cleared).
                        # A window not cleared is done again step by step from its first node (the
                        # outputs written here are written again, or by the phases that follow).
                        ss = s
                        vv = v
                        s_lo = s_hi = s
                        v_lo = v_hi = v
                        for q in range(i, i + WINDOW):
                            out_s[q] = ss
                            out_v[q] = vv
                            ss, vv = _step(tabs, kind, hidx[q], PT[q], Fc, ss, vv)
                            s_lo = min(s_lo, ss)
                            s_hi = max(s_hi, ss)
                            v_lo = min(v_lo, vv)
                            v_hi = max(v_hi, vv)
                        wb = i // WINDOW
                        if _window_clear(win[0, wb], win[1, wb], win[2, wb] * sw1, win[3, wb] * sw1, win[4, wb] * sw1,
                                         win[5, wb] * sw2, win[6, wb] * sw3, s_lo, s_hi, v_lo, v_hi, m_, c_, K_, kc_, cc_, Fc, inv_m, wH,
                                         wi1q, wH8, rows, ev_r0, ev_nr, ev_comb, n_ev, clear_row):
                            for q in range(i, i + WINDOW):
                                out_phase[q] = kind
                                out_sigma[q] = sigma
                            s = ss
                            v = vv
                            i += WINDOW
                            S0, S10 = Dn[0, i], Dn[1, i]
                            e0a = a0_ * S0 + b0_ * S10 + k0_ + l0_ * s + m0_ * v
                            e0b = a1_ * S0 + b1_ * S10 + k1_ + l1_ * s + m1_ * v
                            e0c = a2_ * S0 + b2_ * S10 + k2_ + l2_ * s + m2_ * v
                            e0d = a3_ * S0 + b3_ * S10 + k3_ + l3_ * s + m3_ * v
                            continue
                    out_s[i] = s
                    out_v[i] = v
                    out_phase[i] = kind
                    out_sigma[i] = sigma
                    PTi = PT[i]
                    gi = hidx[i]
                    s1, v1 = _step(tabs, kind, gi, PTi, Fc, s, v)
                    # event values at both nodes; the step is cleared by max(ends) + h^2/8 sup|e''|,
                    # sup|e''| from bounds of |S''|, |S'''| over the step and of |a|, |jerk| from
                    # the left node and the ODE (exact_phase._scan_window's per-step bound)
                    Sn, S1n = Dn[0, i + 1], Dn[1, i + 1]
                    e1a = a0_ * Sn + b0_ * S1n + k0_ + l0_ * s1 + m0_ * v1
                    e1b = a1_ * Sn + b1_ * S1n + k1_ + l1_ * s1 + m1_ * v1
                    e1c = a2_ * Sn + b2_ * S1n + k2_ + l2_ * s1 + m2_ * v1
                    e1d = a3_ * Sn + b3_ * S1n + k3_ + l3_ * s1 + m3_ * v1
                    q_ = grp_q[gi]
                    ca = cb = cc = cd = False
                    if q_ < 0.5:
                        H = grp_H[gi]
                        b1 = Sb[0, i] * sw1
                        b2 = Sb[1, i] * sw2
                        b3 = Sb[2, i] * sw3
                        Vi = abs(v)
                        Ac = abs(kc_ * S0 + cc_ * S10 - Fc - K_ * s - c_ * v)
                        F1 = kc_ * b1 + cc_ * b2
                        Ai = (Ac + H * (F1 + K_ * Vi)) * inv_m * grp_inv1q[gi]
                        Ji = (F1 + c_ * Ai + K_ * (Vi + H * Ai)) * inv_m
                        H8 = grp_H8[gi]
                        ca = max(e0a, e1a) + H8 * (abs(a0_) * b2 + abs(b0_) * b3 + abs(l0_) * Ai + abs(m0_) * Ji) <= 0.0
                        cb = max(e0b, e1b) + H8 * (abs(a1_) * b2 + abs(b1_) * b3 + abs(l1_) * Ai + abs(m1_) * Ji) <= 0.0
                        cc = max(e0c, e1c) + H8 * (abs(a2_) * b2 + abs(b2_) * b3 + abs(l2_) * Ai + abs(m2_) * Ji) <= 0.0
                        cd = max(e0d, e1d) + H8 * (abs(a3_) * b2 + abs(b3_) * b3 + abs(l3_) * Ai + abs(m3_) * Ji) <= 0.0
                    any_open = False
                    if not (ca and cb and cc and cd):
                        clear_row[0], clear_row[1], clear_row[2], clear_row[3] = ca, cb, cc, cd
                        E1[0], E1[1], E1[2], E1[3] = e1a, e1b, e1c, e1d
                        hit = False
                        for q in range(n_ev):
                            up = E1[ev_r0[q]] > 0.0
                            for r in range(ev_r0[q] + 1, ev_r0[q] + ev_nr[q]):
                                up = (up and E1[r] > 0.0) if ev_comb[q] == MIN else (up or E1[r] > 0.0)
                            hit = hit or up
                        if q_ < 0.5 and not hit:
                            for q in range(n_ev):
                                cl = clear_row[ev_r0[q]]
                                for r in range(ev_r0[q] + 1, ev_r0[q] + ev_nr[q]):
                                    cl = (cl or clear_row[r]) if ev_comb[q] == MIN else (cl and clear_row[r])
                                check[q] = not cl
                                any_open = any_open or check[q]
                        else:
                            for q in range(n_ev):
                                check[q] = True
                            any_open = True
                    if any_open:
                        n_detail += 1
                        H = h[i]
                        _expand(m_, c_, K_, kc_, cc_, PTi, H, s, v, Fc, N, a, f)
                        _deriv_into(a, NC, H, da)
                        _deriv_into(PTi, 6, H, dP)
                        _coeffs(rows, nrow, PTi, dP, a, da, NC, E, False, 0.0, 0.0, zr)
                        kind_b, w = _earliest(E, NC, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros,
                                              nodes[i], H)
                        if kind_b >= 0:
                            which = kind_b
                            j = i
                            u = w
                            s = _horner(a, NC, w)
                            v = _horner(da, NC, w)
                            found = True
                            break
                    s = s1
                    v = v1
                    S0, S10 = Sn, S1n
                    e0a, e0b, e0c, e0d = e1a, e1b, e1c, e1d
                    i += 1
                if not found:
                    out_s[ns] = s
                    out_v[ns] = v
                    out_phase[ns] = kind
                    out_sigma[ns] = sigma
                    break
            if j < ns and u >= 1.0:
                j += 1
                u = 0.0
            # ------------------------------------------------ the event (exact._Solver._handle)
            if which == SEPARATION or which == RECONTACT:
                ev = _grow(ev, n_events)
                ev[n_events, 0] = which
                ev[n_events, 1] = _time(nodes, h, ns, j, u)
                ev[n_events, 2] = v
                n_events += 1
                phase = FLIGHT if which == SEPARATION else CONTACT
            else:
                S, S1 = _drive_at(PT, Dn, h, ns, j, u, tmp)
                if which == VZERO:  # phases.velocity_zero
                    force = k * (S - lash - s) + c * S1 if phase == CONTACT else 0.0
                    net = force - W0 - rate * s
                    if abs(net) <= R:
                        phase = STUCK if s > 0.0 else SEATED
                    else:
                        sigma = 1.0 if net > 0.0 else -1.0
                    v = 0.0
                else:  # seat impact: phases.seat_rebound
                    impact = min(v, 0.0)
                    t_now = _time(nodes, h, ns, j, u)
                    ev = _grow(ev, n_events)
                    ev[n_events, 0] = SEAT
                    ev[n_events, 1] = t_now
                    ev[n_events, 2] = impact
                    n_events += 1
                    rebound = -e * impact
                    if rebound <= 0.0:
                        phase, s, v, sigma = SEATED, 0.0, 0.0, 1.0
                    else:
                        x = S - lash
                        force = max(0.0, k * x + c * S1) if x >= 0.0 else 0.0
                        m_rest = M1 if force > 0.0 else M
                        decel = (W0 + R - force) / m_rest
                        if decel > 0.0 and rebound * rebound <= 2.0 * decel * zeno_height:
                            dt = 2.0 * rebound / (decel * (1.0 - e))
                            ev[n_events - 1, 3] = t_now + dt
                            # exact._Solver._advance: nodes passed on the way are seated at 0
                            t_new = t_now + dt
                            j0 = j
                            while j < ns and nodes[j + 1] <= t_new:
                                j += 1
                            start = j0 + (1 if u > 0.0 else 0)
                            if j >= ns:
                                end = j
                                u = 0.0
                            else:
                                u = max(0.0, min((t_new - nodes[j]) / h[j], 1.0 - 1e-16))
                                end = j + (1 if u > 0.0 else 0)
                            for q in range(start, end):
                                out_s[q] = 0.0
                                out_v[q] = 0.0
                                out_phase[q] = SEATED
                            phase, s, v, sigma = SEATED, 0.0, 0.0, 1.0
                        else:
                            phase = CONTACT if force > 0.0 else FLIGHT
                            s, v, sigma = 0.0, rebound, 1.0
        t_now = _time(nodes, h, ns, j, u)
        same_time = same_time + 1 if t_now == last_time else 0
        last_time = t_now
        if same_time > MAX_SAME_TIME:
            status = NO_PROGRESS
            break
    return out_s, out_v, out_sigma, out_phase, ev[:n_events].copy(), status, n_detail


# ---------------------------------------------------------------- one revolution of a sweep's run
# the figures revolution() returns, in this order (the elastic effect's, as the sweep's rows read
# them: explorer/studies/sweep_engine.row_scalars)
FIGURES = ("first_separation_deg", "separations", "flight_time_s", "max_deviation_m", "peak_linkage_force_N",
           "peak_camshaft_back_pressure_N", "lift_off_delay_s", "seating_velocity_m_s", "seat_impacts",
           "largest_bounce_m", "residual_deviation_m", "residual_amplitude_m")


@njit(cache=True)
def _scaled_grid(nodes_th, h_th, Dn_th, h_unique_th, omega):
    """A grid in cam angle (omega = 1) as times at the speed omega: t = theta / omega, S' and S''
    times omega and omega^2 (the step polynomials in u = tau/h do not change)."""
    inv = 1.0 / omega
    nodes = nodes_th * inv
    h = h_th * inv
    Dn = np.empty_like(Dn_th)
    w2 = omega * omega
    for i in range(Dn_th.shape[1]):
        Dn[0, i] = Dn_th[0, i]
        Dn[1, i] = Dn_th[1, i] * omega
        Dn[2, i] = Dn_th[2, i] * w2
    return nodes, h, Dn, h_unique_th * inv


@njit(cache=True)
def _first_sample(n, omega, t, after):
    """The first output sample i (of n; n: none) whose time i (2 pi / n) / omega (the effect's
    time_s column, the same operations as np.arange(n) * (2 pi / n) / omega) is > t (after) or
    >= t: np.searchsorted without the array of times."""
    step = 2.0 * math.pi / n
    lo = 0
    hi = n
    while lo < hi:
        mid = (lo + hi) // 2
        ti = float(mid) * step / omega
        if (ti > t) if after else (ti >= t):
            hi = mid
        else:
            lo = mid + 1
    return lo


@njit(cache=True)
def _largest(x, lo, hi, init):
    """max(init, x[lo:hi]) with four running maxima (one is a chain of dependent compares; max is
    exact in any order)."""
    m0 = m1 = m2 = m3 = init
    i = lo
    while i + 4 <= hi:
        m0 = max(m0, x[i])
        m1 = max(m1, x[i + 1])
        m2 = max(m2, x[i + 2])
        m3 = max(m3, x[i + 3])
        i += 4
    while i < hi:
        m0 = max(m0, x[i])
        i += 1
    return max(max(m0, m1), max(m2, m3))


@njit(cache=True)
def revolution(nodes_th, h_th, PT, Dn_th, Sb_th, hidx, h_unique_th, out_nodes, i0, omega, M, M1, k, c, lash, W0, rate, R, e,
               zeno_height, max_events, N, ratio, preload_closing, take_up_s, ref, dwell, S_dwell, blk, win):
    """One revolution of the elastic effect at the speed omega, on a grid built in cam angle
    (RevolutionGrid: the n output samples from the drive's lowest point, out_nodes their nodes):
    the FIGURES, the valve lift at the output samples in the order of the cam angle (the effect's
    valve_lift_m column), the events of the revolution (rows: code, time within the revolution,
    velocity, cam angle in degrees; in time order) and the solver status.
    The figures are the elastic effect's summary read as sweep_engine.row_scalars reads it:
    force, deviation from S - lash - W/k, separation on the output samples, events from the start
    of the run for one period, times modulo the period (effects/elastic.py, elastic_events.py);
    the residual figures from the lift the cam is made for at the output angles, ref, the dwell's
    first sample (-1: none) and the valve-referred drive there, S_dwell
    (effects/residual.residual_reference); blk, win: grid_bounds of the grid in cam angle."""
    nodes, h, Dn, h_unique = _scaled_grid(nodes_th, h_th, Dn_th, h_unique_th, omega)
    out_s, out_v, out_sigma, out_phase, ev, status, n_detail = solve_nodes(
        nodes, h, PT, Dn, Sb_th, omega, hidx, h_unique, M, M1, k, c, lash, W0, rate, R, e, zeno_height, max_events, N,
        blk, win)
    n = out_nodes.size
    fig = np.full(len(FIGURES), np.nan)
    lift = np.empty(n)
    vel = np.empty(n)
    period = 2.0 * math.pi / omega
    # the output samples: force (exact_output.solution's), deviation, separation
    max_dev = 0.0
    peak = -np.inf
    separated = 0
    col = i0  # the output column of run sample r: (r + i0) mod n, counted (no integer division per sample)
    for r in range(n):
        q = out_nodes[r]
        s = out_s[q]
        v = out_v[q]
        ph = out_phase[q]
        x = Dn[0, q] - lash - s
        if c != 0.0:
            if ph == CONTACT:
                force = max(0.0, k * x + c * (Dn[1, q] - v))
            elif ph == FLIGHT:
                force = 0.0
            else:
                force = max(0.0, k * x + c * Dn[1, q]) if x >= 0.0 else 0.0
        else:
            force = max(k * x, 0.0) * (0.0 if ph == FLIGHT else 1.0)
        peak = max(peak, force)
        if s > 0.0:
            W = preload_closing + rate * s + R * (-1.0 if v < 0.0 else 1.0)
            dev = abs(s - (Dn[0, q] - lash - W / k))
            max_dev = max(max_dev, dev)
            if not force > 0.0:
                separated += 1
        lift[col] = s
        vel[col] = v
        col += 1
        if col == n:
            col = 0
    fig[1] = 0.0
    fig[8] = 0.0
    fig[2] = 360.0 * separated / n / 360.0 * period
    fig[3] = max_dev
    fig[4] = peak
    fig[5] = ratio * peak  # = max(ratio force): the product rounds monotonically (the scene has ratio > 0)
    # the events of the revolution (elastic_events.revolution_events), in time order
    t_start = nodes[out_nodes[0]]
    n_ev = ev.shape[0]
    rev = np.empty((n_ev, 4))
    m = 0
    for q in range(n_ev):
        if not ev[q, 1] < t_start + period:
            continue
        t_ev = np.fmod(ev[q, 1], period)
        rev[m, 0] = ev[q, 0]
        rev[m, 1] = t_ev
        rev[m, 2] = ev[q, 2]
        rev[m, 3] = math.degrees(omega * t_ev) % 360.0
        m += 1
    rev = rev[:m]
    order = np.argsort(rev[:, 1], kind="mergesort")  # (stable: equal instants keep the solver's order)
    rev = rev[order]
    best_bounce = 0.0
    seat_v = np.inf
    delay = np.inf
    for q in range(m):
        code = int(rev[q, 0])
        if code == SEPARATION:
            if fig[1] == 0.0:
                fig[0] = rev[q, 3]
            fig[1] += 1.0
        elif code == SEAT:
            fig[8] += 1.0
            seat_v = min(seat_v, rev[q, 2])
            t0 = rev[q, 1]
            t1 = np.inf
            for p in range(m):
                if rev[p, 1] > t0:
                    t1 = min(t1, rev[p, 1])
            if t1 == np.inf:
                t1 = (n - 1) * (2.0 * math.pi / n) / omega + 1.0
            # the samples after t0 and before t1 (the first after t0 up to the first at or after t1)
            lo = _first_sample(n, omega, t0, True)
            hi = _first_sample(n, omega, t1, False)
            best_bounce = _largest(lift, lo, hi, best_bounce)
        elif code == LIFT_OFF and not math.isnan(take_up_s):
            delay = min(delay, np.fmod(rev[q, 1] - take_up_s + period, period))
    fig[6] = delay if delay < np.inf else np.nan
    fig[7] = seat_v if fig[8] > 0.0 else np.nan
    fig[9] = best_bounce
    # residual vibration (effects/residual.residual_figures)
    # (four running maxima: one would be a chain of n dependent compares; max is exact in any order)
    w0 = w1 = w2 = w3 = 0.0
    n4 = n - n % 4
    for i in range(0, n4, 4):
        w0 = max(w0, abs(lift[i] - ref[i]))
        w1 = max(w1, abs(lift[i + 1] - ref[i + 1]))
        w2 = max(w2, abs(lift[i + 2] - ref[i + 2]))
        w3 = max(w3, abs(lift[i + 3] - ref[i + 3]))
    for i in range(n4, n):
        w0 = max(w0, abs(lift[i] - ref[i]))
    fig[10] = max(max(w0, w1), max(w2, w3))
    if dwell >= 0:
        fig[11] = _free_amplitude(lift[dwell], vel[dwell], S_dwell, k, lash, W0, rate, R, M1)
    return fig, lift, rev, status


# the columns of a batch's run parameters (revolutions())
RUN_PARAMETERS = ("omega", "mass", "oscillating_mass", "stiffness", "damping", "lash", "seated_resistance",
                  "spring_rate", "friction", "restitution", "preload_closing", "take_up_s")


@njit(cache=True)
def _taylor_terms(x):
    """exact_steps.taylor_terms."""
    n = 1
    term = x
    bound = math.exp(x)
    while n < 9 or term * bound > 1e-19:
        n += 1
        term *= x / n
        if n > 60:
            break
    return n


@njit(cache=True)
def _rate(M, M1, k, c, rate):
    """exact_phase's rho: the fastest rate of contact and flight (LinearPhase.rho)."""
    alpha = 0.5 * c / M1
    w2 = (k + rate) / M1
    rho = alpha + math.sqrt(alpha * alpha - w2) if alpha * alpha > w2 else math.sqrt(w2)
    return max(rho, math.sqrt(rate / M))


@njit(cache=True)
def revolutions(nodes_th, h_th, PT, Dn_th, Sb_th, hidx, h_unique_th, out_nodes, i0, h_max_th, ratio, runs,
                zeno_height, max_events, ref, dwell, S_dwell):
    """revolution() for many runs on one grid (runs: one row of RUN_PARAMETERS each): the FIGURES
    per run and the solver status per run (a batch costs no Python per run)."""
    R = runs.shape[0]
    figs = np.empty((R, len(FIGURES)))
    status = np.empty(R, dtype=np.int64)
    blk, win = grid_bounds(h_th, Dn_th, Sb_th)  # once for the batch: they do not depend on the speed
    for r in range(R):
        p = runs[r]
        omega = p[0]
        N = _taylor_terms(_rate(p[1], p[2], p[3], p[4], p[7]) * h_max_th / omega)
        fig, lift, rev, st = revolution(nodes_th, h_th, PT, Dn_th, Sb_th, hidx, h_unique_th, out_nodes, i0, omega,
                                        p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], zeno_height,
                                        max_events, N, ratio, p[10], p[11], ref, dwell, S_dwell, blk, win)
        figs[r] = fig
        status[r] = st
    return figs, status


# ---------------------------------------------------------------- Python side
def _check(status: int) -> None:
    if status == TOO_MANY_EVENTS:
        raise RuntimeError("exact solver (compiled): too many events; the motion does not settle")
    if status == NO_PROGRESS:
        raise RuntimeError("exact solver (compiled): events repeat at one instant without progress")


def model_arguments(model: LinkageModel) -> tuple:
    return (float(model.mass), float(model.oscillating_mass), float(model.stiffness), float(model.damping),
            float(model.lash), float(model.seated_resistance), float(model.spring_rate), float(model.friction),
            float(model.restitution))


def phase_rates(model: LinkageModel) -> float:
    """rho: the fastest rate of the contact and flight phases (exact_phase.PhaseStepper's)."""
    lins = (LinearPhase(model.oscillating_mass, model.damping, model.stiffness + model.spring_rate, model.stiffness,
                        model.damping),
            LinearPhase(model.mass, 0.0, model.spring_rate, 0.0, 0.0))
    return max(lin.rho for lin in lins)


def events_list(ev: np.ndarray) -> list[dict]:
    """The kernel's event rows as exact.py's event dicts."""
    out = []
    for code, t, vel, zeno in ev.tolist():
        item = {"kind": EVENT_NAMES[int(code)], "time_s": t, "velocity_m_s": vel}
        if not math.isnan(zeno):
            item["zeno_accumulation_s"] = zeno
        out.append(item)
    return out


def solve(model: LinkageModel, drive, t: np.ndarray, zeno_height: float = 1e-12,
          max_events: int = 100_000) -> DynamicsSolution:
    """exact.solve compiled: the same grid and output (exact_output.solution), the stepping and
    the events in compiled code; the valve starts at rest on its seat at t[0] (strictly
    increasing output times)."""
    from . import exact_output

    if not supports(model):
        raise ValueError("the compiled exact solver needs a constant linkage stiffness")
    t_req = np.asarray(t, dtype=float).ravel()
    if t_req.size < 2 or not np.isfinite(t_req).all() or np.any(np.diff(t_req) <= 0.0):
        raise ValueError("output times must be a sorted array of at least two distinct finite times")
    hmin = float(np.min(np.diff(t_req)))
    rho = phase_rates(model)
    g = build_grid(drive, t_req, rho, hmin)
    N = taylor_terms(rho * g.h_max)
    Sb = np.ascontiguousarray(g.Sb)
    out_s, out_v, out_sigma, out_phase, ev, status, n_detail = solve_nodes(
        g.nodes, g.h, np.ascontiguousarray(g.PT), g.Dn, Sb, 1.0, g.hidx.astype(np.int64),
        g.h_unique,
        *model_arguments(model), float(zeno_height), int(max_events), int(N), *grid_bounds(g.h, g.Dn, Sb))
    _check(status)
    lins = {CONTACT: LinearPhase(model.oscillating_mass, model.damping, model.stiffness + model.spring_rate,
                                 model.stiffness, model.damping),
            FLIGHT: LinearPhase(model.mass, 0.0, model.spring_rate, 0.0, 0.0)}
    stats = {"method": "exact-compiled", "nodes": int(g.nodes.size), "steps": int(g.h.size), "taylor_terms": N,
             "detail_searches": int(n_detail), "events": int(ev.shape[0]), "warnings": []}
    return exact_output.solution(t_req, None, out_s, out_v, out_sigma, out_phase, g.Dn, g.is_out, lins,
                                 model.stiffness, model.damping, model.lash, model.seated_resistance,
                                 model.friction, events_list(ev), stats)


@dataclass(frozen=True)
class RevolutionGrid:
    """The grid of one revolution in cam angle (exact_grid.build_grid with omega = 1), valid at
    every speed (revolution() scales it): the n output samples of the elastic effect from the
    drive's lowest point (index i0) round to it again, the drive's breakpoints, steps split to
    rho h <= 0.5 for the rate `rho_theta` = rho / omega it was built for."""

    n: int
    i0: int
    nodes: np.ndarray
    h: np.ndarray
    PT: np.ndarray
    Dn: np.ndarray
    Sb: np.ndarray  # bounds of the drive's first three derivatives over each step (exact_grid.Grid.Sb)
    hidx: np.ndarray
    h_unique: np.ndarray
    out_nodes: np.ndarray  # the nodes of the n output samples, in run order
    h_max: float


def revolution_grid(lift, ratio: float, n: int, rho_theta: float = 0.0, base: "RevolutionGrid | None" = None):
    """The RevolutionGrid of a lift curve at `ratio` and n samples per revolution (as the elastic
    effect builds its run: effects/elastic.py), split for the rate rho_theta (0: not split).
    base: the unsplit grid, when known (its start angle and drive values are reused)."""
    from .model import Drive

    drive = Drive(lift, ratio, 1.0)
    theta = np.arange(n) * (2.0 * math.pi / n)
    if base is None:
        i0 = int(np.argmin(drive(theta)[0]))
    else:
        i0 = base.i0
    run = np.concatenate([theta[i0:], theta[:i0] + 2.0 * math.pi])
    run = np.append(run, theta[i0] + 2.0 * math.pi)
    hmin = float(np.min(np.diff(run)))
    g = build_grid(drive, run, rho_theta, hmin)
    out = np.nonzero(g.is_out)[0][:n].astype(np.int64)
    return RevolutionGrid(n=n, i0=i0, nodes=g.nodes, h=g.h, PT=np.ascontiguousarray(g.PT), Dn=g.Dn,
                          Sb=np.ascontiguousarray(g.Sb), hidx=g.hidx.astype(np.int64), h_unique=g.h_unique, out_nodes=out, h_max=g.h_max)


def split_parts(grid: RevolutionGrid, rho_theta: float) -> np.ndarray | None:
    """How build_grid splits the steps of an unsplit grid for the rate rho_theta (None: it does
    not): grids with the same parts are the same grid."""
    if not rho_theta * grid.h_max / MAX_RHO_H > 1.0:
        return None
    return np.maximum(1, np.ceil(rho_theta * grid.h / MAX_RHO_H)).astype(np.int64)


def run_revolution(grid: RevolutionGrid, omega: float, model: LinkageModel, ratio: float, take_up_s: float,
                   ref: np.ndarray, dwell: int, S_dwell: float, zeno_height: float = 1e-12, max_events: int = 100_000):
    """revolution() on a RevolutionGrid: (FIGURES, valve lift at the output samples, revolution
    events as the elastic effect lists them). RuntimeError where exact.py raises. ref, dwell,
    S_dwell: the residual figures' (revolution())."""
    rho = phase_rates(model)
    N = taylor_terms(rho * grid.h_max / omega)
    fig, lift, rev, status = revolution(
        grid.nodes, grid.h, grid.PT, grid.Dn, grid.Sb, grid.hidx, grid.h_unique, grid.out_nodes, grid.i0, float(omega),
        *model_arguments(model), float(zeno_height), int(max_events), int(N), float(ratio),
        float(model.preload + model.closing_load), float(take_up_s), np.ascontiguousarray(ref, dtype=float),
        int(dwell), float(S_dwell), *grid_bounds(grid.h, grid.Dn, grid.Sb))
    _check(status)
    return fig, lift, rev


def run_batch(grid: RevolutionGrid, ratio: float, runs: np.ndarray, ref: np.ndarray, dwell: int, S_dwell: float,
              zeno_height: float = 1e-12, max_events: int = 100_000):
    """revolutions() on a RevolutionGrid: (FIGURES per run, status per run: OK, or the exact
    solver's RuntimeErrors as TOO_MANY_EVENTS, NO_PROGRESS); ref, dwell, S_dwell: revolution()'s,
    shared by the runs (one lever ratio and lash)."""
    return revolutions(grid.nodes, grid.h, grid.PT, grid.Dn, grid.Sb, grid.hidx, grid.h_unique, grid.out_nodes,
                       grid.i0, grid.h_max, float(ratio), np.ascontiguousarray(runs, dtype=float),
                       float(zeno_height), int(max_events), np.ascontiguousarray(ref, dtype=float), int(dwell),
                       float(S_dwell))


def revolution_events(rev: np.ndarray) -> list[dict]:
    """revolution()'s event rows as the elastic effect's event dicts."""
    return [{"kind": EVENT_NAMES[int(code)], "time_s": t, "cam_angle_deg": angle, "velocity_m_s": vel}
            for code, t, vel, angle in rev.tolist()]


def warm() -> None:
    """Compile (or load from the cache) every entry point on a small case."""
    class _Lift:
        def derivatives(self, x):
            x = np.asarray(x, dtype=float)
            return np.stack([1e-3 * (1.0 - np.cos(x)), 1e-3 * np.sin(x), 1e-3 * np.cos(x), -1e-3 * np.sin(x)])

        def breakpoints(self):
            return [1.0]

    from .model import Drive

    model = LinkageModel(mass=0.1, oscillating_mass=0.09, stiffness=3e6, damping=8.0, lash=1e-4, preload=50.0,
                         spring_rate=3e4, friction=5.0, restitution=0.5)
    omega = 2 * math.pi * 100.0
    t = np.linspace(0.0, 2 * math.pi / omega, 181)
    solve(model, Drive(_Lift(), 1.0, omega), t)
    grid = revolution_grid(_Lift(), 1.0, 180)
    ref = np.zeros(180)
    run_revolution(grid, omega, model, 1.0, 0.0, ref, -1, math.nan)
    run_batch(grid, 1.0, np.array([[omega, *model_arguments(model), 50.0, 0.0]]), ref, 3, 1e-3)


if __name__ == "__main__":
    import sys

    if "--warm" in sys.argv[1:]:
        warm()
