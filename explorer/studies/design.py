"""`explorer design`: choose a spline lift's free station values (scipy.optimize, SLSQP).

Objectives (all at the scene's speed, valve side, time units):
  peak-acceleration   max |a|            (epigraph: minimise t with -t <= a_i <= t on the grid)
  peak-jerk           max |j|
  jerk-energy         integral of j^2 over the event (exact: squared polynomials integrated)
  residual-vibration  largest residual amplitude after the event, over a speed band, of a linear
                      follower (mass M, stiffness k + rate) kept in contact: |integral of
                      a(t) exp(i wn t) dt| / wn^2 * wn, in closed form per polynomial segment

Constraints, each reported with its slack at the optimum (>= 0 means met), on a grid of the
event refined at the stations:
  pressure angle <= max_pressure_angle; convex pitch radius >= roller radius + radius_margin
  (written as curvature * (r + margin) <= 1, smooth through straight stretches); rigid contact
  force >= contact_margin at every speed up to contact_rpm (F = w^2 A + G is linear in w^2, so
  the ends of the range suffice); lift >= 0 (no dip below the base circle). The duration is
  fixed: the stations do not move. Optionally the valve's open area (the integral of the valve
  lift max(ratio L - lash, 0) over cam angle, the "lift area" that sets how much the valve
  passes) is held at a given value or at the starting lift's ("keep"): an equality, met when
  within 1e-9 (relative) of it, reported as minus its deviation. The area that is reported and
  held is exact (explorer.lift.open_area: each polynomial piece integrated in closed form between
  the points where the valve lift crosses the lash). SLSQP holds a smooth stand-in, Gauss-Legendre
  between the stations (its kink at the lash inside a panel errs by ~5e-7 of spline_demo's area,
  but it is what SLSQP converges on); its answer is then projected onto the exact area by a few
  Newton steps on the free values (minimum-norm steps along the exact area's gradient, within the
  moves that keep the limits active there unchanged to first order), and every limit is evaluated
  again where the projection ends.

The same objective and constraints are evaluated for the standard laws on the same event (same
height, rise, dwell, return) for the comparison table.

Bounds (issue #22): limits no lift can meet are refused before the optimisation, in one line
naming the option (infeasible: the contact margin against the contact force where the valve
leaves its seat at rest and against the deceleration any rise-and-return needs at the highest
speed; the open area against the largest lift a scene may have); every optimisation stops after
MAX_EVALUATIONS evaluations of its functions (counted, not timed: the same point on every
machine) and reports the point it reached as not met; `progress(evaluations, seconds)` is called
as it runs.

A known optimum, reproduced in tests/test_spline.py: the minimum of the integral of the squared
jerk for a rise with s, v, a given at both ends is the 3-4-5 polynomial (the minimum-jerk
trajectory: Flash & Hogan, J. Neurosci. 5 (1985) 1688-1703; the Euler-Lagrange equation
s^(6) = 0 with six end conditions). Starting from stations whose values are all free, the
optimiser finds it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..core.units import figure
from ..lift.contours.translating import pitch_geometry
from ..lift.curves import LawLift
from ..lift.open_area import affine_open_area, spline_open_area
from ..lift.spline import NAMES, UNITS, solve_spline, with_values
from ..lift.validity import check_computed
from ..mechanics.forces import TrainLoads, friction_direction, load_parts
from ..mechanics.kinematics import lash_crossings
from ..scene.scene import MAX_LIFT

TWO_PI = 2.0 * math.pi
OBJECTIVES = ("peak-acceleration", "peak-jerk", "jerk-energy", "residual-vibration")
STANDARD_LAWS = ("cycloidal", "harmonic", "polynomial-345", "polynomial-4567", "modified-trapezoid", "modified-sine")
GRID = 1200  # points per event (plus the stations)
# evaluations of the objective and the limits (finite-difference steps included) one optimisation
# may spend: about 4x the largest normal design measured (jerk-energy on spline_demo: 916, 6 s)
MAX_EVALUATIONS = 4000


class BudgetSpent(Exception):
    """Raised inside the optimiser's callbacks when MAX_EVALUATIONS are spent."""


class _Counter:
    """Counts the optimiser's function evaluations, keeps the last point the objective saw (the
    answer when the budget ends it), and reports progress."""

    def __init__(self, budget: int, progress=None):
        self.budget, self.progress = budget, progress
        self.count = 0
        self.last = None
        self.started = time.perf_counter()

    def wrap(self, function, objective: bool = False):
        def counted(y, *args):
            self.count += 1
            if self.count > self.budget:
                raise BudgetSpent()
            if objective:
                self.last = np.array(y, dtype=float)
            if self.progress is not None:
                self.progress(self.count, time.perf_counter() - self.started)
            return function(y, *args)

        return counted


@dataclass(frozen=True)
class DesignLimits:
    max_pressure_angle: float | None = None  # rad
    radius_margin: float | None = None  # m, beyond the roller radius
    contact_margin: float | None = None  # N
    contact_rpm: float | None = None  # rev/min
    band: tuple[float, float] | None = None  # rpm, residual-vibration objective
    band_points: int = 11
    open_area: float | str | None = None  # m*rad of valve lift over cam angle, or "keep" (the start's)


AREA_TOLERANCE = 1e-9  # relative: the exact area at the reported optimum, after the projection
PROJECTION_STEPS = 12  # Newton steps onto the exact area at most (2 or 3 suffice: a smooth kink-free equation)
PROJECTION_TOLERANCE = 1e-13  # relative: where the projection stops, well inside AREA_TOLERANCE
ACTIVE = 1e-4  # scaled slack (of order 1) below which the projection keeps a limit where it is


def open_area(scene, d0, weights) -> float:
    """Valve open area (m*rad) by quadrature: sum of weights * max(ratio L - lash, 0) at the nodes
    where d0 = L was taken (Gauss-Legendre between the lift's breakpoints: exact for a spline's
    polynomials only while the valve lift crosses the lash at no node interval's inside). The
    optimiser's smooth stand-in; exact_open_area is the area."""
    lash = scene.valve.lash if scene.valve is not None else 0.0
    return float(np.dot(weights, np.maximum(scene.follower.ratio * np.asarray(d0) - lash, 0.0)))


def exact_open_area(scene, lift) -> float:
    """The valve open area (m*rad): of a spline lift in closed form per piece between its lash
    crossings (explorer.lift.open_area); of any other lift (the standard laws of the comparison),
    Gauss-Legendre between its breakpoints and its lash crossings (lash_crossings, Brent to 1e-15
    rad), so that no panel holds the kink and each integrates a smooth law."""
    ratio = scene.follower.ratio
    lash = scene.valve.lash if scene.valve is not None else 0.0
    coefficients = getattr(lift, "coefficients", None)
    if coefficients is not None:
        return spline_open_area(lift.knots, coefficients, ratio, lash)
    ups, downs = lash_crossings(lift, ratio, lash)
    x, w = _residual_nodes(scene, lift, np.concatenate([ups, downs]))
    return open_area(scene, lift.derivatives(scene.lift.start + x)[0], w)


def area_slack(area: float, target: float) -> float:
    """Minus the deviation from the held area in mm*deg; 0 when within the tolerance."""
    deviation = abs(area - target)
    return 0.0 if deviation <= AREA_TOLERANCE * abs(target) else -1e3 * math.degrees(deviation)


def infeasible(scene, problem, limits: DesignLimits) -> tuple[str, str] | None:
    """(option, reason) for a limit no lift of this event can meet, proven from the physics, or
    None. Each bound holds for every choice of the free values:

    - contact margin, at rest: where the valve leaves its seat (valve lift 0+) the contact force
      at speed 0 -- one end of "every speed up to --contact-rpm" -- is preload + closing loads +
      friction (at most |R|), whatever the lift;
    - contact margin, at speed w: the valve lift s rises from 0 to its peak S and returns to 0
      within the event (angle T), so s'' <= -8 S / T^2 somewhere (a function with s'' >= -c on an
      interval of length T rises at most c T^2 / 8 above its ends); there the force is at most
      w^2 M s'' + preload + rate S + |R| + closing. S is at least the largest given (not free)
      station lift: ratio s_k - lash.
    - open area: the valve lift is at most MAX_LIFT (a scene's largest lift) times the ratio,
      less the lash, over at most the event's angle."""
    ratio = scene.follower.ratio
    lash = scene.valve.lash if scene.valve is not None else 0.0
    span = float(problem.knots[-1] - problem.knots[0])  # the event's angle
    if limits.contact_margin is not None:
        loads = TrainLoads.from_scene(scene)
        rest = loads.preload + loads.closing + abs(loads.friction)
        margin = limits.contact_margin
        if margin > rest:
            return "--contact-margin", (f"{margin:g} N exceeds the contact force where the valve leaves its seat at "
                                        f"rest, {rest:.6g} N (spring.preload + closing loads + friction), whatever "
                                        "the lift: lower it or raise spring.preload")
        given = [st.values[0] for st in problem.options.stations if st.values[0] is not None and not st.free[0]]
        peak = max([ratio * s - lash for s in given] + [0.0])
        rpm = limits.contact_rpm or scene.drive.rpm
        w = rpm * TWO_PI / 60.0
        # the bound uses the least peak the stations allow: a proof only where a higher peak
        # cannot help, i.e. where the inertia grows faster with the peak than the spring force
        if peak > 0.0 and span > 0.0 and 8.0 * w**2 * loads.mass / span**2 >= loads.rate:
            decel = 8.0 * peak / span**2  # per rad**2
            best = -(w**2) * loads.mass * decel + rest + loads.rate * peak
            if best < margin:
                return "--contact-rpm" if limits.contact_rpm is not None else "--contact-margin", (
                    f"{margin:g} N cannot hold up to {rpm:g} rpm: lifting the valve {1e3 * peak:.4g} mm and back within "
                    f"{math.degrees(span):.4g} deg needs a deceleration at which the contact force is at most "
                    f"{best:.6g} N; lower the margin or the speed")
    if isinstance(limits.open_area, float):
        most = span * max(ratio * MAX_LIFT - lash, 0.0)
        if limits.open_area > most:
            return "--open-area", (f"{1e3 * math.degrees(limits.open_area):.6g} mm*deg is more than any lift of this "
                                   f"event opens: at most {1e3 * math.degrees(most):.6g} mm*deg ({MAX_LIFT:g} m of lift, "
                                   f"the largest a scene may have, over the event's {math.degrees(span):.4g} deg)")
    return None


def _free(options):
    return [(i, k) for i, st in enumerate(options.stations) for k in range(len(st.free)) if st.free[k]]


class Problem:
    """The scene's spline with its free values as variables z (scaled to order 1). The lift is
    affine in the station values (they are the right-hand side of one linear system), so on the
    grid its derivatives are d(z) = base + sum_i z_i basis_i, exactly: one spline solve per free
    value, then every evaluation is a matrix product."""

    def __init__(self, scene, objective: str, limits: DesignLimits):
        if scene.lift.law != "spline":
            raise InputError(scene.source, "lift.law", "explorer design works on a spline lift (law = \"spline\")")
        if objective not in OBJECTIVES:
            raise InputError("<command line>", "--objective", f"one of {', '.join(OBJECTIVES)}")
        needs_train = limits.contact_margin is not None or objective == "residual-vibration"
        if needs_train and (scene.valve is None or scene.spring is None
                            or (objective == "residual-vibration" and scene.linkage is None)):
            raise InputError(scene.source, "valve", "the contact margin and the residual vibration need [valve] and "
                             "[spring] (and [linkage] for the vibration)")
        self.scene, self.objective, self.limits = scene, objective, limits
        self.options = scene.lift.options
        self.free = _free(self.options)
        if not self.free:
            raise InputError(scene.source, "lift.stations", "no station value is \"free\": nothing to design")
        knots = np.array([s.angle for s in self.options.stations])
        self.knots = knots
        width = float(np.mean(np.diff(knots)))
        height = max(abs(st.values[0]) for st in self.options.stations if st.values[0] is not None) or 1e-3
        self.scale = np.array([height / width**k for _, k in self.free])
        x = np.unique(np.concatenate([np.linspace(0.0, knots[-1], GRID), knots]))
        self.x = x[x < knots[-1]]
        self.solve = solve_spline
        theta = scene.lift.start + self.x
        zero = np.zeros(len(self.free))
        self.base = self.lift(zero).derivatives(theta)
        self.basis = np.stack([self.lift(np.eye(len(self.free))[i]).derivatives(theta) - self.base
                               for i in range(len(self.free))])

    def lift(self, z):
        values = {key: float(zi * si) for key, zi, si in zip(self.free, z, self.scale)}
        options = with_values(self.options, values)
        return self.solve(options.stations, options.continuity, self.scene.lift.start, self.scene.source)

    def derivatives(self, z) -> np.ndarray:
        return self.base + np.tensordot(np.asarray(z, dtype=float), self.basis, axes=1)

    def start(self) -> np.ndarray:
        return np.array([self.options.stations[i].values[k] for i, k in self.free]) / self.scale


def evaluate(scene, lift, objective: str, limits: DesignLimits, x=None, area=None) -> tuple[float, dict, dict]:
    """(objective value, {name: per-sample slack arrays, scaled for the optimiser}, {name: smallest
    slack in its unit}) of any lift curve on the scene's event (x: event angles since lift.start;
    default a grid over one revolution); area: the open area to hold (m*rad), if any."""
    x = np.linspace(0.0, TWO_PI, 3 * GRID, endpoint=False) if x is None else x
    d = lift.derivatives(scene.lift.start + x)
    arrays, slacks = constraint_arrays(scene, d, limits)
    if area is not None:
        slacks["open area [mm*deg]"] = area_slack(exact_open_area(scene, lift), area)
    return objective_value(scene, lift, d, objective, limits), arrays, slacks


def objective_value(scene, lift, d, objective: str, limits: DesignLimits) -> float:
    """The objective; inf for a peak or energy of a derivative that has a jump below it (the
    harmonic law's acceleration jumps at its ends: its jerk has a Dirac impulse there)."""
    w, ratio = scene.omega, scene.follower.ratio
    below = {"peak-acceleration": 1, "peak-jerk": 2, "jerk-energy": 2}.get(objective)
    if below is not None and _jumps(lift, below):
        return math.inf
    if objective == "peak-acceleration":
        return float(np.max(np.abs(ratio * w**2 * d[2])))
    if objective == "peak-jerk":
        return float(np.max(np.abs(ratio * w**3 * d[3])))
    if objective == "jerk-energy":
        return _jerk_energy(lift, ratio * w**3 / math.sqrt(w))  # over time: j = ratio w^3 L''', dt = d theta / w
    return residual_vibration(scene, lift, limits)


def _jumps(lift, k: int) -> bool:
    """Whether the k-th derivative of the lift jumps at one of its breakpoints."""
    b = np.asarray(lift.breakpoints(), dtype=float)
    if b.size == 0:
        return False
    eps = 1e-9
    left, right = lift.derivatives(b - eps)[k], lift.derivatives(b + eps)[k]
    scale = float(np.max(np.abs(lift.derivatives(np.linspace(0.0, TWO_PI, 721))[k]))) or 1.0
    # a smooth derivative moves by ~2 eps |next derivative| over the gap; a jump is far larger
    return bool(np.any(np.abs(right - left) > 1e-4 * scale))


def constraint_arrays(scene, d, limits: DesignLimits) -> tuple[dict, dict]:
    """Per-sample slacks scaled to order 1 with fixed scales (a scale that moved with the lift
    would bend the optimiser's linearisation), and the smallest slack of each in its unit."""
    f = scene.follower
    ratio = f.ratio
    arrays: dict = {"lift >= 0": d[0] / (f.base_radius + f.roller_radius)}
    slacks: dict = {"lift >= 0 [mm]": 1e3 * float(np.min(d[0]))}
    if limits.max_pressure_angle is not None:
        phi, _ = pitch_geometry(d, f.base_radius, f.roller_radius, f.offset)
        arrays["pressure angle"] = (limits.max_pressure_angle - np.abs(phi)) / limits.max_pressure_angle
        slacks["pressure angle [deg]"] = math.degrees(limits.max_pressure_angle - float(np.max(np.abs(phi))))
    if limits.radius_margin is not None:
        kappa = _pitch_curvature(d, f)
        arrays["convex radius"] = 1.0 - kappa * (f.roller_radius + limits.radius_margin)
        convex = kappa > 0.0
        smallest = float(np.min(1.0 / kappa[convex])) if np.any(convex) else math.inf
        slacks["convex radius [mm]"] = 1e3 * (smallest - f.roller_radius - limits.radius_margin)
    if limits.contact_margin is not None:
        loads = TrainLoads.from_scene(scene)
        a_coef, g_part, is_open = load_parts(d, friction_direction(d[1], d[2]), loads, ratio, scene.valve.lash)
        wc = (limits.contact_rpm or scene.drive.rpm) * TWO_PI / 60.0
        force = np.minimum(wc**2 * a_coef + g_part, g_part)  # the ends of [0, wc]
        scale = max(abs(limits.contact_margin), loads.preload, 1.0)
        arrays["contact margin"] = np.where(is_open, (force - limits.contact_margin) / scale, 1.0)
        slacks["contact margin [N]"] = float(np.min(force[is_open]) - limits.contact_margin) if np.any(is_open) else math.inf
    return arrays, slacks


def _pitch_curvature(d, f) -> np.ndarray:
    e = f.offset
    y = math.sqrt((f.base_radius + f.roller_radius) ** 2 - e * e) + d[0]
    ty = d[1] - e
    return (ty * (2.0 * d[1] - e) - y * (d[2] - y)) / (y * y + ty * ty) ** 1.5


def _jerk_energy(lift, factor: float) -> float:
    """Integral of (factor * L''')^2 d theta over the event, exact for a spline lift (its
    polynomials squared and integrated), else by Gauss-Legendre per breakpoint interval."""
    total = 0.0
    coefficients = getattr(lift, "coefficients", None)
    if coefficients is not None:
        for i, c in enumerate(coefficients):
            width = lift.knots[i + 1] - lift.knots[i]
            p = np.polynomial.Polynomial(c).deriv(3) / width**3
            q = (p * p).integ()
            total += (q(1.0) - q(0.0)) * width
        return factor**2 * total
    b = np.sort(np.mod(lift.breakpoints(), TWO_PI))
    edges = np.append(b, b[0] + TWO_PI)
    u, wts = np.polynomial.legendre.leggauss(40)
    for lo, hi in zip(edges[:-1], edges[1:]):
        t = 0.5 * (hi - lo) * (u + 1.0) + lo
        jj = lift.derivatives(t)[3]
        total += 0.5 * (hi - lo) * float(np.sum(wts * jj * jj))
    return factor**2 * total


def _residual_nodes(scene, lift, cuts=()):
    """Gauss-Legendre nodes and weights over the event between the lift's breakpoints (exact for
    polynomial segments up to degree 95 times the smooth exponential's expansion); `cuts`: more
    angles (rad, absolute) to split at."""
    u, wts = np.polynomial.legendre.leggauss(48)
    marks = np.concatenate([np.asarray(lift.breakpoints(), dtype=float).reshape(-1), np.asarray(cuts, dtype=float)])
    b = np.sort(np.mod(marks - scene.lift.start, TWO_PI))
    b = np.unique(np.append(b, TWO_PI))
    nodes = [0.5 * (hi - lo) * (u + 1.0) + lo for lo, hi in zip(b[:-1], b[1:])]
    weights = [0.5 * (hi - lo) * wts for lo, hi in zip(b[:-1], b[1:])]
    return np.concatenate(nodes), np.concatenate(weights)


def _residual_kernel(scene, limits: DesignLimits, x, wx) -> np.ndarray:
    """(speeds, nodes) complex weights: the residual amplitude at each speed of the band is
    |kernel @ (ratio L'')| (see residual_vibration)."""
    band = limits.band or (scene.drive.rpm, scene.drive.rpm)
    wn = math.sqrt((scene.linkage.stiffness + scene.spring.rate) / scene.valve.mass)
    speeds = np.linspace(band[0], band[1], limits.band_points if band[0] != band[1] else 1) * TWO_PI / 60.0
    # s''(t) = w^2 L''(theta), dt = d theta / w, t = x / w: integral = sum wx w L'' exp(i wn x / w)
    return scene.follower.ratio * wx[None, :] * speeds[:, None] * np.exp(1j * wn * x[None, :] / speeds[:, None]) / wn


def residual_vibration(scene, lift, limits: DesignLimits) -> float:
    """Largest residual amplitude (m) over the speed band of the follower error e of
    M e'' + K e = -M s''(t) (rigid-cam vibration of a linear follower, K = k + rate, kept in
    contact) after the event, from rest: |integral of s''(t) exp(i wn t) dt| / wn."""
    x, wx = _residual_nodes(scene, lift)
    d2 = lift.derivatives(scene.lift.start + x)[2]
    return float(np.max(np.abs(_residual_kernel(scene, limits, x, wx) @ d2)))


@dataclass(frozen=True)
class DesignReport:
    objective: str
    value: float
    start_value: float
    values: dict  # (station, derivative) -> value per rad^k
    slacks: dict  # constraint -> smallest slack (relative; >= 0 met)
    comparison: dict  # law -> (objective, slacks)
    iterations: int
    success: bool
    message: str
    options: object  # the optimised SplineOptions
    method: str = "SLSQP"
    open_area: float | None = None  # m*rad held, if any
    limits: DesignLimits | None = None  # as asked (for the report's statement of the speeds)


def _peak_by_linear_programme(scene, problem, row: int, factor: float, limits: DesignLimits):
    """The peak objective with the linear constraints only (lift >= 0, and the contact margin with
    the friction direction of the starting lift): minimise t with -t <= factor d_row(z) <= t, an LP
    in (z, t) solved exactly by HiGHS. None if HiGHS fails."""
    from scipy.optimize import linprog


    n = len(problem.free)
    # in units of the largest starting value: HiGHS's tolerances are absolute (a jerk in m/s**3
    # of order 1e6 made it give up)
    unit = max(float(np.max(np.abs(problem.derivatives(problem.start())[row]))), 1e-300)
    column0, gain = problem.base[row] / unit, problem.basis[:, row, :].T / unit
    ones = np.ones((gain.shape[0], 1))
    size = scene.follower.base_radius
    blocks = [np.hstack([gain, -ones]), np.hstack([-gain, -ones]),
              np.hstack([-problem.basis[:, 0, :].T / size, np.zeros((gain.shape[0], 1))])]
    bounds = [-column0, column0, problem.base[0] / size]
    if limits.contact_margin is not None:
        loads = TrainLoads.from_scene(scene)
        d0 = problem.derivatives(problem.start())
        ratio, lash = scene.follower.ratio, scene.valve.lash
        opened = ratio * d0[0] - lash > 0.0
        direction = friction_direction(d0[1], d0[2])
        wc = (limits.contact_rpm or scene.drive.rpm) * TWO_PI / 60.0
        for w2 in (wc**2, 0.0):  # F = w^2 M ratio L'' + preload + rate (ratio L - lash) + R dir + closing >= margin
            lin = (w2 * loads.mass * ratio * problem.basis[:, 2, :] + loads.rate * ratio * problem.basis[:, 0, :]).T
            const = (w2 * loads.mass * ratio * problem.base[2] + loads.preload + loads.rate * (ratio * problem.base[0] - lash)
                     + loads.friction * direction + loads.closing)
            scale = max(abs(limits.contact_margin), loads.preload, 1.0)
            blocks.append(np.hstack([-lin[opened], np.zeros((int(opened.sum()), 1))]) / scale)
            bounds.append((const[opened] - limits.contact_margin) / scale)
    cost = np.append(np.zeros(n), 1.0)
    result = linprog(cost, A_ub=np.vstack(blocks), b_ub=np.concatenate(bounds), bounds=[(None, None)] * (n + 1),
                     method="highs")
    return result.x[:-1] if result.status == 0 else None


def _minimize(counter: _Counter, fun, x0, *, jac=None, constraints=(), options=None):
    """scipy's SLSQP with every function counted against the budget: (x, message, iterations,
    spent); when the budget ends it, x is the last point the objective saw."""
    from scipy.optimize import minimize

    cons = []
    for c in constraints:
        c = dict(c)
        c["fun"] = counter.wrap(c["fun"])
        if "jac" in c:
            c["jac"] = counter.wrap(c["jac"])
        cons.append(c)
    try:
        result = minimize(counter.wrap(fun, objective=True), x0, jac=None if jac is None else counter.wrap(jac),
                          method="SLSQP", constraints=cons, options=options)
    except BudgetSpent:
        x = counter.last if counter.last is not None else np.asarray(x0, dtype=float)
        return x, f"stopped: the evaluation budget ({counter.budget} evaluations) is spent", -1, True
    return result.x, str(result.message), int(result.nit), False


def design(scene, objective: str, limits: DesignLimits, maxiter: int = 500, *, max_evaluations: int = MAX_EVALUATIONS,
           progress=None) -> DesignReport:
    """Minimise `objective` over the free station values subject to `limits` (SLSQP). The peak
    objectives are solved in epigraph form (minimise t with -t <= a_i <= t), whose constraints are
    linear in the variables and get their exact Jacobian from the basis. Limits no lift can meet
    raise InputError before any optimisation (infeasible); the optimisation stops after
    `max_evaluations` evaluations; `progress(evaluations, seconds)` is called as it runs."""

    problem = Problem(scene, objective, limits)
    impossible = infeasible(scene, problem, limits)
    if impossible is not None:
        raise InputError("<command line>", *impossible)
    counter = _Counter(max_evaluations, progress)
    z0 = problem.start()
    peak = objective in ("peak-acceleration", "peak-jerk")
    w, ratio = scene.omega, scene.follower.ratio
    row, factor = (2, ratio * w**2) if objective == "peak-acceleration" else (3, ratio * w**3)
    start_value = objective_value(scene, problem.lift(z0), problem.derivatives(z0), objective, limits)
    norm = start_value if start_value > 0 else 1.0

    def limits_of(z):
        return np.concatenate(list(constraint_arrays(scene, problem.derivatives(z), limits)[0].values()))

    target, held, held_area = None, [], None  # the open area, an equality (relative to the target)
    if limits.open_area is not None:
        xa, wa = _residual_nodes(scene, problem.lift(z0))  # the knots do not move: nodes for every z
        a_base = problem.lift(np.zeros(len(problem.free))).derivatives(scene.lift.start + xa)[0]
        a_cols = np.stack([problem.lift(np.eye(len(problem.free))[i]).derivatives(scene.lift.start + xa)[0] - a_base
                           for i in range(len(problem.free))], axis=1)

        def area_of(z):
            return open_area(scene, a_base + a_cols @ z, wa)

        # the exact area (and its gradient) of the pieces, whose coefficients are affine in z too
        n_free = len(problem.free)
        zero = problem.lift(np.zeros(n_free))
        m = max(len(c) for c in zero.coefficients)

        def padded(lift):
            return np.array([np.pad(np.asarray(c, dtype=float), (0, m - len(c))) for c in lift.coefficients])

        c_base = padded(zero)
        c_cols = np.stack([padded(problem.lift(np.eye(n_free)[i])) - c_base for i in range(n_free)])
        exact_area = affine_open_area(c_base, c_cols, np.diff(zero.knots), scene.follower.ratio,
                                      scene.valve.lash if scene.valve is not None else 0.0)
        target = exact_area(z0)[0] if limits.open_area == "keep" else float(limits.open_area)
        if not target > 0.0:
            raise InputError("<command line>", "--open-area", "the valve never opens: no area to hold")
        # SLSQP holds the stand-in; "keep" at the stand-in's own value of the start, which the start
        # meets exactly (asked to hold the exact area's, ~5e-7 off, SLSQP with finite differences
        # spent the budget on jerk-energy); the projection then meets the exact target
        held_area = area_of(z0) if limits.open_area == "keep" else target
        held = [{"type": "eq", "fun": lambda y, n=len(problem.free): area_of(y[:n]) / held_area - 1.0}]

    def area_met(z) -> bool:  # the stand-in's (the exact area is met by the projection after)
        return target is None or area_slack(area_of(z), held_area) == 0.0

    method = "SLSQP"
    if peak:
        # The LP without the nonlinear limits (HiGHS) gives a start near the optimum; SLSQP then
        # minimises with every limit, in epigraph form; the better of the two feasible points wins.
        # (the LP knows no area; with one held, SLSQP starts from the scene's values)
        z_lp = _peak_by_linear_programme(scene, problem, row, factor, limits) if target is None else None
        gain = factor / norm * problem.basis[:, row, :].T  # d(column)/dz, (samples, free)
        n_free = len(problem.free)

        def column(z):
            return factor / norm * problem.derivatives(z)[row]

        def epigraph(y):
            c = column(y[:-1])
            return np.concatenate([y[-1] - c, y[-1] + c])

        def epigraph_jac(y):
            ones = np.ones((gain.shape[0], 1))
            return np.vstack([np.hstack([-gain, ones]), np.hstack([gain, ones])])

        cons = [{"type": "ineq", "fun": epigraph, "jac": epigraph_jac},
                {"type": "ineq", "fun": lambda y: limits_of(y[:-1])}] + held
        first = z0 if z_lp is None else z_lp
        y0 = np.append(first, np.max(np.abs(column(first))))
        x, message, iterations, spent = _minimize(counter, lambda y: y[-1], y0,
                                                  jac=lambda y: np.append(np.zeros(n_free), 1.0), constraints=cons,
                                                  options={"maxiter": maxiter, "ftol": 1e-12})
        candidates = [(x[:-1], "SLSQP")] + ([(z_lp, "HiGHS")] if z_lp is not None else [])
        feasible = [(np.max(np.abs(column(z))), z, name) for z, name in candidates
                    if np.all(limits_of(z) >= -1e-9) and area_met(z)]
        z, method = (min(feasible, key=lambda item: item[0])[1:] if feasible else (x[:-1], "SLSQP"))
        method = ("HiGHS (LP start), then SLSQP" if z_lp is not None else "SLSQP") + f"; best: {method}"
    elif objective == "residual-vibration":
        # the amplitudes are |c_s + G_s z| (linear in z inside the modulus): epigraph on their
        # squares, smooth everywhere, with exact Jacobians
        xq, wq = _residual_nodes(scene, problem.lift(z0))
        theta = scene.lift.start + xq
        base = problem.lift(np.zeros(len(problem.free))).derivatives(theta)[2]
        cols = np.stack([problem.lift(np.eye(len(problem.free))[i]).derivatives(theta)[2] - base
                         for i in range(len(problem.free))], axis=1)
        kernel = _residual_kernel(scene, limits, xq, wq)
        c, G = kernel @ base / norm, kernel @ cols / norm
        n_free = len(problem.free)

        def squared(y):
            amp = c + G @ y[:-1]
            return y[-1] - (amp.real**2 + amp.imag**2)

        def squared_jac(y):
            amp = c + G @ y[:-1]
            dz = -2.0 * (amp.real[:, None] * G.real + amp.imag[:, None] * G.imag)
            return np.hstack([dz, np.ones((len(amp), 1))])

        cons = [{"type": "ineq", "fun": squared, "jac": squared_jac},
                {"type": "ineq", "fun": lambda y: limits_of(y[:-1])}] + held
        y0 = np.append(z0, 1.0)
        x, message, iterations, spent = _minimize(counter, lambda y: y[-1], y0,
                                                  jac=lambda y: np.append(np.zeros(n_free), 1.0), constraints=cons,
                                                  options={"maxiter": maxiter, "ftol": 1e-16})
        z = x[:-1]
    else:
        fun = lambda z: objective_value(scene, problem.lift(z), problem.derivatives(z), objective, limits) / norm  # noqa: E731
        cons = [{"type": "ineq", "fun": limits_of}] + held
        z, message, iterations, spent = _minimize(counter, fun, z0, constraints=cons,
                                                  options={"maxiter": maxiter, "ftol": 1e-14})
    projection = ""
    if target is not None:
        z, projection = _project_on_area(exact_area, z, target, limits_of)
    lift = problem.lift(z)
    # the optimum is a computed cam: the checks of every cam (explorer.lift.validity) before it is reported
    check_computed(lift, scene.follower, scene.source, "lift.stations", f"the optimised lift (--objective {objective})",
                   {"undercut": "keep its curvature with --radius-margin (0 or more)",
                    "pressure angle": "limit it with --max-pressure-angle",
                    "lift range": "hold a smaller --open-area, or give fewer station lifts s as \"free\"",
                    "": "check the scene's units"})
    value, _, slacks = evaluate(scene, lift, objective, limits, problem.x, target)
    values = {key: float(zi * si) for key, zi, si in zip(problem.free, z, problem.scale)}
    comparison = {}
    height, rise, dwell, ret = _event_shape(problem)
    for law_name in STANDARD_LAWS:
        std = LawLift(height=height, start=scene.lift.start, rise=rise, dwell=dwell, ret=ret,
                      rise_law=law_name, return_law=law_name)
        comparison[law_name] = evaluate(scene, std, objective, limits, problem.x, target)[::2]

    # SLSQP often ends a nonsmooth (peak) problem with "positive directional derivative for
    # linesearch" at its optimum: the result counts when every limit is met and it improved on a
    # start that met them too (a start off the held area may have to get worse to reach it)
    start_met = all(v >= -1e-9 for v in evaluate(scene, problem.lift(z0), objective, limits, problem.x, target)[2].values())
    met = all(v >= -1e-9 for v in slacks.values()) and (value <= start_value or not start_met) and not spent
    message += projection
    return DesignReport(objective, value, start_value, values, slacks, comparison, iterations,
                        met, message if met or spent else message + "; a limit is violated or nothing improved",
                        with_values(problem.options, values), method, target, limits)


def _held_directions(limits_of, z) -> np.ndarray | None:
    """An orthonormal basis (free, m) of the moves that leave the limits active at z (scaled slack
    below ACTIVE) unchanged to first order: the null space of their Jacobian (central differences
    of limits_of, 2 x free evaluations). None when no limit is active."""
    slack = limits_of(z)
    active = slack < ACTIVE
    if not np.any(active):
        return None
    h = 1e-6  # the variables are of order 1; the limits' curvature makes the error ~h^2
    jac = np.stack([(limits_of(z + h * e)[active] - limits_of(z - h * e)[active]) / (2.0 * h)
                    for e in np.eye(len(z))], axis=1)
    _, sv, vt = np.linalg.svd(jac)
    rank = int(np.sum(sv > 1e-10 * sv[0])) if sv.size and sv[0] > 0.0 else 0
    return vt[rank:].T


def _project_on_area(exact_area, z, target: float, limits_of=None) -> tuple[np.ndarray, str]:
    """(z moved onto exact_area(z) = target, a note for the solver message). Newton's method on the
    one equation, each step the minimum-norm one: dz = -(A - target) p / (g . p), p the gradient g
    (in the scaled variables) projected onto the moves that keep the active limits where SLSQP left
    them (_held_directions; g itself when none is active or when that leaves no grip on the area).
    SLSQP's point, met on the smooth stand-in, is some 1e-7 off the exact area, so the move is that
    small; the limits are evaluated again after it. At most PROJECTION_STEPS steps; a step that does
    not reduce the deviation ends it, and the area is then reported as not met by its slack."""
    z = np.array(z, dtype=float)
    area, grad = exact_area(z)
    held = _held_directions(limits_of, z) if limits_of is not None else None
    for step in range(PROJECTION_STEPS):
        deviation = area - target
        if abs(deviation) <= PROJECTION_TOLERANCE * abs(target):
            return z, f"; projected onto the exact open area in {step} Newton step{'s' * (step != 1)}"
        direction = grad
        if held is not None:
            kept = held @ (held.T @ grad)
            # an active set that (almost) fixes the area: move along g, and the limits tell
            if np.linalg.norm(kept) > 1e-3 * np.linalg.norm(grad):
                direction = kept
        norm2 = float(grad @ direction)
        if not norm2 > 0.0:
            break
        trial = z - deviation * direction / norm2
        trial_area, trial_grad = exact_area(trial)
        if not abs(trial_area - target) < abs(deviation):
            break
        z, area, grad = trial, trial_area, trial_grad
    if abs(area - target) <= PROJECTION_TOLERANCE * abs(target):
        return z, f"; projected onto the exact open area in {PROJECTION_STEPS} Newton steps"
    return z, f"; the projection onto the exact open area stopped {abs(area - target) / abs(target):.2g} (relative) off it"


def _event_shape(problem) -> tuple[float, float, float, float]:
    """(height, rise, dwell, return) of the spline's event: the stations with the largest s mark
    the top (the first ends the rise, the last starts the return)."""
    st = problem.options.stations
    s = np.array([v.values[0] if v.values[0] is not None else -np.inf for v in st])
    top = np.nonzero(s == s.max())[0]
    knots = problem.knots
    return float(s.max()), float(knots[top[0]]), float(knots[top[-1]] - knots[top[0]]), float(knots[-1] - knots[top[-1]])


def report_text(scene, report: DesignReport) -> str:
    unit = {"peak-acceleration": "m/s**2", "peak-jerk": "m/s**3", "jerk-energy": "m**2/s**5",
            "residual-vibration": "m"}[report.objective]
    w = scene.omega
    lines = [f"{scene.name}: minimise {report.objective} with {report.method}, {report.iterations} iterations "
             f"({'limits met' if report.success else 'FAILED'}; solver: {report.message})",
             f"  optimum {report.value:.6g} {unit} (start {report.start_value:.6g})"]
    if report.open_area is not None:
        lines.append(f"  open area held at {1e3 * math.degrees(report.open_area):.6g} mm*deg")
    lines += speed_notes(scene, report.objective, report.limits)
    for (i, k), value in report.values.items():
        lines.append(f"  station {i} {NAMES[k]} = {value * w**k:.9g} {UNITS[k]}")
    lines.append("  constraint slacks (>= 0 met):")
    for name, slack in report.slacks.items():
        lines.append(f"    {name:<16s} {figure(slack, signed=True)}")
    lines.append(f"  standard laws on the same event ({report.objective}; slacks):")
    for law_name, (value, slacks) in report.comparison.items():
        cells = "  ".join(f"{name.split(' [')[0]} {figure(slack, signed=True)}" for name, slack in slacks.items())
        lines.append(f"    {law_name:<20s} {value:11.6g} {unit}   {cells}{'  VIOLATES' if min(slacks.values()) < 0 else ''}")
    return "\n".join(lines) + "\n"


def speed_notes(scene, objective: str, limits: DesignLimits | None) -> list[str]:
    """The speeds the limits and the objective hold at, defaults named: a default that shapes the
    result is printed with it."""
    lines = []
    if limits is not None and limits.contact_margin is not None:
        upto = (f"{limits.contact_rpm:g} rpm (--contact-rpm)" if limits.contact_rpm is not None
                else f"{scene.drive.rpm:g} rpm (drive.rpm: the default without --contact-rpm)")
        lines.append(f"  contact margin {limits.contact_margin:g} N held at every speed up to {upto}")
    if objective == "residual-vibration":
        band = limits.band if limits is not None else None
        lines.append(f"  residual vibration over {band[0]:g} to {band[1]:g} rpm (--band)" if band is not None
                     else f"  residual vibration at {scene.drive.rpm:g} rpm (drive.rpm: the default without --band)")
    return lines


def stations_toml(scene, report: DesignReport) -> str:
    """The optimised [[lift.stations]] in scene syntax."""
    w = report.options.reference_rpm * TWO_PI / 60.0
    units = ("mm", "m/s", "m/s**2", "m/s**3", "m/s**4")
    scale = (1e3, 1.0, 1.0, 1.0, 1.0)
    out = []
    for st in report.options.stations:
        out.append("[[lift.stations]]")
        out.append(f'angle = "{math.degrees(st.angle):.12g} deg"')
        for k, value in enumerate(st.values):
            if value is not None:
                out.append(f'{NAMES[k]} = "{value * w**k * scale[k]:.12g} {units[k]}"')
        out.append("")
    return "\n".join(out)

