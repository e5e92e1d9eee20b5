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
        return Measure.not_applicable("the follower is not flat-faced")
    rho = np.asarray(contact.geometry.contour_radius, dtype=float)
    i = int(np.argmin(rho))
    return Measure.of([[rho[i]]], [[case.theta_deg[i]]], None, settings)
