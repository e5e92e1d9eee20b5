"""The compiled exact solver's phases (explorer.dynamics.exact_phase and exact._Solver compiled):
one run over a grid from rest on the seat (run_nodes), phase by phase -- a valve at rest
(_rest_phase: exact_phase._run_static), a moving valve in contact or flight (_moving_phase:
exact_phase._run_moving) -- and what happens at their events (_released: phases.release_from_rest;
_handle_event: exact._Solver._handle with phases.velocity_zero and seat_rebound). Part of the
compiled solver (explorer.dynamics.exact_kernel).

The grid is read at the run's speed where a value is used (kernel_grid: node positions and step
lengths times inv are times, S' times sw1 is per time; inv = sw1 = 1 for a grid in time), and a
run writes into buffers (run_buffers) that the runs of a batch share.

The steps are cleared in groups before the per-step bound: a seated valve's BLOCK steps by its push
row's bound over the block, a moving valve's WINDOW steps (their states propagated first) by each
event's rows bounded over the window as exact_phase._scan_window bounds them (the rows' largest
values at the window's nodes); each term of those bounds is at least the per-step bound's, so they
change which steps are looked at, never the states or the events (tests/test_sweep_kernel.py)."""

from __future__ import annotations

import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from . import kernel_stamp  # noqa: F401 (the cache is stale when a source it depends on changed)
from .exact import LAST_U, MAX_SAME_TIME
from .exact_phase import MAX_BOUND_Q, RELEASE_RESIDUAL
from .exact_events import MAX_DEPTH
from .kernel_events import (LIFT_OFF, MIN, RECONTACT, SEARCH_ROWS, SEAT, SEPARATION, UP, VZERO, coeffs, earliest,
                            moving_table, static_table, zero_flags)
from .kernel_grid import BLOCK, WINDOW, drive_at, grid_bounds, node_time
from .kernel_shared import NO_PROGRESS, OK, TOO_MANY_EVENTS  # a run's status (exact.py's RuntimeErrors)
from .kernel_steps import deriv_into, expand, fsum, horner, shift_into, step, step_tables_into
from .phases import CONTACT, FLIGHT, SEATED, STUCK

EVENT_ROWS = 64  # a run's event records before _grow allocates more (a run of elastic_float at 3600 steps has ~16)
WINDOW_LEAD = 4  # steps of a moving phase taken one at a time before its first window
GROUP_MARGIN = 1e-9  # a step group's length bound lies this fraction above its length (the lengths of
# a group differ by rounding)


@intrinsic
def borrowed(typingctx, arr):
    """The array without its reference count (its meminfo and parent NULL): numba counts a
    reference at every binding of an array (each argument of each call, each variable a tuple is
    unpacked into), with an atomic operation, about 1 in 9 of a run's time when some thirty arrays
    reach each phase of a run. A borrowed array's counts are no-ops; it must not outlive the array
    it borrows from (the batch's buffers and grid, held by revolutions() throughout)."""
    if not isinstance(arr, types.Array):
        return None

    def codegen(context, builder, signature, args):
        out = context.make_array(signature.return_type)(context, builder, value=args[0])
        out.meminfo = cgutils.get_null_value(out.meminfo.type)
        out.parent = cgutils.get_null_value(out.parent.type)
        return out._getvalue()

    return arr(arr), codegen


@njit(cache=True)
def borrowed_buffers(buffers):
    """run_buffers' arrays borrowed (borrowed())."""
    out_s, out_v, out_sigma, out_phase, ev, tabs, ws = buffers
    a, da, f, Pw, dP, zero6, rows, E, zr, clear_row, ev_kind, ev_r0, ev_nr, ev_comb, zeros, check, grp, hu, top, \
        tmp, stack = ws
    return (borrowed(out_s), borrowed(out_v), borrowed(out_sigma), borrowed(out_phase), borrowed(ev), borrowed(tabs),
            (borrowed(a), borrowed(da), borrowed(f), borrowed(Pw), borrowed(dP), borrowed(zero6), borrowed(rows),
             borrowed(E), borrowed(zr), borrowed(clear_row), borrowed(ev_kind), borrowed(ev_r0), borrowed(ev_nr),
             borrowed(ev_comb), borrowed(zeros), borrowed(check), borrowed(grp), borrowed(hu), borrowed(top),
             borrowed(tmp), borrowed(stack)))


@njit(cache=True, inline="always")
def _events_cleared(clear_row, ev_r0, ev_nr, ev_comb, n_ev):
    """Every event cleared, given which of its rows are (a MIN event by any row, the others by all)."""
    for q in range(n_ev):
        cl = clear_row[ev_r0[q]]
        for r in range(ev_r0[q] + 1, ev_r0[q] + ev_nr[q]):
            cl = (cl or clear_row[r]) if ev_comb[q] == MIN else (cl and clear_row[r])
        if not cl:
            return False
    return True


@njit(cache=True, inline="always")
def _open_events(clear_row, ev_r0, ev_nr, ev_comb, n_ev, check):
    """check[q]: event q is not cleared (as _events_cleared); True when any is not."""
    any_open = False
    for q in range(n_ev):
        cl = clear_row[ev_r0[q]]
        for r in range(ev_r0[q] + 1, ev_r0[q] + ev_nr[q]):
            cl = (cl or clear_row[r]) if ev_comb[q] == MIN else (cl and clear_row[r])
        check[q] = not cl
        any_open = any_open or check[q]
    return any_open


@njit(cache=True, inline="always")
def _window_clear(top, acm, Vm, b1, b2, b3, c, K, kc, cc, inv_m, H, inv1q, H8, rows, ev_r0, ev_nr, ev_comb, n_ev,
                  clear_row):
    """Every event of a moving phase cleared over a window of steps (exact_phase._scan_window's
    bound over the window): each row's max e + H^2/8 sup|e''| <= 0, with top[r] the row's largest
    value at the window's nodes and sup|e''| from the per-step bound's |a| and |jerk| bounds taken
    with the largest |m a| (acm) and |v| (Vm) at its nodes, the largest |S'|, |S''|, |S'''| over
    its steps (b1, b2, b3) and the largest step (H, 1 / (1 - q), H^2/8): each term is at least the
    per-step bound's of every step of the window. The rows combine into events as in the per-step
    clearing."""
    F1 = abs(kc) * b1 + abs(cc) * b2
    A = (acm + H * (F1 + abs(K) * Vm)) * inv_m * inv1q
    J = (F1 + abs(c) * A + abs(K) * (Vm + H * A)) * inv_m
    for r in range(4):
        clear_row[r] = top[r] + H8 * (abs(rows[r, 0]) * b2 + abs(rows[r, 1]) * b3 + abs(rows[r, 3]) * A
                                      + abs(rows[r, 4]) * J) <= 0.0
    return _events_cleared(clear_row, ev_r0, ev_nr, ev_comb, n_ev)


@njit(cache=True)
def _grow(ev, n):
    if n < ev.shape[0]:
        return ev
    new = np.full((2 * ev.shape[0], 4), np.nan)
    new[:ev.shape[0]] = ev
    return new


@njit(cache=True)
def _record(ev, n_events, code, t, v):
    """The event records with one more (code, time, velocity; Zeno time NaN), and their count."""
    ev = _grow(ev, n_events)
    ev[n_events, 0] = code
    ev[n_events, 1] = t
    ev[n_events, 2] = v
    ev[n_events, 3] = np.nan
    return ev, n_events + 1


@njit(cache=True)
def run_buffers(nn, N, U):
    """What a run writes, for nn nodes, up to N + 1 Taylor terms and U step lengths; a batch's runs
    share them (each run writes every node it reaches; the states are NaN until then).
    (out_s, out_v, out_sigma, out_phase, event records, the one-step tables per phase kind, the
    scratch arrays of the stepping and the event search: a step's series and its derivative, the
    forcing's, the drive's coefficients over a step and their derivative, zeros, the event rows
    and coefficients, per row: started on its zero, cleared; per event: kind, first row, rows,
    combination, started on its zero, to be searched; per step length the bound's H, q,
    1 / (1 - q), H^2/8; the step lengths in time; the window's row maxima; the drive at a point;
    the event search's stack: kernel_events._search.)"""
    NC = N + 1
    return (np.full(nn, np.nan), np.full(nn, np.nan), np.ones(nn), np.full(nn, -1, dtype=np.int8),
            np.full((EVENT_ROWS, 4), np.nan), np.zeros((3, U, 18)),
            (np.zeros(NC), np.zeros(NC), np.zeros(max(6, NC)), np.zeros(6), np.zeros(6), np.zeros(NC),
             np.zeros((4, 5)), np.zeros((4, NC)), np.zeros(4, dtype=np.bool_), np.zeros(4, dtype=np.bool_),
             np.zeros(4, dtype=np.int64), np.zeros(4, dtype=np.int64), np.zeros(4, dtype=np.int64),
             np.zeros(4, dtype=np.int64), np.zeros(4, dtype=np.bool_), np.zeros(4, dtype=np.bool_),
             np.empty((4, U)), np.empty(U), np.empty(4), np.zeros(6),
             np.zeros((SEARCH_ROWS + max(6, NC), MAX_DEPTH + 2))))


@njit(cache=True, inline="always")
def _rest_phase(phase, s_star, j, u, nodes, h, inv, PT, Dn, Sb, sw1, k, c, lash, W0, rate, R, blk, out_s, out_v,
                out_phase, ws):
    """A valve at rest at s_star (seated or stuck) from (j, u) (exact_phase._run_static): its node
    records, and (event UP / DOWN or -1 at the end of the grid, j, u, steps searched in detail)."""
    a, da, f, Pw, dP, zero6, rows, E, zr, clear_row, ev_kind, ev_r0, ev_nr, ev_comb, zeros, check, grp, hu, top, \
        tmp, stack = ws
    ns = h.size
    nn = ns + 1
    sw2 = sw1 * sw1
    sw3 = sw2 * sw1
    n_detail = 0
    if W0 + rate * s_star + R < 0.0:
        return UP, j, u, n_detail
    if j >= ns:
        for q in range(j, nn):
            out_s[q] = s_star
            out_v[q] = 0.0
            out_phase[q] = phase
        return -1, j, u, n_detail
    n_ev, nrow = static_table(s_star, k, c, lash, W0, rate, R, rows, ev_kind, ev_r0, ev_nr, ev_comb)
    u0 = u
    shift_into(PT[j], u0, Pw)
    h_loc = (1.0 - u0) * (h[j] * inv)
    deriv_into(Pw, 6, h_loc, dP)
    coeffs(rows, nrow, Pw, dP, zero6, zero6, 6, E, True, s_star, 0.0, zr)
    zero_flags(E, zr, ev_r0, ev_nr, ev_comb, n_ev, zeros)
    for q in range(n_ev):
        check[q] = True
    kind_b, w = earliest(E, 6, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros,
                         node_time(nodes, h, inv, ns, j, u0), h_loc, stack)
    if u0 == 0.0:
        out_s[j] = s_star
        out_v[j] = 0.0
        out_phase[j] = phase
    if kind_b >= 0:
        return kind_b, j, u0 + w * (1.0 - u0), n_detail
    for q in range(n_ev):
        zeros[q] = False
    # the rows as scalars (padded to 4 with a row that is always -1): the loop below is
    # straight-line code on registers
    for r in range(nrow, 4):
        rows[r, 0], rows[r, 1], rows[r, 2], rows[r, 3], rows[r, 4] = 0.0, 0.0, -1.0, 0.0, 0.0
    a0_, b0_, k0_ = rows[0, 0], rows[0, 1], rows[0, 2]
    a1_, b1_, k1_ = rows[1, 0], rows[1, 1], rows[1, 2]
    a2_, b2_, k2_ = rows[2, 0], rows[2, 1], rows[2, 2]
    a3_, b3_, k3_ = rows[3, 0], rows[3, 1], rows[3, 2]
    i = j + 1
    e0a = e0b = e0c = e0d = -1.0
    if i < nn:
        D0, D1 = Dn[0, i], Dn[1, i] * sw1
        e0a = a0_ * D0 + b0_ * D1 + k0_
        e0b = a1_ * D0 + b1_ * D1 + k1_
        e0c = a2_ * D0 + b2_ * D1 + k2_
        e0d = a3_ * D0 + b3_ * D1 + k3_
    # a valve held only by the "up" event (no "down"): whole blocks of steps are cleared at once by
    # the push row's bound over the block (the drive's largest S and S1 at its nodes, plus the
    # largest sag k h^2/8 |S2| + c h^2/8 |S3|)
    ap_, bp_, kp_ = rows[nrow - 1, 0], rows[nrow - 1, 1], rows[nrow - 1, 2]
    blocks_ok = n_ev == 1 and ap_ >= 0.0 and bp_ >= 0.0
    while i < ns:
        if blocks_ok and i % BLOCK == 0 and i + BLOCK <= ns:
            bk = i // BLOCK
            if ap_ * (blk[0, bk] + blk[2, bk]) + bp_ * ((blk[1, bk] + blk[3, bk]) * sw1) + kp_ <= 0.0:
                for q in range(i, i + BLOCK):
                    uq = np.uint64(q)
                    out_s[uq] = s_star
                    out_v[uq] = 0.0
                    out_phase[uq] = phase
                i += BLOCK
                if i < nn:
                    D0, D1 = Dn[0, i], Dn[1, i] * sw1
                    e0a = a0_ * D0 + b0_ * D1 + k0_
                    e0b = a1_ * D0 + b1_ * D1 + k1_
                    e0c = a2_ * D0 + b2_ * D1 + k2_
                    e0d = a3_ * D0 + b3_ * D1 + k3_
                continue
        ui = np.uint64(i)  # (unsigned: read without numba's negative index wraparound)
        ui1 = np.uint64(i + 1)
        out_s[ui] = s_star
        out_v[ui] = 0.0
        out_phase[ui] = phase
        h_i = h[ui] * inv
        b2 = Sb[1, ui] * sw2
        b3 = Sb[2, ui] * sw3
        H8 = h_i * h_i / 8.0
        D0, D1 = Dn[0, ui1], Dn[1, ui1] * sw1
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
            any_open = _open_events(clear_row, ev_r0, ev_nr, ev_comb, n_ev, check)
        if any_open:
            n_detail += 1
            deriv_into(PT[i], 6, h_i, dP)
            coeffs(rows, nrow, PT[i], dP, zero6, zero6, 6, E, False, 0.0, 0.0, zr)
            kind_b, w = earliest(E, 6, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros, nodes[i] * inv, h_i, stack)
            if kind_b >= 0:  # (at w = 0 the next phase records node i again)
                return kind_b, i, w, n_detail
        i += 1
    for q in range(j + 1, nn):
        out_s[q] = s_star
        out_v[q] = 0.0
        out_phase[q] = phase
    return -1, j, u, n_detail


@njit(cache=True, inline="always")
def _window_contact(PT, Dn, hidx, tab, out_s, out_v, i, s, v, Fc, sw1, k0, l0, m0, m2, K, kc, cc, vzero, ta, tb, tc,
                    acm):
    """The window's states (written from node i on) and, over its nodes, the largest values of the
    contact phase's rows (moving_table: separation -(k S + c S' ) + k lash + k s + c v, the seat -s,
    velocity zero -sigma v when there is friction) and of |m a| = |k S + c S' - Fc - K s - c v|
    and |v|. The rows are moving_table's, evaluated without their zero terms (the same floats:
    adding or multiplying into an exact zero changes no value)."""
    ss = s
    vv = v
    Vm = abs(v)
    q = i
    while q < i + WINDOW:
        uq = np.uint64(q)  # (unsigned: read without numba's negative index wraparound)
        uq1 = np.uint64(q + 1)
        out_s[uq] = ss
        out_v[uq] = vv
        ss, vv = step(tab, hidx[uq], PT, uq, Fc, ss, vv)
        P = kc * Dn[0, uq1] + cc * (Dn[1, uq1] * sw1)
        cv = m0 * vv
        ta = max(ta, ((-P + k0) + l0 * ss) + cv)
        tb = max(tb, -ss)
        if vzero:
            tc = max(tc, m2 * vv)
        acm = max(acm, abs(((P - Fc) - K * ss) - cv))
        Vm = max(Vm, abs(vv))
        q += 1
    return ss, vv, ta, tb, tc, acm, Vm


@njit(cache=True, inline="always")
def _window_flight(PT, Dn, hidx, tab, out_s, out_v, i, s, v, Fc, sw1, a0, k0, l0, b1, m1, m2, m3, K, force_row, nrow,
                   ta, tb, tc, td, acm):
    """_window_contact for the flight phase (moving_table: the gap k S - k lash - k s, with damping
    also the force k S + c S' - k lash - k s - c v, the seat -s, velocity zero -sigma v; |m a| =
    |-Fc - K s|)."""
    ss = s
    vv = v
    Vm = abs(v)
    q = i
    while q < i + WINDOW:
        uq = np.uint64(q)  # (unsigned: read without numba's negative index wraparound)
        uq1 = np.uint64(q + 1)
        out_s[uq] = ss
        out_v[uq] = vv
        ss, vv = step(tab, hidx[uq], PT, uq, Fc, ss, vv)
        kS = a0 * Dn[0, uq1]
        ks = l0 * ss
        ta = max(ta, (kS + k0) + ks)
        if force_row:
            tb = max(tb, ((kS + b1 * (Dn[1, uq1] * sw1)) + k0) + ks + m1 * vv)
            tc = max(tc, -ss)
            if nrow > 3:
                td = max(td, m3 * vv)
        else:
            tb = max(tb, -ss)
            if nrow > 2:
                tc = max(tc, m2 * vv)
        acm = max(acm, abs(-Fc - K * ss))
        Vm = max(Vm, abs(vv))
        q += 1
    return ss, vv, ta, tb, tc, td, acm, Vm


@njit(cache=True, inline="always")
def _moving_phase(kind, s, v, sigma, release, j, u, nodes, h, inv, PT, Dn, Sb, sw1, hidx, masses, tabs, k, c, lash,
                  W0, R, N, win, out_s, out_v, out_sigma, out_phase, ws):
    """A moving valve (contact or flight) from (j, u) with state (s, v) and friction sign sigma
    (exact_phase._run_moving; release: it starts from rest, pushed in the direction sigma): its
    node records, and (event or -1 at the end of the grid, j, u, s, v there, steps searched in
    detail). masses: (M, M1, spring rate) in one argument (a call of more than 30 arguments compiles
    to CALL_FUNCTION_EX, which numba does not inline)."""
    a, da, f, Pw, dP, zero6, rows, E, zr, clear_row, ev_kind, ev_r0, ev_nr, ev_comb, zeros, check, grp, hu, top, \
        tmp, stack = ws
    ns = h.size
    nn = ns + 1
    U = hu.size
    NC = N + 1
    sw2 = sw1 * sw1
    sw3 = sw2 * sw1
    n_detail = 0
    # m, c, K, kc, cc of the phase (exact.py's LinearPhase, as run_nodes' tables), without an array per run
    M, M1, rate = masses
    if kind == CONTACT:
        m_, c_, K_, kc_, cc_ = M1, c, k + rate, k, c
    else:
        m_, c_, K_, kc_, cc_ = M, 0.0, rate, 0.0, 0.0
    Fc = kc_ * lash + W0 + R * sigma
    n_ev, nrow = moving_table(kind, k, c, lash, R, sigma, rows, ev_kind, ev_r0, ev_nr, ev_comb)
    if j >= ns:
        out_s[ns] = s
        out_v[ns] = v
        out_phase[ns] = kind
        out_sigma[ns] = sigma
        return -1, j, u, s, v, n_detail
    # first (possibly partial) step: event functions may start on their zero here
    u0 = u
    shift_into(PT[j], u0, Pw)
    h_loc = (1.0 - u0) * (h[j] * inv)
    expand(m_, c_, K_, kc_, cc_, Pw, h_loc, s, v, Fc, N, a, f)
    if release:
        f0 = 2.0 * m_ * a[2] / (h_loc * h_loc)
        terms = abs(kc_ * Pw[0]) + abs(cc_ * Pw[1] / h_loc) + abs(Fc) + abs(K_ * s)
        if sigma * f0 < 0.0 and abs(f0) <= RELEASE_RESIDUAL * terms:
            expand(m_, c_, K_, kc_, cc_, Pw, h_loc, s, v, Fc + f0, N, a, f)
    deriv_into(a, NC, h_loc, da)
    deriv_into(Pw, 6, h_loc, dP)
    coeffs(rows, nrow, Pw, dP, a, da, NC, E, True, s, v, zr)
    zero_flags(E, zr, ev_r0, ev_nr, ev_comb, n_ev, zeros)
    for q in range(n_ev):
        check[q] = True
    kind_b, w = earliest(E, NC, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros,
                         node_time(nodes, h, inv, ns, j, u0), h_loc, stack)
    if u0 == 0.0:
        out_s[j] = s
        out_v[j] = v
        out_phase[j] = kind
        out_sigma[j] = sigma
    if kind_b >= 0:
        return kind_b, j, u0 + w * (1.0 - u0), horner(a, NC, w), horner(da, NC, w), n_detail
    s = fsum(a, NC)
    v = fsum(da, NC)
    for q in range(n_ev):
        zeros[q] = False
    # per step length: a bound of the steps (a hair above the group's length), the bound's
    # q = H (c + K H) / m and 1 / (1 - q), H^2 / 8; the window bound's: the largest of the groups
    # (q, 1 / (1 - q) and H^2/8 grow with H); no window bound where a group's per-step bound does
    # not apply (q >= MAX_BOUND_Q)
    wH = wq = wi1q = wH8 = 0.0
    for gi in range(U):
        Hq = hu[gi] * (1.0 + GROUP_MARGIN)
        grp[0, gi] = Hq
        grp[1, gi] = Hq * (c_ + K_ * Hq) / m_
        grp[2, gi] = 1.0 / (1.0 - grp[1, gi])
        grp[3, gi] = Hq * Hq / 8.0
        wH = max(wH, grp[0, gi])
        wq = max(wq, grp[1, gi])
        wi1q = max(wi1q, grp[2, gi])
        wH8 = max(wH8, grp[3, gi])
    inv_m = 1.0 / m_
    win_ok = wq < MAX_BOUND_Q
    # the rows as scalars (padded to 4 with a row that is always -1): the loop below is
    # straight-line code on registers
    for r in range(nrow, 4):
        rows[r, 0], rows[r, 1], rows[r, 2], rows[r, 3], rows[r, 4] = 0.0, 0.0, -1.0, 0.0, 0.0
    a0_, b0_, k0_, l0_, m0_ = rows[0, 0], rows[0, 1], rows[0, 2], rows[0, 3], rows[0, 4]
    a1_, b1_, k1_, l1_, m1_ = rows[1, 0], rows[1, 1], rows[1, 2], rows[1, 3], rows[1, 4]
    a2_, b2_, k2_, l2_, m2_ = rows[2, 0], rows[2, 1], rows[2, 2], rows[2, 3], rows[2, 4]
    a3_, b3_, k3_, l3_, m3_ = rows[3, 0], rows[3, 1], rows[3, 2], rows[3, 3], rows[3, 4]
    i = j + 1
    # the first window starts WINDOW_LEAD steps into the phase, at any step (a window across two of
    # the grid's windows takes the larger of their bounds: still at least every step's); after a
    # window that does not clear, the next starts after it
    next_win = i + WINDOW_LEAD
    n_win = ns // WINDOW
    S0 = 0.0
    S10 = 0.0
    if i < nn:
        S0, S10 = Dn[0, i], Dn[1, i] * sw1
    e0a = a0_ * S0 + b0_ * S10 + k0_ + l0_ * s + m0_ * v
    e0b = a1_ * S0 + b1_ * S10 + k1_ + l1_ * s + m1_ * v
    e0c = a2_ * S0 + b2_ * S10 + k2_ + l2_ * s + m2_ * v
    e0d = a3_ * S0 + b3_ * S10 + k3_ + l3_ * s + m3_ * v
    while i < ns:
        if win_ok and i >= next_win and (i + WINDOW - 1) // WINDOW < n_win:
            # the window bound: the states of WINDOW steps propagated first (the same operations
            # as below: the same states), the rows' largest values and the largest |m a| and |v|
            # at its nodes with them, then every event cleared at once by _window_clear. A window
            # not cleared is done again step by step from its first node (the outputs written
            # here are written again, or by the phases that follow).
            acm0 = abs(kc_ * S0 + cc_ * S10 - Fc - K_ * s - c_ * v)
            if kind == CONTACT:
                ss, vv, ta, tb, tc, acm, Vm = _window_contact(
                    PT, Dn, hidx, tabs[CONTACT], out_s, out_v, i, s, v, Fc, sw1, k0_, l0_, m0_, m2_, K_, kc_, cc_,
                    nrow > 2, e0a, e0b, e0c, acm0)
                td = e0d
            else:
                ss, vv, ta, tb, tc, td, acm, Vm = _window_flight(
                    PT, Dn, hidx, tabs[FLIGHT], out_s, out_v, i, s, v, Fc, sw1, a0_, k0_, l0_, b1_, m1_, m2_, m3_,
                    K_, c > 0.0, nrow, e0a, e0b, e0c, e0d, acm0)
            wa = i // WINDOW
            wz = (i + WINDOW - 1) // WINDOW
            top[0], top[1], top[2], top[3] = ta, tb, tc, td
            B1 = win[0, wa]
            B2 = win[1, wa]
            B3 = win[2, wa]
            if wz != wa:
                B1 = B1 if B1 >= win[0, wz] else win[0, wz]
                B2 = B2 if B2 >= win[1, wz] else win[1, wz]
                B3 = B3 if B3 >= win[2, wz] else win[2, wz]
            next_win = i + WINDOW
            if _window_clear(top, acm, Vm, B1 * sw1, B2 * sw2, B3 * sw3, c_, K_, kc_, cc_,
                             inv_m, wH, wi1q, wH8, rows, ev_r0, ev_nr, ev_comb, n_ev, clear_row):
                for q in range(i, i + WINDOW):
                    out_phase[q] = kind
                    out_sigma[q] = sigma
                s = ss
                v = vv
                i += WINDOW
                S0, S10 = Dn[0, i], Dn[1, i] * sw1
                e0a = a0_ * S0 + b0_ * S10 + k0_ + l0_ * s + m0_ * v
                e0b = a1_ * S0 + b1_ * S10 + k1_ + l1_ * s + m1_ * v
                e0c = a2_ * S0 + b2_ * S10 + k2_ + l2_ * s + m2_ * v
                e0d = a3_ * S0 + b3_ * S10 + k3_ + l3_ * s + m3_ * v
                continue
        ui = np.uint64(i)  # (unsigned: read without numba's negative index wraparound)
        ui1 = np.uint64(i + 1)
        out_s[ui] = s
        out_v[ui] = v
        out_phase[ui] = kind
        out_sigma[ui] = sigma
        PTi = PT[ui]
        ug = np.uint64(hidx[ui])
        s1, v1 = step(tabs[kind], ug, PT, ui, Fc, s, v)
        # event values at both nodes; the step is cleared by max(ends) + h^2/8 sup|e''|, sup|e''|
        # from bounds of |S''|, |S'''| over the step and of |a|, |jerk| from the left node and the
        # ODE (exact_phase._scan_window's per-step bound)
        Sn, S1n = Dn[0, ui1], Dn[1, ui1] * sw1
        e1a = a0_ * Sn + b0_ * S1n + k0_ + l0_ * s1 + m0_ * v1
        e1b = a1_ * Sn + b1_ * S1n + k1_ + l1_ * s1 + m1_ * v1
        e1c = a2_ * Sn + b2_ * S1n + k2_ + l2_ * s1 + m2_ * v1
        e1d = a3_ * Sn + b3_ * S1n + k3_ + l3_ * s1 + m3_ * v1
        q_ = grp[1, ug]
        ca = cb = cc = cd = False
        if q_ < MAX_BOUND_Q:
            H = grp[0, ug]
            b1 = Sb[0, ui] * sw1
            b2 = Sb[1, ui] * sw2
            b3 = Sb[2, ui] * sw3
            Vi = abs(v)
            Ac = abs(kc_ * S0 + cc_ * S10 - Fc - K_ * s - c_ * v)
            F1 = kc_ * b1 + cc_ * b2
            Ai = (Ac + H * (F1 + K_ * Vi)) * inv_m * grp[2, ug]
            Ji = (F1 + c_ * Ai + K_ * (Vi + H * Ai)) * inv_m
            H8 = grp[3, ug]
            ca = max(e0a, e1a) + H8 * (abs(a0_) * b2 + abs(b0_) * b3 + abs(l0_) * Ai + abs(m0_) * Ji) <= 0.0
            cb = max(e0b, e1b) + H8 * (abs(a1_) * b2 + abs(b1_) * b3 + abs(l1_) * Ai + abs(m1_) * Ji) <= 0.0
            cc = max(e0c, e1c) + H8 * (abs(a2_) * b2 + abs(b2_) * b3 + abs(l2_) * Ai + abs(m2_) * Ji) <= 0.0
            cd = max(e0d, e1d) + H8 * (abs(a3_) * b2 + abs(b3_) * b3 + abs(l3_) * Ai + abs(m3_) * Ji) <= 0.0
        any_open = False
        if not (ca and cb and cc and cd):
            clear_row[0], clear_row[1], clear_row[2], clear_row[3] = ca, cb, cc, cd
            # an event whose rows are > 0 at the step's end lies in this step: search it whole
            top[0], top[1], top[2], top[3] = e1a, e1b, e1c, e1d
            hit = False
            for q in range(n_ev):
                up = top[ev_r0[q]] > 0.0
                for r in range(ev_r0[q] + 1, ev_r0[q] + ev_nr[q]):
                    up = (up and top[r] > 0.0) if ev_comb[q] == MIN else (up or top[r] > 0.0)
                hit = hit or up
            if q_ < MAX_BOUND_Q and not hit:
                any_open = _open_events(clear_row, ev_r0, ev_nr, ev_comb, n_ev, check)
            else:
                for q in range(n_ev):
                    check[q] = True
                any_open = True
        if any_open:
            n_detail += 1
            H = h[i] * inv
            expand(m_, c_, K_, kc_, cc_, PTi, H, s, v, Fc, N, a, f)
            deriv_into(a, NC, H, da)
            deriv_into(PTi, 6, H, dP)
            coeffs(rows, nrow, PTi, dP, a, da, NC, E, False, 0.0, 0.0, zr)
            kind_b, w = earliest(E, NC, ev_kind, ev_r0, ev_nr, ev_comb, n_ev, check, zeros, nodes[i] * inv, H, stack)
            if kind_b >= 0:
                return kind_b, i, w, horner(a, NC, w), horner(da, NC, w), n_detail
        s = s1
        v = v1
        S0, S10 = Sn, S1n
        e0a, e0b, e0c, e0d = e1a, e1b, e1c, e1d
        i += 1
    out_s[ns] = s
    out_v[ns] = v
    out_phase[ns] = kind
    out_sigma[ns] = sigma
    return -1, j, u, s, v, n_detail


@njit(cache=True, inline="always")
def _released(which, phase, s, j, u, nodes, h, inv, PT, Dn, sw1, k, c, lash, W0, R, ev, n_events, tmp):
    """A resting valve starts to move (phases.release_from_rest): (its phase, friction sign, the
    event records and their count: a seated valve's lift-off recorded)."""
    ns = h.size
    S, S1 = drive_at(PT, Dn, h, inv, sw1, ns, j, u, tmp)
    x = S - lash - s
    pushes = x >= 0.0 and k * x + c * S1 > 0.0
    seated = phase == SEATED
    if which == UP and seated and not pushes and c * S1 > 0.0 and W0 + R > 0.0:
        pushes = True
    sigma = 1.0 if which == UP else -1.0
    if which == UP and seated:
        ev, n_events = _record(ev, n_events, LIFT_OFF, node_time(nodes, h, inv, ns, j, u), 0.0)
    return (CONTACT if pushes else FLIGHT), sigma, ev, n_events


@njit(cache=True, inline="always")
def _handle_event(which, phase, s, v, sigma, j, u, nodes, h, inv, PT, Dn, sw1, M, M1, k, c, lash, W0, rate, R, e,
                  zeno_height, ev, n_events, out_s, out_v, out_phase, tmp):
    """The event `which` of a moving valve (exact._Solver._handle): the phase, state, friction sign
    and grid position after it, the event records and their count."""
    ns = h.size
    if which == SEPARATION or which == RECONTACT:
        ev, n_events = _record(ev, n_events, which, node_time(nodes, h, inv, ns, j, u), v)
        return (FLIGHT if which == SEPARATION else CONTACT), s, v, sigma, j, u, ev, n_events
    S, S1 = drive_at(PT, Dn, h, inv, sw1, ns, j, u, tmp)
    if which == VZERO:  # phases.velocity_zero
        force = k * (S - lash - s) + c * S1 if phase == CONTACT else 0.0
        net = force - W0 - rate * s
        if abs(net) <= R:
            phase = STUCK if s > 0.0 else SEATED
        else:
            sigma = 1.0 if net > 0.0 else -1.0
        return phase, s, 0.0, sigma, j, u, ev, n_events
    # seat impact: phases.seat_rebound
    impact = min(v, 0.0)
    t_now = node_time(nodes, h, inv, ns, j, u)
    ev, n_events = _record(ev, n_events, SEAT, t_now, impact)
    rebound = -e * impact
    if rebound <= 0.0:
        return SEATED, 0.0, 0.0, 1.0, j, u, ev, n_events
    x = S - lash
    force = max(0.0, k * x + c * S1) if x >= 0.0 else 0.0
    m_rest = M1 if force > 0.0 else M
    decel = (W0 + R - force) / m_rest
    if decel > 0.0 and rebound * rebound <= 2.0 * decel * zeno_height:
        # the chatter's closed-form Zeno tail: the valve is seated when its bounces accumulate
        dt = 2.0 * rebound / (decel * (1.0 - e))
        ev[n_events - 1, 3] = t_now + dt
        # exact._Solver._advance: nodes passed on the way are seated at 0
        t_new = t_now + dt
        j0 = j
        while j < ns and nodes[j + 1] * inv <= t_new:
            j += 1
        start = j0 + (1 if u > 0.0 else 0)
        if j >= ns:
            end = j
            u = 0.0
        else:
            u = max(0.0, min((t_new - nodes[j] * inv) / (h[j] * inv), LAST_U))
            end = j + (1 if u > 0.0 else 0)
        for q in range(start, end):
            out_s[q] = 0.0
            out_v[q] = 0.0
            out_phase[q] = SEATED
        return SEATED, 0.0, 0.0, 1.0, j, u, ev, n_events
    return (CONTACT if force > 0.0 else FLIGHT), 0.0, rebound, 1.0, j, u, ev, n_events


@njit(cache=True)
def run_nodes(nodes, h, inv, PT, Dn, Sb, sw1, hidx, h_unique, M, M1, k, c, lash, W0, rate, R, e, zeno_height,
              max_events, N, blk, win, buffers, phase0=SEATED, s0=0.0, v0=0.0, sigma0=1.0, release0=False):
    """One run over the grid (exact_grid.build_grid's nodes, h, P.T, Dn, hidx, h_unique; Sb its
    bounds of the drive's first three derivatives per step), read at the speed sw1: node positions
    and step lengths times inv are times, S' and the bounds times sw1, sw1^2, sw1^3 are per time
    (a grid in cam angle at the speed sw1 = 1 / inv; inv = sw1 = 1 for a grid in time), into
    `buffers` (run_buffers: the node records s, v, friction sign, phase code). Returns (the events:
    rows of code, time, velocity, Zeno accumulation time or NaN; the status: OK, or TOO_MANY_EVENTS
    / NO_PROGRESS, exact.py's RuntimeErrors; the steps searched in detail). blk, win: grid_bounds
    of the grid at the speed 1.
    It starts at rest on the seat; or, given phase0, s0, v0, sigma0, release0, in that phase and
    state at the first node (exact._Solver.run's start from an initial_state: the phase and
    friction sign of phases.phase_of_state, release0 when v0 == 0). (Defaults: numba compiles a
    call that omits them with the constants, so the sweep's runs are the code they were.)"""
    out_s, out_v, out_sigma, out_phase, ev, tabs, ws = buffers
    hu, tmp = ws[17], ws[19]
    ns = h.size
    U = h_unique.size
    for g in range(U):
        hu[g] = h_unique[g] * inv
    n_events = 0
    # per phase kind (m, c, K, kc, cc: exact.py's LinearPhase) the one-step tables, written into the
    # batch's buffer with the stepping's scratch (a, f: not in use yet): no allocation per run
    step_tables_into(tabs[CONTACT], M1, c, k + rate, k, c, hu, N, ws[0], ws[2])
    step_tables_into(tabs[FLIGHT], M, 0.0, rate, 0.0, 0.0, hu, N, ws[0], ws[2])

    phase = phase0
    s = s0
    v = v0
    sigma = sigma0
    j = 0
    u = 0.0
    release = release0
    same_time = 0
    last_time = np.nan
    status = OK
    n_detail = 0  # steps searched in detail (the bound did not clear them)
    while True:
        if n_events > max_events:
            status = TOO_MANY_EVENTS
            break
        if phase == SEATED or phase == STUCK:
            which, j, u, nd = _rest_phase(phase, s, j, u, nodes, h, inv, PT, Dn, Sb, sw1, k, c, lash, W0, rate, R,
                                          blk, out_s, out_v, out_phase, ws)
            n_detail += nd
            if which < 0:
                break
            if j < ns and u >= 1.0:
                j += 1
                u = 0.0
            phase, sigma, ev, n_events = _released(which, phase, s, j, u, nodes, h, inv, PT, Dn, sw1, k, c, lash, W0,
                                                   R, ev, n_events, tmp)
            v = 0.0
            release = True
        else:
            which, j, u, s, v, nd = _moving_phase(phase, s, v, sigma, release, j, u, nodes, h, inv, PT, Dn, Sb, sw1,
                                                  hidx, (M, M1, rate), tabs, k, c, lash, W0, R, N, win,
                                                  out_s, out_v, out_sigma, out_phase, ws)
            n_detail += nd
            release = False
            if which < 0:
                break
            if j < ns and u >= 1.0:
                j += 1
                u = 0.0
            phase, s, v, sigma, j, u, ev, n_events = _handle_event(
                which, phase, s, v, sigma, j, u, nodes, h, inv, PT, Dn, sw1, M, M1, k, c, lash, W0, rate, R, e,
                zeno_height, ev, n_events, out_s, out_v, out_phase, tmp)
        t_now = node_time(nodes, h, inv, ns, j, u)
        same_time = same_time + 1 if t_now == last_time else 0
        last_time = t_now
        if same_time > MAX_SAME_TIME:
            status = NO_PROGRESS
            break
    return ev[:n_events].copy(), status, n_detail


@njit(cache=True)
def solve_nodes(nodes, h, PT, Dn, Sb, hidx, h_unique, M, M1, k, c, lash, W0, rate, R, e, zeno_height, max_events, N,
                phase0, s0, v0, sigma0, release0):
    """run_nodes on a grid in time (its grid_bounds computed here), from the given start (run_nodes'
    phase0 ... release0), with buffers of its own: (out_s, out_v, out_sigma, out_phase, events,
    status, steps searched in detail). The `exact-compiled` solver's one compiled call
    (exact_kernel.solve)."""
    blk, win = grid_bounds(h, Dn, Sb)
    buffers = run_buffers(h.size + 1, N, h_unique.size)
    ev, status, n_detail = run_nodes(nodes, h, 1.0, PT, Dn, Sb, 1.0, hidx, h_unique, M, M1, k, c, lash, W0, rate, R,
                                     e, zeno_height, max_events, N, blk, win, buffers, phase0, s0, v0, sigma0,
                                     release0)
    return buffers[0], buffers[1], buffers[2], buffers[3], ev, status, n_detail


def aot_exports() -> dict:
    """What the ahead-of-time module exports of this module (exact_kernel.build_aot): solve_nodes,
    for the types and layouts exact_kernel.solve passes."""
    from numba import types as T

    A1, A2, I1, F = T.float64[::1], T.float64[:, ::1], T.int64[::1], T.float64
    signature = T.Tuple((A1, A1, A1, T.int8[::1], A2, T.int64, T.int64))(
        A1, A1, A2, A2, A2, I1, A1, F, F, F, F, F, F, F, F, F, F, T.int64, T.int64, T.int64, F, F, F, T.boolean)
    return {"solve_nodes": (signature, solve_nodes)}
