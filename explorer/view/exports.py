"""Exports to make the cam: point table, DXF drawing, STL/GLB solid, grinding table.

All four come from the same closed forms as the kinematics (explorer.lift.contours.translating): the
roller centre (pitch curve) and the contact point with the roller (cam contour) at cam angle
theta, the contact normal and the signed radii of curvature, from the lift's analytic
derivatives. Nothing is sampled and then differentiated.

Chord tolerance. The drawing and the solid approximate the contour by chords; `chord_polyline`
chooses the cam angles so that no chord strays from the exact curve by more than the tolerance
(interval bisection with the distance of exact interior points to the chord as the test, at half
the tolerance so that what lies between those points has room). The tests read the files back
and measure the distance to the exact curve independently.

Grinding. A radial-feed grinder turns the cam and moves the wheel centre along one fixed line
through the cam axis. A wheel of radius Rw touching the contour has its centre at
contact + Rw * normal (the contour's offset curve); the table gives, for uniformly spaced grinder
angles, the distance of that centre from the cam axis. With Rw equal to the roller radius and no
follower offset the table is the follower's own lift (y0 + L at grinder angle = cam angle): a
test. A wheel as large as the contour's smallest concave radius (exact: refined between the
samples) or larger would cut into the flank: an error naming where; one within WHEEL_MARGIN below
it: a warning (in the file's header and on stderr).
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError, echo
from ..effects.lift import build_lift
from ..gears.base import Gear
from ..gears.registry import GEARS
from ..lift.contours.cam_profile import CamProfile, angles_with

TWO_PI = 2.0 * math.pi
FORMATS = ("csv", "dxf", "stl", "glb", "grind")
MIN_TOLERANCE = 1e-9  # m; below this the chords' own rounding (1e-16 relative of a 0.1 m cam) is near
MAX_TOLERANCE = 1e-3  # m; coarser than any cam drawing
MAX_POLYLINE_POINTS = 2_000_000  # a 1 nm tolerance on a 50 mm cam needs ~200 000
MIN_POINTS, MAX_POINTS = 8, 1_000_000
# A wheel as large as the smallest concave radius conforms to the flank (touches it along an arc
# rather than at a point): the geometric limit, with nothing left for the wheel's size tolerance,
# its dressing or the cam's form tolerance, each of which would then cut the flank. At the limit
# (to rounding) it is refused; within WHEEL_MARGIN below it, warned of (engineering judgement: no
# grinding standard fixes a figure; --wheel-margin overrides it).
WHEEL_MARGIN = 0.05  # of the wheel's radius
AT_LIMIT = 1e-9  # relative: a wheel this close to the radius counts as equal (the radius' own rounding)


def cam_source(scene, lift=None) -> CamProfile:
    """The scene's cam (its gear's cam_profile); InputError for a gear that has no cam to make, and
    for a cam that fails the validity checks of every cam (an undercut one folds: nothing to make)."""
    profile = scene.gear_plugin.cam_profile(scene, lift if lift is not None else build_lift(scene))
    if profile is None:
        makers = [name for name, gear in GEARS.items() if type(gear).cam_profile is not Gear.cam_profile]
        raise InputError(scene.source, "follower.type",
                         f"exports are for {', '.join(makers)} cams; this scene's follower is {echo(scene.follower.type)}")
    return profile


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of points p (..., 2) from the segments a-b (..., 2)."""
    ab = b - a
    length2 = np.sum(ab * ab, axis=-1)
    t = np.where(length2 > 0.0, np.sum((p - a) * ab, axis=-1) / np.where(length2 > 0.0, length2, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    q = a + t[..., None] * ab
    return np.hypot(*(p - q).T).T


def chord_polyline(curve, tolerance: float, breakpoints=(), start_points: int = 360,
                   probes: int = 9, max_points: int = MAX_POLYLINE_POINTS, key: str = "--tolerance") -> tuple[np.ndarray, np.ndarray]:
    """Cam angles and points of a closed polyline whose chords stay within `tolerance` of the
    closed curve `curve(theta) -> (N, 2)` (period 2 pi). Breakpoints are always vertices (a
    corner of the exact curve is a corner of the polyline). Returns (theta, points) without
    repeating the first point."""
    theta = angles_with(start_points, breakpoints)
    frac = np.arange(1, probes + 1) / (probes + 1.0)
    while True:
        ends = np.append(theta, theta[0] + TWO_PI)
        a, b = ends[:-1], ends[1:]
        pa = curve(a)
        pb = np.roll(pa, -1, axis=0)
        inner = a[:, None] + frac[None, :] * (b - a)[:, None]
        pin = curve(inner.ravel()).reshape(inner.shape + (2,))
        dist = _segment_distance(pin, pa[:, None, :], pb[:, None, :]).max(axis=1)
        bad = dist > 0.5 * tolerance
        if not np.any(bad):
            return theta, pa
        if theta.size + np.count_nonzero(bad) > max_points:
            raise InputError("<command line>", key,
                             f"a chord tolerance of {tolerance:.3g} m needs more than {max_points} points on this cam; "
                             "use a larger tolerance")
        theta = np.sort(np.concatenate([theta, 0.5 * (a[bad] + b[bad]) % TWO_PI]))


def _drop_repeats(theta: np.ndarray, xy: np.ndarray, within: float) -> tuple[np.ndarray, np.ndarray]:
    """Drop a vertex closer than `within` to the one before it: the roller pivoting on a corner of
    the cam touches one point over a range of angles, and rounding makes near-copies of it
    (1.9e-13 m apart on Schenker's cam) that a solid would turn into degenerate faces. Moving a
    vertex by `within` moves the polyline by no more."""
    step = np.hypot(*np.diff(xy, axis=0, append=xy[:1]).T)
    keep = step > within
    return theta[keep], xy[keep]


# ---------------------------------------------------------------------------------------------
# The four exports: each returns the bytes or text to write (written by the caller through
# explorer.core.outputs, so the usual rules for output files apply).


CENTRE_PATHS = {  # CutFor.centre_path -> what the columns and the drawing's layer hold
    "pitch": ("PITCH", "pitch curve: the roller's centre"),
    "face_centre": ("FACE_CENTRE", "face_centre: the crowned face's (or curved pad's) centre of curvature, contour + R n"),
}


def cut_for_line(src: CamProfile) -> str:
    """The header line every export carries: the follower the contour is cut for."""
    return (f"cut for: {src.cut_for.describe()} (another follower on this contour gives another lift)")


def point_table(src: CamProfile, points: int = 3600) -> str:
    """CSV: one row per cam angle (uniform, plus the lift's breakpoints): contour point, the
    centre path's (a roller's pitch curve, a crowned face's centre; none for a flat face: its
    columns are left out rather than repeat the contour), outward normal, signed curvatures,
    pressure angle; the header names the follower the contour is cut for."""
    theta = angles_with(points, src.breakpoints())
    g = src.at(theta)
    path = src.cut_for.centre_path
    out = io.StringIO()
    out.write(f"# {src.name}: {cut_for_line(src)}\n")
    centre = (f"# {CENTRE_PATHS[path][1]};\n" if path is not None
              else "# a flat face has no centre path (its contact runs along the face): no pitch columns;\n")
    out.write(f"# cam contour in the cam frame (m); the cam turns counter-clockwise,\n{centre}"
              "# the point at cam angle theta touches the follower at that angle; normal outward, unit;\n"
              "# curvature 1/radius, > 0 convex, < 0 concave, 0 straight\n")
    names = ["cam_angle_deg", "contour_x_m", "contour_y_m"]
    columns = [np.degrees(theta), g.contour]
    if path is not None:
        names += [f"{path}_x_m", f"{path}_y_m"]
        columns.append(g.pitch)
    names += ["normal_x", "normal_y", "contour_curvature_1_m"]
    columns += [g.normal, g.contour_curvature]
    if path is not None:
        names.append(f"{path}_curvature_1_m")
        columns.append(g.pitch_curvature)
    names.append("pressure_angle_deg")
    columns.append(np.degrees(g.pressure_angle))
    out.write(",".join(names) + "\n")
    np.savetxt(out, np.column_stack(columns), delimiter=",", fmt="%.17g")
    return out.getvalue()


def contour_polyline(src: CamProfile, tolerance: float, which: str = "contour", merge: float = 0.0) -> np.ndarray:
    """(N, 2) vertices of the closed contour (or pitch curve) to the chord tolerance, counter-
    clockwise (the order drawings and solids expect); vertices closer than max(merge, 1e-3 of the
    tolerance) to their predecessor are dropped."""
    theta, xy = chord_polyline(lambda t: getattr(src.at(t), which), tolerance, src.breakpoints())
    theta, xy = _drop_repeats(theta, xy, max(merge, 1e-3 * tolerance))
    return xy[::-1]  # increasing cam angle runs clockwise around the cam


def dxf_text(src: CamProfile, tolerance: float) -> str:
    """A DXF (R2010, millimetres) with the contour (layer CAM) and the centre path (layer PITCH: a
    roller's pitch curve; FACE_CENTRE: a crowned face's centre; none for a flat face) as closed
    LWPOLYLINEs to the chord tolerance, the shaft centre as a point, and the follower the contour
    is cut for as a note (layer NOTES, a TEXT under the cam) and a custom header property CUT_FOR."""
    import ezdxf
    from ezdxf import units

    doc = ezdxf.new("R2010", units=units.MM)
    doc.layers.add("CAM", color=7)
    paths = [("CAM", "contour")]
    path = src.cut_for.centre_path
    if path is not None:
        layer = CENTRE_PATHS[path][0]
        doc.layers.add(layer, color=1, linetype="DASHED")
        paths.append((layer, "pitch"))
    doc.layers.add("NOTES", color=7)
    msp = doc.modelspace()
    lowest = 0.0
    for layer, which in paths:
        xy = contour_polyline(src, tolerance, which) * 1e3
        msp.add_lwpolyline(xy.tolist(), format="xy", close=True, dxfattribs={"layer": layer})
        if which == "contour":
            lowest = float(xy[:, 1].min())
    msp.add_point((0.0, 0.0), dxfattribs={"layer": "CAM"})
    note = f"{src.name}: {cut_for_line(src)}"
    doc.header.custom_vars.append("CUT_FOR", note)
    msp.add_text(note, height=2.5, dxfattribs={"layer": "NOTES", "insert": (0.0, lowest - 10.0)})
    stream = io.StringIO()
    doc.write(stream)
    return stream.getvalue()


def cam_solid(src: CamProfile, tolerance: float, width: float):
    """trimesh solid of the cam: the contour polyline extruded over `width` along the cam axis
    (z), centred on z = 0; metres."""
    import trimesh

    from .parts import extrude_contour  # trimesh, scipy: only for the mesh formats (stl, glb)

    # float32 in STL and glTF resolves ~4e-9 m at 0.05 m: closer vertices would collapse into
    # degenerate faces
    mesh = extrude_contour(contour_polyline(src, tolerance, merge=1e-8), width)  # contour in (x, z), width along y
    # (x, y, z) -> (x, z, -y): the contour back in the x-y plane, the cam axis along z
    mesh.apply_transform(trimesh.transformations.rotation_matrix(-math.pi / 2.0, [1.0, 0.0, 0.0]))
    return mesh


def stl_bytes(src: CamProfile, tolerance: float, width: float) -> bytes:
    """Binary STL in millimetres (STL carries no unit; CAM software assumes mm)."""
    mesh = cam_solid(src, tolerance, width)
    mesh.apply_scale(1e3)
    return mesh.export(file_type="stl")


def glb_bytes(src: CamProfile, tolerance: float, width: float) -> bytes:
    """Binary glTF in metres (glTF's unit)."""
    return cam_solid(src, tolerance, width).export(file_type="glb")


@dataclass(frozen=True)
class GrindingTable:
    grinder_angle: np.ndarray  # rad, uniform: the cam's rotation on the grinder
    wheel_centre: np.ndarray  # m, distance of the wheel centre from the cam axis
    cam_angle: np.ndarray  # rad, the follower cam angle whose contact point the wheel touches
    wheel_radius: float
    warning: str | None = None  # a wheel within the margin of the smallest concave radius


def wheel_centre(src: CamProfile, theta, wheel_radius: float) -> np.ndarray:
    """(N, 2) wheel centre in the cam frame when the wheel touches the contact point of theta."""
    g = src.at(theta)
    return g.contour + wheel_radius * g.normal


def smallest_concave_radius(src: CamProfile, theta: np.ndarray, curvature: np.ndarray) -> tuple[float, float] | None:
    """(radius, cam angle) of the contour's smallest concave radius, None for a convex cam: the
    samples' most negative curvature, refined by a bounded Brent search between its neighbours
    (the minimum of a smooth flank lies between samples: the sampled one is too large by a
    second-order amount)."""
    from scipy.optimize import minimize_scalar

    if not np.any(curvature < 0.0):
        return None
    i = int(np.argmin(curvature))
    n = theta.size
    lo = theta[i] - (theta[i] - theta[i - 1]) % TWO_PI
    hi = theta[i] + (theta[(i + 1) % n] - theta[i]) % TWO_PI
    best_k, best_t = float(curvature[i]), float(theta[i])
    found = minimize_scalar(lambda t: float(src.at(np.array([t % TWO_PI])).contour_curvature[0]), bounds=(lo, hi),
                            method="bounded", options={"xatol": 1e-9, "maxiter": 100})
    if found.fun < best_k:
        best_k, best_t = float(found.fun), float(found.x % TWO_PI)
    return -1.0 / best_k, best_t


def grinding_table(src: CamProfile, wheel_radius: float, points: int = 3600,
                   margin: float = WHEEL_MARGIN) -> GrindingTable:
    """Wheel-centre distance at `points` uniform grinder angles. The grinder angle a rotates the
    cam so that the wheel centre lies on the wheel's line, the ground y axis (the follower's
    direction), i.e. a = 90 deg - polar angle of the centre in the cam frame."""
    key = "--grinding-wheel-radius"
    theta = angles_with(8 * points, src.breakpoints())
    g = src.at(theta)
    warning = None
    flank = smallest_concave_radius(src, theta, g.contour_curvature)
    if flank is not None:
        radius, at = flank
        if wheel_radius >= radius * (1.0 - AT_LIMIT):
            raise InputError("<command line>", key,
                             f"a wheel of radius {wheel_radius * 1e3:.6g} mm cannot grind the concave flank of radius "
                             f"{radius * 1e3:.6g} mm at cam angle {math.degrees(at):.3f} deg (the wheel must be smaller: "
                             f"at most {radius / (1.0 + margin) * 1e3:.6g} mm keeps a {margin:.3g} margin)")
        if wheel_radius * (1.0 + margin) > radius:
            warning = (f"a wheel of radius {wheel_radius * 1e3:.6g} mm is within {margin:.3g} of the concave flank's "
                       f"radius {radius * 1e3:.6g} mm at cam angle {math.degrees(at):.3f} deg: the wheel's size "
                       "tolerance and dressing would cut the flank (--wheel-margin)")
    c = g.contour + wheel_radius * g.normal
    psi = np.unwrap(np.arctan2(c[:, 1], c[:, 0]))
    step = np.diff(np.append(psi, psi[0] - TWO_PI))
    if not np.all(step < 0.0):
        raise InputError("<command line>", key,
                         "the wheel-centre path winds back on itself: this cam cannot be ground with a radial wheel feed")
    alpha = np.arange(points) * (TWO_PI / points)
    # psi decreases by 2 pi over theta in [0, 2 pi): find theta with psi(theta) = pi/2 - alpha
    target = psi[0] - np.mod(psi[0] - (0.5 * math.pi - alpha), TWO_PI)
    ends = np.append(psi, psi[0] - TWO_PI)
    grid = np.append(theta, TWO_PI)
    j = np.clip(np.searchsorted(-ends, -target, side="right") - 1, 0, theta.size - 1)
    lo, hi = grid[j], grid[j + 1]

    def polar(t):
        p = wheel_centre(src, t, wheel_radius)
        return np.arctan2(p[:, 1], p[:, 0])

    def offset_angle(t):  # psi(t) - target, wrapped near zero (the bracket is one grid cell)
        return np.angle(np.exp(1j * (polar(t) - target)))

    for _ in range(64):  # bisection in the bracket: the polar angle is monotone there
        mid = 0.5 * (lo + hi)
        above = offset_angle(mid) > 0.0  # psi still above target: the root lies later
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    root = 0.5 * (lo + hi)
    centre = wheel_centre(src, root, wheel_radius)
    return GrindingTable(alpha, np.hypot(centre[:, 0], centre[:, 1]), np.mod(root, TWO_PI), wheel_radius, warning)


def grinding_text(src: CamProfile, table: GrindingTable) -> str:
    out = io.StringIO()
    out.write(f"# {src.name}: {cut_for_line(src)}\n")
    if table.warning is not None:
        out.write(f"# warning: {table.warning}\n")
    out.write(f"# grinding table for a wheel of radius {table.wheel_radius * 1e3:.9g} mm fed radially;\n"
              "# grinder_angle: the cam's rotation that brings the ground point to the wheel's line;\n"
              "# wheel_centre: distance of the wheel centre from the cam axis; cam_angle: the follower cam angle of that point\n")
    out.write("grinder_angle_deg,wheel_centre_m,cam_angle_deg\n")
    np.savetxt(out, np.column_stack([np.degrees(table.grinder_angle), table.wheel_centre, np.degrees(table.cam_angle)]),
               delimiter=",", fmt="%.17g")
    return out.getvalue()
