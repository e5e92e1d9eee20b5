"""Cam geometry for the rest of the program: contour points for meshes and viewers, and the
pressure-angle / curvature columns of the kinematics effect (with the validity checks of every cam,
explorer.lift.validity: finite, lift range, pressure angle, undercut).

Both work the same way for law-based and contour-based cams: the envelope of the roller over
the lift curve (translating.py). For a contour cam whose lift came from the contour, that
envelope lies on the given contour (tests check it), so there is one code path.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.roots import roots_in
from ..lift.contours.translating import pitch_geometry, translating_profile
from ..lift.curves import TWO_PI, grid_with, lift_rows
from ..lift.validity import cam_fault, entered_error, lift_fault, sample_angles
from ..mechanics.kinematics import ONE_SIDED
from .lift import build_lift


def _profile(scene, lift, n: int):
    """The scene's translating-roller profile at cam angles 0, 2 pi / n, ... (its own lift unless given)."""
    if lift is None:
        lift = build_lift(scene)
    f = scene.follower
    theta = np.arange(int(n)) * (2.0 * math.pi / int(n))
    return translating_profile(lift, theta, f.base_radius, f.roller_radius, f.offset)


def cam_contour(scene, lift=None, n: int = 720) -> np.ndarray:
    """(n, 2) cam-surface points in the cam frame (m), at cam angles 0, 2 pi / n, ...: point i is
    where the roller touches the cam at cam angle theta_i. Order: clockwise around the cam (the
    order the roller meets them). Works for any lift law and for [cam] contours."""
    return _profile(scene, lift, n).contour


def pitch_curve(scene, lift=None, n: int = 720) -> np.ndarray:
    """(n, 2) roller-centre path in the cam frame (m), same sampling as cam_contour."""
    return _profile(scene, lift, n).pitch


def geometry_columns(scene, theta: np.ndarray, d: np.ndarray, dip: float = 0.0, lift=None) -> tuple[dict, dict]:
    """Columns pressure_angle_deg, pitch_radius_m, contour_radius_m (signed: > 0 convex,
    < 0 concave; +-inf where the curve is straight) and their summary; InputError when the cam
    fails a validity check. With the lift curve given, the verdict is lift_fault's, the very check
    of a computed cam (explorer.lift.validity: the law's breakpoints and a fine grid inside each
    stretch between them), so it does not depend on the run's sample grid; without it, cam_fault on
    the samples (dip: how far the lift may go below the base circle, a measured table's noise)."""
    f = scene.follower
    phi, rho = pitch_geometry(d, f.base_radius, f.roller_radius, f.offset)
    if lift is not None:
        fault = lift_fault(lift, f, dip)
    else:
        fault = cam_fault(theta, d, pressure_angle=phi, pitch_radius=rho, roller_radius=f.roller_radius, dip=dip)
    if fault is not None:
        raise entered_error(fault, scene.source)
    contour_radius = rho - f.roller_radius
    columns = {"pressure_angle_deg": np.degrees(phi), "pitch_radius_m": rho, "contour_radius_m": contour_radius}
    if lift is not None:  # the exact extremes (geometry_extremes), the run's samples among them
        x, p, r = geometry_extremes(lift, f)
        theta, phi, rho = np.concatenate([theta, x]), np.concatenate([phi, p]), np.concatenate([rho, r])
    # where: the earliest angle of the largest |phi| (a symmetric rise and return tie to rounding)
    top = np.abs(phi)
    at = np.mod(theta, TWO_PI)
    k = int(np.argmin(np.where(top >= top.max() * (1.0 - 1e-12), at, np.inf)))
    convex = rho > 0.0
    summary = {
        "max_abs_pressure_angle_deg": float(abs(math.degrees(phi[k]))),
        "max_abs_pressure_angle_at_deg": float(math.degrees(at[k])),
        "min_convex_pitch_radius_m": float(rho[convex].min()) if np.any(convex) else None,
        "min_convex_contour_radius_m": float(rho[convex].min() - f.roller_radius) if np.any(convex) else None,
        "min_concave_contour_radius_m": float(f.roller_radius - rho[~convex].max()) if np.any(~convex) else None,
    }
    return columns, summary


def _rate_terms(d, y0: float, e: float):
    """The two terms whose differences are the rates of d(phi)/d(theta) and d(rho)/d(theta) of the
    translating roller's pitch curve, and the curvature's numerator C (rho = N^1.5 / C,
    N = y^2 + (s1 - e)^2, y = y0 + s; C > 0 convex), from the lift's rows s, s1, s2, s3
    (derivatives per radian): tan(phi) = (s1 - e) / y, so phi' = (s2 y - (s1 - e) s1) / N;
    rho' = N^0.5 (1.5 N' C - N C') / C^2 with N' = 2 y s1 + 2 (s1 - e) s2,
    C = (s1 - e)(2 s1 - e) - y (s2 - y), C' = 3 (s1 - e) s2 + 2 y s1 - y s3."""
    y = y0 + d[0]
    ty = d[1] - e
    n = y * y + ty * ty
    c = ty * (2.0 * d[1] - e) - y * (d[2] - y)
    dn = 2.0 * y * d[1] + 2.0 * ty * d[2]
    dc = 3.0 * ty * d[2] + 2.0 * y * d[1] - y * d[3]
    return (d[2] * y, ty * d[1]), (1.5 * dn * c, n * dc), c


def _rates(d, y0: float, e: float):
    """Signs of d(phi)/d(theta) and d(rho)/d(theta), and C (see _rate_terms)."""
    (p1, p2), (r1, r2), c = _rate_terms(d, y0, e)
    return p1 - p2, r1 - r2, c


# A sign change of a rate whose size at both ends of its bracket is below this fraction of its
# terms' size is rounding on a stretch where the figure is constant (a circular arc's pitch
# radius: Schenker Fig. 2 has 1599 such brackets, their rates 6e-17 .. 1.5e-13 of their terms;
# the true extrema of every built-in cam have 5e-3 or more). The figure's samples there already
# hold its value to rounding, so no root is searched (1599 Brent searches cost 2 s a run).
RATE_ROUNDING = 1e-10


def geometry_extremes(lift, follower) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angles (rad), pressure angles (rad) and signed pitch-curve radii (m) of a translating
    roller's cam where its extremes can be, so that the summary's largest pressure angle and
    smallest radii are exact rather than sampled (as valve_extremes does for the valve's peaks):
    lift_fault's angles (7200, the breakpoints, 256 inside every stretch between them), the
    one-sided limits at the breakpoints (s2 may jump there: the supremum is a limit), and every zero
    of phi' or rho' between two of them (Brent, bounded, on the closed-form derivatives; not across
    a breakpoint, nor where rho passes infinity, nor where a rate is rounding at both ends:
    RATE_ROUNDING). An extremum hidden between two of those angles
    with two sign changes of its rate is not seen."""
    f = follower
    rp = f.base_radius + f.roller_radius
    e = f.offset
    y0 = math.sqrt(rp * rp - e * e)
    rows = (0, 1, 2, 3)
    marks = np.unique(np.mod(np.asarray(lift.breakpoints(), dtype=float).reshape(-1), TWO_PI))
    # np.unique of them all, the same floats (grid_with: the few one-sided angles merged in, no sort)
    angles = grid_with(sample_angles(lift), np.concatenate([np.mod(marks - ONE_SIDED, TWO_PI), marks + ONE_SIDED]))
    angles = np.append(angles, angles[0] + TWO_PI)  # closed round the revolution
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        d = lift_rows(lift, angles, rows)
        (p1, p2), (r1, r2), c = _rate_terms(d, y0, e)
        # each rate with the size of its two terms: a rate far below that is their rounding, not a slope
        rate_phi, rate_rho = p1 - p2, r1 - r2
        scale_phi, scale_rho = np.abs(p1) + np.abs(p2), np.abs(r1) + np.abs(r2)
    # a bracket no wider than a breakpoint's two one-sided angles spans a jump, not a zero
    wide = np.diff(angles) > 4.0 * ONE_SIDED
    brackets, which, lows, highs = [], [], [], []
    for k, rate, scale in ((0, rate_phi, scale_phi), (1, rate_rho, scale_rho)):
        flat = np.abs(rate) <= RATE_ROUNDING * scale
        change = wide & (np.sign(rate[:-1]) * np.sign(rate[1:]) < 0.0) & ~(flat[:-1] & flat[1:])
        if k == 1:  # rho passes infinity where C changes sign: no extremum of rho there
            change &= np.sign(c[:-1]) * np.sign(c[1:]) > 0.0
        at = np.nonzero(change)[0]
        brackets.append(at)
        which.append(np.full(at.size, k))
        lows.append(rate[at])
        highs.append(rate[at + 1])
    at, which = np.concatenate(brackets), np.concatenate(which)

    def rates(th, i):  # the rate of each point's search (phi' or rho'), element by element
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            phi_rate, rho_rate = _rates(lift_rows(lift, th, rows), y0, e)[:2]
        return np.where(which[i] == 0, phi_rate, rho_rate)

    # all searches at once (roots_in: each root the float of its own root_in, one call of the lift per step)
    found = roots_in(rates, angles[at], angles[at + 1], fa=np.concatenate(lows), fb=np.concatenate(highs),
                     xtol=1e-15, maxiter=200)
    found = np.asarray(found, dtype=float)
    x = np.concatenate([angles[:-1], found])
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        # the angles' rows are d's (the lift's value at an angle does not depend on the call's others)
        phi, rho = pitch_geometry(np.concatenate([d[:, :-1], lift_rows(lift, found, rows)], axis=1),
                                  f.base_radius, f.roller_radius, e)
    return x, phi, rho
