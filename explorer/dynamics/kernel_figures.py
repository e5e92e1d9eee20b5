"""The compiled exact solver's figures of a revolution (the elastic effect's summary as the sweep's
rows read it: effects/elastic.py, elastic_events.py, residual.py; studies/sweep_engine.row_scalars)
from one run over a RevolutionGrid (revolution), and of many runs on one grid (revolutions). Part
of the compiled solver (explorer.dynamics.exact_kernel)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import kernel_stamp  # noqa: F401 (the cache is stale when a source it depends on changed)
from .free_vibration import free_amplitude
from .kernel_events import LIFT_OFF, RECONTACT, SEAT, SEPARATION
from .kernel_grid import grid_bounds
from .kernel_phase import borrowed, borrowed_buffers, run_buffers, run_nodes
from .kernel_shared import FIGURES, RUN_PARAMETERS  # noqa: F401 (RUN_PARAMETERS: the rows of revolutions())
from .kernel_steps import phase_rate, taylor_terms
from .phases import CONTACT, FLIGHT

_free_amplitude = njit(cache=True)(free_amplitude)  # the elastic effect's residual amplitude, compiled


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


@njit(cache=True, inline="always")
def _sample(out_s, out_v, out_phase, Dn, q, omega, k, c, lash, rate, R, preload_closing):
    """Node q's linkage force (exact_output.solution's) and its distance from S - lash - W/k while
    the valve is open (else 0)."""
    s = out_s[q]
    v = out_v[q]
    ph = out_phase[q]
    x = Dn[0, q] - lash - s
    if c != 0.0:
        if ph == CONTACT:
            force = max(0.0, k * x + c * (Dn[1, q] * omega - v))
        elif ph == FLIGHT:
            force = 0.0
        else:
            force = max(0.0, k * x + c * (Dn[1, q] * omega)) if x >= 0.0 else 0.0
    else:
        force = max(k * x, 0.0) * (0.0 if ph == FLIGHT else 1.0)
    if s > 0.0:
        W = preload_closing + rate * s + R * (-1.0 if v < 0.0 else 1.0)
        return force, abs(s - (Dn[0, q] - lash - W / k))
    return force, 0.0


@njit(cache=True, inline="always")
def _samples(out_s, out_v, out_phase, out_nodes, Dn, ref, r_lo, r_hi, col0, omega, k, c, lash, rate, R,
             preload_closing, acc):
    """The run samples r in [r_lo, r_hi) (output column r + col0) into the running maxima acc:
    [0, 1] the linkage force, [2, 3] the distance from S - lash - W/k while open, [4, 5] |s - ref|
    (two of each, a sample to each in turn: one would be a chain of dependent compares; max is
    exact in any order)."""
    pk0, pk1, dv0, dv1, rs0, rs1 = acc[0], acc[1], acc[2], acc[3], acc[4], acc[5]
    r = r_lo
    while r + 1 < r_hi:
        # (node and column indices as unsigned: numba then reads them without the negative
        # index wraparound, a third of this loop's instructions; all are >= 0)
        q0 = np.uint64(out_nodes[r])
        q1 = np.uint64(out_nodes[r + 1])
        f0, d0 = _sample(out_s, out_v, out_phase, Dn, q0, omega, k, c, lash, rate, R, preload_closing)
        f1, d1 = _sample(out_s, out_v, out_phase, Dn, q1, omega, k, c, lash, rate, R, preload_closing)
        pk0 = max(pk0, f0)
        pk1 = max(pk1, f1)
        dv0 = max(dv0, d0)
        dv1 = max(dv1, d1)
        rs0 = max(rs0, abs(out_s[q0] - ref[np.uint64(r + col0)]))
        rs1 = max(rs1, abs(out_s[q1] - ref[np.uint64(r + 1 + col0)]))
        r += 2
    if r < r_hi:
        q0 = np.uint64(out_nodes[r])
        f0, d0 = _sample(out_s, out_v, out_phase, Dn, q0, omega, k, c, lash, rate, R, preload_closing)
        pk0 = max(pk0, f0)
        dv0 = max(dv0, d0)
        rs0 = max(rs0, abs(out_s[q0] - ref[np.uint64(r + col0)]))
    acc[0], acc[1], acc[2], acc[3], acc[4], acc[5] = pk0, pk1, dv0, dv1, rs0, rs1


@njit(cache=True, inline="always")
def _largest_open(out_s, out_nodes, r_lo, r_hi, init):
    """max(init, the valve lift at the run samples [r_lo, r_hi)) (four running maxima: one would be a chain of n dependent compares)."""
    m0 = m1 = m2 = m3 = init
    r = r_lo
    while r + 4 <= r_hi:
        m0 = max(m0, out_s[out_nodes[r]])
        m1 = max(m1, out_s[out_nodes[r + 1]])
        m2 = max(m2, out_s[out_nodes[r + 2]])
        m3 = max(m3, out_s[out_nodes[r + 3]])
        r += 4
    while r < r_hi:
        m0 = max(m0, out_s[out_nodes[r]])
        r += 1
    return max(max(m0, m1), max(m2, m3))


@njit(cache=True, inline="always")
def _node(c, n, i0, out_nodes):
    """The node of output column c (run sample c - i0, modulo n)."""
    return out_nodes[c - i0 if c >= i0 else c + n - i0]


@njit(cache=True, inline="always")
def _span_max(out_s, out_nodes, n, i0, c_lo, c_hi, init):
    """max(init, the valve lift at the output columns [c_lo, c_hi)), 0 <= c_lo <= c_hi <= n: the
    run samples of those at or after i0 and of those before."""
    if c_hi > max(c_lo, i0):
        init = _largest_open(out_s, out_nodes, max(c_lo, i0) - i0, c_hi - i0, init)
    if min(c_hi, i0) > c_lo:
        init = _largest_open(out_s, out_nodes, c_lo + n - i0, min(c_hi, i0) + n - i0, init)
    return init


@njit(cache=True)
def openings(n, i0, out_nodes, Dn, lash, opens):
    """The output columns where the rigid valve opens (S - lash > 0 there, not at the column
    before, periodically), in column order, into `opens` (n entries); returns how many. They
    depend on the grid and the lash, not on the speed: revolutions() finds them once per lash."""
    k = 0
    prev = Dn[0, _node(n - 1, n, i0, out_nodes)] - lash > 0.0
    for c in range(n):
        now = Dn[0, _node(c, n, i0, out_nodes)] - lash > 0.0
        if now and not prev:
            opens[k] = c
            k += 1
        prev = now
    return k


@njit(cache=True, inline="always")
def _elapsed(t0, t1, period):
    """elastic_events._elapsed: the time from t0 to t1, t1 in the next revolution when before t0."""
    d = t1 - t0
    return d + period if d < 0.0 else d


@njit(cache=True)
def _valve_periods(rev, n, omega, i0, out_s, out_nodes, Dn, lash, opens, k, is_float):
    """effects/elastic_events.valve_periods on the revolution's events `rev` (time order): (the
    largest bounce, the float's flight time), and is_float[q] = True for the separations while the
    valve is open (its float). The same walk: from the rigid valve's first opening on the grid
    (S - lash > 0 at a column, not at the one before; column 0: none), each event at the first
    sample after it, open from an opening to the first seat impact (not one while the rigid valve
    is open and rising: S' > 0, the sign of the rigid valve's velocity), seated from there to the
    next opening (its lift there: the bounce); the state holds from one opening or event to the
    next; a float separation flies to the next re-contact or seat impact (round once more past the
    walk's end for it; with neither, to the walk's end). opens[:k]: the openings' columns
    (openings())."""
    m = rev.shape[0]
    period = 2.0 * math.pi / omega
    start = opens[0] if k > 0 else 0
    at = np.empty(m, dtype=np.int64)
    for q in range(m):
        at[q] = (_first_sample(n, omega, rev[q, 1], True) % n - start) % n
    order = np.argsort(at, kind="mergesort")  # (stable: events of one sample keep their time order)
    best = 0.0
    flight = 0.0
    flying = -1.0  # the time of the float separation the valve flies from; < 0: not flying
    seated = False
    p = 0
    j = 0
    pos = 0
    while pos < n:  # walk positions: column (start + pos) mod n
        if j < k and opens[j] - start == pos:
            seated = False
            j += 1
        c = start + pos if start + pos < n else start + pos - n
        while p < m and at[order[p]] == pos:
            q = order[p]
            p += 1
            code = int(rev[q, 0])
            if (code == SEAT or code == RECONTACT) and flying >= 0.0:
                flight += _elapsed(flying, rev[q, 1], period)
                flying = -1.0
            if code == SEAT:
                g = _node(c, n, i0, out_nodes)
                seated = seated or not (Dn[0, g] - lash > 0.0 and Dn[1, g] > 0.0)
            elif code == SEPARATION and not seated:
                is_float[q] = True
                if flying < 0.0:
                    flying = rev[q, 1]
        nxt = n
        if j < k:
            nxt = opens[j] - start
        if p < m:
            nxt = min(nxt, at[order[p]])
        if seated:
            lo, hi = start + pos, start + nxt
            if hi <= n:
                best = _span_max(out_s, out_nodes, n, i0, lo, hi, best)
            elif lo >= n:
                best = _span_max(out_s, out_nodes, n, i0, lo - n, hi - n, best)
            else:
                best = _span_max(out_s, out_nodes, n, i0, lo, n, best)
                best = _span_max(out_s, out_nodes, n, i0, 0, hi - n, best)
        pos = nxt
    if flying >= 0.0:  # round once more to the end of the flight, or to the walk's end
        end = float(start) * (2.0 * math.pi / n) / omega  # (the time_s column's operations)
        for p in range(m):
            code = int(rev[order[p], 0])
            if code == SEAT or code == RECONTACT:
                end = rev[order[p], 1]
                break
        flight += _elapsed(flying, end, period)
    return best, flight


@njit(cache=True, error_model="numpy")  # (numpy's: no zero check at the samples' W / k; k > 0)
def revolution(nodes, h, PT, Dn, Sb, hidx, h_unique, out_nodes, i0, omega, M, M1, k, c, lash, W0, rate, R, e,
               zeno_height, max_events, N, ratio, preload_closing, take_up_s, ref, dwell, S_dwell, blk, win, buffers,
               acc, opens, n_opens):
    """One revolution of the elastic effect at the speed omega, on a grid built in cam angle
    (RevolutionGrid: the n output samples from the drive's lowest point, out_nodes their nodes):
    the FIGURES, the events of the revolution (rows: code, time within the revolution, velocity,
    cam angle in degrees; in time order) and the solver status; the node records are left in
    `buffers` (kernel_phase.run_buffers for the grid), the valve lift at output column c is
    out_s[out_nodes[(c - i0) mod n]]. acc: 6 scratch values.
    The figures are the elastic effect's summary read as sweep_engine.row_scalars reads it:
    force and deviation from S - lash - W/k on the output samples, events from the start of the
    run for one period, times modulo the period (effects/elastic.py, elastic_events.py; the
    float's separations, flight time and the bounce: _valve_periods);
    the residual figures from the lift the cam is made for at the output angles, ref, the dwell's
    first sample (-1: none) and the valve-referred drive there, S_dwell
    (effects/residual.residual_reference); blk, win: grid_bounds of the grid in cam angle; opens,
    n_opens: where the rigid valve opens on the grid at this lash (openings())."""
    inv = 1.0 / omega  # the grid at this speed: times theta / omega, S' times omega
    ev, status, n_detail = run_nodes(nodes, h, inv, PT, Dn, Sb, omega, hidx, h_unique, M, M1, k, c, lash, W0, rate,
                                     R, e, zeno_height, max_events, N, blk, win, buffers)
    out_s, out_v, out_phase = buffers[0], buffers[1], buffers[3]
    n = out_nodes.size
    fig = np.full(len(FIGURES), np.nan)
    period = 2.0 * math.pi / omega
    # the output samples in run order: run sample r is output column r + i0 (r < n - i0), else
    # r - (n - i0)
    acc[0] = acc[1] = -np.inf
    acc[2] = acc[3] = acc[4] = acc[5] = 0.0
    _samples(out_s, out_v, out_phase, out_nodes, Dn, ref, 0, n - i0, i0, omega, k, c, lash, rate, R,
             preload_closing, acc)
    _samples(out_s, out_v, out_phase, out_nodes, Dn, ref, n - i0, n, -(n - i0), omega, k, c, lash, rate, R,
             preload_closing, acc)
    peak = max(acc[0], acc[1])
    fig[1] = 0.0
    fig[8] = 0.0
    fig[3] = max(acc[2], acc[3])
    fig[4] = peak
    fig[5] = ratio * peak  # = max(ratio force): the product rounds monotonically (the scene has ratio > 0)
    fig[10] = max(acc[4], acc[5])
    # the events of the revolution (elastic_events.revolution_events), in time order
    t_start = nodes[out_nodes[0]] * inv
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
    is_float = np.zeros(m, dtype=np.bool_)
    fig[9], fig[2] = _valve_periods(rev, n, omega, i0, out_s, out_nodes, Dn, lash, opens, n_opens, is_float)
    seat_v = np.inf
    delay = np.inf
    for q in range(m):
        code = int(rev[q, 0])
        if code == SEPARATION and is_float[q]:  # the valve's float (_valve_periods)
            if fig[1] == 0.0:
                fig[0] = rev[q, 3]
            fig[1] += 1.0
        elif code == SEAT:
            fig[8] += 1.0
            seat_v = min(seat_v, rev[q, 2])
        elif code == LIFT_OFF and not math.isnan(take_up_s):
            delay = min(delay, np.fmod(rev[q, 1] - take_up_s + period, period))
    fig[6] = delay if delay < np.inf else np.nan
    fig[7] = seat_v if fig[8] > 0.0 else np.nan
    # residual vibration (effects/residual.residual_figures)
    if dwell >= 0:
        q = out_nodes[dwell - i0 if dwell >= i0 else dwell + n - i0]
        fig[11] = _free_amplitude(out_s[q], out_v[q], S_dwell, k, lash, W0, rate, R, M1)
    return fig, rev, status


@njit(cache=True)
def revolutions(nodes, h, PT, Dn, Sb, hidx, h_unique, out_nodes, i0, h_max, ratio, runs, zeno_height, max_events,
                ref, dwell, S_dwell):
    """revolution() for many runs on one grid (runs: one row of RUN_PARAMETERS each): the FIGURES
    per run and the solver status per run (a batch costs no Python per run; its runs share the
    grid's bounds and the buffers)."""
    R = runs.shape[0]
    figs = np.empty((R, len(FIGURES)))
    status = np.empty(R, dtype=np.int64)
    blk_owned, win_owned = grid_bounds(h, Dn, Sb)  # once for the batch: they do not depend on the speed
    terms = np.empty(R, dtype=np.int64)
    for r in range(R):
        p = runs[r]
        terms[r] = taylor_terms(phase_rate(p[1], p[2], p[3], p[4], p[7]) * h_max / p[0])
    owned = run_buffers(h.size + 1, terms.max() if R else 1, h_unique.size)
    acc_owned = np.empty(6)
    opens_owned = np.empty(out_nodes.size, dtype=np.int64)  # openings() of the lash of the run before
    n_opens = 0
    last_lash = np.nan
    # every array the runs read or write, borrowed (kernel_phase.borrowed: no reference counting in
    # the runs); the owners live to the end of this function
    buffers = borrowed_buffers(owned)
    acc = borrowed(acc_owned)
    nodes, h, PT, Dn, Sb = borrowed(nodes), borrowed(h), borrowed(PT), borrowed(Dn), borrowed(Sb)
    hidx, h_unique, out_nodes, ref = borrowed(hidx), borrowed(h_unique), borrowed(out_nodes), borrowed(ref)
    blk, win = borrowed(blk_owned), borrowed(win_owned)
    opens = borrowed(opens_owned)
    for r in range(R):
        p = runs[r]
        if not p[5] == last_lash:  # (a batch's runs share one lash: exact_kernel.run_batch)
            n_opens = openings(out_nodes.size, i0, out_nodes, Dn, p[5], opens)
            last_lash = p[5]
        fig, rev, st = revolution(nodes, h, PT, Dn, Sb, hidx, h_unique, out_nodes, i0, p[0], p[1], p[2], p[3], p[4],
                                  p[5], p[6], p[7], p[8], p[9], zeno_height, max_events, terms[r], ratio, p[10], p[11],
                                  ref, dwell, S_dwell, blk, win, buffers, acc, opens, n_opens)
        figs[r] = fig
        status[r] = st
    # (the owners of the borrowed arrays, used last here)
    owned[0][0] = acc_owned[0] = blk_owned[0, 0] = win_owned[0, 0] = 0.0
    opens_owned[0] = 0
    return figs, status


def aot_exports() -> dict:
    """What the ahead-of-time module exports (exact_kernel.build_aot): revolutions, for the types
    and layouts exact_kernel.run_batch passes."""
    from numba import types as T

    A1, A2, I1 = T.float64[::1], T.float64[:, ::1], T.int64[::1]
    signature = T.Tuple((A2, I1))(A1, A1, A2, A2, A2, I1, A1, I1, T.int64, T.float64, T.float64, A2, T.float64,
                                  T.int64, A1, T.int64, T.float64)
    return {"revolutions": (signature, revolutions)}
