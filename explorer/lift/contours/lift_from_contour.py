"""lift.law = "contour": the follower lift computed from the cam contour in [cam] (analysis).

Arcs: closed form per arc (arcs.ArcLift). Point lists: periodic spline through the points and
Newton iteration for the contact (parametric.ParametricLift). Both are LiftCurves whose
derivatives are exact for the contour they describe; the point list's fidelity to the real cam
depends on the point density (parametric.points_accuracy).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...core.errors import InputError
from .arcs import ContourError, make_arc_lift
from .parametric import ContourFollowError, make_parametric_lift, _angle_and_height, pitch_jets

BASE_RADIUS_TOLERANCE = 1e-6  # m: follower.base_radius must match the contour this closely


def contour_lift(spec, follower, file: str):
    """The LiftCurve of a translating roller follower over the contour (spec: a CamSpec of
    explorer.lift.contours.spec; the translating roller's gear calls this when it checks a scene and
    when it builds the lift); InputError when the follower cannot run on it (undercut, base circle
    mismatch, offset too large)."""
    if abs(follower.base_radius - spec.min_radius) > BASE_RADIUS_TOLERANCE:
        raise InputError(
            file,
            "follower.base_radius",
            f"the [cam] contour's base circle (its smallest distance from the cam centre) is "
            f"{spec.min_radius * 1e3:.9g} mm, but follower.base_radius is {follower.base_radius * 1e3:.9g} mm; "
            f"set base_radius = \"{spec.min_radius * 1e3:.9g} mm\"",
        )
    r, e, rb = follower.roller_radius, follower.offset, follower.base_radius
    if spec.kind == "arcs":
        try:
            return make_arc_lift(spec.arcs, r, e, rb)
        except ContourError as exc:
            raise InputError(file, f"follower.{exc.field}" if exc.field in ("roller_radius", "offset") else "cam.arcs", exc.reason) from None

    contour = spec.contour_geometry()
    try:
        lift = make_parametric_lift(contour, r, e, rb)
    except ContourFollowError as exc:
        raise InputError(file, "follower.roller_radius", str(exc)) from None
    if spec.spline_degree == 3:
        # a cubic spline's third derivative jumps at the knots, so L'' does there too
        lift = _with_knot_breakpoints(lift, contour)
    return lift


def _with_knot_breakpoints(lift, contour):

    knots = np.unique(np.mod(contour.spline.t, contour.period))
    q = pitch_jets(contour, knots, 2, lift.roller_radius, lift.sign)
    theta, _ = _angle_and_height(q, lift.offset)
    return replace(lift, kinks=np.unique(np.mod(theta[0], 2.0 * math.pi)))
