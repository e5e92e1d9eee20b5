"""The compiled exact solver's events (explorer.dynamics.exact_events compiled, with the event
tables of phases.py's rules): the rows (aP, bP, const, l0, l1) of each event function of a phase,
aP S + bP S' + const + l0 s + l1 v, combined by ONE / MIN / MAX (moving_table, static_table:
exact_events.event_of), their coefficients over a step (coeffs: exact_events.coeff_list and
start_coeffs) and the first event in a step (earliest: exact_events.earliest, with the same
coefficient bounds, start clearance, Newton in a proven rising bracket, subdivision search and
Illinois polish). Part of the compiled solver (explorer.dynamics.exact_kernel)."""

from __future__ import annotations

import numpy as np
from numba import njit

from . import kernel_stamp  # noqa: F401 (the cache is stale when a source it depends on changed)
from .exact_events import (CLEARANCE_BISECTIONS, EPS, ILLINOIS_STEPS, MAX_DEPTH, NEGLIGIBLE_LEAD, NEWTON_STEPS,
                           SIGN_MARGIN, SUBDIVISIONS, TIE_EPS, TIE_RELATIVE, ZERO_START)
from .kernel_steps import horner, plain_sum
from .phases import CONTACT

# event codes (the kernel's event records): the first four are model.EVENT_KINDS in order; VZERO
# (velocity zero with friction), UP and DOWN (a resting valve starts to move) end a phase only
LIFT_OFF, SEPARATION, RECONTACT, SEAT, VZERO, UP, DOWN = 0, 1, 2, 3, 4, 5, 6
ONE, MIN, MAX = 0, 1, 2  # how an event's rows combine (exact_events' "one", "min", "max")
SEARCH_ROWS = 12  # _search's stack: 4 rows per level, then each event row's value and slope (4 x 2)


# ---------------------------------------------------------------- bounds and roots
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
    for _ in range(NEWTON_STEPS):
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
    val = horner(E[r0], n, x)
    for r in range(r0 + 1, r0 + nr):
        y = horner(E[r], n, x)
        if comb == MIN:
            val = min(val, y)
        else:
            val = max(val, y)
    return val


@njit(cache=True)
def _illinois(E, r0, nr, comb, n, lo, hi, flo, fhi, xtol):
    side = 0
    for _ in range(ILLINOIS_STEPS):
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
        for _ in range(ILLINOIS_STEPS):
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
        if not (abs(val) > SIGN_MARGIN * mag):
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
        if abs(e[i]) > NEGLIGIBLE_LEAD * big:
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
    for _ in range(CLEARANCE_BISECTIONS):
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
def _search(E, r0, nr, comb, n, a, b, xtol, stack):
    """exact_events._first_root/_search: the first w in [a, b] where the combined function turns
    > 0, or -1.0. Each level splits an interval into SUBDIVISIONS pieces; a piece is skipped when
    the coefficient bound excludes a zero there, else refined (to MAX_DEPTH levels) and polished.
    The recursion of exact_events._search with an explicit stack (numba's cache does not keep
    recursive functions): stack (SEARCH_ROWS + n - 2 rows, MAX_DEPTH + 2 columns; run_buffers), per
    level (column) its interval's ends, the next piece and whether it brackets a crossing (1.0)
    (rows 0-3), and what the piece looked at last found at its end, which is the next piece's
    start (_piece: the same float): each event row's value and slope there (rows 4 + 2 r,
    5 + 2 r) and its powers end ** (i - 2), i = 2 .. n - 1 (rows SEARCH_ROWS + i - 2; column
    MAX_DEPTH + 1 holds a piece's new ones). A piece thus evaluates its end only: the same floats
    as evaluating both ends, half the work."""
    sa, sb, sp, sbrent = stack[0], stack[1], stack[2], stack[3]
    new = MAX_DEPTH + 1
    d = 0
    sa[0] = a
    sb[0] = b
    sp[0] = 0.0
    while d >= 0:
        if sp[d] >= SUBDIVISIONS:  # this level found nothing
            d -= 1
            if d >= 0 and sbrent[d] != 0.0:  # its interval brackets a crossing: polish it
                return _brent(E, r0, nr, comb, n, sa[d + 1], sb[d + 1], xtol)
            continue
        p = int(sp[d])
        lo, hi = _piece(sa[d], sb[d], p)
        sp[d] += 1.0
        sbrent[d] = 0.0
        kept = p > 0  # the start's values are the previous piece's end's, kept in column d
        for i in range(2, n):
            stack[SEARCH_ROWS + i - 2, new] = hi ** (i - 2)
            if not kept:
                stack[SEARCH_ROWS + i - 2, d] = lo ** (i - 2)
        ex_all = True
        ex_any = False
        cv0 = 0.0
        cv1 = 0.0
        d_lo = 0.0
        for r in range(nr):
            if kept:
                f0, d0 = stack[4 + 2 * r, d], stack[5 + 2 * r, d]
            else:
                f0, d0 = _value_slope(E[r0 + r], n, lo)
            f1, d1 = _value_slope(E[r0 + r], n, hi)
            stack[4 + 2 * r, d], stack[5 + 2 * r, d] = f1, d1
            B2 = 0.0
            for i in range(2, n):
                w2 = E[r0 + r, i] * (i * (i - 1.0))
                B2 += max(stack[SEARCH_ROWS + i - 2, d] * w2, stack[SEARCH_ROWS + i - 2, new] * w2)
            ex = _excluded(f0, d0, f1, d1, B2, hi - lo)
            ex_all = ex_all and ex
            ex_any = ex_any or ex
            if r == 0:
                cv0, cv1, d_lo = f0, f1, d0
            elif comb == MIN:
                cv0, cv1 = min(cv0, f0), min(cv1, f1)
            else:
                cv0, cv1 = max(cv0, f0), max(cv1, f1)
        for i in range(2, n):
            stack[SEARCH_ROWS + i - 2, d] = stack[SEARCH_ROWS + i - 2, new]
        if (ex_any if comb == MIN else ex_all):
            continue
        if cv0 > 0.0:
            return lo
        if cv1 > 0.0:
            if d < MAX_DEPTH and not _monotone(E, r0, nr, comb, n, lo, hi, d_lo):
                sbrent[d] = 1.0
                d += 1
                sa[d], sb[d], sp[d] = lo, hi, 0.0
                continue
            return _brent(E, r0, nr, comb, n, lo, hi, xtol)
        if d < MAX_DEPTH:
            d += 1
            sa[d], sb[d], sp[d] = lo, hi, 0.0
    return -1.0


@njit(cache=True)
def earliest(E, n, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros, t_abs, h_loc, stack):
    """exact_events.earliest: the first event of a step (E: each row's coefficients over w in
    [0, 1]; check: the events to search; stack: _search's). Returns (kind, w), kind -1: none."""
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
                ex = _excluded1(E[r], n, plain_sum(E[r], n))
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
            e_lo = e[0] if w_lo == 0.0 else horner(e, n, w_lo)
            e_hi = plain_sum(e, n)
            if not (e_lo <= 0.0 < e_hi):
                if (_excluded1(e, n, e_hi) if w_lo == 0.0 else _excluded_range(e, n, w_lo, 1.0)):
                    continue
        else:
            ex_all = True
            ex_any = False
            for r in range(r0, r0 + nr):
                ex = _excluded1(E[r], n, plain_sum(E[r], n)) if w_lo == 0.0 else _excluded_range(E[r], n, w_lo, 1.0)
                ex_all = ex_all and ex
                ex_any = ex_any or ex
            if (ex_any if comb == MIN else ex_all):
                continue
        xtol = max(0.5 * ulp(abs(t_abs)) / h_loc, 1e-300) if h_loc > 0.0 else 1e-300
        if comb == ONE and e_lo <= 0.0 < e_hi and _rising_range(E[r0], n, w_lo, 1.0):
            w = _root_rising(E[r0], n, w_lo, 1.0, xtol, e_lo, e_hi)
        elif _positive_at(E, r0, nr, comb, n, w_lo):
            w = w_lo
        else:
            w = _search(E, r0, nr, comb, n, w_lo, 1.0, xtol, stack)
            if w < 0.0:
                continue
        kind = ev_kind[q]
        if best_kind < 0:
            best_kind = kind
            best_w = w
            continue
        tie = abs(w - best_w) <= TIE_RELATIVE * max(w, 1e-300) + TIE_EPS * EPS
        if (w < best_w and not (tie and best_kind == SEAT)) or (tie and kind == SEAT):
            best_kind = kind
            best_w = w
    return best_kind, best_w


@njit(cache=True)
def ulp(x):
    return np.nextafter(x, np.inf) - x


# ---------------------------------------------------------------- event tables (phases.py's rules)
@njit(cache=True, inline="always")
def moving_table(kind, k, c, lash, R, sigma, rows, ev_kind, ev_r0, ev_nr, ev_comb):
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


@njit(cache=True, inline="always")
def static_table(s_star, k, c, lash, W0, rate, R, rows, ev_kind, ev_r0, ev_nr, ev_comb):
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


@njit(cache=True, inline="always")
def coeffs(rows, nrow, P, dP, a, da, n, E, start, s0, v0, zr):
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


@njit(cache=True, inline="always")
def zero_flags(E, zr, ev_r0, ev_nr, ev_comb, n_ev, zeros):
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
