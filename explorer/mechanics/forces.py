"""Rigid valve-train loads along the cycle: spring, friction, closing loads, contact force, float speed.

Schenker (1902, section 4): the valve, with all moving masses M referred to it (from a scene:
explorer.mechanics.moving_mass.rigid_mass, valve.mass and the gear's moving parts), is driven
open by the linkage (cam, roller, levers) and pushed back by the spring, the stuffing-box friction R and
constant closing loads D (steam on stem and valve, unbalanced weights, spring weight). With the
valve lift s, velocity v and acceleration p of the rigid (prescribed) motion, the force the
linkage must transmit is

    F = M p + F_spring(s) + R sgn(v) + sum D.

F < 0 means the linkage would have to pull: the valve leaves the cam (floats). The spring force
that keeps F = 0 is the required spring force -(M p + R sgn(v) + sum D); the margin is the spring
force present minus the required one, which equals F while the valve is open and the force on the
seat while it is seated (it must hold the valve shut against net opening loads, e.g. the steam on
an intake-valve stem).

Accelerations scale with the square of the speed and the loads do not, so F = w^2 A(theta) + G(theta)
with A = M ratio L''(theta) and G = F_spring + R sgn + D. The float (jump) speed is therefore
w_jump^2 = min over the open stretches with A < 0 of G / (-A), found here on the analytic lift:
a dense grid over the smooth pieces of the cycle (split at the curve's breakpoints, the lash
crossings and the velocity zeros where friction flips), refined by zooming in (vectorised) on the grid minimum.

Sign conventions: forces are positive in the valve's opening direction for F, and positive when
they load the linkage (act to close the valve) for the loads. Friction at rest takes the direction
the valve is about to move (sign of the acceleration): its one-sided limit right after the instant.

The trip gear's latch drives the valve only from the pick-up to the trip; its forces are those
of that window (explorer.gears.trip_latched, its variant of this effect in its gear),
not of the free closing after it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..core.errors import InputError, echo
from ..core.roots import root_in
from ..lift.curves import grid_with, lift_at, lift_rows, wrap_two_pi
from .kinematics import lash_crossings
from .moving_mass import rigid_mass


TWO_PI = 2.0 * math.pi
RPM_PER_RAD_S = 60.0 / TWO_PI
# Endpoints of each smooth piece are evaluated this far inside, which gives the one-sided limit
# there to ~1e-11 relative (the pieces are at least a few 1e-6 rad long on any real cam).
_INSIDE = 1e-11


@dataclass(frozen=True)
class TrainLoads:
    """The loads of a rigid valve train, referred to the valve, SI."""

    mass: float  # kg, all moving masses referred to the valve (from a scene: moving_mass.rigid_mass)
    preload: float  # N, spring force at closed valve
    rate: float  # N/m
    friction: float = 0.0  # N, Coulomb, opposes valve motion
    closing: float = 0.0  # N, sum of constant loads; + acts to close the valve
    source: str = "<arguments>"

    def __post_init__(self) -> None:
        checks = (
            ("valve.mass", self.mass, self.mass > 0.0, "must be greater than zero"),
            ("spring.preload", self.preload, self.preload >= 0.0, "must not be negative"),
            ("spring.rate", self.rate, self.rate >= 0.0, "must not be negative"),
            ("loads.friction", self.friction, self.friction >= 0.0, "must not be negative (Coulomb friction opposes motion by itself)"),
            ("loads.closing", self.closing, True, ""),
        )
        for key, value, ok, reason in checks:
            if not math.isfinite(value):
                raise InputError(self.source, key, f"value must be finite, got {echo(value)}")
            if not ok:
                raise InputError(self.source, key, f"{reason}, got {echo(value)}")

    @staticmethod
    def from_scene(scene) -> "TrainLoads":
        if scene.valve is None:
            raise InputError(scene.source, "valve", "missing section: effect 'forces' needs [valve] mass")
        if scene.spring is None:
            raise InputError(scene.source, "spring", "missing section: effect 'forces' needs [spring] preload and rate")
        return TrainLoads(
            mass=rigid_mass(scene).total,
            preload=scene.spring.preload,
            rate=scene.spring.rate,
            friction=scene.loads.friction,
            closing=scene.loads.closing_total,
            source=scene.source,
        )

    def with_spring(self, preload: float, rate: float) -> "TrainLoads":
        return TrainLoads(self.mass, preload, rate, self.friction, self.closing, self.source)


def friction_direction(velocity, accel) -> np.ndarray:
    """+1 while the valve opens, -1 while it closes; at rest the direction it is about to move."""
    v = np.asarray(velocity, dtype=float)
    a = np.asarray(accel, dtype=float)
    return np.where(v > 0.0, 1.0, np.where(v < 0.0, -1.0, np.sign(a)))


def rigid_train_forces(lift, velocity, accel, loads: TrainLoads, ratio: float = 1.0) -> dict[str, np.ndarray]:
    """Per-step forces of the rigid train from the valve motion (s, v, p arrays, valve side).

    The valve is open where s > 0; while seated the linkage carries nothing (the follower runs
    inside the lash) and the seat carries spring plus closing loads.
    """
    s = np.asarray(lift, dtype=float)
    v = np.asarray(velocity, dtype=float)
    a = np.asarray(accel, dtype=float)
    is_open = s > 0.0
    inertia = np.where(is_open, loads.mass * a, 0.0)
    spring = loads.preload + loads.rate * s
    friction = np.where(is_open, loads.friction * friction_direction(v, a), 0.0)
    closing = np.full_like(s, loads.closing)
    contact = np.where(is_open, inertia + spring + friction + closing, 0.0)
    required = np.where(is_open, -(inertia + friction + closing), -closing)
    return {
        "spring_force_N": spring,
        "inertia_force_N": inertia,
        "friction_force_N": friction,
        "closing_load_N": closing,
        "contact_force_N": contact,
        "linkage_force_N": contact,  # rigid train: the linkage carries exactly the contact force
        "follower_force_N": ratio * contact,  # lever: force scales with the valve/follower travel ratio
        "required_spring_force_N": required,
        "spring_margin_N": spring - required,
    }


# --- the cycle split into smooth pieces ---------------------------------------------------------


@dataclass(frozen=True)
class Pieces:
    """Stretches of one revolution on which the lift and the load pattern are smooth."""

    start: np.ndarray  # rad
    end: np.ndarray  # rad, end > start, may pass 2 pi (wraps)
    is_open: np.ndarray  # bool, valve off its seat
    direction: np.ndarray  # +1 opening, -1 closing, 0 at rest (dwell)


def velocity_zeros(lift, n_grid: int = 4096) -> np.ndarray:
    """Angles where dL/dtheta changes sign (isolated zeros), polished by Brent's method."""
    grid = np.linspace(0.0, TWO_PI, n_grid + 1)
    grid = grid_with(grid, lift.breakpoints())
    d1 = lift_rows(lift, grid, (1,))[0]  # the slope only (lift_rows: the lift's derivatives' floats)
    sg = np.sign(d1)
    roots = []
    for i in np.nonzero(sg[:-1] * sg[1:] < 0.0)[0]:
        f = lambda th: lift_at(lift, th, 1)  # noqa: E731
        roots.append(root_in(f, grid[i], grid[i + 1], fa=d1[i], fb=d1[i + 1], xtol=1e-15, maxiter=200))
    # an exact zero on a grid point between opposite signs (in grid order, as a loop over them
    # would append them; vectorised: a base circle is thousands of zeros of the slope)
    zeros = np.nonzero(sg[1:-1] == 0.0)[0] + 1
    roots.extend(grid[zeros[sg[zeros - 1] * sg[zeros + 1] < 0.0]].tolist())
    return np.mod(np.asarray(roots, dtype=float), TWO_PI)


def smooth_pieces(lift, ratio: float, lash: float, n_grid: int = 4096) -> Pieces:
    ups, downs = lash_crossings(lift, ratio, lash, n_grid)
    cuts = np.concatenate([np.asarray(lift.breakpoints(), dtype=float), ups, downs, velocity_zeros(lift, n_grid)])
    cuts = np.unique(np.mod(cuts, TWO_PI))
    if cuts.size:  # merge cuts closer than rounding
        cuts = cuts[np.concatenate([[True], np.diff(cuts) > 1e-13])]
    if cuts.size == 0:
        start, end = np.array([0.0]), np.array([TWO_PI])
    else:
        start = cuts
        end = np.append(cuts[1:], cuts[0] + TWO_PI)
    mid = 0.5 * (start + end)
    d = lift_rows(lift, mid, (0, 1, 2))
    return Pieces(
        start=start,
        end=end,
        is_open=ratio * d[0] - lash > 0.0,
        direction=friction_direction(d[1], d[2]),
    )


def sample_pieces(pieces: Pieces, select: np.ndarray | None = None, n_grid: int = 4096):
    """(theta, direction, owner) samples of the selected pieces (default: open), ends moved just
    inside so that each end gives its piece's one-sided limit; owner indexes the selected pieces."""
    chosen = np.nonzero(pieces.is_open if select is None else select)[0]
    lengths = pieces.end[chosen] - pieces.start[chosen]
    counts = np.maximum(9, np.ceil(n_grid * lengths / TWO_PI).astype(int))
    thetas, owner = [], []
    for k, (i, m) in enumerate(zip(chosen, counts)):
        a, b = pieces.start[i], pieces.end[i]
        eps = _INSIDE * max(1.0, b - a)
        thetas.append(np.linspace(a + eps, b - eps, m))
        owner.append(np.full(m, k))
    if not thetas:
        return np.zeros(0), np.zeros(0), np.zeros(0, dtype=int), chosen
    owner_a = np.concatenate(owner)
    return np.concatenate(thetas), pieces.direction[chosen][owner_a], owner_a, chosen


def piece_direction(pieces: Pieces, theta: float) -> float:
    """Friction direction of the piece that holds the angle theta."""
    t = (theta - pieces.start[0]) % TWO_PI + pieces.start[0]
    i = int(np.clip(np.searchsorted(pieces.start, t, side="right") - 1, 0, pieces.start.size - 1))
    return float(pieces.direction[i])


def minimise_on_pieces(
    lift,
    pieces: Pieces,
    fun: Callable[[np.ndarray, np.ndarray], np.ndarray],
    select: np.ndarray | None = None,
    n_grid: int = 4096,
    refine: bool = True,
) -> tuple[float, float]:
    """Minimum over the selected pieces (default: the open ones; a piece is open as a whole, so
    callers must not re-test openness per sample: near a seating point the lift rounds to zero)
    of fun(d, direction) (d = lift derivatives (4, N), direction
    the piece's friction sign per sample; +inf where fun does not apply). Returns (value, theta);
    (inf, nan) when nothing applies. Grid minimum per piece, the best pieces refined by bounded
    zooming in on the grid neighbours of their grid minimum (_zoom_minimum)."""
    theta, direction, owner, chosen = sample_pieces(pieces, select, n_grid)
    if chosen.size == 0:
        return math.inf, math.nan
    values = fun(lift.derivatives(np.mod(theta, TWO_PI)), direction)
    return _minimise_sampled(lift, pieces, fun, theta, owner, chosen, values, refine)


def _minimise_sampled(lift, pieces: Pieces, fun, theta, owner, chosen, values, refine: bool = True):
    """minimise_on_pieces from its samples (sample_pieces: theta, owner, chosen; chosen not empty)
    and fun's values there."""
    counts = np.bincount(owner, minlength=chosen.size)
    best_value, best_theta = math.inf, math.nan
    offsets = np.concatenate([[0], np.cumsum(counts)])
    grid_min = np.array([values[offsets[k] : offsets[k + 1]].min() for k in range(chosen.size)])
    if not np.isfinite(grid_min).any():
        return math.inf, math.nan
    floor = np.nanmin(grid_min)
    for k in np.argsort(grid_min):
        if not np.isfinite(grid_min[k]):
            break
        seg = values[offsets[k] : offsets[k + 1]]
        j = int(np.argmin(seg))
        th_grid = theta[offsets[k] + j]
        if grid_min[k] < best_value:
            best_value, best_theta = float(grid_min[k]), float(th_grid)
        # only pieces whose grid minimum is near the best can hold the true minimum
        slack = 1e-3 * abs(floor) + 1e-9
        if not refine or grid_min[k] > floor + slack:
            continue
        ts = theta[offsets[k] : offsets[k + 1]]
        lo, hi = ts[max(j - 1, 0)], ts[min(j + 1, ts.size - 1)]
        if hi <= lo:
            continue
        val, th = _zoom_minimum(lift, fun, pieces.direction[chosen[k]], float(lo), float(hi))
        if val < best_value:
            best_value, best_theta = val, th
    return best_value, float(np.mod(best_theta, TWO_PI))


SPEED_BLOCK = 4096  # speeds per block of min_contact_forces (its (speeds x pieces) arrays)
ZOOM_POINTS = 33  # samples per zoom: the bracket shrinks 16-fold per lift evaluation


def _zoom_minimum(lift, fun, direction: float, lo: float, hi: float, xatol: float = 1e-10) -> tuple[float, float]:
    """(value, theta) of the minimum of fun in [lo, hi] (the grid neighbours of a grid minimum):
    sampled at ZOOM_POINTS angles at once, the bracket narrowed to the best sample's neighbours,
    until it is shorter than xatol (7 rounds from a 4096-point grid; the value is then within
    f'' xatol^2 / 2 of a smooth minimum, |f'| xatol of one at a kink: far below anything measured
    for 1e-10 rad). One vectorised lift
    evaluation a round instead of Brent's one per point: a gear's lift (jets through a linkage,
    a Newton solve for the cam contact) costs nearly the same for 33 angles as for one."""
    best_value, best_theta = math.inf, lo
    dirn = np.full(ZOOM_POINTS, direction)
    for _ in range(60):
        ts = np.linspace(lo, hi, ZOOM_POINTS)
        values = np.asarray(fun(lift.derivatives(np.mod(ts, TWO_PI)), dirn), dtype=float)
        values = np.where(np.isfinite(values), values, np.inf)
        j = int(np.argmin(values))
        if values[j] < best_value:
            best_value, best_theta = float(values[j]), float(ts[j])
        if hi - lo <= xatol:
            break
        lo, hi = float(ts[max(j - 1, 0)]), float(ts[min(j + 1, ZOOM_POINTS - 1)])
    return best_value, best_theta


# --- speed-independent and speed-scaled parts of the contact force ------------------------------


def load_parts(d: np.ndarray, direction, loads: TrainLoads, ratio: float, lash: float):
    """(A, G, open) with contact force F = w^2 A + G on open samples (d = lift derivatives)."""
    x = ratio * d[0] - lash
    is_open = x > 0.0
    s = np.where(is_open, x, 0.0)
    a_coef = loads.mass * ratio * d[2]
    g_part = loads.preload + loads.rate * s + loads.friction * direction + loads.closing
    return a_coef, g_part, is_open


@dataclass(frozen=True)
class FloatSpeed:
    omega: float  # rad/s, lowest camshaft speed where the rigid contact force reaches zero (inf: never)
    theta: float  # rad, cam angle where it does (nan: never)
    static_loss: bool  # True when the loads alone already lose contact (spring too weak at standstill)

    @property
    def rpm(self) -> float:
        return self.omega * RPM_PER_RAD_S


def grid_load_parts(scene, lift, n: int | None = None):
    """(theta, A, G, is_open) on the scene's sampling grid of n steps (default: the scene's): the
    rigid contact force is F = w^2 A + G where the valve is open, so every speed of a sweep costs
    one multiply-add per sample."""
    loads = TrainLoads.from_scene(scene)
    n = n or scene.solver.steps_per_revolution
    theta = np.arange(n) * (TWO_PI / n)  # the floats simulate samples at
    d = lift_rows(lift, theta, (0, 1, 2))  # no jerk read (lift_rows: the same floats)
    lash = scene.valve.lash if scene.valve is not None else 0.0
    a_coef, g_part, is_open = load_parts(d, friction_direction(d[1], d[2]), loads, scene.follower.ratio, lash)
    return theta, a_coef, g_part, is_open


@dataclass(frozen=True)
class SampledParts:
    """The open pieces' samples (sample_pieces) and A, G of F = w^2 A + G there (load_parts of the
    lift's derivatives): what float_speed and min_contact_forces read at every speed, made once
    for a sweep's chunks (studies/sweep_rigid.py keeps it with the pieces)."""

    theta: np.ndarray  # rad, the samples (ends just inside their pieces)
    direction: np.ndarray  # the friction sign per sample
    owner: np.ndarray  # per sample: its index into chosen
    chosen: np.ndarray  # the open pieces' indices
    a_coef: np.ndarray
    g_part: np.ndarray


def sampled_parts(lift, loads: TrainLoads, ratio: float, lash: float, pieces: Pieces, n_grid: int = 4096) -> SampledParts:
    theta, direction, owner, chosen = sample_pieces(pieces, None, n_grid)
    if chosen.size == 0:
        a_coef = g_part = np.zeros(0)
    else:
        d = lift_rows(lift, np.mod(theta, TWO_PI), (0, 2))  # the rows load_parts reads
        a_coef, g_part, _ = load_parts((d[0], None, d[1]), direction, loads, ratio, lash)
    return SampledParts(theta, direction, owner, chosen, a_coef, g_part)


def float_speed(lift, loads: TrainLoads, ratio: float = 1.0, lash: float = 0.0, pieces: Pieces | None = None,
                n_grid: int = 4096, parts: SampledParts | None = None) -> FloatSpeed:
    """Exact float (jump) speed of the rigid train: w^2 = min over open, decelerating stretches of G/(-A).
    `parts`: sampled_parts of these arguments (a sweep's, shared with min_contact_forces), else made here."""
    pieces = pieces or smooth_pieces(lift, ratio, lash, n_grid)
    parts = parts or sampled_parts(lift, loads, ratio, lash, pieces, n_grid)

    def static(d, direction):
        return load_parts(d, direction, loads, ratio, lash)[1]

    def quotient_of(a_coef, g_part):
        with np.errstate(divide="ignore", invalid="ignore"):
            q = g_part / -a_coef
        return np.where(a_coef < 0.0, q, np.inf)

    def quotient(d, direction):
        a_coef, g_part, _ = load_parts(d, direction, loads, ratio, lash)
        return quotient_of(a_coef, g_part)

    if parts.chosen.size == 0:  # no open piece (minimise_on_pieces: nothing applies)
        g_min, g_theta, q_min, q_theta = math.inf, math.nan, math.inf, math.nan
    else:  # minimise_on_pieces of each, its samples' values from the parts (the same floats)
        sampled = (parts.theta, parts.owner, parts.chosen)
        g_min, g_theta = _minimise_sampled(lift, pieces, static, *sampled, parts.g_part)
        if g_min >= 0.0:
            q_min, q_theta = _minimise_sampled(lift, pieces, quotient, *sampled, quotient_of(parts.a_coef, parts.g_part))
    if g_min < 0.0:
        return FloatSpeed(0.0, g_theta, True)
    if not math.isfinite(q_min):
        return FloatSpeed(math.inf, math.nan, False)
    return FloatSpeed(math.sqrt(max(q_min, 0.0)), q_theta, False)


def min_contact_force(lift, loads: TrainLoads, omega: float, ratio: float = 1.0, lash: float = 0.0,
                      pieces: Pieces | None = None, n_grid: int = 4096) -> tuple[float, float]:
    """(smallest rigid contact force over the open stretches, its cam angle), refined on the analytic lift."""
    pieces = pieces or smooth_pieces(lift, ratio, lash, n_grid)
    return minimise_on_pieces(lift, pieces, _contact_force(loads, omega, ratio, lash), n_grid=n_grid)


def max_contact_force(lift, loads: TrainLoads, omega: float, ratio: float = 1.0, lash: float = 0.0,
                      pieces: Pieces | None = None, n_grid: int = 4096) -> tuple[float, float]:
    """(largest rigid contact force over the open stretches, its cam angle): min_contact_force's
    refinement of minus the force (on a piece's end, its one-sided limit: an acceleration step at a
    breakpoint takes the larger side); (-inf, nan) when the valve never opens."""
    pieces = pieces or smooth_pieces(lift, ratio, lash, n_grid)
    force = _contact_force(loads, omega, ratio, lash)
    value, theta = minimise_on_pieces(lift, pieces, lambda d, direction: -force(d, direction), n_grid=n_grid)
    return -value, theta


def _contact_force(loads: TrainLoads, omega: float, ratio: float, lash: float):
    """The rigid contact force F = w^2 A + G (load_parts) as minimise_on_pieces' fun(d, direction)."""

    def force(d, direction):
        a_coef, g_part, _ = load_parts(d, direction, loads, ratio, lash)
        return omega**2 * a_coef + g_part

    return force


def min_contact_forces(lift, loads: TrainLoads, omegas, ratio: float = 1.0, lash: float = 0.0,
                       pieces: Pieces | None = None, n_grid: int = 4096,
                       parts: SampledParts | None = None) -> tuple[np.ndarray, np.ndarray]:
    """min_contact_force at every speed of `omegas` at once: (values, angles), each speed's the
    same floats as min_contact_force's. The samples, the lift there and A, G of F = w^2 A + G are
    shared by all speeds; the zoom of every speed's candidate pieces runs as one batch, one lift
    evaluation a round for all of them (minimise_on_pieces and _zoom_minimum, row by row).
    `parts`: sampled_parts of these arguments (a sweep's chunks share it), else made here."""
    from .sweep_loops import piece_minima  # compiled: the compiled sweep's path only

    pieces = pieces or smooth_pieces(lift, ratio, lash, n_grid)
    w2 = np.asarray(omegas, dtype=float).ravel() ** 2
    values_out, theta_out = np.full(w2.size, math.inf), np.full(w2.size, math.nan)
    if w2.size == 0:
        return values_out, theta_out
    parts = parts or sampled_parts(lift, loads, ratio, lash, pieces, n_grid)
    theta, owner, chosen, a_coef, g_part = parts.theta, parts.owner, parts.chosen, parts.a_coef, parts.g_part
    if chosen.size == 0:
        return values_out, theta_out
    counts = np.bincount(owner, minlength=chosen.size)
    offsets = np.concatenate([[0], np.cumsum(counts)])
    # the grid minimum of every (speed, piece) and where it is, compiled (sweep_kernels.piece_minima:
    # min_contact_force's floats, omega**2 * A + G and the minimum of each piece's samples)
    block = SPEED_BLOCK
    lows, highs = offsets[:-1].astype(np.intp), offsets[1:].astype(np.intp)
    candidates = []  # per block: (speed, piece, lo, hi) of the pieces min_contact_force zooms into
    for b0 in range(0, w2.size, block):
        b1 = min(w2.size, b0 + block)
        grid_min, j_of = piece_minima(w2[b0:b1], a_coef, g_part, lows, highs)
        floor = np.nanmin(grid_min, axis=1)
        slack = 1e-3 * np.abs(floor) + 1e-9
        # its pieces in the order min_contact_force visits them (np.argsort of each row)
        order = np.argsort(grid_min, axis=1)
        rows = np.arange(b1 - b0)
        first = order[:, 0]
        # the best grid value: the first piece of that order (strictly smaller values replace)
        zoom = ~(grid_min > (floor + slack)[:, None])
        best_j = j_of[rows, first]
        best = grid_min[rows, first]
        found = best < math.inf  # else no grid value is below +inf: (inf, nan) as min_contact_force
        values_out[b0:b1] = np.where(found, best, math.inf)
        theta_out[b0:b1] = np.where(found, theta[lows[first] + best_j], math.nan)
        # the zoom's brackets: the grid neighbours of each candidate piece's argmin
        ranked = zoom[rows[:, None], order]  # (speed, rank): zoom into the piece of that rank
        r_idx, rank = np.nonzero(ranked)  # row-major: each speed's pieces in its own order
        k_idx = order[r_idx, rank]
        j = j_of[r_idx, k_idx]
        lo_i = lows[k_idx] + np.maximum(j - 1, 0)
        hi_i = lows[k_idx] + np.minimum(j + 1, counts[k_idx] - 1)
        lo, hi = theta[lo_i], theta[hi_i]
        keep = hi > lo
        candidates.append((r_idx[keep] + b0, lo[keep], hi[keep], pieces.direction[chosen[k_idx[keep]]]))
    rows_a = np.concatenate([c[0] for c in candidates])
    if rows_a.size:
        zoom_value, zoom_theta = _zoom_minima(lift, loads, w2[rows_a], ratio, lash,
                                              np.concatenate([c[3] for c in candidates]).astype(float),
                                              np.concatenate([c[1] for c in candidates]),
                                              np.concatenate([c[2] for c in candidates]))
        # in each speed's own order of its pieces: a strictly smaller zoom value replaces the best
        if np.unique(rows_a).size == rows_a.size:  # one zoom per speed: no order among them
            better = zoom_value < values_out[rows_a]
            values_out[rows_a[better]], theta_out[rows_a[better]] = zoom_value[better], zoom_theta[better]
        else:
            for r, s in enumerate(rows_a.tolist()):
                if zoom_value[r] < values_out[s]:
                    values_out[s], theta_out[s] = zoom_value[r], zoom_theta[r]
    return values_out, np.mod(theta_out, TWO_PI)


def _mod_two_pi(x: np.ndarray) -> np.ndarray:
    """lift.curves.wrap_two_pi (np.mod's floats for the zoom's angles, which are >= 0), always a
    new array: the zoom keeps its samples, and a lift may be given its angles to keep."""
    wrapped = wrap_two_pi(x)
    return wrapped.copy() if wrapped is x else wrapped


def _zoom_minima(lift, loads, w2, ratio, lash, direction, lo, hi, xatol: float = 1e-10):
    """_zoom_minimum of the contact force for many (speed, bracket) rows at once: each row the
    same samples (np.linspace's floats), the same narrowing and the same stop as on its own.
    The rows are zoomed in the order of their brackets' starts (each row's arithmetic is its own,
    so the order changes no float): the samples then come in runs of one stretch of the lift,
    which its derivatives take as slices instead of gathering and scattering by index. Each round
    evaluates only the lift and its second derivative (lift_rows), and each row's F = w^2 A + G
    (load_parts) and its minimum are one compiled pass (sweep_kernels.zoom_minima, the numpy
    form's floats). (Rows of one bracket -- a chunk's slow speeds -- could share the lift there;
    measured, it did not pay: such rows are a few rounds of a few chunks.)"""
    from .sweep_loops import zoom_minima  # compiled: the compiled sweep's path only

    n = lo.size
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], hi[order]
    w2, direction = w2[order], direction[order]
    best_value, best_theta = np.full(n, math.inf), lo.copy()
    idx = np.arange(n)  # the rows still zooming
    steps = np.arange(ZOOM_POINTS, dtype=float)
    # load_parts' constants as it forms them (loads.mass * ratio first: Python's left to right)
    constants = (ratio, lash, loads.mass * ratio, loads.preload, loads.rate, loads.friction, loads.closing)
    for _ in range(60):
        if idx.size == 0:
            break
        a, b = lo[idx], hi[idx]
        ts = steps * ((b - a) / (ZOOM_POINTS - 1))[:, None] + a[:, None]  # np.linspace(a, b, 33)
        ts[:, -1] = b
        d = lift_rows(lift, _mod_two_pi(ts), (0, 2))  # L and L'': what load_parts reads
        v, j = zoom_minima(d[0], d[1], w2[idx], direction[idx], *constants)
        r = np.arange(idx.size)
        better = v < best_value[idx]
        best_value[idx[better]] = v[better]
        best_theta[idx[better]] = ts[r, j][better]
        go = ~((b - a) <= xatol)
        r, j, idx = r[go], j[go], idx[go]
        lo[idx] = ts[r, np.maximum(j - 1, 0)]
        hi[idx] = ts[r, np.minimum(j + 1, ZOOM_POINTS - 1)]
    value_out, theta_out = np.empty(n), np.empty(n)
    value_out[order], theta_out[order] = best_value, best_theta
    return value_out, theta_out


def side_extremes(lift, loads: TrainLoads, omega: float, ratio: float, lash: float, pieces: Pieces,
                  n_grid: int = 4096) -> dict:
    """Schenker's figures per side: largest deceleration p1 (opening, v > 0) and p2 (closing, v < 0)
    of the valve, and the spring forces F1, F2 they require (max of the required spring force there)."""
    out: dict = {}
    for side, sign in (("opening", 1.0), ("closing", -1.0)):
        select = pieces.is_open & (pieces.direction == sign)

        def accel(d, direction):
            return ratio * omega**2 * d[2]

        def neg_required(d, direction):
            a_coef, g_part, _ = load_parts(d, direction, loads, ratio, lash)
            # required spring force = -(w^2 A + R sgn + D); its maximum is minus the minimum of this
            return omega**2 * a_coef + loads.friction * direction + loads.closing

        p, p_theta = minimise_on_pieces(lift, pieces, accel, select=select, n_grid=n_grid)
        r, r_theta = minimise_on_pieces(lift, pieces, neg_required, select=select, n_grid=n_grid)
        out[side] = {
            "peak_deceleration_m_s2": p if math.isfinite(p) else None,
            "peak_deceleration_cam_angle_deg": math.degrees(p_theta) if math.isfinite(p) else None,
            "required_spring_force_N": -r if math.isfinite(r) else None,
            "required_spring_force_cam_angle_deg": math.degrees(r_theta) if math.isfinite(r) else None,
        }
    return out


def loss_intervals(pieces: Pieces, force_of, n_grid: int = 4096) -> list[tuple[float, float]]:
    """Where the force force_of(theta, direction) (vectorised) is <= 0 on the open pieces, as
    (loss, regain) pairs of cam angles in [0, 2 pi), in the order of the revolution (a stretch that
    runs through 0 has loss > regain). One definition for every report of contact loss:

    - loss: the force falls from > 0 to <= 0 inside a piece (a grid sign change polished by
      Brent's method), or a piece starts with it <= 0 although it was > 0 at the end of the piece
      before or the valve was seated (a jump at a breakpoint, the lash take-up);
    - regain: it rises back above 0 inside a piece, at a piece start, or at the end of the open
      stretch (the valve seats and its seat holds it).
    """
    n = pieces.start.size
    if n == 0:
        return []
    first = np.zeros(n, dtype=bool)  # force <= 0 just after the piece's start (closed: never)
    last = np.zeros(n, dtype=bool)  # ... just before its end
    inside: list[list[tuple[float, bool]]] = [[] for _ in range(n)]  # (angle, is_loss)
    for i in np.nonzero(pieces.is_open)[0]:
        a, b = pieces.start[i], pieces.end[i]
        eps = _INSIDE * max(1.0, b - a)
        th = np.linspace(a + eps, b - eps, max(9, int(math.ceil(n_grid * (b - a) / TWO_PI))))
        direction = float(pieces.direction[i])
        f = force_of(th, direction)
        first[i], last[i] = f[0] <= 0.0, f[-1] <= 0.0
        negative = f <= 0.0
        for j in np.nonzero(negative[:-1] != negative[1:])[0]:
            root = root_in(lambda t: float(force_of(np.atleast_1d(t), direction)[0]), th[j], th[j + 1],
                           fa=f[j], fb=f[j + 1], xtol=1e-14, maxiter=200)
            inside[i].append((float(root), bool(negative[j + 1])))
    transitions: list[tuple[float, bool]] = []
    for i in range(n):
        if first[i] != last[(i - 1) % n]:
            transitions.append((float(pieces.start[i]), bool(first[i])))
        transitions.extend(inside[i])
    if not transitions:
        return []
    # pair each loss with the regain after it, wrapping around the revolution
    k = next((j for j, (_, loss) in enumerate(transitions) if loss), None)
    if k is None:
        return []
    ordered = transitions[k:] + transitions[:k]
    out = []
    for (t0, loss0), (t1, loss1) in zip(ordered[0::2], ordered[1::2]):
        if loss0 and not loss1:  # they alternate by construction
            out.append((float(np.mod(t0, TWO_PI)), float(np.mod(t1, TWO_PI))))
    return out


def contact_loss_intervals(lift, loads: TrainLoads, omega: float, ratio: float, lash: float, pieces: Pieces,
                           n_grid: int = 4096) -> list[tuple[float, float]]:
    """Where the rigid contact force is <= 0 at speed omega: (loss, regain) cam angles, rad."""

    def force_of(t, direction):
        a_coef, g_part, _ = load_parts(lift.derivatives(np.mod(t, TWO_PI)), direction, loads, ratio, lash)
        return omega**2 * a_coef + g_part

    return loss_intervals(pieces, force_of, n_grid)


def loss_report(intervals, omega: float, min_force: float, min_theta: float) -> tuple[list[dict], str]:
    """The events (a loss and its regain, paired) and the phrase the warnings use, from one list."""
    events, stretches = [], []
    for loss, regain in intervals:
        events.append({"kind": "rigid-contact-loss", "time_s": loss / omega, "cam_angle_deg": math.degrees(loss)})
        events.append({"kind": "rigid-contact-regain", "time_s": regain / omega,
                       "cam_angle_deg": math.degrees(regain)})
        stretches.append(f"{math.degrees(loss):.2f} to {math.degrees(regain):.2f} deg")
    phrase = ""
    if stretches:
        phrase = (f"the rigid contact force is at or below zero from cam angle {', and from '.join(stretches)} "
                  f"(least {min_force:.4g} N at {math.degrees(min_theta):.2f} deg)")
    return events, phrase


# --- the effect ---------------------------------------------------------------------------------


