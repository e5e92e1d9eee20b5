"""Cam curvature under a flat face: the cam's radius of curvature rho = Rb + s + s'' must stay
positive (a cusp otherwise)."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    counter = np.asarray(contact.geometry.counter_radius, dtype=float)
    if not np.all(np.isinf(counter)):
        # a crowned face or a roller: its own curvature enters the cam's, and an undercut or cusp
        # under it is refused when the scene is read (explorer.lift.validity, the gear's check)
        r = float(np.min(np.abs(counter)))
        return Measure.not_applicable(f"the follower's face is curved (radius {r * 1e3:.4g} mm), not flat: a cusp or "
                                      "undercut under it is refused when the scene is read")
    rho = np.asarray(contact.geometry.contour_radius, dtype=float)
    i = int(np.argmin(rho))
    return Measure.of([[rho[i]]], [[case.theta_deg[i]]], None, settings)
