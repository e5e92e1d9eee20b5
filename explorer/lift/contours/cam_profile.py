"""The cam to make, as the exports see it (point table, DXF, STL/GLB, grinding table): a CamProfile
gives the contour, the pitch curve (the follower's reference point), the outward normal and the
curvatures at any cam angle, in closed form from the lift's analytic derivatives.

A gear that has a cam to make returns one from its `cam_profile` (explorer.gears.base.Gear, item
9). TranslatingCam is the translating roller's (the closed forms of
explorer.lift.contours.translating, with the follower's base circle, roller and offset).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class CamGeometry:
    """Closed-form geometry at cam angles theta (cam frame, metres; normals outward, unit)."""

    theta: np.ndarray
    pitch: np.ndarray  # (N, 2) centre path (CutFor): a roller's centre, a crowned face's; flat face: the contour
    contour: np.ndarray  # (N, 2) contact point on the cam
    normal: np.ndarray  # (N, 2) outward contact normal
    pitch_curvature: np.ndarray  # 1/m, of the centre path, > 0 convex, 0 straight
    contour_curvature: np.ndarray  # 1/m, > 0 convex
    pressure_angle: np.ndarray  # rad


def geometry(lift, theta, base_radius: float, roller_radius: float, offset: float) -> CamGeometry:
    """The pitch curve, contour, normal and curvatures at `theta` (see geometry.translating for
    the closed forms; curvature = 1/radius keeps straight stretches finite)."""
    theta = np.asarray(theta, dtype=float)
    d = lift.derivatives(theta)
    e = offset
    y0 = math.sqrt((base_radius + roller_radius) ** 2 - e * e)
    y = y0 + d[0]
    tx, ty = y, d[1] - e
    norm_t = np.hypot(tx, ty)
    cross = ty * (2.0 * d[1] - e) - y * (d[2] - y)
    pitch_curvature = cross / norm_t**3
    with np.errstate(divide="ignore", invalid="ignore"):
        # 1/(rho - r) = k / (1 - r k): finite wherever the contour is not a cusp (undercut is refused)
        contour_curvature = pitch_curvature / (1.0 - roller_radius * pitch_curvature)
    nx, ny = -ty / norm_t, tx / norm_t
    c, s = np.cos(theta), np.sin(theta)

    def to_cam(x, yy):
        return np.column_stack([c * x + s * yy, -s * x + c * yy])

    centre_x = np.full_like(y, e)
    return CamGeometry(
        theta=theta,
        pitch=to_cam(centre_x, y),
        contour=to_cam(centre_x - roller_radius * nx, y - roller_radius * ny),
        normal=to_cam(nx, ny),
        pitch_curvature=pitch_curvature,
        contour_curvature=contour_curvature,
        pressure_angle=np.arctan2(ty, tx),
    )


def angles_with(uniform: int, breakpoints) -> np.ndarray:
    """`uniform` equally spaced cam angles in [0, 2 pi) and the breakpoints, sorted, without
    near-copies: a breakpoint computed as start + knot and the grid angle k 2 pi / n that it
    equals differ by an ulp, and two points one ulp apart make a zero chord and a zero step."""
    theta = np.sort(np.concatenate([np.linspace(0.0, TWO_PI, uniform, endpoint=False),
                                    np.mod(np.asarray(breakpoints, dtype=float), TWO_PI)]))
    keep = np.append(True, np.diff(theta) > 1e-12)
    theta = theta[keep]
    if theta.size > 1 and theta[-1] > TWO_PI - 1e-12:  # the same as angle 0
        theta = theta[:-1]
    return theta


@dataclass(frozen=True)
class CutFor:
    """The follower a contour is cut for. A cam is cut for its own follower: the same contour read
    by another follower gives another lift (a 3 m crowned bucket's cam read by a flat tappet lifts
    more, by e^2 / (2 R) at a contact offset e: the crown's sag there), so every exported file names it.

    surface: "roller" (radius: the roller's) or "face" (a sliding face, pad or lifter face; radius:
    its crown's, inf for a flat face). The centre path CamGeometry.pitch is the centre of the
    follower's curvature at the contact, contour + radius * normal: a roller's centre (the pitch
    curve), a crowned face's or pad's centre; a flat face has none (pitch is then the contour)."""

    follower: str  # the scene's follower.type
    surface: str  # "roller" | "face"
    radius: float  # m; inf: a flat face

    @property
    def centre_path(self) -> str | None:
        """The exports' name of the centre path: "pitch" (a roller's centre), "face_centre" (a
        crowned face's or curved pad's centre of curvature), None (a flat face: no centre)."""
        if self.surface == "roller":
            return "pitch"
        return "face_centre" if math.isfinite(self.radius) else None

    def describe(self) -> str:
        """One line for a file's header: the follower type, its surface and radius in mm."""
        if self.surface == "roller":
            what = f"roller of radius {self.radius * 1e3:.9g} mm"
        elif math.isfinite(self.radius):
            what = f"crowned (curved) face of radius {self.radius * 1e3:.9g} mm"
        else:
            what = "flat face"
        return f"{self.follower}, {what}"


class CamProfile(Protocol):
    """What an export needs of a cam: its geometry at cam angles, the angles where it may have a
    corner (the lift's breakpoints, in [0, 2 pi)), the scene's name and file (for the files' headers)
    and the follower it is cut for."""

    name: str
    source: str
    cut_for: CutFor

    def at(self, theta) -> CamGeometry: ...

    def breakpoints(self) -> np.ndarray: ...


@dataclass(frozen=True)
class TranslatingCam:
    """The cam of a translating (roller) follower: its lift curve and follower geometry."""

    lift: object
    base_radius: float
    roller_radius: float
    offset: float
    name: str
    source: str

    follower: str = "translating roller follower"  # the scene's follower.type (the gear passes it)

    @property
    def cut_for(self) -> CutFor:
        return CutFor(self.follower, "roller", self.roller_radius)

    def at(self, theta) -> CamGeometry:
        return geometry(self.lift, theta, self.base_radius, self.roller_radius, self.offset)

    def breakpoints(self) -> np.ndarray:
        return np.mod(np.asarray(self.lift.breakpoints(), dtype=float), TWO_PI)
