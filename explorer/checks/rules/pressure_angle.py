"""Pressure angle: the largest angle between the contact normal and the driven point's travel
over the revolution; the limit depends on the travel (a straight guide or an arc)."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    alpha = np.abs(np.asarray(contact.geometry.pressure_angle, dtype=float))
    i = int(np.argmax(alpha))
    name = "fail_oscillating" if contact.oscillating else "fail_translating"
    travel = "an oscillating follower (the driven point travels on an arc)" if contact.oscillating \
        else "a translating follower"
    return Measure.of([[alpha[i]]], [[case.theta_deg[i]]], None, settings, fail=settings[name],
                      note=f"limit for {travel} (setting {name})", limit_source=name)
