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

from ..lift.contours.translating import pitch_geometry, translating_profile
from ..lift.validity import cam_fault, entered_error, lift_fault
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
    phi_deg = np.degrees(phi)
    k = int(np.argmax(np.abs(phi_deg)))
    convex = rho > 0.0
    summary = {
        "max_abs_pressure_angle_deg": float(abs(phi_deg[k])),
        "max_abs_pressure_angle_at_deg": float(math.degrees(theta[k])),
        "min_convex_pitch_radius_m": float(rho[convex].min()) if np.any(convex) else None,
        "min_convex_contour_radius_m": float(contour_radius[convex].min()) if np.any(convex) else None,
        "min_concave_contour_radius_m": float(-contour_radius[~convex].max()) if np.any(~convex) else None,
    }
    columns = {"pressure_angle_deg": phi_deg, "pitch_radius_m": rho, "contour_radius_m": contour_radius}
    return columns, summary
