"""Self-locking margin 90 deg - rho - |alpha| while the cam lifts the follower (seed 004: the
guide locks at alpha + rho = 90 deg; rho the friction angle of [contact])."""

from __future__ import annotations

import math

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    rho = case.contact_spec.friction_angle
    margin = 0.5 * math.pi - rho - np.abs(np.asarray(contact.geometry.pressure_angle, dtype=float))
    lifting = case.derivs[1] > 0.0
    if not lifting.any():
        lifting = np.ones_like(lifting)
    masked = np.where(lifting, margin, np.inf)
    i = int(np.argmin(masked))
    return Measure.of([[margin[i]]], [[case.theta_deg[i]]], None, settings,
                      note=f"while the cam lifts the follower; friction angle {math.degrees(rho):.4g} deg ([contact])")
