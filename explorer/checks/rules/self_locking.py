"""Self-locking margin 90 deg - rho - |alpha| while the cam lifts the follower (seed 004: the
guide locks at alpha + rho = 90 deg; rho the friction angle of [contact])."""

from __future__ import annotations

import math

import numpy as np

from ...mechanics.contact import self_locking_worst
from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    rho = case.contact_spec.friction_angle
    margin = 0.5 * math.pi - rho - np.abs(np.asarray(contact.geometry.pressure_angle, dtype=float))
    i = self_locking_worst(margin, case.derivs[1])
    return Measure.of([[margin[i]]], [[case.theta_deg[i]]], None, settings,
                      note=f"while the cam lifts the follower; friction angle {math.degrees(rho):.4g} deg ([contact])")
