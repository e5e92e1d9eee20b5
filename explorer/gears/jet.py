"""Third-order jets: a value with its first three derivatives, carried through arithmetic.

A linkage position is a chain of closed forms (circle intersections, atan2, acos, sqrt) of the
cam angle. Writing out the third derivative of such a chain by hand is error-prone; a jet
applies the chain rule mechanically: each operation maps the derivatives of its inputs to the
derivatives of its output exactly (Leibniz for products, Faa di Bruno for functions). The result
is the analytic derivative, with nothing differenced numerically.

A Jet holds `c`, an array of shape (4, ...): c[k] = d^k f / dx^k for one independent variable x
(the cam angle, or whatever the caller seeds with `Jet.variable`). Plain floats and arrays act
as constants. `solve_implicit` extends jets through equations F(y, x) = 0 (loop closures, cam
contact) by Newton's method on the jets themselves.

The arithmetic itself (Leibniz, Faa di Bruno, atan2, the inverse-function rule) is explorer.core.jets,
shared with the cam geometry; this module adds the operators, the elementary functions' own
derivatives and the solvers.
"""

from __future__ import annotations

import numpy as np

from ..core import jets

ORDER = 3


class Jet:
    __slots__ = ("c",)
    __array_priority__ = 1000  # numpy arrays on the left defer to Jet's reflected operators

    def __init__(self, c):
        self.c = c if type(c) is np.ndarray and c.dtype == np.float64 else np.asarray(c, dtype=float)

    # -- construction ---------------------------------------------------------------------
    @staticmethod
    def constant(value) -> "Jet":
        value = np.asarray(value, dtype=float)
        c = np.zeros((ORDER + 1,) + value.shape)
        c[0] = value
        return Jet(c)

    @staticmethod
    def variable(value) -> "Jet":
        """The independent variable itself: derivative 1, higher derivatives 0."""
        x = Jet.constant(value)
        x.c[1] = 1.0
        return x

    @property
    def value(self) -> np.ndarray:
        return self.c[0]

    def frozen(self) -> "Jet":
        """The same value with zero derivatives (for partial derivatives)."""
        return Jet.constant(self.c[0])

    def __getitem__(self, index) -> "Jet":
        return Jet(self.c[(slice(None),) + (index if isinstance(index, tuple) else (index,))])

    # -- arithmetic -----------------------------------------------------------------------
    def __add__(self, other):
        if isinstance(other, Jet):
            return Jet(self.c + other.c)
        c = self.c.copy()
        c[0] = c[0] + other
        return Jet(c)

    __radd__ = __add__

    def __neg__(self):
        return Jet(-self.c)

    def __sub__(self, other):
        return self + (-other)

    def __rsub__(self, other):
        return (-self) + other

    def __mul__(self, other):
        if not isinstance(other, Jet):
            return Jet(self.c * np.asarray(other, dtype=float))
        return Jet(jets.mul(self.c, other.c))

    __rmul__ = __mul__

    def __truediv__(self, other):
        if not isinstance(other, Jet):
            return Jet(self.c / np.asarray(other, dtype=float))
        return Jet(jets.div(self.c, other.c))

    def __rtruediv__(self, other):
        return reciprocal(self) * other

    def __pow__(self, n):
        if n == 2:
            return self * self
        x = self.c[0]
        return self.compose(x**n, n * x ** (n - 1), n * (n - 1) * x ** (n - 2), n * (n - 1) * (n - 2) * x ** (n - 3))

    def compose(self, f0, f1, f2, f3) -> "Jet":
        """h = f(self) given f and its derivatives f1..f3 evaluated at self.value (Faa di Bruno)."""
        return Jet(jets.compose(self.c, f0, f1, f2, f3))

    def shift(self) -> "Jet":
        """Jet of the derivative: known to one order less (the top entry is NaN)."""
        c = np.empty_like(self.c)
        c[:-1] = self.c[1:]
        c[-1] = np.nan
        return Jet(c)


def as_jet(x) -> Jet:
    return x if isinstance(x, Jet) else Jet.constant(x)


def value(x) -> np.ndarray:
    return x.c[0] if isinstance(x, Jet) else np.asarray(x, dtype=float)


def reciprocal(x: Jet) -> Jet:
    v = x.c[0]
    r = 1.0 / v
    return x.compose(r, -(r**2), 2.0 * r**3, -6.0 * r**4)


def sin(x):
    if not isinstance(x, Jet):
        return np.sin(x)
    s, c = np.sin(x.c[0]), np.cos(x.c[0])
    return x.compose(s, c, -s, -c)


def cos(x):
    if not isinstance(x, Jet):
        return np.cos(x)
    s, c = np.sin(x.c[0]), np.cos(x.c[0])
    return x.compose(c, -s, -c, s)


def sqrt(x):
    if not isinstance(x, Jet):
        return np.sqrt(x)
    return Jet(jets.sqrt(x.c))


def exp(x):
    if not isinstance(x, Jet):
        return np.exp(x)
    e = np.exp(x.c[0])
    return x.compose(e, e, e, e)


def log(x):
    if not isinstance(x, Jet):
        return np.log(x)
    v = x.c[0]
    return x.compose(np.log(v), 1.0 / v, -1.0 / v**2, 2.0 / v**3)


def acos(x):
    if not isinstance(x, Jet):
        return np.arccos(x)
    v = x.c[0]
    w = 1.0 - v * v
    return x.compose(np.arccos(v), -(w**-0.5), -v * w**-1.5, -(1.0 + 2.0 * v * v) * w**-2.5)


def atan2(y, x):
    """Angle of (x, y); derivative (x y' - y x') / (x^2 + y^2)."""
    if not isinstance(y, Jet) and not isinstance(x, Jet):
        return np.arctan2(y, x)
    return Jet(jets.atan2(as_jet(y).c, as_jet(x).c))


def hypot(x, y):
    return sqrt(x * x + y * y)


def reparametrize(y: Jet, x: Jet) -> Jet:
    """Derivatives of y with respect to x, both given as jets in a common parameter."""
    return Jet(jets.reparametrize(y.c, x.c))


def solve_implicit(residual, y0, args=(), iterations: int = ORDER):
    """Jet of y(x) defined by residual(y, *args) = 0, given values y0 that already solve it.

    Newton on jets with the Jacobian frozen at the solution: each pass makes one more derivative
    order exact (the residual is linear in the highest unknown order), so ORDER passes give the
    full jet. `args` are the jets through which the residual depends on the independent variable.
    """
    y0 = np.asarray(y0, dtype=float)
    slope = residual(Jet.variable(y0), *[a.frozen() if isinstance(a, Jet) else a for a in args]).c[1]
    y = Jet.constant(y0)
    for _ in range(iterations):
        y = y - residual(y, *args) / slope
    return y


def newton(function, x0, *, tol=1e-14, max_iter=50, step_limit=None, order=ORDER):
    """Vectorised scalar Newton: `function(x: Jet)` returns the residual jet (derivative in c[1]).

    Returns (x, converged mask). `step_limit` caps the step size (in x units) for robustness
    far from the root; continuation supplies x0 close enough that it rarely acts. `order=1`
    seeds a first-order jet: Newton needs only f and f', which the truncated arithmetic gives
    bit for bit as the full jet does, at about half the cost (if `function` takes it).
    """
    x = np.array(x0, dtype=float, copy=True)
    done = np.zeros(x.shape, dtype=bool)
    for _ in range(max_iter):
        seed = np.zeros((order + 1,) + x.shape)
        seed[0], seed[1] = x, 1.0
        r = function(Jet(seed))
        f, df = r.c[0], r.c[1]
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(df != 0.0, f / df, 0.0)
        if step_limit is not None:
            step = np.clip(step, -step_limit, step_limit)
        step = np.where(done, 0.0, step)
        x = x - step
        done = done | (np.abs(step) <= tol * np.maximum(1.0, np.abs(x)))
        if np.all(done):
            break
    return x, done & np.isfinite(x)
