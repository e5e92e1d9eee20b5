"""A numba RK4 of the elastic valve model (the baseline bench_engine_trees --analysis compares the
exact batch engine with): the same LinkageModel as the exact solver (explorer/dynamics/exact.py),
integrated with the classical fourth-order Runge-Kutta method on the exact solver's own grid
(each of its steps cut into m equal substeps; the drive S, S' read from the grid's step
polynomials, kernel_grid.drive_at, so both solvers see the same cam).

Right-hand side (valve-referred, SI; reference.py's contact/flight accelerations): the linkage is
loaded when x = S - lash - s > 0 and F = k x + c (S' - v) > 0, then a = (F - W(s) - f sgn v) / M1,
else a = (-W(s) - f sgn v) / M; W(s) = W0 + rate s. A seated valve (s = 0, v = 0) stays seated
while F - W0 <= f. A seat impact is located inside its substep (root of the substep's cubic Hermite
interpolant of s, by bisection, 60 halvings), the velocity reversed times e, the rest of the
substep integrated from there; an impact slower than V_REST ends the bounces (a bounce of
V_REST^2 / (2 W0 / M) ~ 1e-14 m is below every tolerance used here). Lift-off, separation and
re-contact are not located (they change the acceleration's law, not the state), which is what a
fixed-step RK4 does and why it needs small steps near them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from explorer.dynamics.kernel_grid import drive_at

V_REST = 1e-5  # m/s: slower impacts end the bounce chain (see the docstring)
MAX_HALVINGS = 60  # bisection of an event within a substep (2^-60 of a substep)
MAX_EVENTS_PER_STEP = 16  # events located within one substep (more: the rest of it is left undone)


@njit(cache=True)
def _acc(S, S1, s, v, loaded, d, M, M1, k, c, lash, W0, rate, f):
    """The acceleration under a fixed law: linkage loaded or not, friction direction d."""
    W = W0 + rate * s
    if loaded:
        return (k * (S - lash - s) + c * (S1 - v) - W - f * d) / M1
    return (-W - f * d) / M


@njit(cache=True)
def _law_holds(S, S1, s, v, loaded, d, k, c, lash):
    """The state is still under the law (loaded, d) and above the seat."""
    if s < 0.0:
        return False
    x = S - lash - s
    now = x > 0.0 and k * x + c * (S1 - v) > 0.0
    if now != loaded:
        return False
    return v * d >= 0.0


@njit(cache=True)
def _rk4(PT, Dn, h, inv, sw1, ns, j, u0, du, dt, s, v, loaded, d, M, M1, k, c, lash, W0, rate, f, tmp):
    """One RK4 step over u in [u0, u0 + du] of grid step j (dt: its length in time) under a fixed
    law; returns the state and the drive at its end."""
    Sa, S1a = drive_at(PT, Dn, h, inv, sw1, ns, j, u0, tmp)
    Sm, S1m = drive_at(PT, Dn, h, inv, sw1, ns, j, u0 + 0.5 * du, tmp)
    Sb, S1b = drive_at(PT, Dn, h, inv, sw1, ns, j, u0 + du, tmp)
    a1 = _acc(Sa, S1a, s, v, loaded, d, M, M1, k, c, lash, W0, rate, f)
    s2, v2 = s + 0.5 * dt * v, v + 0.5 * dt * a1
    a2 = _acc(Sm, S1m, s2, v2, loaded, d, M, M1, k, c, lash, W0, rate, f)
    s3, v3 = s + 0.5 * dt * v2, v + 0.5 * dt * a2
    a3 = _acc(Sm, S1m, s3, v3, loaded, d, M, M1, k, c, lash, W0, rate, f)
    s4, v4 = s + dt * v3, v + dt * a3
    a4 = _acc(Sb, S1b, s4, v4, loaded, d, M, M1, k, c, lash, W0, rate, f)
    return (s + dt / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4), v + dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4),
            Sb, S1b)


@njit(cache=True)
def rk4_revolution(nodes, h, PT, Dn, out_nodes, omega, m, M, M1, k, c, lash, W0, rate, f, e, out):
    """The valve lift at the grid's output nodes (out, run order) over one revolution at omega, m
    RK4 substeps per grid step, from the seated valve at the run's first node."""
    inv = 1.0 / omega
    ns = h.size
    tmp = np.empty(6)
    s, v, seated = 0.0, 0.0, True
    loaded, d = True, 1.0
    r = 0
    nout = out_nodes.size
    du = 1.0 / m
    for j in range(ns):
        if r < nout and out_nodes[r] == j:
            out[r] = s
            r += 1
        dt = h[j] * inv * du
        for i in range(m):
            u0 = i * du
            frac = 0.0  # the part of the substep done
            for _ in range(MAX_EVENTS_PER_STEP):
                if frac >= 1.0:
                    break
                ua = u0 + frac * du
                if seated:
                    # lift-off: the first u where the net push exceeds friction (bisection on the drive)
                    Sb, S1b = drive_at(PT, Dn, h, inv, omega, ns, j, u0 + du, tmp)
                    xb = Sb - lash
                    if not (xb > 0.0 and k * xb + c * S1b - W0 > f):
                        break  # seated to the substep's end
                    lo, hi = frac, 1.0
                    for _ in range(MAX_HALVINGS):
                        mid = 0.5 * (lo + hi)
                        Sm, S1m = drive_at(PT, Dn, h, inv, omega, ns, j, u0 + mid * du, tmp)
                        xm = Sm - lash
                        if xm > 0.0 and k * xm + c * S1m - W0 > f:
                            hi = mid
                        else:
                            lo = mid
                    frac = hi
                    seated, loaded, d = False, True, 1.0
                    continue
                s1, v1, Sb, S1b = _rk4(PT, Dn, h, inv, omega, ns, j, ua, (1.0 - frac) * du, (1.0 - frac) * dt, s, v,
                                       loaded, d, M, M1, k, c, lash, W0, rate, f, tmp)
                if _law_holds(Sb, S1b, s1, v1, loaded, d, k, c, lash):
                    s, v = s1, v1
                    break
                # an event in the substep: the first tau where the law fails, by bisection
                lo, hi = 0.0, 1.0
                for _ in range(MAX_HALVINGS):
                    mid = 0.5 * (lo + hi)
                    sm, vm, Sm, S1m = _rk4(PT, Dn, h, inv, omega, ns, j, ua, mid * (1.0 - frac) * du,
                                           mid * (1.0 - frac) * dt, s, v, loaded, d, M, M1, k, c, lash, W0, rate, f,
                                           tmp)
                    if _law_holds(Sm, S1m, sm, vm, loaded, d, k, c, lash):
                        lo = mid
                    else:
                        hi = mid
                s, v, Sh, S1h = _rk4(PT, Dn, h, inv, omega, ns, j, ua, hi * (1.0 - frac) * du,
                                     hi * (1.0 - frac) * dt, s, v, loaded, d, M, M1, k, c, lash, W0, rate, f, tmp)
                frac = frac + hi * (1.0 - frac)
                if s < 0.0:  # seat impact
                    v = -e * v
                    s = 0.0
                    if v < V_REST:
                        s, v, seated = 0.0, 0.0, True
                        continue
                x = Sh - lash - s
                loaded = x > 0.0 and k * x + c * (S1h - v) > 0.0
                d = 1.0 if v > 0.0 else -1.0
    while r < nout:
        out[r] = s
        r += 1
    return out


def rk4_lift(grid, omega: float, m: int, params: np.ndarray) -> np.ndarray:
    """rk4_revolution for a RevolutionGrid and a run's exact_kernel.RUN_PARAMETERS row."""
    p = params
    out = np.empty(grid.out_nodes.size)
    return rk4_revolution(grid.nodes, grid.h, grid.PT, grid.Dn, grid.out_nodes, float(omega), int(m), p[1], p[2],
                          p[3], p[4], p[5], p[6], p[7], p[8], p[9], out)
