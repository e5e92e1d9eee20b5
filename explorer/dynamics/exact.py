"""`exact` solver (the default): piecewise-exact stepping of the elastic valve linkage.

Each moving phase is a linear ODE with constant coefficients,
    m s'' + c s' + K s = kc (S(t) - lash) + cc S'(t) - F0,
  contact: m = M1, c = damping, K = k + rate, kc = k, cc = c, F0 = preload + closing + R sign(v)
  flight:  m = M,  c = 0,       K = rate,     kc = cc = 0,  F0 = the same
and a valve at rest (seated, or stuck by friction) has s = const. Over every step the drive S is
replaced by the quintic Hermite polynomial through S, S', S'' at both ends (taken from the analytic
drive; steps end at the drive's breakpoints, so jumps of S'' fall on step ends). With polynomial
forcing the response over a step is known in closed form; it is carried as its Taylor series in
the step variable u = tau/h, whose coefficients follow exactly from the ODE,
    m (n+2)(n+1) a[n+2] + c h (n+1) a[n+1] + K h^2 a[n] = h^2 f[n]        (a[n] = s^(n) h^n / n!),
i.e. the matrix exponential of the augmented system (the "phi functions" of exponential
integrators) as a power series. Steps are at most 0.5 / rho long (rho: the phase's fastest rate,
the natural frequency), so 9-17 terms reach 1e-19 and no digits are lost to the cancellation
between particular and homogeneous solution that the textbook closed form suffers when
omega_n h is small. Longer steps (very stiff linkages) are split. There is no stability limit
and no tuning knob: the only error is the interpolation of S, O(h^6) (a drive feature narrower
than the output step, e.g. a bump, is seen only through that interpolation).

From step to step the state follows x[i+1] = Phi(h) x[i] + g[i]; for runs of equal steps this
linear recurrence is solved in closed form (cumulative sums of the inputs times powers of the
eigenvalue) in modal coordinates (s, (v + alpha s)/beta), in which Phi is a damped rotation (well
conditioned for any omega_n h). The module needs numpy only (fast to import).

Events are roots of the closed forms, per step:
  seated -> lift-off    linkage force k (S - lash) + c S' exceeds preload + closing + friction
  contact -> separation linkage force k (S - lash - s) + c (S' - v) falls to 0
  flight -> re-contact  gap S - lash - s closes (with damping: and the force would be positive)
  any -> seat           s = 0 moving down: rebound v -> -e v
  velocity zero         (only with friction) the friction force flips, or the valve sticks
No crossing inside a step is missed. A step is cleared only by a rigorous bound: the event
function e is at most the larger end value plus h^2/8 sup e''. sup e'' is bounded first for a
whole chunk of steps from node values and the ODE (cheap), then, for the few steps this does
not clear, from the step's own Taylor coefficients (values and slopes at both ends and a signed
bound of e''). Steps still not cleared are sampled at 8 points, recursively, and the first sign
change is polished to machine precision (Newton steps inside the bracket, or the Illinois
variant of regula falsi), returning the first representable instant past the zero so that the
next phase starts on its own side. At a phase start the function that began it sits on its
zero: its leading Taylor terms against the positive part of the rest clear an initial stretch
analytically (e(w) <= w^k (e_k + sum max(e_n, 0) w^(n-k))).

Chattering seat impacts (e > 0) are followed until the next bounce would rise less than
`zeno_height`; the remaining infinitely many bounces are summed as a geometric series (durations
2 v e^n / A, A the net deceleration on the seat) and the valve stays seated from that
accumulation instant on.

Output: s, v, a, jerk (the closed-form third derivative within the phase), linkage force and
phase at the requested times; the valve starts at rest on its seat at t[0] unless
initial_state = (s, v) is given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .model import PHASE_CODES, DynamicsSolution, LinkageModel

SEATED, CONTACT, FLIGHT, STUCK = (PHASE_CODES[k] for k in ("seated", "contact", "flight", "stuck"))
EPS = float(np.finfo(float).eps)
MAX_RHO_H = 0.5  # longest step times the fastest rate: short, well-conditioned series; cheap chunk bounds
MAX_DEPTH = 6  # refinement levels of the event search (8 sub-intervals each: 4e-6 of a step)
SUBDIVISIONS = 8
ZERO_START = 1e-11  # |e(0)| below this fraction of its terms' size: the function starts on its zero
MAX_SAME_TIME = 60  # events at one instant before the phase logic is declared looping
MIN_RUN = 16  # shorter runs of equal steps (or strongly damped ones) use a plain loop


@dataclass(frozen=True)
class _Linear:
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
class _Tables:
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


def _tables(lin: _Linear, h: np.ndarray, n_terms: int) -> _Tables:
    h = np.asarray(h, dtype=float)
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
    Phi = np.array([[end[0], end[1]], [slope[0], slope[1]]])
    return _Tables(
        h=h, A=a[:, 0], B=a[:, 1], C1=a[:, 2], R=a[:, 3:9], Phi=Phi,
        g1=np.array([end[2], slope[2]]), WP=np.array([end[3:9], slope[3:9]]),
    )


def _expand(lin: _Linear, P, h: float, s: float, v: float, Fc: float, n_terms: int) -> np.ndarray:
    """Scaled Taylor coefficients of s over one step from (s, v), P the step's drive polynomial."""
    m, c, K, kc, cc = lin.m, lin.c, lin.K, lin.kc, lin.cc
    p = [float(x) for x in P] + [0.0]
    f = [kc * p[n] + cc * (n + 1) * p[n + 1] / h for n in range(6)]
    f[0] -= Fc
    h2 = h * h
    a = [s, v * h]
    for n in range(n_terms - 1):
        rhs = -c * h * (n + 1) * a[n + 1] - K * h2 * a[n]
        if n < 6:
            rhs += h2 * f[n]
        a.append(rhs / (m * (n + 1) * (n + 2)))
    return a


def _n_terms(x: float) -> int:
    """Taylor terms for a relative truncation error below 1e-19 at rho*h = x (<= MAX_RHO_H)."""
    n, term = 1, x
    bound = math.exp(x)
    while n < 9 or term * bound > 1e-19:
        n += 1
        term *= x / n
        if n > 60:
            break
    return n


def _taylor_shift(D: np.ndarray, d) -> np.ndarray:
    """Drive derivatives (4, n) at x moved to x + d by their Taylor polynomial (d ~ 1e-7 h)."""
    S, S1, S2, S3 = D
    return np.stack([
        S + d * (S1 + d * (S2 / 2 + d * S3 / 6)),
        S1 + d * (S2 + d * S3 / 2),
        S2 + d * S3,
        S3,
    ])


def _hermite5(h: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Scaled coefficients (6, n) in u = tau/h of the quintic with S, S', S'' given at both ends."""
    c0, c1, c2 = start[0], h * start[1], 0.5 * h * h * start[2]
    d0 = end[0] - (c0 + c1 + c2)
    d1 = h * end[1] - (c1 + 2.0 * c2)
    d2 = h * h * end[2] - 2.0 * c2
    c3 = 10.0 * d0 - 4.0 * d1 + 0.5 * d2
    c4 = -15.0 * d0 + 7.0 * d1 - d2
    c5 = 6.0 * d0 - 3.0 * d1 + 0.5 * d2
    return np.stack([c0, c1, c2, c3, c4, c5])


_BINOM = np.array([[math.comb(n, m) for n in range(6)] for m in range(6)], dtype=float)
_UPPER = np.triu(np.ones((6, 6)))


def _shift_poly(P: np.ndarray, u0: float) -> np.ndarray:
    """Coefficients in w of P(u0 + (1 - u0) w) for w in [0, 1] (the rest of a step)."""
    powers = u0 ** np.maximum(np.arange(6)[None, :] - np.arange(6)[:, None], 0)
    return ((_BINOM * powers * _UPPER) @ P) * (1.0 - u0) ** np.arange(6)


def _shift_list(P, u0: float) -> list:
    """_shift_poly on a list (plain Python: single steps)."""
    P = [float(x) for x in P]
    if u0 == 0.0:
        return P
    lam = 1.0 - u0
    out, scale = [], 1.0
    for m in range(6):
        acc, pw = 0.0, 1.0
        for n in range(m, 6):
            acc += math.comb(n, m) * P[n] * pw
            pw *= u0
        out.append(acc * scale)
        scale *= lam
    return out


def _deriv_list(c, h: float) -> list:
    """_deriv on a list."""
    return [(n + 1) * c[n + 1] / h for n in range(len(c) - 1)] + [0.0]


def _coeff_list(comp, P, dP, a, da) -> list:
    """_coefficients for one step on lists (a, da None at rest)."""
    aP, bP, const, l0, l1 = comp
    n_rows = len(a) if a is not None else 6
    e = [0.0] * n_rows
    if a is not None and (l0 or l1):
        e = [l0 * x + l1 * y for x, y in zip(a, da)]
    if aP or bP:
        for n in range(6):
            e[n] += aP * P[n] + bP * dP[n]
    e[0] += const
    return e


def _deriv(c: np.ndarray, h) -> np.ndarray:
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


def _excluded(Ea, Da, Eb, Db, B2, D):
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


def _excluded_steps(e: np.ndarray) -> np.ndarray:
    """_excluded for whole steps, e (n, L) the scaled coefficients of one event function."""
    n = np.arange(e.shape[0], dtype=float)
    B2 = 2.0 * e[2] + (n[3:] * (n[3:] - 1.0)) @ np.maximum(e[3:], 0.0)
    return _excluded(e[0], e[1], e.sum(axis=0), n @ e, B2, 1.0)


def _excluded1(e) -> bool:
    """_excluded_steps for one step, e a list of floats (plain Python: no numpy overhead)."""
    Ea, Da = e[0], e[1]
    Eb = Db = 0.0
    B2 = 2.0 * e[2]
    for n, en in enumerate(e):
        Eb += en
        Db += n * en
        if n >= 3 and en > 0.0:
            B2 += n * (n - 1.0) * en
    if max(Ea, Eb) + max(B2, 0.0) / 8.0 <= 0.0:
        return True
    return min(Ea + _qmax1(Da, B2), Eb + _qmax1(-Db, B2)) <= 0.0


def _qmax1(d: float, B: float, D: float = 1.0) -> float:
    """max over x in [0, D] of d x + B x^2 / 2."""
    val = max(d * D + 0.5 * B * D * D, 0.0)
    if B < 0.0 and 0.0 < -d / B < D:
        val = max(val, -0.5 * d * d / B)
    return val


def _excluded_range(e, lo: float, hi: float) -> bool:
    """_excluded on [lo, hi] for one coefficient list e (plain Python)."""
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


def _rising_range(e, lo: float, hi: float) -> bool:
    """e' > 0 on [lo, hi], proven from e'(lo) and a signed lower bound of e'' (plain Python)."""
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


def _root_rising(e, lo: float, hi: float, xtol: float) -> float:
    """The root of e in [lo, hi] with e(lo) <= 0 < e(hi) and e' > 0 there: Newton steps kept
    inside the bracket (bisection when they leave it), then the first point with e > 0."""
    de = [n * e[n] for n in range(1, len(e))]
    x = lo
    for _ in range(100):
        fx = _horner(e, x)
        if fx > 0.0:
            hi = x
        else:
            lo = x
        tol = xtol + 4.0 * EPS * hi
        if hi - lo <= tol:
            break
        dx = _horner(de, x)
        x_new = x - fx / dx if dx > 0.0 else 0.5 * (lo + hi)
        if abs(x_new - x) < tol:  # Newton has converged from one side: step across the root
            x_new += tol if fx <= 0.0 else -tol
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
        x = x_new
    return hi


def _illinois(f, lo: float, hi: float, flo: float, fhi: float, xtol: float) -> float:
    """First point past the zero of f in [lo, hi] (f(lo) <= 0 < f(hi)): regula falsi with the
    Illinois modification (superlinear), bisection when it stalls."""
    side = 0
    for _ in range(200):
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


def _start_clearance(e) -> float:
    """For e with e[0] = 0 (a function starting on its zero): the largest w0 in [0, 1] such that
    e < 0 on (0, w0] is certain, from e(w) <= w^k (e_k + sum_{n>k} max(e_n, 0) w^(n-k)) with e_k
    the first nonzero coefficient. 0 when e rises (e_k > 0); 1 when e < 0 on the whole step."""
    # leading terms far below the rest are rounding left by the event that began the phase
    # (they would decide the sign only for w below ~1e-9 of the step)
    big = max(abs(en) for en in e)
    k = next((n for n, en in enumerate(e) if abs(en) > 1e-9 * big), None)
    if k is None or e[k] > 0.0:
        return 0.0
    tail = [max(en, 0.0) for en in e[k + 1:]]

    def phi(w):
        return e[k] + w * _horner(tail, w) if tail else e[k]

    if phi(1.0) < 0.0:
        return 1.0
    lo, hi = 0.0, 1.0  # phi rises with w: bisect for its zero (coarse is enough)
    for _ in range(12):
        mid = 0.5 * (lo + hi)
        if phi(mid) < 0.0:
            lo = mid
        else:
            hi = mid
    return lo


def _combine(values, comb):
    if comb == "min":
        return np.min(values, axis=0)
    if comb == "max":
        return np.max(values, axis=0)
    return values[0]


def _combine_excluded(ex, comb):
    if comb == "min":
        return np.any(ex, axis=0)
    if comb == "max":
        return np.all(ex, axis=0)
    return ex[0]


@dataclass(frozen=True)
class _Event:
    """An event function: components e = aP P + bP P' + const + l0 s + l1 s', combined by min/max;
    the event is the first instant where it becomes > 0."""

    kind: str
    comps: tuple  # of (aP, bP, const, l0, l1)
    comb: str = "one"


def _coefficients(comp, P, dP, a, da, n_rows):
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


def _lincomb(terms, const: float):
    """const + sum of coefficient * array over the terms whose coefficient is not 0."""
    out = None
    for coef, arr in terms:
        if coef:
            out = coef * arr if out is None else out + coef * arr
    return out + const if const else out


def _term_scale(comp, P, dP, s0, v0) -> float:
    aP, bP, const, l0, l1 = comp
    return abs(aP * P[0]) + abs(bP * dP[0]) + abs(const) + abs(l0 * s0) + abs(l1 * v0)


def _snap_zero_start(Es, comps, comb, P, dP, s0, v0) -> bool:
    """At a phase start, event functions that sit on their zero up to rounding (the event that
    began the phase put them there) are set exactly to zero, so that their sign right after the
    start comes from their derivatives, not from the rounding of the event location.
    Returns True when the combined function starts on its zero."""
    any_zero = False
    for e, cp in zip(Es, comps):
        if abs(e[0]) <= ZERO_START * _term_scale(cp, P, dP, s0, v0):
            e[0] = 0.0
            any_zero = True
    if len(Es) == 1:
        return any_zero
    starts = [e[0] for e in Es]
    return any_zero and (min(starts) if comb == "min" else max(starts)) == 0.0


def _horner(c, x: float) -> float:
    acc = 0.0
    for ck in reversed(c):
        acc = acc * x + ck
    return acc


def _powers(lam, B: int):
    """lam^n and lam^-n for n = 1..B from one logarithm: |lam^n| does not drift by n eps as
    repeated products would; an undamped rotation (|lam| = 1 to rounding) stays exactly on the
    unit circle."""
    n = np.arange(1, B + 1)
    mu = np.log(complex(lam)) if isinstance(lam, complex) else math.log(lam)
    if isinstance(mu, complex) and abs(abs(lam) - 1.0) <= 4.0 * EPS:
        mu = complex(0.0, mu.imag)
    return np.exp(n * mu), np.exp(-n * mu)


def _first_order(lam, w: np.ndarray, z0, cache: dict | None = None):
    """z[i+1] = lam z[i] + w[i] (|lam| <= 1): z[1..L] as lam^n (z0 + cumsum(lam^-(m+1) w[m])),
    in blocks short enough that |lam|^-B stays below 8 (at most one digit of the inputs lost);
    None when the blocks would be too short to pay (strong damping: use the loop)."""
    L = w.size
    mag = abs(lam)
    B = L if mag >= 1.0 else int(math.log(8.0) / -math.log(mag)) if mag > 0.0 else 0
    if B < min(L, 64):
        return None
    B = min(B, L)
    hit = cache.get(lam) if cache is not None else None
    if hit is not None and hit[0].size >= B:
        up, down = hit
    else:
        up, down = _powers(lam, max(B, 1024))
        if cache is not None:
            cache[lam] = (up, down)
    out = np.empty(L, dtype=np.result_type(lam, w, z0))
    z = z0
    for b in range(0, L, B):
        m = min(B, L - b)
        out[b:b + m] = up[:m] * (z + np.cumsum(down[:m] * w[b:b + m]))
        z = out[b + m - 1]
    return out


class _Recurrence:
    """x[i+1] = Phi x[i] + g[i] for a run of steps sharing Phi (one table column).

    Modal coordinates y = (s, (v + alpha s)/beta) turn Phi into e^(-alpha h) times a rotation
    (underdamped) or a hyperbolic rotation (overdamped), whose eigenvectors are orthogonal:
    the recurrence becomes one complex (or two real) first-order recurrences, solved in closed
    form by _first_order."""

    def __init__(self, lin: _Linear, Phi: np.ndarray):
        self.Phi = Phi
        self.cache: dict = {}  # powers of the eigenvalues
        m, c, K = lin.m, lin.c, lin.K
        alpha = 0.5 * c / m
        disc = K / m - alpha * alpha
        self.alpha = alpha
        if K == 0.0 and c == 0.0:
            self.mode = "cumsum"
            return
        scale = max(K / m, alpha * alpha)
        if abs(disc) <= 1e-8 * scale:  # (nearly) critical damping: Jordan block, no modal form
            self.mode = "loop"
            return
        root = math.sqrt(abs(disc))
        T = np.array([[1.0, 0.0], [alpha / root, 1.0 / root]])
        Tinv = np.array([[1.0, 0.0], [-alpha, root]])
        Py = T @ Phi @ Tinv
        diag, off_a, off_b = 0.5 * (Py[0, 0] + Py[1, 1]), Py[0, 1], Py[1, 0]
        self.root = root
        if disc > 0.0:
            self.mode = "complex"
            self.lam = complex(diag, 0.5 * (off_b - off_a))
        else:
            self.mode = "real"
            off = 0.5 * (off_a + off_b)
            self.lam_p, self.lam_m = diag + off, diag - off

    def run(self, g: np.ndarray, s: float, v: float):
        """Node states after each step: arrays (L,) of s and v."""
        mode = self.mode
        L = g.shape[1]
        if mode == "cumsum":
            V = v + np.cumsum(g[1])
            Vprev = np.concatenate([[v], V[:-1]])
            S = s + np.cumsum(self.Phi[0, 1] * Vprev + g[0])
            return S, V
        if mode == "loop" or L < MIN_RUN:
            return self._loop(g, s, v)
        a, r = self.alpha, self.root
        w2 = (a * g[0] + g[1]) / r
        y2 = (v + a * s) / r
        if mode == "complex":
            z = _first_order(self.lam, g[0] + 1j * w2, complex(s, y2), self.cache)
            if z is None:
                return self._loop(g, s, v)
            S = z.real
            V = r * z.imag - a * S
            return S, V
        zp = _first_order(self.lam_p, g[0] + w2, s + y2, self.cache)
        zm = _first_order(self.lam_m, g[0] - w2, s - y2, self.cache)
        if zp is None or zm is None:
            return self._loop(g, s, v)
        S = 0.5 * (zp + zm)
        V = r * 0.5 * (zp - zm) - a * S
        return S, V

    def _loop(self, g, s, v):
        (p11, p12), (p21, p22) = self.Phi.tolist()
        g1, g2 = g[0].tolist(), g[1].tolist()
        L = len(g1)
        S, V = [0.0] * L, [0.0] * L
        for i in range(L):
            s, v = p11 * s + p12 * v + g1[i], p21 * s + p22 * v + g2[i]
            S[i], V[i] = s, v
        return np.array(S), np.array(V)


class _Solver:
    def __init__(self, model: LinkageModel, drive, t: np.ndarray, initial_state, zeno_height: float,
                 max_events: int, chunk: int):
        self.model = model
        self.k, self.c, self.lash = model.stiffness, model.damping, model.lash
        self.rate, self.R = model.spring_rate, model.friction
        self.M, self.M1 = model.mass, model.oscillating_mass
        self.e = model.restitution
        self.W0 = model.preload + model.closing_load
        self.zeno_height = zeno_height
        self.max_events = max_events
        self.chunk = chunk
        self.lins = {
            CONTACT: _Linear(self.M1, self.c, self.k + self.rate, self.k, self.c),
            FLIGHT: _Linear(self.M, 0.0, self.rate, 0.0, 0.0),
        }
        rho = max(lin.rho for lin in self.lins.values())
        self._build_grid(drive, t, rho)
        h_max = float(self.h.max()) if self.h.size else 0.0
        self.n_terms = _n_terms(rho * h_max)
        self.tabs = {kind: _tables(lin, self.h_unique, self.n_terms) for kind, lin in self.lins.items()}
        self.recurrences: dict = {}
        self._matrices: dict = {}
        nn = self.nodes.size
        self.out = {name: np.full(nn, np.nan) for name in ("s", "v", "a", "j", "f")}
        self.out_phase = np.full(nn, -1, dtype=np.int8)
        self.events: list[dict] = []
        self.stats = {
            "method": "exact", "nodes": int(nn), "steps": int(nn - 1), "taylor_terms": self.n_terms,
            "max_rho_h": rho * h_max, "phases": 0, "detail_searches": 0, "velocity_reversals": 0,
            "sticks": 0, "zeno": 0, "impact_energy_loss_J": 0.0, "mass_switch_energy_J": 0.0,
            "warnings": [],
        }
        self.initial_state = initial_state

    # ---------------------------------------------------------------- grid and drive data
    def _build_grid(self, drive, t: np.ndarray, rho: float) -> None:
        t0, t1 = float(t[0]), float(t[-1])
        hmin = float(np.min(np.diff(t)))
        tol = 1e-9 * hmin
        nodes, is_out, brk = t.copy(), np.ones(t.size, bool), np.zeros(t.size, bool)
        bps = np.asarray(drive.breakpoints(t0, t1), dtype=float).ravel()
        bps = bps[(bps >= t0) & (bps <= t1)]
        if bps.size:
            idx = np.clip(np.searchsorted(t, bps), 1, t.size - 1)
            near_l = bps - t[idx - 1] <= tol
            near_r = (t[idx] - bps <= tol) & ~near_l
            brk[idx[near_l] - 1] = True
            brk[idx[near_r]] = True
            new = np.unique(bps[~(near_l | near_r)])
            if new.size:
                new = new[np.diff(new, prepend=-np.inf) > tol]
                nodes = np.concatenate([nodes, new])
                is_out = np.concatenate([is_out, np.zeros(new.size, bool)])
                brk = np.concatenate([brk, np.ones(new.size, bool)])
                order = np.argsort(nodes, kind="stable")
                nodes, is_out, brk = nodes[order], is_out[order], brk[order]
        # split steps longer than MAX_RHO_H / rho (stiff linkages)
        h = np.diff(nodes)
        parts = np.maximum(1, np.ceil(rho * h / MAX_RHO_H)).astype(np.int64)
        if np.any(parts > 1):
            starts = np.repeat(nodes[:-1], parts)
            frac = np.arange(parts.sum()) - np.repeat(np.cumsum(parts) - parts, parts)
            inner = starts + np.repeat(h / parts, parts) * frac
            keep = frac > 0
            nodes = np.concatenate([nodes, inner[keep]])
            is_out = np.concatenate([is_out, np.zeros(int(keep.sum()), bool)])
            brk = np.concatenate([brk, np.zeros(int(keep.sum()), bool)])
            order = np.argsort(nodes, kind="stable")
            nodes, is_out, brk = nodes[order], is_out[order], brk[order]
        self.nodes, self.is_out = nodes, is_out
        h = np.diff(nodes)
        self.h = h
        # one-sided drive data at breakpoint nodes: evaluated a hair inside and moved back by Taylor
        bi = np.nonzero(brk)[0]
        nb = bi.size
        if nb:
            hl = np.where(bi > 0, np.concatenate([[np.inf], h])[bi], np.inf)
            hr = np.where(bi < nodes.size - 1, np.concatenate([h, [np.inf]])[bi], np.inf)
            d = 1e-7 * np.minimum(hl, hr)
            D = np.asarray(drive(np.concatenate([nodes, nodes[bi] + d, nodes[bi] - d])), dtype=float)
            right, left = D[:, :nodes.size].copy(), D[:, :nodes.size].copy()
            right[:, bi] = _taylor_shift(D[:, nodes.size:nodes.size + nb], -d)
            left[:, bi] = _taylor_shift(D[:, nodes.size + nb:], d)
        else:
            right = left = np.asarray(drive(nodes), dtype=float)
        self.P = _hermite5(h, right[:, :-1], left[:, 1:])  # (6, steps)
        self.dP = _deriv(self.P, h)
        # drive at the nodes as the following step sees it (the last node: the end of its step):
        # S, S', S'', S''' of the step polynomials, so node values match the step expansions
        fact = np.array([1.0, 1.0, 2.0, 6.0])[:, None]
        self.Dn = np.empty((4, nodes.size))
        self.Dn[:, :-1] = fact * self.P[:4] / h ** np.arange(4)[:, None]
        n = np.arange(6, dtype=float)[:, None]
        last = self.P[:, -1:]
        self.Dn[0, -1] = last.sum()
        self.Dn[1, -1] = (n * last).sum() / h[-1]
        self.Dn[2, -1] = (n * (n - 1) * last).sum() / h[-1] ** 2
        self.Dn[3, -1] = (n * (n - 1) * (n - 2) * last).sum() / h[-1] ** 3
        # per step: bounds of |S'|, |S''|, |S'''| over the step (from the polynomial)
        nn = n.ravel()
        weights = np.stack([nn, nn * (nn - 1), nn * (nn - 1) * (nn - 2)])
        self.Sb = (weights @ np.abs(self.P)) / h ** np.arange(1, 4)[:, None]
        # steps of (nearly) equal length share their tables
        if h.max() - h.min() <= 1e-11 * h.max():  # a uniform grid (its steps differ in the last bits)
            self.h_unique = np.array([h.mean()])
            self.hidx = np.zeros(h.size, dtype=np.int64)
            return
        order = np.argsort(h, kind="stable")
        hs = h[order]
        new = np.concatenate([[True], np.diff(hs) > 1e-11 * hs[1:]])
        group = np.cumsum(new) - 1
        # tables for the mean length of a group (unbiased); the state error is |h - mean| |v|,
        # ~1e-18 m per step for a uniform grid whose steps differ in the last bits
        self.h_unique = np.bincount(group, weights=hs) / np.bincount(group)
        self.hidx = np.empty(h.size, dtype=np.int64)
        self.hidx[order] = group

    def time(self, j: int, u: float) -> float:
        if j >= self.h.size:
            return float(self.nodes[-1])
        return float(self.nodes[j] + u * self.h[j])

    # ---------------------------------------------------------------- event functions
    def _moving_events(self, kind: int, sigma: float) -> list[_Event]:
        k, c, lash = self.k, self.c, self.lash
        events = [_Event("seat", ((0.0, 0.0, 0.0, -1.0, 0.0),))]
        if kind == CONTACT:
            events.append(_Event("separation", ((-k, -c, k * lash, k, c),)))
        else:
            gap = (k, 0.0, -k * lash, -k, 0.0)
            if c > 0.0:
                events.append(_Event("re-contact", (gap, (k, c, -k * lash, -k, -c)), "min"))
            else:
                events.append(_Event("re-contact", (gap,)))
        if self.R > 0.0:
            events.append(_Event("velocity-zero", ((0.0, 0.0, 0.0, 0.0, -sigma),)))
        return events

    def _event_matrix(self, kind: int, sigma: float, events):
        """Rows (aP, bP, l0, l1, const) of all event components, and per event its rows and
        combination (cached per phase kind and friction sign)."""
        key = (kind, sigma)
        hit = self._matrices.get(key)
        if hit is None:
            rows, groups = [], []
            for ev in events:
                groups.append((list(range(len(rows), len(rows) + len(ev.comps))), ev.comb))
                rows.extend((aP, bP, l0, l1, const) for aP, bP, const, l0, l1 in ev.comps)
            hit = self._matrices[key] = (np.array(rows, dtype=float), groups)
        return hit

    def _static_events(self, s_star: float) -> list[_Event]:
        k, c = self.k, self.c
        off = -k * (self.lash + s_star)
        thr_up = self.W0 + self.rate * s_star + self.R
        events = []
        if c > 0.0:
            events.append(_Event("up", ((k, c, off - thr_up, 0.0, 0.0), (k, 0.0, off, 0.0, 0.0)), "min"))
        else:
            events.append(_Event("up", ((k, 0.0, off - thr_up, 0.0, 0.0),)))
        thr_dn = self.W0 + self.rate * s_star - self.R
        if s_star > 0.0 and thr_dn > 0.0:
            if c > 0.0:
                events.append(_Event("down", ((-k, -c, thr_dn - off, 0.0, 0.0), (-k, 0.0, -off, 0.0, 0.0)), "max"))
            else:
                events.append(_Event("down", ((-k, 0.0, thr_dn - off, 0.0, 0.0),)))
        return events

    # ---------------------------------------------------------------- root search in one step
    def _earliest(self, events, coeff_sets, zero_flags, t_abs: float, h_loc: float):
        """Earliest event over one step: (kind, w) or None. coeff_sets: per event, its components'
        coefficient vectors over w in [0, 1]."""
        best = None
        for ev, Es, zero in zip(events, coeff_sets, zero_flags):
            lists = [e.tolist() if isinstance(e, np.ndarray) else e for e in Es]
            w_lo = 0.0
            if zero:
                # starting on its zero: most often it leaves it downwards and the plain test for
                # the whole step suffices; otherwise clear the start analytically, test the rest
                ex = [_excluded1(e) for e in lists]
                if (any(ex) if ev.comb == "min" else all(ex)):
                    continue
                clear = [_start_clearance(e) if e[0] == 0.0 else 0.0 for e in lists]
                w_lo = max(clear) if ev.comb == "min" else min(clear)
                if w_lo >= 1.0:
                    continue
            ex = [_excluded1(e) if w_lo == 0.0 else _excluded_range(e, w_lo, 1.0) for e in lists]
            if (any(ex) if ev.comb == "min" else all(ex)):
                continue
            e = lists[0]
            if (ev.comb == "one" and _horner(e, w_lo) <= 0.0 < _horner(e, 1.0)
                    and _rising_range(e, w_lo, 1.0)):  # one simple crossing: polish it directly
                self.stats["newton_roots"] = self.stats.get("newton_roots", 0) + 1
                w = _root_rising(e, w_lo, 1.0, max(0.5 * math.ulp(abs(t_abs)) / h_loc, 1e-300))
            else:
                w = self._first_root(Es, ev.comb, w_lo, t_abs, h_loc)
            if w is None:
                continue
            # the seat is rigid: when the valve lands in the same instant as another event
            # (zero lash on the base circle: gap and lift close together) the seat decides
            tie = best is not None and abs(w - best[1]) <= 1e-9 * max(w, 1e-300) + 64.0 * EPS
            if best is None or w < best[1] and not (tie and best[0] == "seat") or tie and ev.kind == "seat":
                best = (ev.kind, w)
        return best

    def _first_root(self, Es, comb, w_lo: float, t_abs: float, h_loc: float):
        """First w in [w_lo, 1] where the combined function becomes > 0, or None."""
        self.stats["detail_searches"] += 1
        pts = np.linspace(w_lo, 1.0, SUBDIVISIONS + 1)
        xtol = max(0.5 * math.ulp(abs(t_abs)) / h_loc, 1e-300) if h_loc > 0 else 1e-300
        E = np.array(Es)  # (components, N+1)
        return self._search(E, comb, pts, 0, xtol)

    def _search(self, E, comb, pts, depth, xtol):
        nc, nr = E.shape
        powers = pts[:, None] ** np.arange(nr)
        n = np.arange(nr, dtype=float)
        vals = (powers @ E.T).T  # (nc, K)
        ders = (powers[:, :-1] @ (E[:, 1:] * n[1:]).T).T
        cv = _combine(vals, comb)
        w2 = E[:, 2:] * (n[2:] * (n[2:] - 1.0))  # (nc, nr-2)
        pa, pb = powers[:-1, :nr - 2], powers[1:, :nr - 2]
        D = pts[1:] - pts[:-1]
        ex = np.array([
            _excluded(vals[c, :-1], ders[c, :-1], vals[c, 1:], ders[c, 1:],
                      np.maximum(pa * w2[c], pb * w2[c]).sum(axis=1), D)
            for c in range(nc)
        ])
        ex = _combine_excluded(ex, comb)
        for i in np.nonzero(~ex)[0]:
            lo, hi = float(pts[i]), float(pts[i + 1])
            if cv[i] > 0.0:
                return lo
            if cv[i + 1] > 0.0:
                if depth < MAX_DEPTH and not self._monotone(E, comb, lo, hi, ders[:, i]):
                    r = self._search(E, comb, np.linspace(lo, hi, SUBDIVISIONS + 1), depth + 1, xtol)
                    if r is not None:
                        return r
                return self._brent(E, comb, lo, hi, xtol)
            if depth < MAX_DEPTH:
                r = self._search(E, comb, np.linspace(lo, hi, SUBDIVISIONS + 1), depth + 1, xtol)
                if r is not None:
                    return r
        return None

    @staticmethod
    def _monotone(E, comb, lo, hi, d_lo) -> bool:
        """e' > 0 on [lo, hi] for a single-component function (then its root there is unique)."""
        if comb != "one":
            return False
        e = E[0]
        n = np.arange(2, e.size, dtype=float)
        w = n * (n - 1.0) * e[2:]
        B2lo = np.minimum(w * lo ** (n - 2.0), w * hi ** (n - 2.0)).sum()
        return float(d_lo[0]) + min(0.0, B2lo) * (hi - lo) > 0.0

    @staticmethod
    def _brent(E, comb, lo, hi, xtol):
        cs = [list(map(float, e)) for e in E]
        if comb == "one":
            c0 = cs[0]

            def f(x):
                return _horner(c0, x)
        elif comb == "min":

            def f(x):
                return min(_horner(c, x) for c in cs)
        else:

            def f(x):
                return max(_horner(c, x) for c in cs)
        flo = f(lo)
        if flo > 0.0:
            return lo
        if flo == 0.0:  # leave the zero: bisect on the sign for the first point where f > 0
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                if mid <= lo or mid >= hi:
                    break
                if f(mid) > 0.0:
                    hi = mid
                else:
                    lo = mid
            return hi
        return _illinois(f, lo, hi, flo, f(hi), xtol)

    # ---------------------------------------------------------------- recording
    def _static_force_nodes(self, sl, s_star: float):
        D = self.Dn[:, sl]
        x = D[0] - self.lash - s_star
        return np.where(x >= 0.0, np.maximum(0.0, self.k * x + self.c * D[1]), 0.0)

    def _record_static(self, j0: int, j1: int, s_star: float, phase: int) -> None:
        """Nodes j0..j1-1 at rest at s_star."""
        if j1 <= j0:
            return
        sl = slice(j0, j1)
        self.out["s"][sl] = s_star
        self.out["v"][sl] = 0.0
        self.out["a"][sl] = 0.0
        self.out["j"][sl] = 0.0
        self.out["f"][sl] = self._static_force_nodes(sl, s_star)
        self.out_phase[sl] = phase

    def _node_motion(self, kind: int, sl: slice, S, V, Fc: float):
        """Acceleration and jerk at nodes from the phase ODE (exact: the closed form's derivatives)."""
        lin = self.lins[kind]
        D = self.Dn[:, sl]
        f = lin.kc * D[0] + lin.cc * D[1] - Fc  # Fc holds kc * lash
        A = (f - lin.c * V - lin.K * S) / lin.m
        J = (lin.kc * D[1] + lin.cc * D[2] - lin.c * A - lin.K * V) / lin.m
        return A, J

    def _record_moving(self, kind: int, j0: int, S, V, A, J) -> None:
        n = len(S)
        if n == 0:
            return
        sl = slice(j0, j0 + n)
        self.out["s"][sl] = S
        self.out["v"][sl] = V
        self.out["a"][sl] = A
        self.out["j"][sl] = J
        if kind == CONTACT:
            D = self.Dn[:, sl]
            self.out["f"][sl] = np.maximum(0.0, self.k * (D[0] - self.lash - S) + self.c * (D[1] - V))
        else:
            self.out["f"][sl] = 0.0
        self.out_phase[sl] = kind

    # ---------------------------------------------------------------- phases
    def _run_static(self, j: int, u0: float, s_star: float, phase: int):
        """Valve at rest at s_star from (j, u0). Returns (kind, j, u) of the release, or None."""
        nsteps = self.h.size
        if self.W0 + self.rate * s_star + self.R < 0.0:
            return "up", j, u0  # the loads alone push the valve open: no rest
        if j >= nsteps:
            self._record_static(j, nsteps + 1, s_star, phase)
            return None
        events = self._static_events(s_star)
        # first (possibly partial) step
        P = _shift_list(self.P[:, j], u0)
        h_loc = (1.0 - u0) * float(self.h[j])
        dP = _deriv_list(P, h_loc)
        sets, zeros = [], []
        for ev in events:
            Es = [_coeff_list(cp, P, dP, None, None) for cp in ev.comps]
            zeros.append(_snap_zero_start(Es, ev.comps, ev.comb, P, dP, s_star, 0.0))
            sets.append(Es)
        best = self._earliest(events, sets, zeros, self.time(j, u0), h_loc)
        if u0 == 0.0:
            self._record_static(j, j + 1, s_star, phase)
        if best is not None:
            return best[0], j, u0 + best[1] * (1.0 - u0)
        j += 1
        while j < nsteps:
            L = min(nsteps - j, 65536)
            sl = slice(j, j + L + 1)
            h = self.h[j:j + L]
            suspect = np.zeros(L, bool)
            for ev in events:
                ex = []
                for aP, bP, const, _, _ in ev.comps:
                    E = aP * self.Dn[0, sl] + bP * self.Dn[1, sl] + const
                    sag = h * h / 8.0 * (abs(aP) * self.Sb[1, j:j + L] + abs(bP) * self.Sb[2, j:j + L])
                    ex.append(np.maximum(E[:-1], E[1:]) + sag <= 0.0)
                suspect |= ~_combine_excluded(np.array(ex), ev.comb)
            cand = np.nonzero(suspect)[0]
            if cand.size:
                P = self.P[:, j + cand]
                dP = self.dP[:, j + cand]
                sets = [[_coefficients(cp, P, dP, None, None, 6) for cp in ev.comps] for ev in events]
                for i_c, i in enumerate(cand):
                    col = [[e[:, i_c] for e in Es] for Es in sets]
                    best = self._earliest(events, col, [False] * len(events), self.time(j + i, 0.0), float(h[i]))
                    if best is not None:
                        self._record_static(j, j + i + (1 if best[1] > 0.0 else 0), s_star, phase)
                        return best[0], j + i, best[1]
            self._record_static(j, j + L, s_star, phase)
            j += L
        self._record_static(nsteps, nsteps + 1, s_star, phase)
        return None

    def _recurrence(self, kind: int, col: int) -> _Recurrence:
        key = (kind, col)
        rec = self.recurrences.get(key)
        if rec is None:
            rec = self.recurrences[key] = _Recurrence(self.lins[kind], self.tabs[kind].Phi[:, :, col])
        return rec

    def _propagate(self, kind: int, j: int, L: int, s: float, v: float, Fc: float):
        """Node states at j+1..j+L from (s, v) at node j: runs of equal steps in closed form."""
        tab = self.tabs[kind]
        idx = self.hidx[j:j + L]
        cuts = np.concatenate([[0], np.nonzero(np.diff(idx))[0] + 1, [L]])
        S_out, V_out = np.empty(L), np.empty(L)
        for r0, r1 in zip(cuts[:-1], cuts[1:]):
            col = idx[r0]
            g = tab.WP[:, :, col] @ self.P[:, j + r0:j + r1] - Fc * tab.g1[:, col][:, None]
            S, V = self._recurrence(kind, col).run(g, s, v)
            S_out[r0:r1], V_out[r0:r1] = S, V
            s, v = float(S[-1]), float(V[-1])
        return S_out, V_out

    def _run_moving(self, kind: int, j: int, u0: float, s: float, v: float, sigma: float, release: bool = False):
        """Valve moving (contact or flight) from (j, u0) with state (s, v) and friction sign sigma.
        release: the valve starts from rest, pushed in the direction sigma.
        Returns (event kind, j, u, s, v) or None at the end of the grid."""
        lin, tab = self.lins[kind], self.tabs[kind]
        Fc = lin.kc * self.lash + self.W0 + self.R * sigma
        events = self._moving_events(kind, sigma)
        nsteps = self.h.size
        N = self.n_terms
        if j >= nsteps:
            sl = slice(nsteps, nsteps + 1)
            A, J = self._node_motion(kind, sl, np.array([s]), np.array([v]), Fc)
            self._record_moving(kind, nsteps, [s], [v], A, J)
            return None
        # first (possibly partial) step: event functions may start on their zero here
        P = _shift_list(self.P[:, j], u0)
        h_loc = (1.0 - u0) * float(self.h[j])
        a = _expand(lin, P, h_loc, s, v, Fc, N)
        if release:
            # the release instant was found where the net force just passed zero in the direction
            # sigma; recomputed here it may differ by rounding (~1e-16 of its terms) and start the
            # valve the wrong way. Such a residual is removed from this first step's forcing.
            f0 = 2.0 * lin.m * a[2] / (h_loc * h_loc)
            terms = abs(lin.kc * P[0]) + abs(lin.cc * P[1] / h_loc) + abs(Fc) + abs(lin.K * s)
            if sigma * f0 < 0.0 and abs(f0) <= 1e-12 * terms:
                a = _expand(lin, P, h_loc, s, v, Fc + f0, N)
        da = _deriv_list(a, h_loc)
        dP = _deriv_list(P, h_loc)
        sets, zeros = [], []
        for ev in events:
            Es = [_coeff_list(cp, P, dP, a, da) for cp in ev.comps]
            zeros.append(_snap_zero_start(Es, ev.comps, ev.comb, P, dP, s, v))
            sets.append(Es)
        best = self._earliest(events, sets, zeros, self.time(j, u0), h_loc)
        if u0 == 0.0:
            A, J = self._node_motion(kind, slice(j, j + 1), np.array([s]), np.array([v]), Fc)
            self._record_moving(kind, j, [s], [v], A, J)
        if best is not None:
            w = best[1]
            return best[0], j, u0 + w * (1.0 - u0), _horner(a, w), _horner(da, w)
        s, v = math.fsum(a), math.fsum(da)
        j += 1
        L = self.chunk
        m, c, K = lin.m, lin.c, lin.K
        while j < nsteps:
            L = min(nsteps - j, L)
            S, V = self._propagate(kind, j, L, s, v, Fc)
            S = np.concatenate([[s], S])  # nodes j..j+L
            V = np.concatenate([[v], V])
            sl = slice(j, j + L + 1)
            A, J = self._node_motion(kind, sl, S, V, Fc)
            h = self.h[j:j + L]
            H = float(h.max())
            # chunk bounds of |a| and |jerk| between nodes (see the module docstring): from the
            # node maxima and the ODE, a = a_node + int j, j = (f' - c a - K v)/m
            q = H * (c + K * H) / m
            Vn = float(np.abs(V).max())
            prefilter = q < 0.5
            if prefilter:
                S1b, S2b, S3b = (float(x.max()) for x in self.Sb[:, j:j + L])
                F1 = lin.kc * S1b + lin.cc * S2b
                Ahat = (float(np.abs(A).max()) + H * (F1 + K * Vn) / m) / (1.0 - q)
                Jhat = (F1 + c * Ahat + K * (Vn + H * Ahat)) / m
            # all event components at the nodes at once: rows of C times (S, S', s, v, 1)
            C, groups = self._event_matrix(kind, sigma, events)
            X = np.empty((5, L + 1))
            X[0], X[1], X[2], X[3], X[4] = self.Dn[0, sl], self.Dn[1, sl], S, V, 1.0
            E = C @ X
            # an event happens at the latest in the step where some function turns > 0
            last = L
            up_rows = E[:, 1:] > 0.0
            for rows, comb in groups:
                hit = up_rows[rows[0]] if len(rows) == 1 else (
                    up_rows[rows].all(axis=0) if comb == "min" else up_rows[rows].any(axis=0))
                first = int(np.argmax(hit))
                if hit[first]:
                    last = min(last, first + 1)
            if prefilter:
                sag = H * H / 8.0 * (np.abs(C[:, :4]) @ np.array([S2b, S3b, Ahat, Jhat]))
                ex = np.maximum(E[:, :-1], E[:, 1:]) + sag[:, None] <= 0.0
                suspect = np.zeros(L, bool)
                for rows, comb in groups:
                    suspect |= ~(ex[rows[0]] if len(rows) == 1 else _combine_excluded(ex[rows], comb))
                cand = np.nonzero(suspect[:last])[0]
            else:
                cand = np.arange(last)
            if 0 < cand.size <= 4:  # the usual case near an event: expand those steps in Python
                for i in cand.tolist():
                    h_i = float(self.h[j + i])
                    P = self.P[:, j + i].tolist()
                    a = _expand(lin, P, h_i, float(S[i]), float(V[i]), Fc, N)
                    da, dP = _deriv_list(a, h_i), _deriv_list(P, h_i)
                    col = [[_coeff_list(cp, P, dP, a, da) for cp in ev.comps] for ev in events]
                    best = self._earliest(events, col, [False] * len(events), self.time(j + i, 0.0), h_i)
                    if best is not None:
                        w = best[1]
                        n_rec = i + (1 if w > 0.0 else 0)
                        self._record_moving(kind, j, S[:n_rec], V[:n_rec], A[:n_rec], J[:n_rec])
                        return best[0], j + i, w, _horner(a, w), _horner(da, w)
            elif cand.size:
                steps = j + cand
                cols = self.hidx[steps]
                P = self.P[:, steps]
                hc = self.h[steps]
                a = (tab.A[:, cols] * S[cand] + tab.B[:, cols] * V[cand]
                     + np.einsum("nku,ku->nu", tab.R[:, :, cols], P) - Fc * tab.C1[:, cols])
                da = _deriv(a, hc)
                dP = self.dP[:, steps]
                sets = [[_coefficients(cp, P, dP, a, da, N + 1) for cp in ev.comps] for ev in events]
                if cand.size > 32:  # many (stiff linkage): the exact per-step test vectorized first
                    still = np.zeros(cand.size, bool)
                    for ev, Es in zip(events, sets):
                        still |= ~_combine_excluded(np.array([_excluded_steps(e) for e in Es]), ev.comb)
                    order = np.nonzero(still)[0]
                else:  # few: _earliest tests each step in plain Python
                    order = range(cand.size)
                for i_c in order:
                    i = int(cand[i_c])
                    col = [[e[:, i_c] for e in Es] for Es in sets]
                    best = self._earliest(events, col, [False] * len(events), self.time(j + i, 0.0), float(hc[i_c]))
                    if best is not None:
                        w = best[1]
                        n_rec = i + (1 if w > 0.0 else 0)
                        self._record_moving(kind, j, S[:n_rec], V[:n_rec], A[:n_rec], J[:n_rec])
                        return best[0], j + i, w, _horner(a[:, i_c], w), _horner(da[:, i_c], w)
            self._record_moving(kind, j, S[:L], V[:L], A[:L], J[:L])
            s, v = float(S[L]), float(V[L])
            j += L
            L = min(4 * L, 16384)
        A, J = self._node_motion(kind, slice(nsteps, nsteps + 1), np.array([s]), np.array([v]), Fc)
        self._record_moving(kind, nsteps, [s], [v], A, J)
        return None

    # ---------------------------------------------------------------- helpers at an instant
    def _drive_at(self, j: int, u: float):
        """S, S' of the step polynomial at (j, u) (the last node: its left value)."""
        if j >= self.h.size:
            return float(self.Dn[0, -1]), float(self.Dn[1, -1])
        return _horner(self.P[:, j], u), _horner(self.dP[:, j], u)

    def _static_force(self, S: float, S1: float, s: float) -> float:
        x = S - self.lash - s
        return max(0.0, self.k * x + self.c * S1) if x >= 0.0 else 0.0

    def _advance(self, j: int, u: float, dt: float, s_star: float):
        """Position dt later; nodes passed on the way are recorded seated at s_star."""
        t_new = self.time(j, u) + dt
        j0 = j
        while j < self.h.size and self.nodes[j + 1] <= t_new:
            j += 1
        start = j0 + (1 if u > 0.0 else 0)
        if j >= self.h.size:
            self._record_static(start, j, s_star, SEATED)
            return j, 0.0
        u_new = max(0.0, min((t_new - self.nodes[j]) / self.h[j], 1.0 - 1e-16))
        self._record_static(start, j + (1 if u_new > 0.0 else 0), s_star, SEATED)
        return j, u_new

    def _event(self, kind: str, j: int, u: float, v: float | None = None, **extra) -> None:
        ev = {"kind": kind, "time_s": self.time(j, u)}
        if v is not None:
            ev["velocity_m_s"] = float(v)
        ev.update(extra)
        self.events.append(ev)

    # ---------------------------------------------------------------- main loop
    def run(self) -> None:
        if self.initial_state is None:
            phase, s, v, sigma = SEATED, 0.0, 0.0, 1.0
        else:
            s, v = (float(x) for x in self.initial_state)
            phase, sigma = self._phase_at(0, 0.0, s, v)
        j, u = 0, 0.0
        release = self.initial_state is not None and v == 0.0
        same_time, last_time = 0, None
        while True:
            self.stats["phases"] += 1
            if len(self.events) > self.max_events:
                raise RuntimeError(f"exact solver: more than {self.max_events} events; the motion does not settle")
            if phase in (SEATED, STUCK):
                res = self._run_static(j, u, s, phase)
                if res is None:
                    break
                which, j, u = res
                if j < self.h.size and u >= 1.0:
                    j, u = j + 1, 0.0
                S, S1 = self._drive_at(j, u)
                touching = S - self.lash - s >= 0.0 and self.k * (S - self.lash - s) + self.c * S1 > 0.0
                if which == "up":
                    sigma = 1.0
                    if phase == SEATED:
                        self._event("lift-off", j, u, 0.0)
                else:
                    sigma = -1.0
                v = 0.0
                phase = CONTACT if touching else FLIGHT
                release = True
            else:
                res = self._run_moving(phase, j, u, s, v, sigma, release)
                release = False
                if res is None:
                    break
                which, j, u, s, v = res
                if j < self.h.size and u >= 1.0:
                    j, u = j + 1, 0.0
                phase, s, v, sigma, j, u = self._handle(which, phase, j, u, s, v, sigma)
            t_now = self.time(j, u)
            same_time = same_time + 1 if t_now == last_time else 0
            last_time = t_now
            if same_time > MAX_SAME_TIME:
                raise RuntimeError(f"exact solver: events repeat at t = {t_now!r} s without progress")

    def _phase_at(self, j: int, u: float, s: float, v: float):
        """Phase and friction sign of a valve given at (s, v)."""
        S, S1 = self._drive_at(j, u)
        x = S - self.lash - s
        force = self.k * x + self.c * (S1 - v)
        touching = x >= 0.0 and force > 0.0
        kind = CONTACT if touching else FLIGHT
        if v != 0.0:
            return kind, math.copysign(1.0, v)
        net = (force if touching else 0.0) - self.W0 - self.rate * s
        if s <= 0.0 and net <= self.R:
            return SEATED, 1.0
        if abs(net) <= self.R:
            return STUCK, 1.0
        return kind, (1.0 if net > 0.0 else -1.0)

    def _handle(self, which: str, phase: int, j: int, u: float, s: float, v: float, sigma: float):
        S, S1 = self._drive_at(j, u)
        m_phase = self.M1 if phase == CONTACT else self.M
        if which == "separation":
            self._event("separation", j, u, v)
            self.stats["mass_switch_energy_J"] += 0.5 * (self.M - self.M1) * v * v
            return FLIGHT, s, v, sigma, j, u
        if which == "re-contact":
            self._event("re-contact", j, u, v)
            self.stats["mass_switch_energy_J"] -= 0.5 * (self.M - self.M1) * v * v
            return CONTACT, s, v, sigma, j, u
        if which == "velocity-zero":
            self.stats["velocity_reversals"] += 1
            force = self.k * (S - self.lash - s) + self.c * S1 if phase == CONTACT else 0.0
            net = force - self.W0 - self.rate * s
            if abs(net) <= self.R:
                self.stats["sticks"] += 1
                return (STUCK if s > 0.0 else SEATED), s, 0.0, sigma, j, u
            return phase, s, 0.0, (1.0 if net > 0.0 else -1.0), j, u
        # seat impact
        impact = min(v, 0.0)
        self._event("seat", j, u, impact)
        self.stats["impact_energy_loss_J"] += 0.5 * m_phase * (1.0 - self.e * self.e) * impact * impact
        rebound = -self.e * impact
        if rebound <= 0.0:
            return SEATED, 0.0, 0.0, 1.0, j, u
        force = self._static_force(S, S1, 0.0)
        m_rest = self.M1 if force > 0.0 else self.M
        decel = (self.W0 + self.R - force) / m_rest
        if decel > 0.0 and rebound * rebound <= 2.0 * decel * self.zeno_height:
            # the rest of the chatter: bounces of durations 2 v e^n / decel, summed
            dt = 2.0 * rebound / (decel * (1.0 - self.e))
            self.stats["zeno"] += 1
            self.stats["impact_energy_loss_J"] += 0.5 * m_rest * rebound * rebound
            self.events[-1]["zeno_accumulation_s"] = self.time(j, u) + dt
            j, u = self._advance(j, u, dt, 0.0)
            return SEATED, 0.0, 0.0, 1.0, j, u
        kind = CONTACT if force > 0.0 else FLIGHT
        return kind, 0.0, rebound, 1.0, j, u

    def solution(self, t_req: np.ndarray, inverse) -> DynamicsSolution:
        sel = self.is_out
        pick = {k: v[sel][inverse] for k, v in self.out.items()}
        phase = self.out_phase[sel][inverse]
        self.stats["events"] = len(self.events)
        return DynamicsSolution(
            t=t_req, s=pick["s"], v=pick["v"], a=pick["a"], linkage_force=pick["f"],
            contact=pick["f"] > 0.0, events=tuple(self.events), stats=self.stats,
            jerk=pick["j"], phase=phase.astype(np.int64),
        )


def solve(
    model: LinkageModel,
    drive,
    t: np.ndarray,
    initial_state: tuple[float, float] | None = None,
    zeno_height: float = 1e-12,
    max_events: int = 100_000,
    chunk: int = 256,
) -> DynamicsSolution:
    """Piecewise-exact solution at the output times t (sorted).

    initial_state: (s, v) at t[0]; default: at rest on the seat.
    zeno_height: seat chatter ends (in closed form) once a rebound would rise less than this (m).
    max_events: guard against a motion that never settles (raises RuntimeError).
    chunk: steps advanced at the start of a phase before the events are scanned (grows 4x).
    """
    t_req = np.asarray(t, dtype=float).ravel()
    if t_req.size == 0 or np.any(np.diff(t_req) < 0.0) or not np.all(np.isfinite(t_req)):
        raise ValueError("output times must be a non-empty, sorted array of finite numbers")
    t_nodes, inverse = np.unique(t_req, return_inverse=True)
    if t_nodes.size == 1:  # one instant: the state itself
        t_nodes = np.array([t_nodes[0], t_nodes[0] + 1e-9])
    solver = _Solver(model, drive, t_nodes, initial_state, zeno_height, max_events, chunk)
    solver.run()
    return solver.solution(t_req, inverse.ravel())
