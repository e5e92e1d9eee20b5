"""Drive and stiffness tabulated as piecewise Hermite polynomials, for solvers that ask one
instant at a time.

solve_ivp calls its right-hand side at one instant per stage (13 per DOP853 step, plus the dense
output and the event functions). For a cam law that costs a few microseconds; for a gear's lift
(jets through a four-bar and a rolling law) and its valve-referred stiffness it costs a
millisecond, i.e. seconds per revolution. Here both are evaluated once, vectorised, at nodes
with their analytic derivatives, and replaced between nodes by Hermite polynomials: quintic for
S (through S, S', S'' at both ends) and cubic for k (through k, k'). Their errors, h^6 S^(6)/
46080 and h^4 k^(4)/384, are below the rounding of the values at the node spacing the solver
uses (a fraction of an output step: tests/test_dynamics_varying.py compares with the analytic
evaluation). The drive's breakpoints are nodes, with one-sided values on each side (taken a hair
inside and moved back by Taylor), so the jumps of S'' and k' stay exact.
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from .model import Drive, StiffnessProfile
from .series import hermite5, taylor_shift


def node_values(drive: Drive, profile: StiffnessProfile | None, nodes: np.ndarray, inner: np.ndarray, delta):
    """Drive rows S, S', S'' and (with a profile) k, k' at the nodes, as (right, left, k_right,
    k_left): the values a step starting and a step ending there sees. They differ only at the
    breakpoint nodes `inner`, where each side is taken `delta` inside and moved back by Taylor."""
    D = np.asarray(drive(nodes), dtype=float)
    right, left = D[:3].copy(), D[:3].copy()
    K = profile(nodes) if profile is not None else None
    k_right, k_left = (K, K.copy()) if K is not None else (None, None)
    if inner.any():
        at = nodes[inner]
        right[:, inner] = taylor_shift(np.asarray(drive(at + delta), dtype=float), -delta)[:3]
        left[:, inner] = taylor_shift(np.asarray(drive(at - delta), dtype=float), delta)[:3]
        if profile is not None:
            for out, sign in ((k_right, 1.0), (k_left, -1.0)):
                kk = profile(at + sign * delta)
                out[0, inner] = kk[0] - sign * delta * kk[1]
                out[1, inner] = kk[1]
    return right, left, k_right, k_left


def _cubic(h: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(4, n) coefficients in u of the cubic through (k, k') = a at u = 0, b at u = 1."""
    y0, y1 = a[0], a[1] * h
    z0, z1 = b[0], b[1] * h
    r0, r1 = z0 - y0 - y1, z1 - y1
    return np.array([y0, y1, 3.0 * r0 - r1, r1 - 2.0 * r0])


class TabulatedDrive:
    """S(t), S'(t), S''(t) and k(t), k'(t) on [t0, t1] from Hermite tables; the interface of
    reference._VaryingCache (call with one time -> (S, S'); attributes Sdd, k, kd)."""

    def __init__(self, drive: Drive, profile: StiffnessProfile | None, t0: float, t1: float, spacing: float):
        n = max(1, math.ceil((t1 - t0) / spacing))
        nodes = np.linspace(t0, t1, n + 1)
        h_min = (t1 - t0) / n
        bps = np.asarray(drive.breakpoints(t0, t1), dtype=float)
        bps = bps[(bps > t0) & (bps < t1)]
        if bps.size:  # breakpoints become nodes; uniform nodes very near one are dropped
            near = np.min(np.abs(nodes[:, None] - bps[None, :]), axis=1) < 1e-3 * h_min
            nodes = np.union1d(nodes[~near | (nodes == t0) | (nodes == t1)], bps)
        h = np.diff(nodes)
        delta = 1e-7 * float(h.min())
        inner = np.isin(nodes, bps)
        right, left, k_right, k_left = node_values(drive, profile, nodes, inner, delta)
        self.nodes = nodes.tolist()
        self.h = h.tolist()
        self._S = hermite5(h, right[:, :-1], left[:, 1:]).T.tolist()
        self._K = None
        if profile is not None:
            self._K = _cubic(h, k_right[:, :-1], k_left[:, 1:]).T.tolist()
        self.t = math.nan
        self.S0 = self.Sd = self.Sdd = 0.0
        self.k = self.kd = 0.0

    def _locate(self, t: float) -> tuple[int, float]:
        j = min(max(bisect.bisect_right(self.nodes, t) - 1, 0), len(self.h) - 1)
        return j, (t - self.nodes[j]) / self.h[j]

    def __call__(self, t: float):
        if t != self.t:
            j, u = self._locate(t)
            h = self.h[j]
            c0, c1, c2, c3, c4, c5 = self._S[j]
            self.S0 = c0 + u * (c1 + u * (c2 + u * (c3 + u * (c4 + u * c5))))
            self.Sd = (c1 + u * (2.0 * c2 + u * (3.0 * c3 + u * (4.0 * c4 + u * 5.0 * c5)))) / h
            self.Sdd = (2.0 * c2 + u * (6.0 * c3 + u * (12.0 * c4 + u * 20.0 * c5))) / (h * h)
            if self._K is not None:
                k0, k1, k2, k3 = self._K[j]
                self.k = k0 + u * (k1 + u * (k2 + u * k3))
                self.kd = (k1 + u * (2.0 * k2 + u * 3.0 * k3)) / h
            self.t = t
        return self.S0, self.Sd

    def stiffness(self, t: float) -> float:
        self(t)
        return self.k
