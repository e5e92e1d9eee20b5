"""Compiled inner loops of the spring chain's exact solver (chain_exact.py), with numba.

Why compiled: the solver's work between events is a recurrence over steps (the state at the end
of a step feeds the next) and, at an event, a bisection and Newton search over closed forms of
a few dozen modes. In numpy every one of these is a handful of calls on arrays of ~20 numbers, so
Python's per-call overhead was most of the cost (profile of benchmarks/bench_spring_chain.py:
windows scanned past the first uncertified step, closures and dict caches in the search). Here the
same formulas run as plain loops: the step recurrence stops at the first step that is not
certified free of an event, and the event search runs whole in one call.

The formulas are those documented in chain_exact.py, in the same order of operations where it
matters (rounding only differs); chain_exact.py holds the method's description. Imported only by
chain_exact.py, itself imported on demand by the solver registry: never at `import explorer`.
The compiled code is cached on disk (cache=True) next to this file.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# phi_j(x) = sum_n x^n / (n + j)!, j = 1..6, n < 24 (the next term is below 1e-24 for |x| < 1)
PHI_SERIES = np.array([[1.0 / math.factorial(n + j) for j in range(1, 7)] for n in range(24)])
INV_FACT = np.array([1.0 / math.factorial(k) for k in range(8)])
FACT = np.array([float(math.factorial(k)) for k in range(7)])
EPS = np.finfo(np.float64).eps
STACK = 512  # bisection depth is bounded by the step's width over 1e-15 of the time: ~60 levels
MAX_INTERVALS = 200_000  # intervals one event search may bisect (a few dozen in practice)
NOISE = 1e-12  # an event function's rounding, relative to the size of its terms


@njit(cache=True)
def phi_into(x, out):
    """out (7, m) complex: phi_0 = e^x, phi_j (j = 1..6) of each x (complex (m,)); the series
    below |x| = 1, the recurrence phi_j = (phi_(j-1) - 1/(j-1)!) / x beyond."""
    acc = np.empty(6, dtype=np.complex128)
    for i in range(x.size):
        xi = x[i]
        e = np.exp(xi)
        out[0, i] = e
        if abs(xi) < 1.0:
            for j in range(6):
                acc[j] = 0.0
            p = 1.0 + 0.0j
            for n in range(24):
                for j in range(6):
                    acc[j] += p * PHI_SERIES[n, j]
                p = p * xi
            for j in range(6):
                out[j + 1, i] = acc[j]
        else:
            f = e
            for j in range(1, 7):
                f = (f - INV_FACT[j - 1]) / xi
                out[j, i] = f


@njit(cache=True)
def sub_poly(P, a, b, c):
    """c (6,): the step polynomial P (in u) as a polynomial in u' over [a, b] (u = a + (b-a) u')."""
    for k in range(6):
        c[k] = P[k]
    if a != 0.0:
        for i in range(5):
            for k in range(4, i - 1, -1):
                c[k] += a * c[k + 1]
    d = b - a
    if d != 1.0:
        f = 1.0
        for i in range(1, 6):
            f *= d
            c[i] *= f


@njit(cache=True)
def advance(lam, mB, z0, Pc, hh, F, out):
    """out: modal state after hh from z0 under the drive polynomial Pc (in u = tau/hh);
    z = e^(lam hh) z0 + sum_k Gamma_k hh k! phi_(k+1)(lam hh). F (7, m): scratch."""
    m = lam.size
    if hh <= 0.0:
        for i in range(m):
            out[i] = z0[i]
        return
    phi_into(lam * hh, F)
    wp = np.empty(6)
    wd = np.empty(6)
    for k in range(6):
        c = hh * FACT[k]
        wp[k] = Pc[k] * c
        wd[k] = (k + 1) * Pc[k + 1] / hh * c if k < 5 else 0.0
    c0 = hh * FACT[0]
    for i in range(m):
        sp = 0.0j
        sd = 0.0j
        for k in range(6):
            sp += wp[k] * F[k + 1, i]
            sd += wd[k] * F[k + 1, i]
        out[i] = F[0, i] * z0[i] + mB[0, i] * sp + mB[1, i] * sd + mB[2, i] * (c0 * F[1, i])


@njit(cache=True)
def drive_at(P, hh, u):
    """S, S', S'', S''' of the step polynomial P at u."""
    S = 0.0
    S1 = 0.0
    S2 = 0.0
    S3 = 0.0
    for k in range(5, -1, -1):
        S = S * u + P[k]
    for k in range(5, 0, -1):
        S1 = S1 * u + k * P[k]
    for k in range(5, 1, -1):
        S2 = S2 * u + k * (k - 1) * P[k]
    for k in range(5, 2, -1):
        S3 = S3 * u + k * (k - 1) * (k - 2) * P[k]
    return S, S1 / hh, S2 / hh**2, S3 / hh**3


@njit(cache=True)
def local(lam, mB, rows, ev, z, P, hh, u, g, g1, ddz_abs):
    """g, g' of every event function and |z''| of every mode at u of a step (state z there)."""
    S, S1, S2, S3 = drive_at(P, hh, u)
    m = lam.size
    dz = np.empty(m, dtype=np.complex128)
    for i in range(m):
        gam = mB[0, i] * S + mB[1, i] * S1 + mB[2, i]
        gam1 = mB[0, i] * S1 + mB[1, i] * S2
        dz[i] = lam[i] * z[i] + gam
        ddz_abs[i] = abs(lam[i] * dz[i] + gam1)
    for e in range(rows.shape[0]):
        a = 0.0
        b = 0.0
        for i in range(m):
            r = rows[e, i]
            a += r.real * z[i].real - r.imag * z[i].imag
            b += r.real * dz[i].real - r.imag * dz[i].imag
        g[e] = a + ev[0, e] * S + ev[1, e] * S1 + ev[2, e]
        g1[e] = b + ev[0, e] * S1 + ev[1, e] * S2


@njit(cache=True)
def local_one(lam, mB, rows, ev, e, z, P, hh, u, ddz_abs):
    """(g_e, g_e') of one event function and |z''| of every mode at u of a step: `local` for one
    function (the same operations), O(modes) rather than O(modes x functions)."""
    S, S1, S2, S3 = drive_at(P, hh, u)
    m = lam.size
    a = 0.0
    b = 0.0
    for i in range(m):
        gam = mB[0, i] * S + mB[1, i] * S1 + mB[2, i]
        gam1 = mB[0, i] * S1 + mB[1, i] * S2
        dzi = lam[i] * z[i] + gam
        ddz_abs[i] = abs(lam[i] * dzi + gam1)
        r = rows[e, i]
        a += r.real * z[i].real - r.imag * z[i].imag
        b += r.real * dzi.real - r.imag * dzi.imag
    return a + ev[0, e] * S + ev[1, e] * S1 + ev[2, e], b + ev[0, e] * S1 + ev[1, e] * S2


@njit(cache=True)
def bound(absmB, absrows, ev, e, ddz_abs, hh, S2b, S3b):
    """M2 >= |g_e''| over a (sub)step of length hh from its start's |z''| (|z_i''(tau)| <=
    |z_i''(0)| + tau max|Gamma_i''|, Re lambda <= 0)."""
    acc = 0.0
    for i in range(ddz_abs.size):
        acc += absrows[e, i] * (ddz_abs[i] + hh * (absmB[0, i] * S2b + absmB[1, i] * S3b))
    return acc + abs(ev[0, e]) * S2b + abs(ev[1, e]) * S3b


@njit(cache=True)
def excluded(g0, g1a, gb, g1b, M2, hh):
    """True when g keeps its sign over [0, hh]: the parabola bounds from both ends cannot meet
    zero within the interval."""
    if not g0 * gb > 0.0:
        return False
    s = 1.0 if g0 > 0.0 else -1.0
    a0, sa, b0, sb = s * g0, s * g1a, s * gb, -s * g1b
    M = M2 * (1.0 + 1e-9) + 1e-300
    tl = (sa + math.sqrt(sa * sa + 2.0 * M * a0)) / M
    tr = (sb + math.sqrt(sb * sb + 2.0 * M * b0)) / M
    return tl + tr > hh * (1.0 + 1e-12)


@njit(cache=True)
def armed_from(ev, g, g1, hstep, previous, out):
    """An event function is armed while it is on the near side of its crossing (sign * g < 0),
    or within rounding of 0 and moving in; once armed it stays so while on the near side."""
    for e in range(g.size):
        sg = ev[3, e] * g[e]
        sg1 = ev[3, e] * g1[e]
        scale = abs(g1[e]) * hstep + 1e-300
        tiny = abs(g[e]) <= 1e-9 * scale
        a = (sg < 0.0) or (tiny and sg1 < 0.0)
        if previous.size:
            a = a or (previous[e] and sg < 0.0)
        out[e] = a


@njit(cache=True)
def arm(lam, mB, rows, ev, z, P, hh, u, previous, out):
    """armed_from at u of a step (state z there)."""
    E = rows.shape[0]
    g = np.empty(E)
    g1 = np.empty(E)
    dd = np.empty(lam.size)
    local(lam, mB, rows, ev, z, P, hh, u, g, g1, dd)
    armed_from(ev, g, g1, hh, previous, out)


@njit(cache=True)
def _group_margin(rows, ev, gs, z):
    """min |g_e| over the grouped functions e >= gs (functions of the state alone) at the state z,
    and the size of the terms that made them (their rounding)."""
    mu = math.inf
    scale = 0.0
    for e in range(gs, rows.shape[0]):
        a = 0.0
        t = 0.0
        for i in range(z.size):
            r = rows[e, i]
            x = r.real * z[i].real - r.imag * z[i].imag
            a += x
            t += abs(x)
        a += ev[2, e]
        t += abs(ev[2, e])
        mu = min(mu, abs(a))
        scale = max(scale, t)
    return mu, scale


@njit(cache=True)
def _group_bound(colmax, za, zanc, dza, ddza_abs, mb, hk):
    """max over the grouped functions of |g_e(tau) - g_e(anchor)| for tau in the step from za:
    sum_i colmax_i |z_i(tau) - z_i(anchor)|, with |z_i(tau) - z_i(a)| <= tau |z_i'(a)| +
    tau^2 / 2 (|z_i''(a)| + tau max|Gamma_i''|) (complex moduli bounded by |re| + |im|)."""
    acc = 0.0
    for i in range(za.size):
        d = abs(za[i].real - zanc[i].real) + abs(za[i].imag - zanc[i].imag)
        d += hk * (abs(dza[i].real) + abs(dza[i].imag)) + 0.5 * hk * hk * (ddza_abs[i] + hk * mb[i])
        acc += colmax[i] * d
    return acc


@njit(cache=True)
def scan(j, z, steps, lam, mB, rows, absrows, absmB, ev, W, E0, group, P, h, S2b, S3b, z_nodes, armed, gs, colmax):
    """From the state z at node j, step on while each step is certified free of a sign change of
    every event function: z_(k+1) = E z_k + Q_k with the step's tables, stored in z_nodes[k + 1].
    Returns (number of clear steps, state at the end of the first step that is not clear). The
    armed flags are updated at the last clear node.

    The functions e < gs are certified one by one (the parabola bounds of `excluded`); those from
    gs on (functions of the state alone, such as the coil clashes: one per element) together: their
    smallest distance from zero at an anchor node against one bound of how far all of them can move
    from there (colmax_i = max_e |rows[e, i]|), O(modes) per step whatever their number; a step that
    bound does not clear is anchored anew at its start, then tested one by one."""
    m = lam.size
    nE = rows.shape[0]
    za = z.copy()
    zb = np.empty(m, dtype=np.complex128)
    dza = np.empty(m, dtype=np.complex128)
    dzb = np.empty(m, dtype=np.complex128)
    ddza_abs = np.empty(m)
    mb = np.empty(m)
    gb = np.empty(nE)
    g1b = np.empty(nE)
    gb_last = np.empty(nE)
    g1b_last = np.empty(nE)
    zanc = z.copy()
    anchor_k = -1  # the node whose state zanc holds (-1: none yet), mu its grouped functions' margin
    mu = 0.0
    gscale = 0.0
    const_max = 0.0
    for e in range(gs, nE):
        const_max = max(const_max, abs(ev[2, e]))
    done = 0
    k = j
    while k < steps:
        hk = h[k]
        g = group[k]
        p0, p1, p2, p3, p4, p5 = P[0, k], P[1, k], P[2, k], P[3, k], P[4, k], P[5, k]
        d0, d1, d2, d3, d4 = p1 / hk, 2.0 * p2 / hk, 3.0 * p3 / hk, 4.0 * p4 / hk, 5.0 * p5 / hk
        for i in range(m):
            qp = (p0 * W[0, g, i] + p1 * W[1, g, i] + p2 * W[2, g, i] + p3 * W[3, g, i] + p4 * W[4, g, i]
                  + p5 * W[5, g, i])
            qd = d0 * W[0, g, i] + d1 * W[1, g, i] + d2 * W[2, g, i] + d3 * W[3, g, i] + d4 * W[4, g, i]
            zb[i] = E0[g, i] * za[i] + (qp * mB[0, i] + qd * mB[1, i] + W[0, g, i] * mB[2, i])
        # the drive at both ends of the step and the bounds of its derivatives over it
        S0, S10, S20 = p0, p1 / hk, 2.0 * p2 / hk**2
        Se = p0 + p1 + p2 + p3 + p4 + p5
        S1e = (p1 + 2.0 * p2 + 3.0 * p3 + 4.0 * p4 + 5.0 * p5) / hk
        S2e = (2.0 * p2 + 6.0 * p3 + 12.0 * p4 + 20.0 * p5) / hk**2
        s2b, s3b = S2b[k], S3b[k]
        for i in range(m):
            gam_a = mB[0, i] * S0 + mB[1, i] * S10 + mB[2, i]
            gam_b = mB[0, i] * Se + mB[1, i] * S1e + mB[2, i]
            gam1_a = mB[0, i] * S10 + mB[1, i] * S20
            dza[i] = lam[i] * za[i] + gam_a
            dzb[i] = lam[i] * zb[i] + gam_b
            # |z''| bounded by |re| + |im| (<= sqrt 2 times the modulus): a certificate's bound
            # needs no square root, and this is the scan's costliest line with one
            dd = lam[i] * dza[i] + gam1_a
            ddza_abs[i] = abs(dd.real) + abs(dd.imag)
            mb[i] = absmB[0, i] * s2b + absmB[1, i] * s3b
        clear = True
        one_by_one = gs
        if gs < nE:
            if anchor_k < 0:
                mu, gscale = _group_margin(rows, ev, gs, za)
                zanc[:] = za
                anchor_k = k
            B = _group_bound(colmax, za, zanc, dza, ddza_abs, mb, hk)
            if not B * (1.0 + 1e-9) + 1e-12 * gscale < mu and anchor_k != k:
                # anchored at an earlier node: anchor at this step's start and try again
                mu, gscale = _group_margin(rows, ev, gs, za)
                zanc[:] = za
                anchor_k = k
                B = _group_bound(colmax, za, zanc, dza, ddza_abs, mb, hk)
            if not B * (1.0 + 1e-9) + 1e-12 * gscale < mu:
                one_by_one = nE
        for e in range(one_by_one):
            ga = 0.0
            gbe = 0.0
            g1a = 0.0
            g1be = 0.0
            M2 = 0.0
            for i in range(m):
                rr, ri = rows[e, i].real, rows[e, i].imag
                ga += rr * za[i].real - ri * za[i].imag
                gbe += rr * zb[i].real - ri * zb[i].imag
                g1a += rr * dza[i].real - ri * dza[i].imag
                g1be += rr * dzb[i].real - ri * dzb[i].imag
                M2 += absrows[e, i] * (ddza_abs[i] + hk * mb[i])
            al, be = ev[0, e], ev[1, e]
            ga += al * S0 + be * S10 + ev[2, e]
            gbe += al * Se + be * S1e + ev[2, e]
            g1a += al * S10 + be * S20
            g1be += al * S1e + be * S2e
            M2 += abs(al) * s2b + abs(be) * s3b
            if not excluded(ga, g1a, gbe, g1be, M2, hk):
                clear = False
                break
            gb[e] = gbe
            g1b[e] = g1be
        if not clear:
            break
        for i in range(m):
            z_nodes[k + 1, i] = zb[i]
            za[i] = zb[i]
        for e in range(one_by_one):
            gb_last[e] = gb[e]
            g1b_last[e] = g1b[e]
        for e in range(one_by_one, nE):
            gb_last[e] = math.nan  # certified together: their values at the last clear node come below
        if one_by_one > gs:
            # tested one by one: their values at the step's end anchor the next step for free
            mu = math.inf
            for e in range(gs, nE):
                mu = min(mu, abs(gb[e]))
            gscale = const_max
            for i in range(m):
                gscale += colmax[i] * (abs(zb[i].real) + abs(zb[i].imag))
            zanc[:] = zb
            anchor_k = k + 1
        done += 1
        k += 1
    if done > 0:
        kl = j + done - 1
        if gs < nE and math.isnan(gb_last[nE - 1]):
            # the grouped functions' values and slopes at the last clear node (the end of step
            # kl), in the one-by-one test's arithmetic
            hk = h[kl]
            p0, p1, p2, p3, p4, p5 = P[0, kl], P[1, kl], P[2, kl], P[3, kl], P[4, kl], P[5, kl]
            Se = p0 + p1 + p2 + p3 + p4 + p5
            S1e = (p1 + 2.0 * p2 + 3.0 * p3 + 4.0 * p4 + 5.0 * p5) / hk
            for i in range(m):
                dzb[i] = lam[i] * za[i] + (mB[0, i] * Se + mB[1, i] * S1e + mB[2, i])
            for e in range(gs, nE):
                gbe = 0.0
                g1be = 0.0
                for i in range(m):
                    rr, ri = rows[e, i].real, rows[e, i].imag
                    gbe += rr * za[i].real - ri * za[i].imag
                    g1be += rr * dzb[i].real - ri * dzb[i].imag
                al, be = ev[0, e], ev[1, e]
                gb_last[e] = gbe + (al * Se + be * S1e + ev[2, e])
                g1b_last[e] = g1be + (al * S1e + be * ((2.0 * p2 + 6.0 * p3 + 12.0 * p4 + 20.0 * p5) / hk**2))
        # the functions' values at the last clear node arm or disarm them
        armed_from(ev, gb_last, g1b_last, h[kl], armed, armed)
    return done, zb


@njit(cache=True)
def _state(lam, mB, z0, P, u0, u, hj, F, c, out):
    if u == u0:
        for i in range(z0.size):
            out[i] = z0[i]
        return
    sub_poly(P, u0, u, c)
    advance(lam, mB, z0, c, (u - u0) * hj, F, out)


@njit(cache=True)
def _hermite_root(a, b, fa, fb, da, db):
    """The root in (a, b) of the cubic through f and df/du at both ends: Newton's start."""
    w = b - a
    c0, c1 = fa, w * da
    c2 = 3.0 * (fb - fa) - w * (2.0 * da + db)
    c3 = 2.0 * (fa - fb) + w * (da + db)
    lo, hi = 0.0, 1.0
    x = fa / (fa - fb)
    for _ in range(8):
        p = ((c3 * x + c2) * x + c1) * x + c0
        if (p < 0.0) == (fa < 0.0):
            lo = x
        else:
            hi = x
        dp = (3.0 * c3 * x + 2.0 * c2) * x + c1
        xn = x - p / dp if dp != 0.0 else 0.5 * (lo + hi)
        if not lo < xn < hi:
            xn = 0.5 * (lo + hi)
        if abs(xn - x) < 1e-15:
            break
        x = xn
    return a + w * x



@njit(cache=True)
def _g_one(lam, mB, rows, ev, e, z0, P, u0, u, hj, F, c, zs, g, g1, dd):
    """(sign g_e, sign g_e') at u, the state from z0 at u0."""
    _state(lam, mB, z0, P, u0, u, hj, F, c, zs)
    ge, g1e = local_one(lam, mB, rows, ev, e, zs, P, hj, u, dd)
    return ge * ev[3, e], g1e * ev[3, e]


@njit(cache=True)
def _newton(lam, mB, rows, ev, e, z0, P, u0, hj, a, b, fa, fb, start, F, c, zs, g, g1, dd):
    """The root of the monotone sign*g_e in [a, b] (opposite signs at the ends): Newton with the
    analytic slope kept inside the shrinking bracket (bisection when a step leaves it)."""
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    u = start if a < start < b else a + (b - a) * fa / (fa - fb)
    for _ in range(100):
        f, df = _g_one(lam, mB, rows, ev, e, z0, P, u0, u, hj, F, c, zs, g, g1, dd)
        if f == 0.0:
            return u
        if (f < 0.0) == (fa < 0.0):
            a, fa = u, f
        else:
            b, fb = u, f
        if b - a <= 4.0 * EPS * max(abs(a), abs(b), 1e-300):
            break
        un = u - f / (df * hj) if df != 0.0 else math.inf
        if not a < un < b:
            un = 0.5 * (a + b)
        if abs(un - u) <= 1e-13:
            # u is a fraction of the step: 1e-13 of it is far below the events' time rounding
            return un
        u = un
    return b if fb > 0.0 else a


@njit(cache=True)
def _first_crossing(lam, mB, rows, absrows, absmB, ev, e, armed, z0, P, u0, u1, hj, S2b, S3b, tnode,
                    F, c, g, g1, dd, noise):
    """First u in (u0, u1] where event e crosses in its direction while armed (NaN: none).
    Bisection of the intervals not certified free, Newton on a certified monotone crossing.

    noise: the function's rounding (NOISE times the size of its terms). A function within it of
    zero throughout an interval is zero there to the arithmetic's resolution: not armed, it
    cannot arm (it would have to reach below -noise), armed it cannot fire (above +noise); such
    intervals are done. (Two parts flying free side by side keep their gap at 0 to within a
    rounding: without this the bisection would split that interval to its last digit.) The
    intervals are bounded by MAX_INTERVALS all the same."""
    m = lam.size
    sa = np.empty(STACK)
    sb = np.empty(STACK)
    za_s = np.empty((STACK, m), dtype=np.complex128)
    zb_s = np.empty((STACK, m), dtype=np.complex128)
    za = np.empty(m, dtype=np.complex128)
    zb = np.empty(m, dtype=np.complex128)
    zs = np.empty(m, dtype=np.complex128)
    dda = np.empty(m)
    sign = ev[3, e]
    top = 0
    sa[0], sb[0] = u0, u1
    za_s[0] = z0
    _state(lam, mB, z0, P, u0, u1, hj, F, c, zb_s[0])
    top = 1
    intervals = 0
    while top > 0:
        intervals += 1
        if intervals > MAX_INTERVALS:
            raise RuntimeError("chain event search: too many intervals (an event function stuck at its zero)")
        top -= 1
        a, b = sa[top], sb[top]
        za[:] = za_s[top]
        zb[:] = zb_s[top]
        ga, g1a = local_one(lam, mB, rows, ev, e, za, P, hj, a, dda)
        ga, g1a = ga * sign, g1a * sign
        if not armed and ga < 0.0 and abs(ga) > 1e-9 * abs(g1a) * hj:
            # on the near side, by more than a rounding (armed_from's rule): armed from here on
            # (the intervals come in time order)
            armed = True
        gb, g1b = local_one(lam, mB, rows, ev, e, zb, P, hj, b, dd)
        gb, g1b = gb * sign, g1b * sign
        width = (b - a) * hj
        M2 = bound(absmB, absrows, ev, e, dda, width, S2b, S3b)
        reach = 0.5 * M2 * width * width * (1.0 + 1e-9)
        if not armed and min(ga, ga + g1a * width) - reach >= -noise:
            continue  # cannot get below -noise here: cannot arm, so cannot fire
        if armed and max(ga, ga + g1a * width) + reach <= noise:
            continue  # cannot rise above +noise here
        if not armed:
            if ga >= 0.0 and gb > 0.0 and excluded(ga, g1a, gb, g1b, M2, width):
                continue
        elif ga < 0.0 and gb < 0.0 and excluded(ga, g1a, gb, g1b, M2, width):
            continue
        if (ga < 0.0) != (gb < 0.0) and (abs(g1a) - M2 * width > 0.0) and g1a * g1b > 0.0:
            if not armed and gb < 0.0:
                # one monotone crossing back to the near side: armed from there on, and no
                # crossing out again in this interval
                armed = True
                continue
            r = _newton(lam, mB, rows, ev, e, z0, P, u0, hj, a, b, ga, gb,
                        _hermite_root(a, b, ga, gb, g1a * hj, g1b * hj), F, c, zs, g, g1, dd)
            if armed and gb > 0.0:
                return r
            if not armed and gb < 0.0:
                armed = True
                rest = min(r + 1e-15, b)
                if rest < b:
                    sa[top], sb[top] = rest, b
                    _state(lam, mB, z0, P, u0, rest, hj, F, c, za_s[top])
                    zb_s[top] = zb
                    top += 1
            continue
        if width < 1e-15 * max(1.0, abs(tnode)):
            if armed and gb > 0.0:
                return b
            continue
        if top + 2 > STACK:
            raise RuntimeError("chain event search: bisection too deep")
        mid = 0.5 * (a + b)
        _state(lam, mB, z0, P, u0, mid, hj, F, c, zs)
        # right half later, left half first
        sa[top], sb[top] = mid, b
        za_s[top] = zs
        zb_s[top] = zb
        sa[top + 1], sb[top + 1] = a, mid
        za_s[top + 1] = za
        zb_s[top + 1] = zs
        top += 2
    return math.nan


@njit(cache=True)
def search_step(lam, mB, rows, absrows, absmB, ev, armed, z, P, hj, S2b, S3b, tnode, u0, u1):
    """The first crossing of an armed function in (u0, u1] of a step (state z at u0):
    (u, event index), index -1 when there is none. All functions are first bounded over the
    whole interval at once; only those not certified free of a sign change are searched."""
    m = lam.size
    nE = rows.shape[0]
    F = np.empty((7, m), dtype=np.complex128)
    c = np.empty(6)
    ga = np.empty(nE)
    g1a = np.empty(nE)
    gb = np.empty(nE)
    g1b = np.empty(nE)
    dda = np.empty(m)
    dd = np.empty(m)
    zb = np.empty(m, dtype=np.complex128)
    local(lam, mB, rows, ev, z, P, hj, u0, ga, g1a, dda)
    _state(lam, mB, z, P, u0, u1, hj, F, c, zb)
    local(lam, mB, rows, ev, zb, P, hj, u1, gb, g1b, dd)
    width = (u1 - u0) * hj
    best = math.inf
    best_e = -1
    g = np.empty(nE)
    g1 = np.empty(nE)
    S0, S10, _, _ = drive_at(P, hj, u0)
    for e in range(nE):
        M2 = bound(absmB, absrows, ev, e, dda, width, S2b, S3b)
        if excluded(ga[e], g1a[e], gb[e], g1b[e], M2, width):
            continue
        size = abs(ev[0, e] * S0) + abs(ev[1, e] * S10) + abs(ev[2, e])
        for i in range(m):
            size += absrows[e, i] * abs(z[i])
        r = _first_crossing(lam, mB, rows, absrows, absmB, ev, e, armed[e], z, P, u0, u1, hj, S2b, S3b, tnode,
                            F, c, g, g1, dd, NOISE * size)
        if not math.isnan(r) and r < best:
            best, best_e = r, e
    return best, best_e


@njit(cache=True)
def advance_to(lam, mB, z0, P, u0, u, hj):
    """The modal state at u of a step from z0 at u0 (a new array)."""
    F = np.empty((7, lam.size), dtype=np.complex128)
    c = np.empty(6)
    out = np.empty(lam.size, dtype=np.complex128)
    _state(lam, mB, z0, P, u0, u, hj, F, c, out)
    return out


@njit(cache=True)
def aberth(lam, p, b2, ms, c0, k0, max_iterations):
    """The roots of the long chain's secular function (chain_modes.py) in the upper half plane by
    Aberth's iteration from the starts lam (changed in place): each root's Newton correction
    P/P' of the characteristic polynomial P = f prod_k d_k, from g = d_k f with its nearest pole
    p_k removed (d factored, (lambda - p)(lambda - conj p): nothing cancels near a pole), repelled
    from the other roots' approximations and their conjugates. Returns the iterations taken
    (max_iterations + 1: not converged to 4 eps of each root)."""
    n = lam.size
    N = p.size
    eps = np.finfo(np.float64).eps
    step = np.empty(n, dtype=np.complex128)
    for it in range(max_iterations):
        done = True
        for i in range(n):
            L = lam[i]
            k = 0
            best = math.inf
            for l in range(N):
                dist = abs(L - p[l])
                if dist < best:
                    best, k = dist, l
            S = 0.0j
            S1 = 0.0j
            rest = 0.0j
            dk = 0.0j
            ddk = 0.0j
            for l in range(N):
                a = L - p[l]
                c = L - p[l].conjugate()
                D = a * c
                dD = a + c
                if l == k:
                    dk, ddk = D, dD
                    continue
                iD = 1.0 / D
                q = b2[l] * iD
                r = dD * iD
                S += q
                S1 += q * r
                rest += r
            l2 = L * L
            fk = ms * l2 + c0 * L + k0 - l2 * l2 * S
            dfk = 2.0 * ms * L + c0 - 4.0 * l2 * L * S + l2 * l2 * S1
            g = dk * fk - l2 * l2 * b2[k]
            dg = ddk * fk + dk * dfk - 4.0 * l2 * L * b2[k]
            Nw = 1.0 / (dg / g + rest)
            rep = 0.0j
            for j in range(n):
                if j != i:
                    rep += 1.0 / (L - lam[j])
                rep += 1.0 / (L - lam[j].conjugate())
            step[i] = Nw / (1.0 - Nw * rep)
        for i in range(n):
            lam[i] -= step[i]
            if not (abs(step[i]) <= 4.0 * eps * abs(lam[i])):
                done = False
        if done:
            return it + 1
    return max_iterations + 1
