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
    from scipy.optimize import brentq

    # a grid's sign change: values on either side of zero (a zero counts on either side)
    proven = fa is not None and fb is not None and min(fa, fb) <= 0.0 <= max(fa, fb) and (fa, fb) != (0.0, 0.0)
    ga, gb = float(f(a)), float(f(b))
    if ga == 0.0:
        return float(a)
    if gb == 0.0:
        return float(b)
    if not (math.isfinite(ga) and math.isfinite(gb)) or (ga > 0.0) == (gb > 0.0):
        if proven and math.isfinite(ga) and math.isfinite(gb):
            return float(a) if abs(ga) <= abs(gb) else float(b)
        raise NoBracket(a, b, ga, gb)
    root, _ = brentq(f, a, b, xtol=xtol, rtol=rtol, maxiter=maxiter, full_output=True, disp=False)
    return float(root)
