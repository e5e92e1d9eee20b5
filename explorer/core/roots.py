"""Root searches with a proven bracket: the one way the program looks for a zero of a scalar
function on an interval.

Every root the program searches for (an event angle, a contact change, a fitted swing, a
balanced split) is either bracketed by a sign change it has proven (a monotone law with its
ends evaluated, a sign change on a grid) or reported as impossible by the caller in one line
naming the input that makes it so. scipy's brentq raises a bare ValueError when the ends have
the same sign: that is a traceback, never a message. `root_in` takes the ends' values the
bracket was proven with, when the caller has them, and:

- returns an end whose value is exactly zero;
- raises NoBracket when the ends' signs agree and were not given (the caller words it: which
  input makes the root impossible);
- when the caller's values (from a vectorised evaluation) changed sign but the scalar ones at
  the same ends do not, the signs differ by rounding only: the zero lies at the end whose value
  is smaller in size, to that rounding, and that end is returned;
- else Brent's method with at most `maxiter` iterations (200 by default; about 55 bisections
  take an interval of a few radians to 1e-15). If the tolerance is not met by then, the best
  point found, still inside the bracket, is returned: a bound on the work, never an error.

Brent's method is `brent`, here in Python: the same steps in the same floating-point operations
as scipy.optimize.brentq (its C routine, scipy/optimize/Zeros/brentq.c), so every root is the
same float as brentq's (tests/test_roots.py compares them bit for bit). Why not brentq itself:
importing scipy.optimize costs ~0.3 s of CPU (it loads scipy.linalg, scipy.sparse, scipy.special
and more), which was a third of a fresh process's first sweep (issue #27.3) for a routine of 40
lines; a root search calls f some 10-60 times, so the Python loop costs nothing measurable.

`roots_in` runs many such searches at once (root_in's end checks, then the same Brent steps, one
generator `_brent_steps` for both) and calls f on all their current points together, once a step:
where f is an array evaluation (a lift's derivatives) whose cost hardly depends on the number of
points, a few calls replace hundreds, and every root is still the float root_in gives.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

EPS_RTOL = 4.0 * float(np.finfo(float).eps)  # brentq's smallest relative tolerance


class NoBracket(ValueError):
    """The ends of the interval do not bracket a root (same sign, or not finite)."""

    def __init__(self, a: float, b: float, fa: float, fb: float):
        self.a, self.b, self.fa, self.fb = a, b, fa, fb
        super().__init__(f"no sign change on [{a:.17g}, {b:.17g}]: f = {fa:.6g}, {fb:.6g}")


def root_in(f: Callable[[float], float], a: float, b: float, *, fa: float | None = None, fb: float | None = None,
            xtol: float = 1e-15, rtol: float = EPS_RTOL, maxiter: int = 200) -> float:
    """A zero of `f` in [a, b] (see the module docstring). `fa`, `fb`: the values at the ends that
    proved the bracket (a grid's), if the caller has them."""
    ga, gb = float(f(a)), float(f(b))
    end = _ends(float(a), float(b), ga, gb, (fa, fb))
    return end if end is not None else brent(f, float(a), float(b), ga, gb, xtol, rtol, maxiter)


def _div(n: float, d: float) -> float:
    """n / d as C divides doubles (IEEE 754: +-inf or NaN by zero, where Python raises): a
    quotient of underflowed values (a very flat f) then makes the step a bisection, as in C."""
    n, d = float(n), float(d)  # numpy scalars (a caller's tolerance) would warn on inf / inf
    try:
        return n / d
    except ZeroDivisionError:
        with np.errstate(divide="ignore", invalid="ignore"):
            return float(np.float64(n) / np.float64(d))


def brent(f: Callable[[float], float], a: float, b: float, fa: float, fb: float, xtol: float, rtol: float,
          maxiter: int) -> float:
    """Brent's method (R. P. Brent, Algorithms for Minimization without Derivatives, 1973, ch. 4)
    on [a, b] with f(a) = fa, f(b) = fb of opposite signs, neither zero: scipy.optimize.brentq's
    iteration, step for step (see the module docstring). Stops when the bracket is shorter than
    xtol + rtol |x| or after maxiter steps (then the best point so far); a NaN value of f raises
    ValueError, as brentq does."""
    steps = _brent_steps(a, b, fa, fb, xtol, rtol, maxiter)
    try:
        x = next(steps)
        while True:
            x = steps.send(float(f(x)))
    except StopIteration as done:
        return done.value


def _brent_steps(a: float, b: float, fa: float, fb: float, xtol: float, rtol: float, maxiter: int):
    """brent's iteration as a generator: it yields each point where it needs f and is sent f's
    value there; its return value (StopIteration.value) is the root. One arithmetic for brent
    (one search, f called in turn) and roots_in (many searches, f called on all their points at
    once), so both give the same floats."""
    x_pre, x_cur, f_pre, f_cur = a, b, fa, fb
    x_blk = f_blk = s_pre = s_cur = 0.0
    for _ in range(maxiter):
        # the bracket is [x_pre, x_cur]: x_blk is its other end (signs compared by their bits, as
        # scipy's C does: a product of two tiny values underflows to -0.0 and would hide the change)
        if f_pre != 0.0 and f_cur != 0.0 and (math.copysign(1.0, f_pre) < 0.0) != (math.copysign(1.0, f_cur) < 0.0):
            x_blk, f_blk = x_pre, f_pre
            s_pre = s_cur = x_cur - x_pre
        if abs(f_blk) < abs(f_cur):  # x_cur: the end with the smaller value
            x_pre, x_cur, x_blk = x_cur, x_blk, x_cur
            f_pre, f_cur, f_blk = f_cur, f_blk, f_cur
        delta = (xtol + rtol * abs(x_cur)) / 2
        s_bis = (x_blk - x_cur) / 2
        if f_cur == 0.0 or abs(s_bis) < delta:
            return x_cur
        step_bisect = True
        if abs(s_pre) > delta and abs(f_cur) < abs(f_pre):
            if x_pre == x_blk:  # secant
                s_try = _div(-f_cur * (x_cur - x_pre), f_cur - f_pre)
            else:  # inverse quadratic interpolation
                d_pre = _div(f_pre - f_cur, x_pre - x_cur)
                d_blk = _div(f_blk - f_cur, x_blk - x_cur)
                s_try = _div(-f_cur * (f_blk * d_blk - f_pre * d_pre), d_blk * d_pre * (f_blk - f_pre))
            bound = 3 * abs(s_bis) - delta
            if 2 * abs(s_try) < (abs(s_pre) if abs(s_pre) < bound else bound):  # C's MIN(a, b)
                s_pre, s_cur = s_cur, s_try
                step_bisect = False
        if step_bisect:
            s_pre = s_cur = s_bis
        x_pre, f_pre = x_cur, f_cur
        x_cur += s_cur if abs(s_cur) > delta else (delta if s_bis > 0 else -delta)
        f_cur = yield x_cur
        if math.isnan(f_cur):
            raise ValueError(f"The function value at x={x_cur} is NaN; solver cannot continue.")
    return x_cur


def roots_in(f: Callable[[np.ndarray, np.ndarray], np.ndarray], a, b, *, fa=None, fb=None, xtol: float = 1e-15,
             rtol: float = EPS_RTOL, maxiter: int = 200) -> list[float]:
    """root_in on many brackets [a[i], b[i]] at once: f(x, i) takes an array of points and the
    index of the bracket each belongs to, and returns f_i at each point (element by element: the
    value at a point must not depend on the other points of the call). Every search takes the
    same steps in the same floating-point operations as root_in (root_in's end checks, then
    _brent_steps), so the roots are the floats of
        [root_in(lambda t: f(np.array([t]), np.array([i]))[0], a[i], b[i], fa=fa[i], fb=fb[i]) ...]
    and the error raised is that loop's first (the lowest bracket's); only f is called on the
    points of all searches together, once per step (at most maxiter + 1 calls): the cost of a
    search's Python arithmetic is a few microseconds, that of a call of f on one point tens."""
    a = [float(x) for x in np.asarray(a, dtype=float).reshape(-1)]
    b = [float(x) for x in np.asarray(b, dtype=float).reshape(-1)]
    n = len(a)
    if len(b) != n:
        raise ValueError(f"roots_in: {n} lower ends but {len(b)} upper ends")
    if n == 0:
        return []
    given = [None] * n if fa is None or fb is None else list(zip(np.asarray(fa, dtype=float).reshape(-1).tolist(),
                                                                np.asarray(fb, dtype=float).reshape(-1).tolist()))
    index = np.arange(n)
    ends = np.asarray(f(np.array(a + b), np.concatenate([index, index])), dtype=float).reshape(-1)
    out: list[float | None] = [None] * n
    errors: dict[int, Exception] = {}
    running: dict[int, tuple] = {}  # bracket -> (its search, the point it waits for f at)
    for i in range(n):
        ga, gb = float(ends[i]), float(ends[n + i])
        try:
            out[i] = _ends(a[i], b[i], ga, gb, given[i])
        except NoBracket as error:
            errors[i] = error
            continue
        if out[i] is None:
            steps = _brent_steps(a[i], b[i], ga, gb, xtol, rtol, maxiter)
            _advance(i, steps, None, out, running, errors)
    while running:
        wanted = sorted(running)
        values = np.asarray(f(np.array([running[i][1] for i in wanted]), np.array(wanted)), dtype=float).reshape(-1)
        for i, value in zip(wanted, values.tolist()):
            _advance(i, running.pop(i)[0], value, out, running, errors)
    if errors:
        raise errors[min(errors)]
    return out


def _ends(a: float, b: float, ga: float, gb: float, given) -> float | None:
    """root_in's decision from the values at the ends (ga, gb) and the caller's (given: (fa, fb)
    or None): the root when an end gives it, None when Brent must search, NoBracket as there."""
    fa, fb = given if given is not None else (None, None)
    # a grid's sign change: values on either side of zero (a zero counts on either side)
    proven = fa is not None and fb is not None and min(fa, fb) <= 0.0 <= max(fa, fb) and (fa, fb) != (0.0, 0.0)
    if ga == 0.0:
        return a
    if gb == 0.0:
        return b
    if not (math.isfinite(ga) and math.isfinite(gb)) or (ga > 0.0) == (gb > 0.0):
        if proven and math.isfinite(ga) and math.isfinite(gb):
            return a if abs(ga) <= abs(gb) else b
        raise NoBracket(a, b, ga, gb)
    return None


def _advance(i: int, steps, value, out: list, running: dict, errors: dict) -> None:
    """One step of search i: send it f's value (None: start it); it finishes (out[i]), fails
    (errors[i]: a NaN value) or waits for f at its next point (running[i])."""
    try:
        x = next(steps) if value is None else steps.send(value)
    except StopIteration as done:
        out[i] = done.value
    except ValueError as error:
        errors[i] = error
    else:
        running[i] = (steps, x)
