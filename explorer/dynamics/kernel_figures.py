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
from .kernel_events import LIFT_OFF, SEAT, SEPARATION
from .kernel_grid import grid_bounds
from .kernel_phase import run_buffers, run_nodes
from .kernel_steps import phase_rate, taylor_terms
from .phases import CONTACT, FLIGHT

_free_amplitude = njit(cache=True)(free_amplitude)  # the elastic effect's residual amplitude, compiled

# the figures revolution() returns, in this order (the elastic effect's, as the sweep's rows read
# them: explorer/studies/sweep_engine.row_scalars)
FIGURES = ("first_separation_deg", "separations", "flight_time_s", "max_deviation_m", "peak_linkage_force_N",
           "peak_camshaft_back_pressure_N", "lift_off_delay_s", "seating_velocity_m_s", "seat_impacts",
           "largest_bounce_m", "residual_deviation_m", "residual_amplitude_m")


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


@njit(cache=True, inline="always")
def _sample(out_s, out_v, out_phase, Dn, q, omega, k, c, lash, rate, R, preload_closing):
    """Node q's linkage force (exact_output.solution's), its distance from S - lash - W/k while the
    valve is open (else 0) and whether it is open with the linkage unloaded (1, else 0)."""
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
        return force, abs(s - (Dn[0, q] - lash - W / k)), 0 if force > 0.0 else 1
    return force, 0.0, 0


@njit(cache=True)
def revolution(nodes, h, PT, Dn, Sb, hidx, h_unique, out_nodes, i0, omega, M, M1, k, c, lash, W0, rate, R, e,
               zeno_height, max_events, N, ratio, preload_closing, take_up_s, ref, dwell, S_dwell, blk, win, buffers,
               lift, vel):
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
    (effects/residual.residual_reference); blk, win: grid_bounds of the grid in cam angle;
    buffers: kernel_phase.run_buffers for the grid; lift, vel: n each, the valve lift and velocity
    at the output samples are written there."""
    inv = 1.0 / omega  # the grid at this speed: times theta / omega, S' times omega
    ev, status, n_detail = run_nodes(nodes, h, inv, PT, Dn, Sb, omega, hidx, h_unique, M, M1, k, c, lash, W0, rate,
                                     R, e, zeno_height, max_events, N, blk, win, buffers)
    out_s, out_v, out_phase = buffers[0], buffers[1], buffers[3]
    n = out_nodes.size
    fig = np.full(len(FIGURES), np.nan)
    period = 2.0 * math.pi / omega
    # the output samples: force (exact_output.solution's), deviation, separation; two samples a
    # turn, each into its own running maxima (a single one would be a chain of n dependent compares;
    # max is exact in any order)
    pk0 = pk1 = -np.inf
    dv0 = dv1 = 0.0
    separated = 0
    for r in range(0, n - 1, 2):
        f0, d0, o0 = _sample(out_s, out_v, out_phase, Dn, out_nodes[r], omega, k, c, lash, rate, R, preload_closing)
        f1, d1, o1 = _sample(out_s, out_v, out_phase, Dn, out_nodes[r + 1], omega, k, c, lash, rate, R,
                             preload_closing)
        pk0 = max(pk0, f0)
        pk1 = max(pk1, f1)
        dv0 = max(dv0, d0)
        dv1 = max(dv1, d1)
        separated += o0 + o1
    if n % 2:
        f0, d0, o0 = _sample(out_s, out_v, out_phase, Dn, out_nodes[n - 1], omega, k, c, lash, rate, R,
                             preload_closing)
        pk0 = max(pk0, f0)
        dv0 = max(dv0, d0)
        separated += o0
    peak = max(pk0, pk1)
    max_dev = max(dv0, dv1)
    # the valve lift and velocity by cam angle: run sample r is output column (r + i0) mod n
    for r in range(n - i0):
        lift[r + i0] = out_s[out_nodes[r]]
        vel[r + i0] = out_v[out_nodes[r]]
    for r in range(n - i0, n):
        lift[r - (n - i0)] = out_s[out_nodes[r]]
        vel[r - (n - i0)] = out_v[out_nodes[r]]
    fig[1] = 0.0
    fig[8] = 0.0
    fig[2] = 360.0 * separated / n / 360.0 * period
    fig[3] = max_dev
    fig[4] = peak
    fig[5] = ratio * peak  # = max(ratio force): the product rounds monotonically (the scene has ratio > 0)
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
    return fig, rev, status


# the columns of a batch's run parameters (revolutions())
RUN_PARAMETERS = ("omega", "mass", "oscillating_mass", "stiffness", "damping", "lash", "seated_resistance",
                  "spring_rate", "friction", "restitution", "preload_closing", "take_up_s")


@njit(cache=True)
def revolutions(nodes, h, PT, Dn, Sb, hidx, h_unique, out_nodes, i0, h_max, ratio, runs, zeno_height, max_events,
                ref, dwell, S_dwell):
    """revolution() for many runs on one grid (runs: one row of RUN_PARAMETERS each): the FIGURES
    per run and the solver status per run (a batch costs no Python per run; its runs share the
    grid's bounds and the buffers)."""
    R = runs.shape[0]
    figs = np.empty((R, len(FIGURES)))
    status = np.empty(R, dtype=np.int64)
    blk, win = grid_bounds(h, Dn, Sb)  # once for the batch: they do not depend on the speed
    terms = np.empty(R, dtype=np.int64)
    for r in range(R):
        p = runs[r]
        terms[r] = taylor_terms(phase_rate(p[1], p[2], p[3], p[4], p[7]) * h_max / p[0])
    n = out_nodes.size
    buffers = run_buffers(h.size + 1, terms.max() if R else 1, h_unique.size)
    lift = np.empty(n)
    vel = np.empty(n)
    for r in range(R):
        p = runs[r]
        fig, rev, st = revolution(nodes, h, PT, Dn, Sb, hidx, h_unique, out_nodes, i0, p[0], p[1], p[2], p[3], p[4],
                                  p[5], p[6], p[7], p[8], p[9], zeno_height, max_events, terms[r], ratio, p[10], p[11],
                                  ref, dwell, S_dwell, blk, win, buffers, lift, vel)
        figs[r] = fig
        status[r] = st
    return figs, status
