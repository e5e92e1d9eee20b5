"""`table` law: a measured lift (angle, lift) from a CSV file, smoothed by a periodic spline.

Measured lifts are noisy, and differentiating noise amplifies it: a lift error e over a sample
spacing h becomes a velocity error ~ e/h and an acceleration error ~ e/h^2. So the samples are
not interpolated but fitted with a periodic penalised quintic spline (a P-spline, Eilers & Marx
1996): uniform knots over the revolution, coefficients c minimising

    |y - B c|^2 + lambda |D3 c|^2          (D3: cyclic third differences of the coefficients)

whose limit for fine knots is the quintic smoothing spline (penalty on the integral of L'''^2).
Velocity, acceleration and jerk are the spline's own derivatives (quintic: C4, so the jerk is
continuous and no derivative ever jumps). The smoothing weight lambda is chosen by generalised
cross-validation ("auto"), or from a stated noise level sigma so that the residual sum of
squares equals N sigma^2 (Reinsch's criterion). `explorer.studies.accuracy` measures what noise and
sample count do to v and p. A C4 spline cannot follow a jump of the jerk (the ends of a cycloidal
rise): even noise-free 1 deg samples of the cycloidal demo leave ~1.5 % acceleration error next
to those instants, and noise soon dominates (see the study's table).

CSV format: two columns, cam angle and lift (units from `angle_unit`, `lift_unit`); separators
comma, semicolon or blanks; lines starting with '#' and one header line are skipped. The angles
must increase strictly, span less than one revolution and cover it (no gap above MAX_GAP_DEG,
wrap-around included): the base circle is part of the measurement.

Physical range, row by row (the error names the file's line, never its content): every value
finite, every angle within ten turns, every lift at most MAX_LIFT (1 m) and on or above the base
circle -- the lift is measured from it, the cam's smallest radius -- up to the gauge's noise:
NOISE_SHARE (1 %) of the table's largest lift or NOISE_SIGMAS (5) times the noise level stated in
`smoothing`, whichever is larger (`dip_allowance`). The smoothed lift passes the checks of every cam
(explorer.lift.validity) with the same allowance below the base circle.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from ..core.errors import InputError, echo
from ..core.reader import Table
from ..core.files import data_folder, read_text
from ..core.ranges import RANGES
from ..core.roots import root_in
from ..core.units import unit_scale
from .validity import MAX_LIFT, check_computed

TWO_PI = 2.0 * math.pi
DEGREE = 5  # quintic: L''' continuous
PENALTY_ORDER = 3  # roughness measured on L''' (jerk)
MAX_KNOTS = 360  # 1 deg knot spacing resolves any valve event; beyond that only cost grows
MIN_SAMPLES = 24
MAX_GAP_DEG = 15.0
MAX_ROWS = 1_000_000
NOISE_SHARE = 0.01  # of the largest lift: a measured base circle may read this far below zero
NOISE_SIGMAS = 5.0  # times a stated noise level: the same, when the gauge's noise is known
UNUSED_KEYS = ("height", "rise", "dwell", "return", "return_law")


@dataclass(frozen=True)
class TableOptions:
    path: str  # resolved CSV path
    angles: tuple[float, ...]  # rad, strictly increasing, as in the file (before `start`)
    lifts: tuple[float, ...]  # m
    noise: float | None  # m, stated noise sigma; None = choose by cross-validation
    angle_unit: str = "deg"
    lift_unit: str = "mm"
    dip_allowance: float = 0.0  # m: how far the lift may read below the base circle (gauge noise)


def parse_table_options(table: Table, fields: dict[str, Any]) -> TableOptions:
    """[lift] keys of the table law: file, angle_unit, lift_unit, smoothing. Reads the CSV now,
    so that every problem with it is reported when the scene loads."""
    for name in UNUSED_KEYS:
        if table.has(name):
            raise table.error(name, "not used by law 'table' (the lift comes from the file); remove it")
    name = table.string("file")
    if not name.strip():
        raise table.error("file", "empty file name")
    path = (data_folder(fields) / name).resolve() if not Path(name).is_absolute() else Path(name)
    angle_unit = table.string("angle_unit", "deg")
    lift_unit = table.string("lift_unit", "mm")
    angle_scale = unit_scale(angle_unit, "angle", file=table.file, key=table.key("angle_unit"))
    lift_scale = unit_scale(lift_unit, "length", file=table.file, key=table.key("lift_unit"))
    if not angle_scale > 0.0:
        raise table.error("angle_unit", f"{echo(angle_unit)} is not a usable angle unit")
    if not lift_scale > 0.0:
        raise table.error("lift_unit", f"{echo(lift_unit)} is not a usable length unit")
    smoothing = table.raw("smoothing", "auto")
    if smoothing == "auto":
        noise = None
    else:
        try:
            noise = table.quantity("smoothing", "length", nonnegative=True)
        except InputError as exc:
            raise table.error("smoothing", f'expected "auto" or the noise level of the lift, such as "0.005 mm": {exc.reason}') from None
    angles, lifts = read_lift_csv(path, angle_scale, lift_scale, file=table.file, key=table.key("file"), noise=noise)
    return TableOptions(
        path=str(path), angles=tuple(angles.tolist()), lifts=tuple(lifts.tolist()), noise=noise,
        angle_unit=angle_unit, lift_unit=lift_unit, dip_allowance=dip_allowance(lifts, noise),
    )


def dip_allowance(lifts, noise: float | None = None) -> float:
    """How far (m) a measured lift may read below the base circle: the gauge's noise, taken as
    NOISE_SHARE of the largest lift or NOISE_SIGMAS times the stated noise level, the larger."""
    peak = float(np.max(lifts)) if np.size(lifts) else 0.0
    return max(NOISE_SHARE * peak, NOISE_SIGMAS * (noise or 0.0), 0.0) + 0.0  # + 0.0: never -0.0


_SEPARATORS = re.compile(r"[,;\s]+")


def read_lift_csv(path, angle_scale: float, lift_scale: float, *, file: str, key: str, noise: float | None = None):
    """(angles in rad, lifts in m) from a two-column text file, or InputError naming the line of the
    first bad row (never its content: the file may be one the user should not see, /etc/shadow)."""
    shown = Path(path).name

    def fail(reason: str) -> InputError:
        return InputError(file, key, f"{shown}: {reason}")

    if not Path(path).exists():
        raise fail(f"file not found ({path})")
    text = read_text(path, file=file, key=key, prefix=f"{shown}: ")
    rows: list[tuple[float, float]] = []
    lines: list[int] = []  # the file's line of each row
    header_allowed = True
    # (line, reason) of the first line that is no row; reading goes on, so that the noise allowance
    # of the range check comes from the whole file, and a bad row before it is reported instead
    unreadable = None
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.strip().lstrip("\ufeff")
        if not line or line.startswith("#"):
            continue
        cells = [c for c in _SEPARATORS.split(line) if c]
        try:
            values = [float(c) for c in cells]
        except ValueError:
            if header_allowed:  # one header line such as "angle_deg,lift_mm"
                header_allowed = False
                continue
            unreadable = unreadable or (number, "cannot read it as two numbers (angle, lift)")
            continue
        header_allowed = False
        if len(values) != 2:
            unreadable = unreadable or (number, f"expected 2 columns (angle, lift), got {len(values)}")
            continue
        rows.append((values[0], values[1]))
        lines.append(number)
        if len(rows) > MAX_ROWS:
            raise fail(f"more than {MAX_ROWS} rows")
    data = np.array(rows, dtype=float).reshape(-1, 2)
    with np.errstate(over="ignore", invalid="ignore"):
        angles, lifts = data[:, 0] * angle_scale, data[:, 1] * lift_scale
    bad = first_out_of_range(angles, lifts, noise)
    if bad is not None and (unreadable is None or lines[bad[0]] < unreadable[0]):
        raise fail(f"line {lines[bad[0]]}: {bad[1]}")
    if unreadable is not None:
        raise fail(f"line {unreadable[0]}: {unreadable[1]}")
    if len(rows) < MIN_SAMPLES:
        raise fail(f"{len(rows)} samples; at least {MIN_SAMPLES} are needed over the revolution")
    steps = np.diff(angles)
    if np.any(steps <= 0.0):
        i = int(np.argmax(steps <= 0.0))
        raise fail(f"line {lines[i + 1]}: angles must increase strictly (this row's angle is not above the one before)")
    span = angles[-1] - angles[0]
    if span >= TWO_PI:
        raise fail(f"angles span {math.degrees(span):.6g} deg; one revolution (< 360 deg) is expected")
    gaps = np.append(steps, TWO_PI - span)
    if math.degrees(gaps.max()) > MAX_GAP_DEG:
        i = int(np.argmax(gaps))
        where = f"after line {lines[i]}" if i < len(steps) else "between the last and the first row (wrap-around)"
        raise fail(
            f"gap of {math.degrees(gaps.max()):.4g} deg {where}; the samples must cover the whole revolution, "
            f"base circle included (gaps up to {MAX_GAP_DEG:g} deg)"
        )
    return angles, lifts


MAX_ANGLE = RANGES["angle"][1]  # rad: ten turns, as any angle of a scene


def first_out_of_range(angles, lifts, noise: float | None = None) -> tuple[int, str] | None:
    """(row index, reason) of the first row outside the physical range (module doc), or None. The
    reason states the range, never the row's values."""
    angles, lifts = np.asarray(angles, dtype=float), np.asarray(lifts, dtype=float)
    floor = -dip_allowance(lifts[np.isfinite(lifts) & (lifts <= MAX_LIFT)], noise)  # rows in range set the peak
    tests = (
        (~(np.isfinite(angles) & np.isfinite(lifts)), "values must be finite numbers (after angle_unit and lift_unit)"),
        (np.abs(np.where(np.isfinite(angles), angles, 0.0)) > MAX_ANGLE,
         f"the angle is outside +-{math.degrees(MAX_ANGLE):g} deg; check angle_unit"),
        (np.where(np.isfinite(lifts), lifts, 0.0) > MAX_LIFT,
         f"a lift above {MAX_LIFT:g} m is outside any valve gear; check lift_unit"),
        (np.where(np.isfinite(lifts), lifts, 0.0) < floor,
         f"the lift is below the base circle by more than {-floor * 1e3:.4g} mm (the lift is measured from the base "
         f"circle, the cam's smallest radius; allowed below it: the gauge's noise, {100 * NOISE_SHARE:g} % of the "
         f"largest lift or {NOISE_SIGMAS:g} times lift.smoothing)"),
    )
    found = [(int(np.argmax(mask)), reason) for mask, reason in tests if np.any(mask)]
    return min(found, key=lambda item: item[0]) if found else None


# --- the periodic penalised spline ------------------------------------------------------------


@dataclass(frozen=True)
class PeriodicSplineFit:
    """A periodic spline over [0, 2 pi) with its exact derivatives, plus how it was fitted."""

    splines: tuple  # scipy BSpline of L and its first three derivatives, periodic extrapolation
    knots: int
    lam: float  # smoothing weight in units of trace(B'B) / trace(P): independent of N and K
    residual_rms: float  # of the fit at the samples, same unit as the data
    effective_dof: float  # trace of the hat matrix
    samples: int

    def derivatives(self, x) -> np.ndarray:
        x = np.mod(np.asarray(x, dtype=float), TWO_PI)
        return np.stack([s(x) for s in self.splines])


def default_knots(samples: int) -> int:
    """Half as many knots as samples, at most one per degree (MAX_KNOTS). With a knot per sample
    the spline could interpolate the noise, and cross-validation degenerates towards that (its
    denominator N - dof vanishes: measured errors of v and p grew tenfold). The penalty, not the
    knot count, decides the smoothness (the P-spline idea); 1 deg resolves any valve event."""
    return int(min(MAX_KNOTS, max(2 * DEGREE, samples // 2)))


def fit_periodic_spline(angles, values, noise: float | None = None, knots: int | None = None) -> PeriodicSplineFit:
    """Fit a periodic quintic P-spline to samples (angles in rad, any order within a revolution).

    noise None: lambda by generalised cross-validation; noise >= 0: lambda such that the residual
    sum of squares equals N noise^2 (the smallest lambda tried, 1e-10, when the data are cleaner:
    then the spline nearly interpolates)."""
    from scipy import linalg, sparse
    from scipy.interpolate import BSpline
    from scipy.optimize import minimize_scalar

    x = np.mod(np.asarray(angles, dtype=float), TWO_PI)
    y = np.asarray(values, dtype=float)
    n = x.size
    K = default_knots(n) if knots is None else int(knots)
    if K < 2 * DEGREE or K > n:
        raise ValueError(f"knots must lie in [{2 * DEGREE}, samples = {n}], got {K}")
    h = TWO_PI / K
    k = DEGREE
    t = h * np.arange(-k, K + k + 1)
    # K + k B-splines on the extended knots; basis j and j + K are the same periodic function
    B = BSpline.design_matrix(x, t, k, extrapolate=False).tocsc()
    fold = sparse.csc_array((np.ones(K + k), (np.arange(K + k), np.arange(K + k) % K)), shape=(K + k, K))
    Bp = (B @ fold).tocsr()
    A = (Bp.T @ Bp).toarray()
    A[np.abs(A) < 1e-15 * A.max()] = 0.0  # B-spline tails ~1e-80: subnormal arithmetic is slow
    Bty = Bp.T @ y
    D = np.zeros((K, K))
    stencil = np.array([-1.0, 3.0, -3.0, 1.0])  # third difference
    for i in range(K):
        D[i, (i + np.arange(PENALTY_ORDER + 1)) % K] = stencil
    P = D.T @ D
    scale = np.trace(A) / np.trace(P)  # makes lambda dimensionless and independent of K and n

    # Demmler-Reinsch form, taken relative to C = A + scale P (definite and well conditioned even
    # where samples leave a basis function uncovered): with C = L L' and L^-1 A L^-T = U diag(mu) U',
    # mu in [0, 1], A + lam scale P = L U diag(mu + lam (1 - mu)) U' L'. Every lambda then costs
    # O(K), and mu is accurate because nothing ill-conditioned was inverted.
    L = linalg.cholesky(A + scale * P, lower=True)
    M = linalg.solve_triangular(L, linalg.solve_triangular(L, A, lower=True).T, lower=True)
    mu, U = linalg.eigh(0.5 * (M + M.T), driver="evd")  # divide and conquer: ~5x faster here than the default
    mu = np.clip(mu, 0.0, 1.0)
    z = U.T @ linalg.solve_triangular(L, Bty, lower=True)
    yy = float(y @ y)

    def rss(lam: float) -> float:
        # |y - B c|^2 = y'y - 2 z' D^-1 z + z' D^-1 diag(mu) D^-1 z,  D = diag(mu + lam (1 - mu))
        d = mu + lam * (1.0 - mu)
        return max(yy - float(np.sum(z * z * (2.0 * d - mu) / (d * d))), 0.0)

    def dof(lam: float) -> float:
        return float(np.sum(mu / (mu + lam * (1.0 - mu))))

    lo, hi = -10.0, 14.0  # log10 lambda: from nearly interpolating to nearly constant
    if noise is None:
        def gcv(log_lam: float) -> float:
            lam = 10.0**log_lam
            return n * rss(lam) / max(n - dof(lam), 1e-300) ** 2

        grid = np.linspace(lo, hi, 97)  # 4 per decade
        values_gcv = [gcv(g) for g in grid]
        i = int(np.argmin(values_gcv))
        a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        best = minimize_scalar(gcv, bounds=(a, b), method="bounded", options={"xatol": 1e-3}).x if b > a else grid[i]
        log_lam = float(best if gcv(best) <= values_gcv[i] else grid[i])
    else:
        target = n * float(noise) ** 2
        if rss(10.0**lo) >= target:
            log_lam = lo
        elif rss(10.0**hi) <= target:
            log_lam = hi
        else:
            log_lam = root_in(lambda g: rss(10.0**g) - target, lo, hi, xtol=1e-6)  # the ends' signs checked above
    lam = 10.0**log_lam

    # coefficients in the same stable form: c = L^-T U D^-1 z
    c = linalg.solve_triangular(L.T, U @ (z / (mu + lam * (1.0 - mu))), lower=False)
    residual = y - Bp @ c
    c_ext = c[np.arange(K + k) % K]
    spline = BSpline(t, c_ext, k, extrapolate="periodic")
    splines = (spline, *(spline.derivative(nu) for nu in (1, 2, 3)))
    return PeriodicSplineFit(
        splines=splines, knots=K, lam=lam, residual_rms=float(np.sqrt(np.mean(residual**2))),
        effective_dof=dof(lam), samples=n,
    )


@dataclass(frozen=True)
class TableLift:
    """LiftCurve of a measured table: the periodic spline, shifted to start at `start`."""

    fit: PeriodicSplineFit
    start: float = 0.0  # rad; table angle 0 sits at this cam angle
    report: Any = None  # summary entries (mapping) added by the kinematics effect
    warnings: tuple[str, ...] = ()
    dip_allowance: float = 0.0  # m below the base circle that is the gauge's noise (explorer.lift.validity)

    def derivatives(self, theta) -> np.ndarray:
        return self.fit.derivatives(np.asarray(theta, dtype=float) - self.start)

    def breakpoints(self) -> np.ndarray:
        return np.zeros(0)  # a quintic spline has continuous L, L', L'', L'''


# a sample's residual beyond this many robust standard deviations is a gross error, not gauge noise:
# Gaussian noise passes it once in ~1e15 samples; the fit's own misfit of a clean table stays below
# 3 (table_demo: 2.7); a 0.05 mm slip in table_demo's 0.005 mm noise is 9
OUTLIER_SIGMAS = 8.0


class GrossErrors(NamedTuple):
    count: int  # samples beyond OUTLIER_SIGMAS robust standard deviations
    worst: float  # m, the largest residual (signed: sample - fit)
    angle: float  # rad, its table angle
    sigma: float  # m, the residuals' robust standard deviation (1.4826 MAD)


def gross_errors(angles, lifts, fit: PeriodicSplineFit) -> GrossErrors:
    """The samples that sit far off the smoothed lift by the residuals' own robust scale (the
    median absolute deviation, which a few gross errors do not inflate as they inflate the rms)."""
    residual = np.asarray(lifts, dtype=float) - fit.derivatives(np.asarray(angles, dtype=float))[0]
    sigma = 1.4826 * float(np.median(np.abs(residual - np.median(residual))))
    i = int(np.argmax(np.abs(residual)))
    count = int(np.count_nonzero(np.abs(residual) > OUTLIER_SIGMAS * sigma)) if sigma > 0.0 else 0
    return GrossErrors(count, float(residual[i]), float(np.asarray(angles, dtype=float)[i]), sigma)


def build_table_lift(scene) -> TableLift:
    options: TableOptions = scene.lift.options
    fit = fit_periodic_spline(np.array(options.angles), np.array(options.lifts), noise=options.noise)
    report = {
        "table_samples": fit.samples,
        "table_knots": fit.knots,
        "table_smoothing_lambda": fit.lam,
        "table_residual_rms_m": fit.residual_rms,
        "table_effective_dof": fit.effective_dof,
    }
    warnings = []
    lifts = np.array(options.lifts)
    peak = float(np.max(np.abs(lifts))) or 1.0
    outliers = gross_errors(np.array(options.angles), lifts, fit)
    report.update(table_max_residual_m=outliers.worst, table_max_residual_angle_deg=math.degrees(outliers.angle))
    if outliers.count:
        warnings.append(
            f"table law: {outliers.count} sample(s) lie more than {OUTLIER_SIGMAS:g} robust standard deviations "
            f"({1e3 * outliers.sigma:.3g} mm) off the smoothed lift, the worst at table angle "
            f"{math.degrees(outliers.angle):.4g} deg by {1e3 * outliers.worst:+.3g} mm: a gross error in the "
            f"table? the smoothing bends the whole curve towards it (effective dof {fit.effective_dof:.3g}); "
            "correct or remove it"
        )
    if fit.residual_rms > 0.05 * peak:
        warnings.append(
            f"table law: the smoothed lift misses the samples by {1e3 * fit.residual_rms:.3g} mm rms "
            f"({100 * fit.residual_rms / peak:.2g} % of the peak); check lift.smoothing"
        )
    lift = TableLift(fit=fit, start=scene.lift.start, report=report, warnings=tuple(warnings),
                     dip_allowance=options.dip_allowance)
    # the smoothed lift is a computed cam: the checks of every cam, with the data's noise allowance
    check_computed(lift, scene.follower, scene.source, "lift.file", f"the smoothed lift of {Path(options.path).name}",
                   "check the measurement's zero (the base circle), lift_unit and lift.smoothing")
    return lift
