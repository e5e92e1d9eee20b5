"""3D parts of a scene's valve gear (trimesh, z up, metres, real dimensions) and their pose per
step: the entry the browser explorer (viser) and the rerun recordings call, so both show the same
machine.

Each gear draws itself (explorer/view/gear_views.py: its GearView, keyed by follower type);
`layout`, `build_parts`, `part_poses` and `spring_axial_scale` ask the scene's view, and
PART_COLORS knows every registered gear's parts. The drawing kit they share (Layout, the spring,
rotations, the displayed valve lift, the camera's framing) is explorer.view.drawing, whose names
the viewers read from here too.
"""

from __future__ import annotations

import numpy as np

from ..gears.registry import DEFAULT
from .drawing import (ROLLER_MARKS, SPRING_ACTIVE_COILS, SPRING_DEAD_COILS, SPRING_SEGMENTS_PER_TURN,
                      SPRING_WIRE_SEGMENTS, VIEW_DIRECTION, VIEW_UP, CameraFrame, Layout, axial_scale, camera_axes,
                      coil_points, displayed_valve_lift, extrude_contour, frame_bounds, loop_spin, motion_bounds,
                      quat_about_y, spring_faces, spring_length, spring_surge, spring_vertices)
from .gear_views import VIEWS, view_of
from .train_motion import TRAIN_MAGNIFICATION, default_magnification, train_motion, train_shape

__all__ = [  # the drawing kit's names the viewers read from here, and this module's own
    "ROLLER_MARKS", "SPRING_ACTIVE_COILS", "SPRING_DEAD_COILS", "SPRING_SEGMENTS_PER_TURN", "SPRING_WIRE_SEGMENTS",
    "VIEW_DIRECTION", "VIEW_UP", "CameraFrame", "Layout", "camera_axes", "coil_points", "displayed_valve_lift",
    "extrude_contour", "frame_bounds", "loop_spin", "motion_bounds", "quat_about_y", "spring_faces", "spring_length",
    "spring_surge", "spring_vertices",
    "TRAIN_MAGNIFICATION", "default_magnification", "train_shape",
    "STATIC_PARTS", "PART_COLORS", "layout", "build_parts", "part_poses", "spring_axial_scale", "parts_follow_cam",
]

# Parts that never move (their pose is the same at every step), by name in every gear's drawing.
STATIC_PARTS = ("follower_guide", "lever_pivot", "seat")


class _PartColors(dict):
    """Display colours (RGB 0-255) by part name, shared by the viewers so parts look the same
    everywhere: the translating roller's drawing's, then any registered gear's (looked up on
    demand, so the table lists exactly the stock parts until asked for another)."""

    def __missing__(self, name):
        for view in VIEWS.entries():
            if name in view.colors:
                return view.colors[name]
        raise KeyError(name)


PART_COLORS = _PartColors(VIEWS[DEFAULT].colors)  # the stock drawing's


def layout(scene, result=None, lift=None) -> Layout:
    """Every dimension of the displayed gear (its view's layout)."""
    return view_of(scene).layout(scene, result, lift)


def build_parts(scene, result=None, lay: Layout | None = None, lift=None, contour_samples: int = 720,
                only: tuple[str, ...] | None = None) -> dict:
    """Every part's mesh in its local frame (see `part_poses` for where each frame sits); `only`
    limits it to some parts (a viewer whose layout did not change rebuilds just the cam)."""
    return view_of(scene).parts(scene, result, lay=lay, lift=lift, contour_samples=contour_samples, only=only)


def part_poses(scene, result, magnification: float = 1.0, lay: Layout | None = None, lift=None) -> dict:
    """One world pose per step of `result.columns` for every part: name -> (positions (N, 3),
    wxyz (N, 4)). The spring's pose is fixed; its shape follows `spring_length(lay,
    displayed_valve_lift(result, magnification))`. A result of an elastic train of parts
    (explorer.view.train_motion) poses the parts each mass carries from that mass's own motion,
    its deviation from the rigid motion times `magnification` (the view's items 7 and 8)."""
    view = view_of(scene)
    poses = view.poses(scene, result, magnification=magnification, lay=lay, lift=lift)
    motion = train_motion(scene, result, len(view.train_stations(scene)), magnification) if train_shape(scene)[0] else None
    if motion is not None:
        poses.update(view.train_poses(scene, result, motion, poses, lay=lay, lift=lift))
    return poses


def spring_axial_scale(scene, result, magnification: float = 1.0, lay: Layout | None = None) -> np.ndarray:
    """Per-step z-scale of the rest-length spring mesh from `build_parts` (cheap alternative to
    per-step vertices for viewers that can only scale a node; the wire's section flattens a little)."""
    return axial_scale(lay or layout(scene, result), result, magnification)


def parts_follow_cam(scene) -> bool:
    """Whether parts other than the cam change with the scene's lift (a viewer then rebuilds them)."""
    return view_of(scene).parts_follow_cam
