"""The drawing kit every gear's view shares (trimesh, z up, metres, real dimensions): the Layout of
the valve group, solids (prisms of contours, cylinders, bars), the valve, its spring and seat, the
displayed valve lift, rotations about y, the roller's looped spin, and the framing of the parts'
motion for a camera. The gears' views (explorer/view/gear_views.py) draw with it; explorer.view.parts
is the entry the viewers call.

Conventions: the gear in the x-z plane, shafts along y; a counter-clockwise turn by a in the gear's
plane (x, y) -> world (x, z) is the world rotation quat_about_y(-a). Every part's mesh is in its own
frame; a view's poses give one (positions (N, 3), wxyz (N, 4)) per step of a Result.

Magnification m (for the lash and sub-millimetre dynamics): the displayed valve lift is
s' = max(0, s_rigid + m (s - s_rigid)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import trimesh

# The drawn rollers (this module's and explorer.view.gear_parts') have four bores, a quarter turn
# apart: they look the same after a quarter turn.
ROLLER_MARKS = 4

SPRING_ACTIVE_COILS = 6
SPRING_DEAD_COILS = 1.0  # closed, touching coil at each end
SPRING_SEGMENTS_PER_TURN = 36
SPRING_WIRE_SEGMENTS = 12  # a multiple of 4: the wire's top and bottom are vertices


@dataclass(frozen=True)
class Layout:
    """Every dimension of the displayed gear, in metres (world frame, z up)."""

    base_radius: float
    roller_radius: float
    offset: float
    prime_y: float  # roller-centre height at zero lift, sqrt((Rb + rr)^2 - e^2)
    ratio: float
    max_follower_lift: float
    valve_travel: float  # ratio * max follower lift: the valve's travel without lash, for sizing
    cam_width: float
    roller_width: float
    roller_draw_radius: float  # drawn radius (a knife edge, rr = 0, gets a small tip)
    shaft_radius: float
    rod_radius: float
    arm_follower: float  # a
    arm_valve: float  # b = ratio * a
    lever_half_thickness: float
    pivot: tuple[float, float, float]
    ball_radius: float  # adjusting-screw ball
    valve_x: float
    stem_top_rest: float  # z of the stem top with the valve closed
    stem_radius: float
    valve_radius: float
    seat_z: float  # z of the seat contact (top face of the closed valve head)
    retainer_drop: float  # stem top to retainer underside (spring top)
    retainer_thickness: float
    spring_seat_z: float  # z of the fixed spring seat (spring bottom)
    spring_rest_length: float  # spring length with the valve closed
    spring_mean_radius: float
    spring_wire_radius: float

    @property
    def spring_solid_length(self) -> float:
        return 2.0 * self.spring_wire_radius * (SPRING_ACTIVE_COILS + 2.0 * SPRING_DEAD_COILS + 1.0)


def _drop_duplicates(xy: np.ndarray) -> np.ndarray:
    step = np.linalg.norm(np.diff(xy, axis=0, append=xy[:1]), axis=1)
    keep = step > 1e-12 * max(1.0, float(np.abs(xy).max()))
    return xy[keep]


def signed_area(xy: np.ndarray) -> float:
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _is_star_shaped(xy: np.ndarray) -> bool:
    """True when the polar angle about the origin strictly increases around the contour, so a
    triangle fan from the shaft centre covers the disc without overlap."""
    angle = np.unwrap(np.arctan2(xy[:, 1], xy[:, 0]))
    step = np.diff(np.append(angle, angle[0] + 2.0 * math.pi))
    return bool(np.all(step > 0.0)) and abs(angle[-1] - angle[0]) < 2.0 * math.pi


def _ear_clip(xy: np.ndarray) -> np.ndarray:
    """Triangulate a simple counter-clockwise polygon (fallback for cams not star-shaped about
    their centre; O(n^2), used only for unusual contours)."""
    idx = list(range(len(xy)))
    tris = []

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    guard = 0
    while len(idx) > 3 and guard < 10 * len(xy) ** 2:
        guard += 1
        clipped = False
        for k in range(len(idx)):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % len(idx)]
            a, b, c = xy[i0], xy[i1], xy[i2]
            if cross(a, b, c) <= 0.0:
                continue
            inside = False
            for j in idx:
                if j in (i0, i1, i2):
                    continue
                p = xy[j]
                if cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0:
                    inside = True
                    break
            if not inside:
                tris.append((i0, i1, i2))
                del idx[k]
                clipped = True
                break
        if not clipped:
            break
    if len(idx) == 3:
        tris.append(tuple(idx))
    return np.asarray(tris, dtype=np.int64)


def extrude_contour(xy: np.ndarray, width: float) -> trimesh.Trimesh:
    """Prism of a counter-clockwise contour (cam frame x, y -> world x, z) over y in
    [-width/2, width/2]. Caps and side have their own vertices, so the edges shade sharp."""
    n = len(xy)
    x, z = xy[:, 0], xy[:, 1]
    half = 0.5 * width
    front = np.column_stack([x, np.full(n, -half), z])  # y = -w/2
    back = np.column_stack([x, np.full(n, half), z])
    i = np.arange(n)
    j = (i + 1) % n
    if _is_star_shaped(xy):
        cap = np.column_stack([np.full(n, n), i, j])  # fan from the centre vertex
        cap_vertices = np.vstack([xy, [[0.0, 0.0]]])
    else:
        cap = _ear_clip(xy)
        cap_vertices = xy
    m = len(cap_vertices)
    cap_front = np.column_stack([cap_vertices[:, 0], np.full(m, -half), cap_vertices[:, 1]])
    cap_back = np.column_stack([cap_vertices[:, 0], np.full(m, half), cap_vertices[:, 1]])
    # A counter-clockwise polygon in the (x, z) plane has its right-hand normal along -y, so the
    # front cap (y = -w/2) keeps the winding and the back cap reverses it.
    vertices = np.vstack([cap_front, cap_back, front, back])
    faces_front = cap
    faces_back = cap[:, ::-1] + m
    o = 2 * m
    # outward side normal for a counter-clockwise contour is (dz, -dx) in (x, z): with t the
    # contour step, (back - front) x t = w e_y x t points that way
    side = np.vstack([np.column_stack([o + i, o + n + j, o + j]), np.column_stack([o + i, o + n + i, o + n + j])])
    mesh = trimesh.Trimesh(vertices, np.vstack([faces_front, faces_back, side]), process=False)
    if mesh.volume < 0.0:
        mesh.invert()
    return mesh


# ---------------------------------------------------------------------------------------------
# Simple solids


def cylinder_y(radius: float, length: float, sections: int = 48, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=radius, height=length, sections=sections)
    m.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2.0, [1.0, 0.0, 0.0]))
    m.apply_translation(center)
    return m


def cylinder_z(radius: float, z0: float, z1: float, sections: int = 40, x: float = 0.0) -> trimesh.Trimesh:
    m = trimesh.creation.cylinder(radius=radius, height=abs(z1 - z0), sections=sections)
    m.apply_translation([x, 0.0, 0.5 * (z0 + z1)])
    return m


def tube_z(r_in: float, r_out: float, z0: float, z1: float, sections: int = 40, x: float = 0.0) -> trimesh.Trimesh:
    m = trimesh.creation.annulus(r_min=r_in, r_max=r_out, height=abs(z1 - z0), sections=sections)
    m.apply_translation([x, 0.0, 0.5 * (z0 + z1)])
    return m


def box(extents, center) -> trimesh.Trimesh:
    m = trimesh.creation.box(extents=extents)
    m.apply_translation(center)
    return m


def concat(meshes) -> trimesh.Trimesh:
    return trimesh.util.concatenate([m for m in meshes if m is not None])


def stadium_bar(x0: float, x1: float, half: float, width: float, sections: int = 24) -> trimesh.Trimesh:
    """A flat bar along x with semicircular ends of radius `half` centred at x0 and x1 (in x-z),
    extruded over y; its round ends are the lever's contact pads."""
    top = np.linspace(-0.5 * math.pi, 0.5 * math.pi, sections)
    right = np.column_stack([x1 + half * np.cos(top), half * np.sin(top)])
    left = np.column_stack([x0 - half * np.cos(top), -half * np.sin(top)])
    return extrude_contour(np.vstack([right, left]), width)


# ---------------------------------------------------------------------------------------------
# Parts


def _valve_mesh(lay: Layout) -> trimesh.Trimesh:
    """Stem, retainer and head as one solid of revolution; local origin at the stem top."""
    rs, rv = lay.stem_radius, lay.valve_radius
    ret_top = -lay.retainer_drop
    ret_bot = ret_top - lay.retainer_thickness
    ret_r = lay.spring_mean_radius + 1.6 * lay.spring_wire_radius
    head_top = lay.seat_z - lay.stem_top_rest  # seat contact, relative to the stem top
    head_face = 0.25 * rv  # height of the 45-degree seat face
    neck = 0.55 * rv
    head_thick = 0.12 * rv
    profile = np.array([
        [0.0, 0.0],
        [rs, 0.0],
        [rs, ret_top],
        [ret_r, ret_top],
        [ret_r, ret_bot],
        [rs, ret_bot],
        [rs, head_top + neck],
        [1.6 * rs, head_top + 0.35 * neck],
        [rv - head_face, head_top],
        [rv, head_top - head_face],
        [rv, head_top - head_face - head_thick],
        [0.0, head_top - head_face - head_thick],
    ])
    return trimesh.creation.revolve(profile[::-1], sections=48)


def _seat_mesh(lay: Layout) -> trimesh.Trimesh:
    """Fixed parts around the valve: seat ring, valve guide, spring seat and two ribs between."""
    x, rv, rs = lay.valve_x, lay.valve_radius, lay.stem_radius
    face = 0.25 * rv
    # the ring's inner lower edge lies on the valve's 45-degree face: line contact when closed
    ring = tube_z(rv - 0.5 * face, 1.3 * rv, lay.seat_z - 0.5 * face, lay.seat_z + 0.35 * rv, 64, x)
    guide_bottom = lay.seat_z + 0.35 * rv + 0.55 * rv
    guide = tube_z(1.15 * rs, 2.0 * rs, guide_bottom, lay.spring_seat_z, 32, x)
    washer = tube_z(1.15 * rs, lay.spring_mean_radius + 1.8 * lay.spring_wire_radius,
                     lay.spring_seat_z - 0.5 * rs, lay.spring_seat_z, 48, x)
    ribs = []
    rib_h = guide_bottom + 0.4 * rv - (lay.seat_z + 0.35 * rv)
    for ang in (0.5 * math.pi, 1.5 * math.pi):  # two ribs along y: seen edge-on from the front
        r_mid = 0.5 * (2.0 * rs + 1.3 * rv)
        rib = box([1.3 * rv - 2.0 * rs, 0.15 * rs, rib_h], [0.0, 0.0, 0.0])
        rib.apply_transform(trimesh.transformations.rotation_matrix(ang, [0.0, 0.0, 1.0]))
        rib.apply_translation([x + r_mid * math.cos(ang), r_mid * math.sin(ang), lay.seat_z + 0.35 * rv + 0.5 * rib_h])
        ribs.append(rib)
    return concat([ring, guide, washer, *ribs])


# ---------------------------------------------------------------------------------------------
# Spring


def spring_faces(lay: Layout | None = None, segments_per_turn: int = SPRING_SEGMENTS_PER_TURN,
                 wire_segments: int = SPRING_WIRE_SEGMENTS) -> np.ndarray:
    """Faces of the spring tube (same for every length; pass the resolution used for the vertices)."""
    turns = SPRING_ACTIVE_COILS + 2.0 * SPRING_DEAD_COILS
    n_path = int(round(turns * segments_per_turn)) + 1
    k = wire_segments
    i = np.arange(n_path - 1)[:, None] * k
    j = np.arange(k)[None, :]
    a = i + j
    b = i + (j + 1) % k
    c = a + k
    d = b + k
    tube = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    # end caps: fans to the two centre vertices appended after the tube rings
    n_ring = n_path * k
    first = np.column_stack([np.full(k, n_ring), (np.arange(k) + 1) % k, np.arange(k)])
    last0 = (n_path - 1) * k
    last = np.column_stack([np.full(k, n_ring + 1), last0 + np.arange(k), last0 + (np.arange(k) + 1) % k])
    return np.concatenate([tube, first, last]).astype(np.int64)


def spring_vertices(lay: Layout, length, segments_per_turn: int = SPRING_SEGMENTS_PER_TURN,
                    wire_segments: int = SPRING_WIRE_SEGMENTS, surge=None) -> np.ndarray:
    """Vertices of the spring at `length` (scalar -> (V, 3); array (N,) -> (N, V, 3)), local frame
    with the spring's bottom at z = 0 on the z axis.

    The resolution (segments per turn, polygon of the wire) is a choice: a viewer that resends
    the spring every frame uses a coarser one. Closed ends: one dead coil at each end with pitch = wire diameter (touching), the active coils
    share what is left, so the ends stay flat as the spring compresses, as real springs do."""
    length = np.asarray(length, dtype=float)
    scalar = length.ndim == 0
    length = np.atleast_1d(length)
    rw, rm = lay.spring_wire_radius, lay.spring_mean_radius
    dead, active = SPRING_DEAD_COILS, SPRING_ACTIVE_COILS
    turns = active + 2.0 * dead
    n_path = int(round(turns * segments_per_turn)) + 1
    t = np.linspace(0.0, turns, n_path)  # turns along the wire
    phi = 2.0 * math.pi * t
    # axial position: dead coils at pitch 2 rw, active coils at the pitch that fills the length
    dead_pitch = 2.0 * rw
    active_span = length[:, None] - 2.0 * rw - 2.0 * dead * dead_pitch  # centre-line span of active coils
    active_pitch = np.maximum(active_span / active, dead_pitch)
    u = np.clip(t - dead, 0.0, active)[None, :]
    z = rw + dead_pitch * (np.minimum(t, dead)[None, :] + np.maximum(t - dead - active, 0.0)[None, :]) + active_pitch * u
    if surge is not None:
        w = np.atleast_2d(np.asarray(surge, dtype=float))
        N = w.shape[1]
        # node j sits at the fraction 1 - j/(N+1) of the active coils from the seat; the ends hold
        frac = np.concatenate([[0.0], 1.0 - np.arange(N, 0, -1) / (N + 1), [1.0]])
        vals = np.concatenate([np.zeros((w.shape[0], 1)), w[:, ::-1], np.zeros((w.shape[0], 1))], axis=1)
        f = u[0] / active
        z = z - np.stack([np.interp(f, frac, row) for row in vals])
    centre = np.stack(np.broadcast_arrays(rm * np.cos(phi)[None, :], rm * np.sin(phi)[None, :], z), axis=-1)
    # frame along the helix: radial direction and the tangent-normal in the (tangent, z) plane
    radial = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], -1)[None, :, :]
    pitch_here = np.where((t >= dead) & (t <= dead + active), 1.0, 0.0)[None, :] * active_pitch + \
        np.where((t < dead) | (t > dead + active), 1.0, 0.0)[None, :] * dead_pitch
    tangent = np.stack(np.broadcast_arrays(
        -2.0 * math.pi * rm * np.sin(phi)[None, :], 2.0 * math.pi * rm * np.cos(phi)[None, :], pitch_here), -1)
    tangent /= np.linalg.norm(tangent, axis=-1, keepdims=True)
    binormal = np.cross(tangent, radial)
    ang = np.linspace(0.0, 2.0 * math.pi, wire_segments, endpoint=False)
    ring = rw * (np.cos(ang)[None, None, :, None] * radial[:, :, None, :]
                 + np.sin(ang)[None, None, :, None] * binormal[:, :, None, :])
    tube = (centre[:, :, None, :] + ring).reshape(len(length), -1, 3)
    ends = np.stack([centre[:, 0], centre[:, -1]], axis=1)
    out = np.concatenate([tube, ends], axis=1)
    return out[0] if scalar else out


def spring_length(lay: Layout, valve_lift) -> np.ndarray:
    """Spring length for a (displayed) valve lift: the retainer moves down with the valve."""
    return lay.spring_rest_length - np.asarray(valve_lift, dtype=float)


def valve_group(lay: Layout, only=None) -> dict[str, trimesh.Trimesh]:
    """The valve (origin at the stem top), its spring at rest length (origin at its bottom) and the
    fixed seat, guide and spring seat (world frame): the parts every gear's valve end shares."""
    builders = {
        "valve": lambda: _valve_mesh(lay),
        "spring": lambda: trimesh.Trimesh(spring_vertices(lay, lay.spring_rest_length), spring_faces(lay), process=False),
        "seat": lambda: _seat_mesh(lay),
    }
    return {name: build() for name, build in builders.items() if only is None or name in only}


def quat_about_y(angle) -> np.ndarray:
    """(N, 4) wxyz quaternions of right-handed rotations by `angle` (rad) about +y."""
    angle = np.asarray(angle, dtype=float)
    out = np.zeros(angle.shape + (4,))
    out[..., 0] = np.cos(0.5 * angle)
    out[..., 2] = np.sin(0.5 * angle)
    return out


def displayed_valve_lift(result, magnification: float = 1.0) -> np.ndarray:
    """Valve lift as drawn: the rigid lift plus `magnification` times the deviation of the
    most detailed valve motion from it; never below the seat."""
    s = np.asarray(result.columns["valve_lift_m"], dtype=float)
    rigid = np.asarray(result.columns.get("rigid_valve_lift_m", s), dtype=float)
    return np.maximum(rigid + magnification * (s - rigid), 0.0)


def loop_spin(spin: np.ndarray, total: float, marks: int = ROLLER_MARKS) -> np.ndarray:
    """The roller spin as drawn in a looped animation of one revolution.

    A revolution turns the roller by `total` (rad), in general not a whole number of quarter
    turns, so replaying the revolution made the bores jump at 360 -> 0 (by up to 45 degrees,
    against a fraction of a degree per step). The drawing scales the spin by the least factor
    that makes `total` a whole number of the marks' period 2 pi / marks: the roller then rolls as
    if its radius were off by that factor, at most (pi / marks) / |total| (3.4 % for Schenker's
    Fig. 2 gear) and looks the same at the end of the revolution as at its start. A roller that
    turns less than half a period in a revolution gets a constant correction instead (a ramp of
    at most (pi / marks) / (2 pi) rad per radian of cam angle). `spin` holds the n uniform steps
    of one revolution, zero at the first."""
    period = 2.0 * math.pi / marks
    turns = round(total / period)
    if turns == 0:
        theta_fraction = np.arange(len(spin)) / len(spin)
        return spin - total * theta_fraction
    return spin * (turns * period / total)


def looped_roller_rotation(wxyz: np.ndarray) -> np.ndarray:
    """`loop_spin` for a roller given as per-step rotations about y (the other gears' rollers,
    whose spin explorer.view.gear_parts integrates from its own geometry). The revolution's last
    step back to the start is estimated from its neighbours (a drawing, not a result)."""
    wxyz = np.asarray(wxyz, dtype=float)
    if len(wxyz) < 3 or not np.allclose(wxyz[:, [1, 3]], 0.0, atol=1e-12):
        return wxyz
    angle = np.unwrap(2.0 * np.arctan2(wxyz[:, 2], wxyz[:, 0]))
    steps = np.diff(angle)
    total = angle[-1] - angle[0] + 0.5 * (steps[-1] + steps[0])
    return quat_about_y(angle[0] + loop_spin(angle - angle[0], total))


def spring_surge(result, magnification: float = 1.0) -> np.ndarray | None:
    """(T, N): the coils' displacements beyond the quasi-static shape u_j - s (1 - j/(N+1)), times
    the magnification, from a result of the spring as N masses (coil_<j>_displacement_m); None
    for a massless spring."""
    cols = result.columns
    N = 0
    while f"coil_{N + 1}_displacement_m" in cols:
        N += 1
    if N == 0:
        return None
    s = np.asarray(cols["valve_lift_m"], dtype=float)
    r = 1.0 - np.arange(1, N + 1) / (N + 1)
    u = np.column_stack([np.asarray(cols[f"coil_{j}_displacement_m"], dtype=float) for j in range(1, N + 1)])
    return magnification * (u - s[:, None] * r[None, :])


def axial_scale(lay: Layout, result, magnification: float = 1.0) -> np.ndarray:
    """Per-step z-scale of the rest-length spring mesh (cheap alternative to per-step vertices for
    viewers that can only scale a node; the wire's section flattens a little)."""
    return spring_length(lay, displayed_valve_lift(result, magnification)) / lay.spring_rest_length


def coil_points(lay: Layout, result, magnification: float = 1.0) -> np.ndarray | None:
    """(T, N, 3): the spring's coil masses (spring as N masses) in the frame of the rest-length
    spring mesh, for a recording that scales that mesh along its axis per step
    (spring_axial_scale): on the wire's mean circle, at the node's place in the active coils,
    moved by the surge (divided by the axial scale the frame applies). None: massless spring."""
    w = spring_surge(result, magnification)
    if w is None:
        return None
    T, N = w.shape
    sz = axial_scale(lay, result, magnification)
    r = 1.0 - np.arange(1, N + 1) / (N + 1)
    rw, rm = lay.spring_wire_radius, lay.spring_mean_radius
    turns = SPRING_DEAD_COILS + r * SPRING_ACTIVE_COILS
    span = lay.spring_rest_length - 2.0 * rw - 4.0 * SPRING_DEAD_COILS * rw
    z_rest = rw + 2.0 * rw * SPRING_DEAD_COILS + r * span
    out = np.empty((T, N, 3))
    out[:, :, 0] = rm * np.cos(2.0 * math.pi * turns)[None, :]
    out[:, :, 1] = rm * np.sin(2.0 * math.pi * turns)[None, :]
    out[:, :, 2] = z_rest[None, :] - w / np.asarray(sz, dtype=float)[:, None]
    return out


# ---------------------------------------------------------------------------------------------
# Framing: the box the parts sweep over a revolution, and a camera that sees all of it


def _part_vertices(mesh) -> np.ndarray:
    """(V, 3) float vertices of a trimesh, a (vertices, faces) pair or a bare vertex array."""
    if hasattr(mesh, "vertices"):
        return np.asarray(mesh.vertices, dtype=float)
    if isinstance(mesh, tuple):
        return np.asarray(mesh[0], dtype=float)
    return np.asarray(mesh, dtype=float)


def _hull_2d(points: np.ndarray) -> np.ndarray:
    """Vertices of the convex hull of (V, 2) points (all of them when the hull is degenerate):
    the extremes of a rotated set are those of its rotated hull, and the hull is much smaller."""
    if len(points) <= 16:
        return points
    from scipy.spatial import ConvexHull, QhullError

    try:
        return points[ConvexHull(points).vertices]
    except (QhullError, ValueError):
        return points


def _rotation_matrices(wxyz: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotation matrices of (N, 4) quaternions w, x, y, z (normalised here)."""
    q = np.asarray(wxyz, dtype=float)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], axis=1)


def _swept_extents(vertices: np.ndarray, wxyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-rotation (N, 3) lows and highs of the rotated vertices (before the translation)."""
    q = np.asarray(wxyz, dtype=float)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    if np.all(q[:, 1] == 0.0) and np.all(q[:, 3] == 0.0):
        # a turn about y (every part of these gears): y is unchanged, and x-z is a plane rotation
        # of the part's outline, so its hull in x-z decides the extremes
        hull = _hull_2d(vertices[:, [0, 2]])
        angle = 2.0 * np.arctan2(q[:, 2], q[:, 0])
        n = len(q)
        lo = np.column_stack([np.empty(n), np.full(n, vertices[:, 1].min()), np.empty(n)])
        hi = np.column_stack([np.empty(n), np.full(n, vertices[:, 1].max()), np.empty(n)])
        # in blocks: (rotations x hull points) at a million steps was gigabytes. cos and sin are
        # taken whole: numpy's vector loops may round a block's last elements differently
        cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
        chunk = max(1, 2_000_000 // max(len(hull), 1))
        for start in range(0, n, chunk):
            block = slice(start, start + chunk)
            c, s = cos[block], sin[block]
            x = c * hull[None, :, 0] + s * hull[None, :, 1]
            z = -s * hull[None, :, 0] + c * hull[None, :, 1]
            lo[block, 0], hi[block, 0] = x.min(axis=1), x.max(axis=1)
            lo[block, 2], hi[block, 2] = z.min(axis=1), z.max(axis=1)
        return lo, hi
    lo, hi = np.empty((len(q), 3)), np.empty((len(q), 3))
    rotations = _rotation_matrices(q)
    chunk = max(1, 2_000_000 // max(len(vertices), 1))
    for start in range(0, len(q), chunk):
        world = np.einsum("nij,vj->nvi", rotations[start:start + chunk], vertices)
        lo[start:start + chunk], hi[start:start + chunk] = world.min(axis=1), world.max(axis=1)
    return lo, hi


def motion_bounds(parts, poses) -> tuple[np.ndarray, np.ndarray]:
    """World box (lo, hi) holding every part at every step of `poses`: the union over the
    revolution, not one instant (the valve opens, levers swing, a tripped latch swings aside).

    `parts`: name -> trimesh, (vertices, faces) or vertices, in the part's own frame; `poses`:
    name -> (positions (N, 3), wxyz (N, 4)) as from `part_poses` (a part without a pose is
    already in the world frame). Exact, not sampled: each distinct rotation of a part is applied
    to its vertices (to its x-z hull for turns about y). The spring is drawn at its rest length
    and only shortens as the valve opens (its bottom stays put), so its rest mesh bounds it."""
    lows, highs = [], []
    for name, mesh in parts.items():
        vertices = _part_vertices(mesh)
        if vertices.size == 0:
            continue
        if name not in poses:
            lows.append(vertices.min(axis=0))
            highs.append(vertices.max(axis=0))
            continue
        positions = np.asarray(poses[name][0], dtype=float)
        wxyz = np.asarray(poses[name][1], dtype=float)
        rotations, inverse = np.unique(wxyz, axis=0, return_inverse=True)
        lo, hi = _swept_extents(vertices, rotations)
        inverse = np.asarray(inverse).reshape(-1)
        lows.append((lo[inverse] + positions).min(axis=0))
        highs.append((hi[inverse] + positions).max(axis=0))
    if not lows:
        raise ValueError("no vertices to bound")
    return np.min(lows, axis=0), np.max(highs, axis=0)


# The gear works in the x-z plane: look at it from the front (along +y), a little from the
# right and from above, so that the parts' thickness shows.
VIEW_DIRECTION = (0.2, -1.0, 0.3)  # from the target towards the camera
VIEW_UP = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class CameraFrame:
    """A perspective camera: where it is, what it looks at, its up vector and vertical field of
    view (rad), for a picture of width/height `aspect`."""

    position: tuple[float, float, float]
    look_at: tuple[float, float, float]
    up: tuple[float, float, float]
    fov: float
    aspect: float


def camera_axes(position, look_at, up) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit right, up and forward vectors of a camera at `position` looking at `look_at`."""
    forward = np.asarray(look_at, dtype=float) - np.asarray(position, dtype=float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(up, dtype=float))
    right /= np.linalg.norm(right)
    return right, np.cross(right, forward), forward


def frame_bounds(lo, hi, fov: float = math.radians(45.0), aspect: float = 1.0, direction=VIEW_DIRECTION,
                 up=VIEW_UP, margin: float = 0.05) -> CameraFrame:
    """The nearest camera looking along -`direction` whose picture (vertical field of view
    `fov`, width/height `aspect`) holds the whole box lo..hi, `margin` of the half-width and
    half-height to spare on the tightest side, with the box's picture centred.

    With the camera's axes fixed (right, up, forward) and corners k at (x_k, y_k, d_k) along
    them, a camera at (p_r, p_u, p_f) sees corner k when |x_k - p_r| <= t_h (d_k - p_f), and
    likewise upwards, t = tan(half angle). Linear constraints: the largest p_f they allow
    sideways is (A + B) / 2 with A = min(d_k - x_k / t_h), B = min(d_k + x_k / t_h) (the two
    side planes then both touch a corner), and the camera takes the smaller of the sideways and
    upward limits. At that depth it is placed sideways and upwards where the extreme corners
    project symmetrically (max u = -min u, a monotone root), which also minimises the largest
    |u|, so every corner stays in view."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    centre = 0.5 * (lo + hi)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    direction = np.asarray(direction, dtype=float)
    direction = direction / np.linalg.norm(direction)
    right, upward, forward = camera_axes(centre + direction, centre, up)
    x, y, d = corners @ right, corners @ upward, corners @ forward
    tan_v = math.tan(0.5 * fov) * (1.0 - margin)
    tan_h = math.tan(0.5 * fov) * aspect * (1.0 - margin)

    def reach(c, t):
        return 0.5 * (float(np.min(d - c / t)) + float(np.min(d + c / t)))

    # a box without depth seen edge-on would put the camera on it: keep a near distance
    near = 1e-3 * max(float(np.linalg.norm(hi - lo)), 1e-6)
    p_f = min(reach(x, tan_h), reach(y, tan_v), float(d.min()) - near)
    depth = d - p_f

    def symmetric(c):
        """p with max((c - p) / depth) = -min((c - p) / depth), by bisection (decreasing in p)."""
        a, b = float(c.min()), float(c.max())
        for _ in range(200):
            m = 0.5 * (a + b)
            u = (c - m) / depth
            if u.max() + u.min() > 0.0:
                a = m
            else:
                b = m
            if b - a <= 1e-15 * max(1.0, abs(m)):
                break
        return 0.5 * (a + b)

    position = symmetric(x) * right + symmetric(y) * upward + p_f * forward
    look_at = position + (float(centre @ forward) - p_f) * forward
    return CameraFrame(position=tuple(map(float, position)), look_at=tuple(map(float, look_at)),
                       up=tuple(map(float, np.asarray(up, dtype=float))), fov=float(fov), aspect=float(aspect))
