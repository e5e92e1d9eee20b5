"""`acceleration` law: a lift defined by its acceleration curve, integrated exactly.

Schenker (1902): "if the acceleration is given, v and s follow by integration". The scene gives
points (cam angle since `start`, acceleration) over the event; between points the acceleration
is linear (`interpolation = "linear"`, the default) or held constant until the next point
(`"step"`, the last point's value then only marks the end). Outside the event the follower
rests on the base circle.

Units: `angle_unit` (default deg) for the angles; `acceleration_unit` either a time-based
acceleration (default m/s**2), taken at `reference_rpm` (default: the drive.rpm the scene
file was written with, Drive.cam_omega) and converted with L'' = a / w_ref^2, or a lift per angle
squared such as mm/deg**2. Either way the cam is fixed once the file is read: running it at
another speed (--set drive.rpm, a sweep, the browser) does not reshape it.

The acceleration is a scipy PPoly; its second antiderivative is the lift, so L, L', L'', L'''
are exact piecewise polynomials (no quadrature, no finite differences). A valve gear must end
the event at rest on the seat: the closure checks

    integral of p dt over the event = 0      (v returns to zero)
    integral of v dt over the event = 0      (s returns to zero: the lift closes)

are reported in the summary with the areas of the acceleration curve above and below zero, which
must be equal (seed 004). A residual above CLOSURE_WARN (relative to the peak velocity or lift)
gives a warning, above CLOSURE_ERROR the scene is rejected. So is a lift that dips below the
base circle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.errors import InputError, echo
from ..core.reader import Table
from ..core.units import plain_number, registry, short_repr, unit_scale
from .validity import MAX_LIFT, check_computed  # MAX_LIFT: a bigger result means wrong units; it guards overflow

TWO_PI = 2.0 * math.pi
INTERPOLATIONS = ("linear", "step")
CLOSURE_WARN = 1e-6  # relative residual: rounding of hand-typed points beyond ~6 digits
CLOSURE_ERROR = 1e-2  # relative residual: the curve does not describe a closed event
UNUSED_KEYS = ("height", "rise", "dwell", "return", "return_law")
ANGLE_UNITS = {"radian", "degree", "turn", "revolution", "arcminute", "arcsecond", "gradian", "milliradian"}


@dataclass(frozen=True)
class AccelerationOptions:
    angles: tuple[float, ...]  # rad since `start`; first 0, strictly increasing, last = event end
    values: tuple[float, ...]  # L'' in m/rad^2 (converted from the scene's unit)
    interpolation: str = "linear"
    acceleration_unit: str = "m/s**2"
    reference_rpm: float | None = None  # rev/min for time-based units, None for per-angle units


def parse_acceleration_options(table: Table, fields: dict[str, Any]) -> AccelerationOptions:
    """[lift] keys of the acceleration law: points, angle_unit, acceleration_unit, interpolation,
    reference_rpm. Integrates the curve once so that a curve that does not close fails at load."""
    for name in UNUSED_KEYS:
        if table.has(name):
            raise table.error(name, "not used by law 'acceleration' (the lift follows from the points); remove it")
    angle_unit = table.string("angle_unit", "deg")
    angle_scale = unit_scale(angle_unit, "angle", file=table.file, key=table.key("angle_unit"))
    if not angle_scale > 0.0:
        raise table.error("angle_unit", f"{echo(angle_unit)} is not a usable angle unit")
    unit = table.string("acceleration_unit", "m/s**2")
    scale, time_based = _acceleration_scale(table, unit)
    reference_rpm = None
    if time_based:
        if table.has("reference_rpm"):
            omega_ref = table.quantity("reference_rpm", "speed", positive=True)
        else:
            omega_ref = fields["drive"].cam_omega
        scale /= omega_ref**2  # a = w^2 L''  ->  L'' = a / w^2
        reference_rpm = omega_ref * 60.0 / TWO_PI
    elif table.has("reference_rpm"):
        raise table.error("reference_rpm", f"only used with a time-based acceleration_unit, not {echo(unit)}")
    interpolation = table.string("interpolation", "linear", choices=INTERPOLATIONS)
    angles, values = _read_points(table, angle_scale, scale)
    options = AccelerationOptions(
        angles=tuple(angles.tolist()), values=tuple(values.tolist()), interpolation=interpolation,
        acceleration_unit=unit, reference_rpm=reference_rpm,
    )
    check = closure_of_points(angles, values, interpolation)  # numpy only: loading needs no scipy
    where = table.key("points")
    if not all(math.isfinite(v) for v in (check.end_velocity, check.end_lift, check.peak_velocity, check.peak_lift)):
        raise InputError(table.file, where, "the accelerations are too large: the integrated lift overflows")
    if check.peak_lift > MAX_LIFT:
        raise InputError(table.file, where, f"the curve lifts {check.peak_lift:.4g} m (more than {MAX_LIFT:g} m): check acceleration_unit and reference_rpm")
    if check.peak_lift <= 0.0:
        raise InputError(table.file, where, "the acceleration curve gives no lift above the base circle")
    if check.worst > CLOSURE_ERROR:
        raise InputError(table.file, where, f"the curve does not close: {check.describe()} (limit {CLOSURE_ERROR:.0%})")
    return options


def _acceleration_scale(table: Table, unit: str) -> tuple[float, bool]:
    """SI factor of `unit` and whether it is per time squared (True) or per angle squared."""
    key = table.key("acceleration_unit")
    try:
        return unit_scale(unit, "acceleration", file=table.file, key=key), True
    except InputError:
        pass
    try:
        scale = unit_scale(unit, "length", file=table.file, key=key)
    except InputError:
        raise table.error(
            "acceleration_unit",
            f"{echo(unit)} is neither an acceleration (such as m/s**2) nor a lift per angle squared (such as mm/deg**2)",
        ) from None
    # pint treats angles as dimensionless, so mm/deg and mm would pass as lengths: insist on
    # exactly angle**-2 to catch a missing square.

    exponent = sum(p for name, p in registry().parse_units(unit)._units.items() if name in ANGLE_UNITS)
    if exponent != -2:
        raise table.error("acceleration_unit", f"{echo(unit)}: a lift per angle must be per angle squared, such as mm/deg**2")
    return scale, False


def _read_points(table: Table, angle_scale: float, value_scale: float) -> tuple[np.ndarray, np.ndarray]:
    raw = table.raw("points")
    if not isinstance(raw, list) or len(raw) < 2:
        raise table.error("points", "expected a list of at least two [angle, acceleration] pairs")
    rows = []
    for i, pair in enumerate(raw):
        ok = (
            isinstance(pair, list) and len(pair) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in pair)
        )
        if not ok:
            raise table.error("points", f"point {i + 1}: expected [angle, acceleration] as two plain numbers, got {short_repr(pair)}")
        try:  # float() of a 400-digit int raises OverflowError
            values = [plain_number(v, file=table.file, key=table.key("points")) for v in pair]
        except InputError as exc:
            raise table.error("points", f"point {i + 1}: {exc.reason}") from None
        rows.append((values[0], values[1]))
    data = np.array(rows)
    if data[0, 0] != 0.0:
        raise table.error("points", f"the first point must be at angle 0 (the event starts at lift.start), got {data[0, 0]:g}")
    steps = np.diff(data[:, 0])
    if np.any(steps <= 0.0):
        i = int(np.argmax(steps <= 0.0))
        raise table.error("points", f"angles must increase strictly: point {i + 2} ({data[i + 1, 0]:g}) follows {data[i, 0]:g}")
    angles = data[:, 0] * angle_scale
    if np.any(np.diff(angles) <= 0.0):  # spacings so small that they vanish in radians
        raise table.error("points", "angles lie too close together to be told apart")
    if angles[-1] > TWO_PI * (1.0 + 1e-12):
        raise table.error("points", f"the event spans {math.degrees(angles[-1]):.6g} deg, more than 360 deg")
    values = data[:, 1] * value_scale
    if not np.all(np.isfinite(values)):
        raise table.error("points", "accelerations overflow after unit conversion")
    return angles, values


@dataclass(frozen=True)
class ClosureCheck:
    """Closure of the event in angle units (L' in m/rad, L in m); see `report` for time units."""

    end_velocity: float  # L'(end) = integral of L'' over the event
    end_lift: float  # L(end) = integral of L' over the event
    area_above: float  # integral of max(L'', 0)
    area_below: float  # integral of min(L'', 0), <= 0
    peak_velocity: float  # max |L'|
    peak_lift: float  # max L
    min_lift: float  # min L (a dip below the base circle is < 0)

    @property
    def relative_velocity(self) -> float:
        return abs(self.end_velocity) / self.peak_velocity if self.peak_velocity > 0 else 0.0

    @property
    def relative_lift(self) -> float:
        return abs(self.end_lift) / self.peak_lift if self.peak_lift > 0 else 0.0

    @property
    def relative_dip(self) -> float:
        return max(0.0, -self.min_lift) / self.peak_lift if self.peak_lift > 0 else 0.0

    @property
    def worst(self) -> float:
        return max(self.relative_velocity, self.relative_lift, self.relative_dip)

    def describe(self) -> str:
        return (
            f"velocity at the end {self.relative_velocity:.3g} of its peak, lift at the end "
            f"{self.relative_lift:.3g} of the peak lift, dip below the base circle {self.relative_dip:.3g} of the peak lift"
        )


def closure_of_points(angles, values, interpolation: str = "linear") -> ClosureCheck:
    """See _closure_of_points. Absurd inputs (hypothesis tries them) may overflow to inf; the
    non-finite result is refused by the caller with an InputError, so numpy need not warn."""
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        return _closure_of_points(angles, values, interpolation)


def _closure_of_points(angles, values, interpolation: str = "linear") -> ClosureCheck:
    """The closure check in closed form, piece by piece (numpy only, used when a scene loads;
    AccelerationLift.closure_check computes the same from the PPoly antiderivatives). On a piece
    of width w with end accelerations a0, a1 (a1 = a0 for steps) and k = (a1 - a0)/w:
    v = v0 + a0 x + k x^2/2, s = s0 + v0 x + a0 x^2/2 + k x^3/6."""
    x = np.asarray(angles, dtype=float)
    a = np.asarray(values, dtype=float)
    w = np.diff(x)
    a0 = a[:-1]
    a1 = a[1:] if interpolation == "linear" else a0
    k = (a1 - a0) / w
    v = np.concatenate([[0.0], np.cumsum(w * (a0 + a1) / 2.0)])
    s = np.concatenate([[0.0], np.cumsum(v[:-1] * w + w * w * (2.0 * a0 + a1) / 6.0)])
    v0, s0 = v[:-1], s[:-1]

    def inside(r):
        return np.isfinite(r) & (r > 0.0) & (r < w)

    with np.errstate(divide="ignore", invalid="ignore"):
        # velocity extrema where a = 0 inside a piece; lift extrema where v = 0 inside a piece
        xa = np.where(k != 0.0, -a0 / k, np.nan)
        disc = np.sqrt(a0 * a0 - 2.0 * k * v0)
        roots = [np.where(k != 0.0, (-a0 + disc) / k, np.where(a0 != 0.0, -v0 / a0, np.nan)),
                 np.where(k != 0.0, (-a0 - disc) / k, np.nan)]
    v_extra = [v0[inside(xa)] + a0[inside(xa)] * xa[inside(xa)] + k[inside(xa)] * xa[inside(xa)] ** 2 / 2.0]
    s_extra = []
    for r in roots:
        m = inside(r)
        rr = r[m]
        s_extra.append(s0[m] + v0[m] * rr + a0[m] * rr**2 / 2.0 + k[m] * rr**3 / 6.0)
    v_all = np.concatenate([v, *v_extra])
    s_all = np.concatenate([s, *s_extra])
    # areas of a above and below zero, linear pieces split where they cross zero
    crossing = (a0 * a1 < 0.0) & (k != 0.0)
    xr = np.where(crossing, -a0 / np.where(k != 0.0, k, 1.0), w)
    first = a0 * xr / 2.0 if interpolation == "linear" else a0 * w
    first = np.where(crossing | (interpolation != "linear"), first, w * (a0 + a1) / 2.0)
    second = np.where(crossing, a1 * (w - xr) / 2.0, 0.0)
    parts = np.concatenate([first, second])
    return ClosureCheck(
        end_velocity=float(v[-1]), end_lift=float(s[-1]),
        area_above=float(parts[parts > 0].sum()), area_below=float(parts[parts < 0].sum()),
        peak_velocity=float(np.abs(v_all).max()), peak_lift=float(s_all.max()), min_lift=float(s_all.min()),
    )


@dataclass(frozen=True)
class AccelerationLift:
    """LiftCurve from piecewise-polynomial L'' over [start, start + span), base circle elsewhere."""

    lift_poly: Any  # scipy PPoly of L(x), x = theta - start in [0, span]
    derivative_polys: tuple  # PPolys of L', L'', L'''
    start: float
    span: float
    omega: float | None = None  # rad/s for the report in time units (the scene's speed)

    @staticmethod
    def from_options(options: AccelerationOptions, start: float, omega: float | None = None) -> "AccelerationLift":
        from scipy.interpolate import PPoly

        x = np.asarray(options.angles, dtype=float)
        a = np.asarray(options.values, dtype=float)
        width = np.diff(x)
        if options.interpolation == "linear":
            coefficients = np.vstack([np.diff(a) / width, a[:-1]])  # local power basis, highest first
        else:
            coefficients = a[:-1][np.newaxis, :]
        accel = PPoly(coefficients, x, extrapolate=False)
        lift = accel.antiderivative(2)  # L(0) = L'(0) = 0, continuous L and L' at every point
        derivs = (lift.derivative(1), accel, accel.derivative(1))
        return AccelerationLift(lift_poly=lift, derivative_polys=derivs, start=float(start), span=float(x[-1]), omega=omega)

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        x = np.mod(theta - self.start, TWO_PI)
        out = np.zeros((4,) + x.shape)
        inside = x < self.span
        if np.any(inside):
            xi = x[inside]
            out[0][inside] = self.lift_poly(xi)
            for k, poly in enumerate(self.derivative_polys, start=1):
                out[k][inside] = poly(xi)
        return out

    def breakpoints(self) -> np.ndarray:
        return np.unique(np.mod(self.start + self.lift_poly.x, TWO_PI))

    def closure_check(self) -> ClosureCheck:
        x = self.lift_poly.x
        velocity, accel = self.derivative_polys[0], self.derivative_polys[1]
        above, below = _signed_areas(accel)
        # extrema of the piecewise polynomials: at the points and at the roots of their derivatives
        candidates_v = np.concatenate([x, _roots(accel)])
        candidates_s = np.concatenate([x, _roots(velocity)])
        lift_values = self.lift_poly(candidates_s)
        return ClosureCheck(
            end_velocity=float(velocity(x[-1])),
            end_lift=float(self.lift_poly(x[-1])),
            area_above=above,
            area_below=below,
            peak_velocity=float(np.max(np.abs(velocity(candidates_v)))),
            peak_lift=float(np.max(lift_values)),
            min_lift=float(np.min(lift_values)),
        )

    @property
    def report(self) -> dict[str, float]:
        """Summary entries: the closure checks in time units at the scene's speed."""
        c = self.closure_check()
        w = self.omega if self.omega is not None else float("nan")
        return {
            # integral p dt = w * integral L'' d(theta); integral v dt = integral L' d(theta)
            "closure_integral_p_dt_m_s": w * c.end_velocity,
            "closure_integral_v_dt_m": c.end_lift,
            "acceleration_area_above_m_s": w * c.area_above,
            "acceleration_area_below_m_s": w * c.area_below,
            "closure_relative_error": c.worst,
            "acceleration_law_peak_lift_m": c.peak_lift,
            "acceleration_law_event_deg": math.degrees(self.span),
        }

    @property
    def dip_allowance(self) -> float:
        """m below the base circle that the closure check allows (CLOSURE_ERROR of the peak lift):
        the validity checks of every cam (explorer.lift.validity) take the same allowance."""
        return CLOSURE_ERROR * max(self.closure_check().peak_lift, 0.0)

    @property
    def warnings(self) -> tuple[str, ...]:
        c = self.closure_check()
        if c.worst > CLOSURE_WARN:
            return (f"acceleration law does not close exactly: {c.describe()}",)
        return ()


def _roots(poly) -> np.ndarray:
    roots = poly.roots(discontinuity=False, extrapolate=False)
    return roots[np.isfinite(roots)]


def _signed_areas(accel) -> tuple[float, float]:
    """Exact integrals of the positive and negative parts of a piecewise polynomial: split every
    piece at its roots and integrate the pieces of constant sign."""
    x = accel.x
    cuts = np.unique(np.concatenate([x, _roots(accel)]))
    integral = accel.antiderivative(1)
    pieces = integral(cuts[1:]) - integral(cuts[:-1])
    signs = accel(0.5 * (cuts[1:] + cuts[:-1]))
    return float(np.sum(pieces[signs > 0])), float(np.sum(pieces[signs < 0]))


def build_acceleration_lift(scene) -> AccelerationLift:
    lift = AccelerationLift.from_options(scene.lift.options, scene.lift.start, omega=scene.drive.omega)
    # the integrated lift is a computed cam: the checks of every cam (explorer.lift.validity)
    check_computed(lift, scene.follower, scene.source, "lift.points", "the lift integrated from these accelerations",
                   "check acceleration_unit, reference_rpm and the points, or enlarge the base circle")
    return lift
