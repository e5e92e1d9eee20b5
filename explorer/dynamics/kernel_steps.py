"""The compiled exact solver's step (explorer.dynamics.exact_steps compiled): a step's response as
the Taylor series of the phase ODE (expand: exact_steps.expand_step), the one-step propagator's
tables per step length (step_tables) and the propagation of a node state over one step (step);
the polynomial helpers they share with the event search. Part of the compiled solver
(explorer.dynamics.exact_kernel, which alone imports it)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import kernel_stamp  # noqa: F401 (the cache is stale when a source it depends on changed)
from .exact_steps import TAYLOR_MAX_TERMS, TAYLOR_MIN_TERMS, TAYLOR_TRUNCATION

_INV_PAIR = np.array([1.0 / ((n + 1) * (n + 2)) for n in range(64)])  # exact_steps._INV_PAIR


# ---------------------------------------------------------------- small polynomial helpers
@njit(cache=True, inline="always")
def horner(c, n, x):
    acc = 0.0
    for i in range(n - 1, -1, -1):
        acc = acc * x + c[i]
    return acc


@njit(cache=True, inline="always")
def plain_sum(c, n):
    acc = 0.0
    for i in range(n):
        acc += c[i]
    return acc


@njit(cache=True, inline="always")
def fsum(c, n):
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


@njit(cache=True, inline="always")
def deriv_into(c, n, h, out):
    inv = 1.0 / h
    for k in range(1, n):
        out[k - 1] = k * c[k] * inv
    out[n - 1] = 0.0


@njit(cache=True, inline="always")
def shift_into(P, u0, out):
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


# ---------------------------------------------------------------- the step ODE
@njit(cache=True, inline="always")
def expand(m, c, K, kc, cc, P, h, s, v, Fc, N, a, f):
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
def step_tables(m, c, K, kc, cc, h_unique, N):
    """Per step length: Phi (end value and slope of the responses to s0 = 1 and v0 = 1), g1 (to a
    unit constant forcing) and W_P (to the drive P = u^k): exact_steps' tables at u = 1, in the
    columns [Phi00 Phi01 Phi10 Phi11 g0 g1 W0_0..5 W1_0..5]."""
    out = np.zeros((h_unique.size, 18))
    step_tables_into(out, m, c, K, kc, cc, h_unique, N, np.zeros(N + 1), np.zeros(6))
    return out


@njit(cache=True, inline="always")
def step_tables_into(out, m, c, K, kc, cc, h_unique, N, a, f):
    """step_tables written into out (U rows, every column written), with the scratch a (N + 1 or
    more values) and f (6 or more): a run's tables without allocating (the same floats)."""
    U = h_unique.size
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


@njit(cache=True, inline="always")
def step(tab, g, PT, q, Fc, s, v):
    """The state one step later: x1 = Phi x + (drive part - Fc g), with the tables tab[g] of the
    step's length and the drive PT[q]. The drive's and the constant force's part does not depend
    on the state: summed first, so that the chain carried from step to step (s, v -> s1, v1) is
    one multiply and two adds long, not nine operations (the adds are not reassociated for us: no
    fastmath). The indices are read as unsigned (both are >= 0): numba then drops the negative
    index wraparound from every read."""
    ug = np.uint64(g)
    uq = np.uint64(q)
    ds = -Fc * tab[ug, 4]
    dv = -Fc * tab[ug, 5]
    for p in range(6):
        ds += tab[ug, 6 + p] * PT[uq, p]
        dv += tab[ug, 12 + p] * PT[uq, p]
    return (tab[ug, 0] * s + tab[ug, 1] * v) + ds, (tab[ug, 2] * s + tab[ug, 3] * v) + dv


@njit(cache=True)
def taylor_terms(x):
    """exact_steps.taylor_terms."""
    n = 1
    term = x
    bound = math.exp(x)
    while n < TAYLOR_MIN_TERMS or term * bound > TAYLOR_TRUNCATION:
        n += 1
        term *= x / n
        if n > TAYLOR_MAX_TERMS:
            break
    return n


@njit(cache=True)
def phase_rate(M, M1, k, c, rate):
    """exact_phase's rho: the fastest rate of contact and flight (LinearPhase.rho)."""
    alpha = 0.5 * c / M1
    w2 = (k + rate) / M1
    rho = alpha + math.sqrt(alpha * alpha - w2) if alpha * alpha > w2 else math.sqrt(w2)
    return max(rho, math.sqrt(rate / M))
