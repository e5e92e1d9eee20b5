"""Part of the `exact` solver (exact.py): one moving phase's linear ODE with constant coefficients,
    m s'' + c s' + K s = kc (P - lash) + cc P' - Fc,
solved over a step as its Taylor series in u = tau/h (the matrix exponential of the augmented
system as a power series): the unit-response tables of a grid's steps, the drive's forcing
through them, and one step's expansion from a state. See exact.py for the method."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

@dataclass(frozen=True)
class LinearPhase:
    """m s'' + c s' + K s = kc (P - lash) + cc P' - Fc: the ODE of one moving phase."""

    m: float
    c: float
    K: float
    kc: float
    cc: float

    @property
    def rho(self) -> float:
        """Spectral radius of the phase's state matrix: its fastest rate (1/s)."""
        alpha = 0.5 * self.c / self.m
        w2 = self.K / self.m
        if alpha * alpha > w2:
            return alpha + math.sqrt(alpha * alpha - w2)
        return math.sqrt(w2)


@dataclass(frozen=True)
class StepTables:
    """Scaled Taylor coefficients of the unit responses over steps of lengths h (one column each).

    A: s0 = 1; B: v0 = 1; C1: unit constant forcing; R[:, k]: forcing from P = u^k (zero initial
    state). Phi, g1, WP are their values and slopes at the step end (u = 1)."""

    h: np.ndarray  # (U,)
    A: np.ndarray  # (N+1, U)
    B: np.ndarray
    C1: np.ndarray
    R: np.ndarray  # (N+1, 6, U)
    Phi: np.ndarray  # (2, 2, U)
    g1: np.ndarray  # (2, U)
    WP: np.ndarray  # (2, 6, U)


def step_tables(lin: LinearPhase, h: np.ndarray, n_terms: int) -> StepTables:
    h = np.asarray(h, dtype=float)
    if h.size <= 2:
        return _tables_small(lin, h, n_terms)
    U = h.size
    a = np.zeros((n_terms + 1, 9, U))
    a[0, 0] = 1.0
    a[1, 1] = h
    f = np.zeros((6, 9, U))
    f[0, 2] = 1.0
    for k in range(6):
        f[k, 3 + k] += lin.kc
        if k >= 1:
            f[k - 1, 3 + k] += lin.cc * k / h
    h2 = h * h
    ch, Kh2 = lin.c * h, lin.K * h2
    for n in range(n_terms - 1):
        rhs = -ch * (n + 1) * a[n + 1] - Kh2 * a[n]
        if n < 6:
            rhs = rhs + h2 * f[n]
        a[n + 2] = rhs / (lin.m * (n + 1) * (n + 2))
    n_idx = np.arange(n_terms + 1, dtype=float)[:, None, None]
    end = a.sum(axis=0)  # (9, U)
    slope = (n_idx * a).sum(axis=0) / h  # d/dtau
    return _assemble_tables(h, a, end, slope)


def _assemble_tables(h, a, end, slope) -> StepTables:
    Phi = np.array([[end[0], end[1]], [slope[0], slope[1]]])
    return StepTables(
        h=h, A=a[:, 0], B=a[:, 1], C1=a[:, 2], R=a[:, 3:9], Phi=Phi,
        g1=np.array([end[2], slope[2]]), WP=np.array([end[3:9], slope[3:9]]),
    )


def _tables_small(lin: LinearPhase, h: np.ndarray, n_terms: int) -> StepTables:
    """step_tables for one or two step lengths in plain Python (the numpy version's cost is the
    overhead of its ~60 calls on tiny arrays). The same recursion in the same order."""
    m, c, K, kc, cc = lin.m, lin.c, lin.K, lin.kc, lin.cc
    cols = []
    for hu in h.tolist():
        h2 = hu * hu
        ch, Kh2 = c * hu, K * h2
        # forcing rows f[n] of the 9 unit responses: A (s0 = 1), B (v0 = 1), C1 (constant),
        # R_k (drive u^k: kc u^k + cc k u^(k-1) / h)
        basis = []
        for b in range(9):
            a = [0.0] * (n_terms + 1)
            f = [0.0] * 6
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
            for n in range(n_terms - 1):
                rhs = -ch * (n + 1) * a[n + 1] - Kh2 * a[n]
                if n < 6:
                    rhs = rhs + h2 * f[n]
                a[n + 2] = rhs / (m * (n + 1) * (n + 2))
            basis.append(a)
        cols.append(basis)
    a = np.array(cols).transpose(2, 1, 0)  # (n_terms + 1, 9, U)
    end = a.sum(axis=0)
    slope = (np.arange(n_terms + 1, dtype=float)[:, None, None] * a).sum(axis=0) / h
    return _assemble_tables(h, a, end, slope)


def drive_response(lin: LinearPhase, h: float, n_terms: int) -> np.ndarray:
    """WP of the step tables for one step length (2, 6): end value and slope of the responses
    R_k to the drive P = u^k from rest. The same recursion and sums as _tables_small (numpy's
    pairwise sums), in plain Python: only these 6 of its 9 columns, for the forcing of a phase
    kind over the whole grid."""
    m, c, K, kc, cc = lin.m, lin.c, lin.K, lin.kc, lin.cc
    h2 = h * h
    ch, Kh2 = c * h, K * h2
    ends, slopes = [], []
    for k in range(6):
        f = [0.0] * 6
        f[k] += kc
        if k >= 1:
            f[k - 1] += cc * k / h
        a = [0.0] * (n_terms + 1)
        # (the terms before the forcing's first are zeros: the same sums without those steps)
        for n in range(max(k - 1, 0), n_terms - 1):
            rhs = -ch * (n + 1) * a[n + 1] - Kh2 * a[n]
            if n < 6:
                rhs = rhs + h2 * f[n]
            a[n + 2] = rhs / (m * (n + 1) * (n + 2))
        ends.append(_pairwise_sum(a))
        slopes.append(_pairwise_sum([float(n) * x for n, x in enumerate(a)]) / h)
    return np.array([ends, slopes])


def _pairwise_sum(x: list) -> float:
    """numpy's sum of a short contiguous array, operation for operation (its pairwise_sum with
    eight partial sums; up to 128 terms), so plain-Python table values equal the numpy ones."""
    n = len(x)
    if n < 8:
        res = 0.0
        for v in x:
            res += v
        return res
    r = x[:8]
    i = 8
    while i < n - n % 8:
        r = [rj + xj for rj, xj in zip(r, x[i:i + 8])]
        i += 8
    res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    for v in x[i:]:
        res += v
    return res


def expand_step(lin: LinearPhase, P, h: float, s: float, v: float, Fc: float, n_terms: int) -> list:
    """Scaled Taylor coefficients of s over one step from (s, v), P the step's drive polynomial
    (a list of floats). Plain Python: one step at a time, no numpy overhead."""
    m, c, K, kc, cc = lin.m, lin.c, lin.K, lin.kc, lin.cc
    h2m = h * h / m
    beta = K * h2m
    if cc:
        ch = cc / h
        f = [(kc * P[n] + ch * (n + 1) * P[n + 1]) * h2m for n in range(5)] + [kc * P[5] * h2m]
    else:
        f = [kc * x * h2m for x in P]
    f[0] -= Fc * h2m
    f.extend(_ZEROS[:n_terms - 7])
    a = [s, v * h] + _ZEROS[:n_terms - 1]
    a0, a1 = s, v * h
    if c:
        alpha = c * h / m
        for n in range(n_terms - 1):
            a0, a1 = a1, (f[n] - alpha * (n + 1) * a1 - beta * a0) * _INV_PAIR[n]
            a[n + 2] = a1
    else:
        for n in range(n_terms - 1):
            a0, a1 = a1, (f[n] - beta * a0) * _INV_PAIR[n]
            a[n + 2] = a1
    return a


_INV_PAIR = tuple(1.0 / ((n + 1) * (n + 2)) for n in range(64))
_ZEROS = [0.0] * 64
TAYLOR_MIN_TERMS = 9  # fewest terms of a step's series
TAYLOR_TRUNCATION = 1e-19  # relative truncation error of a step's series
TAYLOR_MAX_TERMS = 60  # the series is cut here whatever x (never reached for x <= MAX_RHO_H)


def taylor_terms(x: float) -> int:
    """Taylor terms for a relative truncation error below 1e-19 at rho*h = x (<= MAX_RHO_H)."""
    n, term = 1, x
    bound = math.exp(x)
    while n < TAYLOR_MIN_TERMS or term * bound > TAYLOR_TRUNCATION:
        n += 1
        term *= x / n
        if n > TAYLOR_MAX_TERMS:
            break
    return n
