"""Part of the `exact` solver (exact.py): the event functions of a step and the search for their
first zero -- scaled Taylor coefficients of the components (gap, linkage force, velocity, lift),
the rigorous bounds that clear a step (end values plus h^2/8 sup e''), the combination of
min/max components, the start-of-phase clearance, the search in one step (earliest: the first
event of a step and where) and the root polish (Newton from the secant point, Illinois). The
events themselves are phases.py's rules, turned into rows here (event_of). See exact.py for the
method."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .series import horner

EPS = float(np.finfo(float).eps)
ZERO_START = 1e-11  # |e(0)| below this fraction of its terms' size: the function starts on its zero
NEWTON_STEPS = 100  # most Newton steps of root_rising (each at least halves a stalled bracket)
ILLINOIS_STEPS = 200  # most steps of illinois and of the bisection off a zero in _search's polish
SIGN_MARGIN = 1e-12  # positive_at: a value beyond this fraction of its terms' size has a certain sign
NEGLIGIBLE_LEAD = 1e-9  # start_clearance: leading coefficients below this fraction of the largest
CLEARANCE_BISECTIONS = 12  # start_clearance's bisection (coarse is enough)
TIE_RELATIVE, TIE_EPS = 1e-9, 64.0  # earliest: two events closer than this are at the same instant


BOUND_WEIGHTS = np.array([[n, n * (n - 1), n * (n - 1) * (n - 2)] for n in range(6)], dtype=float).T


def shift_list(P, u0: float) -> list:
    """Coefficients in w of P(u0 + (1 - u0) w) for w in [0, 1] (the rest of a step; lists).
    The m-th: (1 - u0)^m sum_n C(n, m) P[n] u0^(n-m), by Horner in u0 (written out)."""
    p0, p1, p2, p3, p4, p5 = P.tolist() if isinstance(P, np.ndarray) else (float(x) for x in P)
    if u0 == 0.0:
        return [p0, p1, p2, p3, p4, p5]
    u = u0
    l1 = 1.0 - u0
    l2 = l1 * l1
    l3 = l2 * l1
    l4 = l3 * l1
    return [
        ((((p5 * u + p4) * u + p3) * u + p2) * u + p1) * u + p0,
        ((((5.0 * p5 * u + 4.0 * p4) * u + 3.0 * p3) * u + 2.0 * p2) * u + p1) * l1,
        (((10.0 * p5 * u + 6.0 * p4) * u + 3.0 * p3) * u + p2) * l2,
        ((10.0 * p5 * u + 4.0 * p4) * u + p3) * l3,
        (5.0 * p5 * u + p4) * l4,
        p5 * (l4 * l1),
    ]


def deriv_list(c, h: float) -> list:
    """deriv on a list."""
    inv = 1.0 / h
    return [k * x * inv for k, x in enumerate(c) if k] + [0.0]


def coeff_list(comp, P, dP, a, da) -> list:
    """coefficients for one step on lists (a, da None at rest)."""
    aP, bP, const, l0, l1 = comp
    if a is not None and (l0 or l1):
        if not l1:
            e = [l0 * x for x in a]
        elif not l0:
            e = [l1 * y for y in da]
        else:
            e = [l0 * x + l1 * y for x, y in zip(a, da)]
    else:
        e = [0.0] * (len(a) if a is not None else 6)
    if bP:
        for n in range(6):
            e[n] += aP * P[n] + bP * dP[n]
    elif aP:
        for n in range(6):
            e[n] += aP * P[n]
    e[0] += const
    return e


def deriv(c: np.ndarray, h) -> np.ndarray:
    """Scaled coefficients of d/dtau of sum c[n] u^n (same length, last row 0)."""
    out = np.zeros_like(c)
    n = np.arange(1, c.shape[0], dtype=float)
    out[:-1] = (n.reshape((-1,) + (1,) * (c.ndim - 1)) * c[1:]) / h
    return out


def _qmax(d, B, D):
    """max over x in [0, D] of d x + B x^2 / 2 (arrays)."""
    val = np.maximum(d * D + 0.5 * B * D * D, 0.0)
    neg = B < 0.0
    if np.any(neg):
        xs = np.divide(-d, B, out=np.full(np.shape(d), np.inf), where=neg)
        inner = (xs > 0.0) & (xs < D)
        if np.any(inner):
            val = np.where(inner, np.maximum(val, -0.5 * d * xs), val)
    return val


def excluded(Ea, Da, Eb, Db, B2, D):
    """True where e <= 0 on [a, b] is certain, from the end values Ea, Eb, the slopes Da, Db and
    an upper bound B2 of e'' on the interval (D = b - a; all in the same variable).

    Three upper bounds of max e: the chord plus the sag B2 D^2/8, and the Taylor parabolas from
    either end (their maximum over the interval taken exactly)."""
    D = np.broadcast_to(D, np.shape(Ea))
    out = np.maximum(Ea, Eb) + np.maximum(B2, 0.0) * D * D / 8.0 <= 0.0
    rest = np.nonzero(~out)[0]
    if rest.size:
        Ea, Da, Eb, Db, B2, D = (np.asarray(x)[rest] for x in (Ea, Da, Eb, Db, B2, D))
        u2 = Ea + _qmax(Da, B2, D)
        u3 = Eb + _qmax(-Db, B2, D)
        out[rest] = np.minimum(u2, u3) <= 0.0
    return out


def excluded_steps(e: np.ndarray) -> np.ndarray:
    """excluded for whole steps, e (n, L) the scaled coefficients of one event function."""
    n = np.arange(e.shape[0], dtype=float)
    B2 = 2.0 * e[2] + (n[3:] * (n[3:] - 1.0)) @ np.maximum(e[3:], 0.0)
    return excluded(e[0], e[1], e.sum(axis=0), n @ e, B2, 1.0)


def excluded1(e, Eb: float | None = None) -> bool:
    """excluded_steps for one step, e a list of floats (plain Python: no numpy overhead).
    Eb: sum(e), when known."""
    Ea = e[0]
    if Eb is None:
        Eb = sum(e)
    B2 = 2.0 * e[2]
    for n in range(3, len(e)):
        en = e[n]
        if en > 0.0:
            B2 += _PAIR[n] * en
    if (Ea if Ea > Eb else Eb) + (0.125 * B2 if B2 > 0.0 else 0.0) <= 0.0:
        return True
    Db = sum([n * en for n, en in enumerate(e)])
    return min(Ea + _qmax1(e[1], B2), Eb + _qmax1(-Db, B2)) <= 0.0


_PAIR = tuple(n * (n - 1.0) for n in range(64))


def _qmax1(d: float, B: float, D: float = 1.0) -> float:
    """max over x in [0, D] of d x + B x^2 / 2."""
    val = max(d * D + 0.5 * B * D * D, 0.0)
    if B < 0.0 and 0.0 < -d / B < D:
        val = max(val, -0.5 * d * d / B)
    return val


def excluded_range(e, lo: float, hi: float) -> bool:
    """excluded on [lo, hi] for one coefficient list e (plain Python)."""
    Ea = Da = Eb = Db = 0.0
    B2 = 0.0
    plo = phi = 1.0  # lo^(n-2), hi^(n-2)
    for n, en in enumerate(e):
        if n >= 2:
            B2 += n * (n - 1.0) * max(en * plo, en * phi)
            plo *= lo
            phi *= hi
    for en in reversed(e):
        Ea = Ea * lo + en
        Eb = Eb * hi + en
    for n in range(len(e) - 1, 0, -1):
        Da = Da * lo + n * e[n]
        Db = Db * hi + n * e[n]
    D = hi - lo
    if max(Ea, Eb) + max(B2, 0.0) * D * D / 8.0 <= 0.0:
        return True
    return min(Ea + _qmax1(Da, B2, D), Eb + _qmax1(-Db, B2, D)) <= 0.0


def rising_range(e, lo: float, hi: float) -> bool:
    """e' > 0 on [lo, hi], proven from e'(lo) and a signed lower bound of e'' (plain Python)."""
    if lo == 0.0:  # (the usual case: a whole step) e'(0) = e[1]; lo^(n-2) = 0 beyond n = 2
        B2lo = 2.0 * e[2]
        phi = hi
        for n in range(3, len(e)):
            en = e[n] * phi
            if en < 0.0:
                B2lo += _PAIR[n] * en
            phi *= hi
        return e[1] + (B2lo if B2lo < 0.0 else 0.0) * hi > 0.0
    d = 0.0
    for n in range(len(e) - 1, 0, -1):
        d = d * lo + n * e[n]
    B2lo = 0.0
    plo = phi = 1.0
    for n in range(2, len(e)):
        B2lo += n * (n - 1.0) * min(e[n] * plo, e[n] * phi)
        plo *= lo
        phi *= hi
    return d + min(0.0, B2lo) * (hi - lo) > 0.0


def root_rising(e, lo: float, hi: float, xtol: float, flo: float | None = None,
                 fhi: float | None = None) -> float:
    """The root of e in [lo, hi] with e(lo) <= 0 < e(hi) and e' > 0 there: Newton steps kept
    inside the bracket (bisection when they leave it), from the secant point of the bracket
    (flo, fhi: e at its ends, when known), then the first point with e > 0."""
    x = lo
    if flo is not None and fhi is not None and fhi > flo:
        x = lo - flo * (hi - lo) / (fhi - flo)
        if not lo <= x < hi:
            x = lo
    rev = e[::-1]
    for _ in range(NEWTON_STEPS):
        fx, dx = rev[0], 0.0
        for ck in rev[1:]:  # value and slope in one Horner pass
            dx = dx * x + fx
            fx = fx * x + ck
        if fx > 0.0:
            hi = x
        else:
            lo = x
        tol = xtol + 4.0 * EPS * hi
        if hi - lo <= tol:
            break
        x_new = x - fx / dx if dx > 0.0 else 0.5 * (lo + hi)
        if abs(x_new - x) < tol:  # Newton has converged from one side: step across the root
            x_new += tol if fx <= 0.0 else -tol
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
        x = x_new
    return hi


def illinois(f, lo: float, hi: float, flo: float, fhi: float, xtol: float) -> float:
    """First point past the zero of f in [lo, hi] (f(lo) <= 0 < f(hi)): regula falsi with the
    Illinois modification (superlinear), bisection when it stalls."""
    side = 0
    for _ in range(ILLINOIS_STEPS):
        if hi - lo <= xtol + 4.0 * EPS * abs(hi):
            break
        x = hi - fhi * (hi - lo) / (fhi - flo) if fhi != flo else 0.5 * (lo + hi)
        if not lo < x < hi:
            x = 0.5 * (lo + hi)
        fx = f(x)
        if fx > 0.0:
            hi, fhi = x, fx
            if side == 1:
                flo *= 0.5
            side = 1
        else:
            lo, flo = x, fx
            if side == -1:
                fhi *= 0.5
            side = -1
    return hi


def positive_at(lists, comb: str, w: float) -> bool:
    """The combined function is > 0 at w beyond doubt (by far more than the rounding of its
    terms): the detail search would return w itself (its first sample), at a fraction of the
    cost."""
    vals = []
    for e in lists:
        val = mag = 0.0
        for en in reversed(e):
            val = val * w + en
            mag = mag * w + abs(en)
        if not abs(val) > SIGN_MARGIN * mag:
            return False
        vals.append(val)
    return (min(vals) if comb == "min" else max(vals)) > 0.0


def start_clearance(e) -> float:
    """For e with e[0] = 0 (a function starting on its zero): the largest w0 in [0, 1] such that
    e < 0 on (0, w0] is certain, from e(w) <= w^k (e_k + sum_{n>k} max(e_n, 0) w^(n-k)) with e_k
    the first nonzero coefficient. 0 when e rises (e_k > 0); 1 when e < 0 on the whole step."""
    # leading terms far below the rest are rounding left by the event that began the phase
    # (they would decide the sign only for w below ~1e-9 of the step)
    big = max(abs(en) for en in e)
    k = next((n for n, en in enumerate(e) if abs(en) > NEGLIGIBLE_LEAD * big), None)
    if k is None or e[k] > 0.0:
        return 0.0
    tail = [max(en, 0.0) for en in e[k + 1:]]

    def phi(w):
        return e[k] + w * horner(tail, w) if tail else e[k]

    if phi(1.0) < 0.0:
        return 1.0
    lo, hi = 0.0, 1.0  # phi rises with w: bisect for its zero (coarse is enough)
    for _ in range(CLEARANCE_BISECTIONS):
        mid = 0.5 * (lo + hi)
        if phi(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    return lo


def combine(values, comb):
    if comb == "min":
        return np.min(values, axis=0)
    if comb == "max":
        return np.max(values, axis=0)
    return values[0]


def combine_excluded(ex, comb):
    if comb == "min":
        return np.any(ex, axis=0)
    if comb == "max":
        return np.all(ex, axis=0)
    return ex[0]


def combine_hits(up: np.ndarray, groups) -> np.ndarray:
    """Steps whose end value of some event function is > 0 (rows combined per event)."""
    if all(comb == "one" for _, comb in groups):
        return up.any(axis=0) if up.shape[0] > 1 else up[0]
    hit = np.zeros(up.shape[1], bool)
    for rows, comb in groups:
        if len(rows) == 1:
            hit |= up[rows[0]]
        else:
            hit |= up[rows].all(axis=0) if comb == "min" else up[rows].any(axis=0)
    return hit


def combine_cleared(ex: np.ndarray, groups) -> np.ndarray:
    """Steps where every event is excluded, from the per-row exclusions ex (rows, steps)."""
    if all(comb == "one" for _, comb in groups):
        return ex.all(axis=0) if ex.shape[0] > 1 else ex[0]
    cleared = np.ones(ex.shape[1], bool)
    for rows, comb in groups:
        cleared &= ex[rows[0]] if len(rows) == 1 else combine_excluded(ex[rows], comb)
    return cleared


def combine_cleared1(ex: list, comb: str) -> bool:
    """combine_excluded for one event in one step (ex: its rows' exclusions)."""
    return any(ex) if comb == "min" else all(ex)


def lincomb_into(out: np.ndarray, terms, const: float) -> None:
    """out = sum of coefficient * array over the terms whose coefficient is not 0, + const."""
    started = False
    for coef, arr in terms:
        if coef:
            if started:
                out += coef * arr
            else:
                np.multiply(arr, coef, out=out)
                started = True
    if not started:
        out[...] = 0.0
    if const:
        out += const


@dataclass(frozen=True)
class Event:
    """An event function: components e = aP P + bP P' + const + l0 s + l1 s', combined by min/max;
    the event is the first instant where it becomes > 0."""

    kind: str
    comps: tuple  # of (aP, bP, const, l0, l1)
    comb: str = "one"


def _neg(x: float) -> float:
    return -x if x else 0.0  # (a zero stays +0.0)


def event_of(rule, k: float, c: float, lash: float, s_star: float = 0.0) -> Event:
    """The Event of a phases.EventRule: each component as a row (aP, bP, const, l0, l1), in
    force units (a gap or a lift is not rescaled: only its sign matters where it stands alone;
    a gap combined with a force is k gap). s_star: the rest height of a valve at rest."""
    rows = []
    for quantity, sign, threshold in rule.comps:
        if quantity == "force":
            row = (k, c, -k * lash, -k, -c)
        elif quantity == "gap" and rule.kind in ("up", "down"):  # at rest: the gap at s_star
            row = (k, 0.0, -k * (lash + s_star), 0.0, 0.0)
        elif quantity == "gap":
            row = (k, 0.0, -k * lash, -k, 0.0)
        elif quantity == "push":
            row = (k, c, -k * (lash + s_star) - threshold, 0.0, 0.0)
        elif quantity == "lift":
            row = (0.0, 0.0, 0.0, 1.0, 0.0)
        elif quantity == "velocity":
            row = (0.0, 0.0, 0.0, 0.0, 1.0)
        else:
            raise ValueError(f"unknown event quantity {quantity!r}")
        rows.append(row if sign > 0.0 else tuple(_neg(x) for x in row))
    return Event(rule.kind, tuple(rows), rule.comb)


def coefficients(comp, P, dP, a, da, n_rows):
    """Scaled Taylor coefficients (n_rows, ...) of one event component over a step."""
    aP, bP, const, l0, l1 = comp
    if a is not None and (l0 or l1):
        e = l0 * a if l0 else l1 * da
        if l0 and l1:
            e = e + l1 * da
    else:
        e = np.zeros((n_rows,) + P.shape[1:])
    if aP or bP:
        e[:6] += aP * P + bP * dP if bP else aP * P
    if const:
        e[0] += const
    return e


def start_coeffs(comps, comb, P, dP, a, da, s0, v0):
    """coeff_list of each component of an event at a phase start (state s0, v0; a, da None at
    rest), with the components that sit on their zero up to rounding (the event that began the
    phase put them there: |e(0)| below ZERO_START of the size of its terms) set exactly to zero,
    so that their sign right after the start comes from their derivatives, not from the
    rounding of the event location. Returns (coefficient lists, the combined function starts
    on its zero)."""
    Es, any_zero = [], False
    for comp in comps:
        aP, bP, const, l0, l1 = comp
        e = coeff_list(comp, P, dP, a, da)
        scale = abs(aP * P[0]) + abs(const) if aP else abs(const)  # the size of its terms
        if bP:
            scale += abs(bP * dP[0])
        if l0:
            scale += abs(l0 * s0)
        if l1:
            scale += abs(l1 * v0)
        if abs(e[0]) <= ZERO_START * scale:
            e[0] = 0.0
            any_zero = True
        Es.append(e)
    if len(Es) == 1:
        return Es, any_zero
    starts = [e[0] for e in Es]
    return Es, any_zero and (min(starts) if comb == "min" else max(starts)) == 0.0


# ---------------------------------------------------------------- the search in one step
MAX_DEPTH = 6  # refinement levels of the event search (8 sub-intervals each: 4e-6 of a step)
SUBDIVISIONS = 8


def earliest(events, coeff_sets, zero_flags, t_abs: float, h_loc: float, stats: dict):
    """Earliest event over one step: (kind, w) or None. coeff_sets: per event, its components'
    coefficient vectors over w in [0, 1]."""
    best = None
    for ev, Es, zero in zip(events, coeff_sets, zero_flags):
        lists = Es
        w_lo = 0.0
        if zero:
            # starting on its zero: most often it leaves it downwards and the plain test for
            # the whole step suffices; otherwise clear the start analytically, test the rest
            if len(lists) == 1:
                if excluded1(lists[0]):
                    continue
            else:
                ex = [excluded1(e) for e in lists]
                if (any(ex) if ev.comb == "min" else all(ex)):
                    continue
            clear = [start_clearance(e) if e[0] == 0.0 else 0.0 for e in lists]
            w_lo = max(clear) if ev.comb == "min" else min(clear)
            if w_lo >= 1.0:
                continue
        e = lists[0]
        if len(lists) == 1:
            e_lo, e_hi = (e[0] if w_lo == 0.0 else horner(e, w_lo)), sum(e)
            # (a sign change from one end to the other needs no exclusion test)
            if not e_lo <= 0.0 < e_hi and (
                    excluded1(e, e_hi) if w_lo == 0.0 else excluded_range(e, w_lo, 1.0)):
                continue
        else:
            ex = [excluded1(e) if w_lo == 0.0 else excluded_range(e, w_lo, 1.0) for e in lists]
            if (any(ex) if ev.comb == "min" else all(ex)):
                continue
        if (ev.comb == "one" and e_lo <= 0.0 < e_hi
                and rising_range(e, w_lo, 1.0)):  # one simple crossing: polish it directly
            stats["newton_roots"] = stats.get("newton_roots", 0) + 1
            w = root_rising(e, w_lo, 1.0, max(0.5 * math.ulp(abs(t_abs)) / h_loc, 1e-300), e_lo, e_hi)
        elif positive_at(lists, ev.comb, w_lo):  # already > 0 where the search would begin
            w = w_lo
        else:
            w = _first_root(Es, ev.comb, w_lo, t_abs, h_loc, stats)
        if w is None:
            continue
        # the seat is rigid: when the valve lands in the same instant as another event
        # (zero lash on the base circle: gap and lift close together) the seat decides
        tie = best is not None and abs(w - best[1]) <= TIE_RELATIVE * max(w, 1e-300) + TIE_EPS * EPS
        if best is None or w < best[1] and not (tie and best[0] == "seat") or tie and ev.kind == "seat":
            best = (ev.kind, w)
    return best


def _first_root(Es, comb, w_lo: float, t_abs: float, h_loc: float, stats: dict):
    """First w in [w_lo, 1] where the combined function becomes > 0, or None."""
    stats["detail_searches"] += 1
    pts = np.linspace(w_lo, 1.0, SUBDIVISIONS + 1)
    xtol = max(0.5 * math.ulp(abs(t_abs)) / h_loc, 1e-300) if h_loc > 0 else 1e-300
    E = np.array(Es)  # (components, N+1)
    return _search(E, comb, pts, 0, xtol)


def _search(E, comb, pts, depth, xtol):
    nc, nr = E.shape
    powers = pts[:, None] ** np.arange(nr)
    n = np.arange(nr, dtype=float)
    vals = (powers @ E.T).T  # (nc, K)
    ders = (powers[:, :-1] @ (E[:, 1:] * n[1:]).T).T
    cv = combine(vals, comb)
    w2 = E[:, 2:] * (n[2:] * (n[2:] - 1.0))  # (nc, nr-2)
    pa, pb = powers[:-1, :nr - 2], powers[1:, :nr - 2]
    D = pts[1:] - pts[:-1]
    ex = np.array([
        excluded(vals[c, :-1], ders[c, :-1], vals[c, 1:], ders[c, 1:],
                  np.maximum(pa * w2[c], pb * w2[c]).sum(axis=1), D)
        for c in range(nc)
    ])
    ex = combine_excluded(ex, comb)
    for i in np.nonzero(~ex)[0]:
        lo, hi = float(pts[i]), float(pts[i + 1])
        if cv[i] > 0.0:
            return lo
        if cv[i + 1] > 0.0:
            if depth < MAX_DEPTH and not _monotone(E, comb, lo, hi, ders[:, i]):
                r = _search(E, comb, np.linspace(lo, hi, SUBDIVISIONS + 1), depth + 1, xtol)
                if r is not None:
                    return r
            return _brent(E, comb, lo, hi, xtol)
        if depth < MAX_DEPTH:
            r = _search(E, comb, np.linspace(lo, hi, SUBDIVISIONS + 1), depth + 1, xtol)
            if r is not None:
                return r
    return None


def _monotone(E, comb, lo, hi, d_lo) -> bool:
    """e' > 0 on [lo, hi] for a single-component function (then its root there is unique)."""
    if comb != "one":
        return False
    e = E[0]
    n = np.arange(2, e.size, dtype=float)
    w = n * (n - 1.0) * e[2:]
    B2lo = np.minimum(w * lo ** (n - 2.0), w * hi ** (n - 2.0)).sum()
    return float(d_lo[0]) + min(0.0, B2lo) * (hi - lo) > 0.0


def _brent(E, comb, lo, hi, xtol):
    cs = [list(map(float, e)) for e in E]
    if comb == "one":
        c0 = cs[0]

        def f(x):
            return horner(c0, x)
    elif comb == "min":

        def f(x):
            return min(horner(c, x) for c in cs)
    else:

        def f(x):
            return max(horner(c, x) for c in cs)
    flo = f(lo)
    if flo > 0.0:
        return lo
    if flo == 0.0:  # leave the zero: bisect on the sign for the first point where f > 0
        for _ in range(ILLINOIS_STEPS):
            mid = 0.5 * (lo + hi)
            if mid <= lo or mid >= hi:
                break
            if f(mid) > 0.0:
                hi = mid
            else:
                lo = mid
        return hi
    return illinois(f, lo, hi, flo, f(hi), xtol)
