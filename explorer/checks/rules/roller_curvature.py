"""Cam curvature against the roller: the smallest convex radius of the pitch curve (the roller
centre's path) as a multiple of the roller radius; at or below 1 the cam is undercut."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    if contact.pitch_radius is None:
        return Measure.not_applicable("the follower has no roller (its faces' radii are the gear's design)")
    r = contact.roller_radius
    rho = np.asarray(contact.pitch_radius, dtype=float)
    convex = np.isfinite(rho) & (rho > 0.0)
    if not convex.any():
        return Measure.of([[np.inf]], [[np.nan]], None, settings, note="no convex stretch")
    ratio = np.where(convex, rho / r, np.inf)
    i = int(np.argmin(ratio))
    return Measure.of([[ratio[i]]], [[case.theta_deg[i]]], None, settings,
                      note=f"pitch radius {rho[i] * 1e3:.4g} mm, roller radius {r * 1e3:.4g} mm")
