"""Translating roller follower: pitch curve, exact cam contour (envelope of the roller), pressure
angle and radii of curvature, all in closed form from the analytic lift derivatives.

Conventions: the cam turns by theta (counter-clockwise, omega > 0) about the origin. The follower
axis is parallel to y, offset by e in x; the roller centre sits at q = (e, y0 + L) in the ground
frame, y0 = sqrt(Rp^2 - e^2), Rp = base_radius + roller_radius (the prime circle). In the cam frame
the roller centre is P = R(-theta) q. With L', L'' per radian, the local tangent and second
derivative are T = (y, L' - e) and B = (2 L' - e, L'' - y), y = y0 + L, so
  rho_pitch = |T|^3 / ((L' - e)(2 L' - e) - y (L'' - y))    (> 0 convex, < 0 concave)
  tan(phi)  = (L' - e) / y                                    (pressure angle)
and the contour is the roller centre moved by the roller radius along the contact normal,
n = (e - L', y)/|T|, towards the cam. This is the envelope of the roller circle, not the radial
development of the lift (Schenker 1902 stresses the difference).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.errors import InputError


@dataclass(frozen=True)
class Profile:
    theta: np.ndarray  # rad, cam angle of each sample
    pitch: np.ndarray  # (N, 2) roller-centre path in the cam frame, m
    contour: np.ndarray  # (N, 2) cam surface in the cam frame, m
    contact_local: np.ndarray  # (N, 2) contact point in the ground frame at that cam angle, m
    pressure_angle: np.ndarray  # rad, between contact normal and follower axis (signed)
    pitch_radius: np.ndarray  # m, signed radius of curvature of the pitch curve (> 0 convex)
    contour_radius: np.ndarray  # m, pitch_radius - roller_radius (> 0 convex, < 0 concave)


def rotate_to_cam(theta: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Ground-frame points (N, 2) at cam angles theta -> cam frame (rotation by -theta)."""
    c, s = np.cos(theta), np.sin(theta)
    x, y = xy[:, 0], xy[:, 1]
    return np.column_stack([c * x + s * y, -s * x + c * y])


def translating_profile(lift, theta, base_radius: float, roller_radius: float, offset: float = 0.0) -> Profile:
    theta = np.asarray(theta, dtype=float)
    d = lift.derivatives(theta)
    return profile_from_derivatives(theta, d, base_radius, roller_radius, offset)


def profile_from_derivatives(theta, d, base_radius: float, roller_radius: float, offset: float) -> Profile:
    e = offset
    rp = base_radius + roller_radius
    y0 = math.sqrt(rp * rp - e * e)
    y = y0 + d[0]
    tx, ty = y, d[1] - e
    norm_t = np.hypot(tx, ty)
    cross = ty * (2.0 * d[1] - e) - y * (d[2] - y)
    with np.errstate(divide="ignore"):
        pitch_radius = norm_t**3 / cross
    nx, ny = -ty / norm_t, tx / norm_t  # outward unit normal (away from the cam)
    centre = np.column_stack([np.full_like(y, e), y])
    contact = centre - roller_radius * np.column_stack([nx, ny])
    return Profile(
        theta=theta,
        pitch=rotate_to_cam(theta, centre),
        contour=rotate_to_cam(theta, contact),
        contact_local=contact,
        pressure_angle=np.arctan2(ty, tx),
        pitch_radius=pitch_radius,
        contour_radius=pitch_radius - roller_radius,
    )


def pitch_geometry(d, base_radius: float, roller_radius: float, offset: float = 0.0):
    """Pressure angle (rad) and signed pitch-curve radius (m) only: the same closed forms as
    profile_from_derivatives without the contour points, cheap enough for every simulation."""
    e = offset
    rp = base_radius + roller_radius
    y = math.sqrt(rp * rp - e * e) + d[0]
    ty = d[1] - e
    cross = ty * (2.0 * d[1] - e) - y * (d[2] - y)
    with np.errstate(divide="ignore", invalid="ignore"):
        pitch_radius = (y * y + ty * ty) ** 1.5 / cross
    return np.arctan2(ty, y), pitch_radius


def find_undercut(pitch_radius: np.ndarray, roller_radius: float) -> int | None:
    """Index of the worst sample where a convex stretch of the pitch curve is sharper than the
    roller (radius <= roller radius, including a cusp, radius 0), or None."""
    bad = (pitch_radius > 0.0) & (pitch_radius <= roller_radius)
    if not np.any(bad):
        return None
    return int(np.argmin(np.where(bad, pitch_radius, np.inf)))


def undercut_error(theta: float, pitch_radius: float, roller_radius: float, file: str,
                   key: str = "follower.roller_radius") -> InputError:
    return InputError(
        file,
        key,
        f"undercut: roller radius {roller_radius * 1e3:.4g} mm exceeds the convex pitch-curve radius "
        f"{pitch_radius * 1e3:.4g} mm at cam angle {math.degrees(theta):.3f} deg "
        f"(reduce the roller, enlarge the base circle or lengthen the event)",
    )


def check_undercut(profile: Profile, roller_radius: float, file: str, key: str = "follower.roller_radius") -> None:
    """Undercut: a convex stretch of the pitch curve sharper than the roller (the envelope folds
    into a cusp and the cam cannot be made). Raises InputError naming the worst cam angle."""
    i = find_undercut(profile.pitch_radius, roller_radius)
    if i is not None:
        raise undercut_error(float(profile.theta[i]), float(profile.pitch_radius[i]), roller_radius, file, key)
