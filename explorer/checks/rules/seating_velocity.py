"""Seating velocity: the hardest seat impact of a revolution at each speed, from the elastic
linkage (the sweep engine); without a linkage the rigid closing impact, Schenker's v2 =
omega ratio |L'| at the lash crossing."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..case import RPM, lash_crossing_angles
from ..rule import Measure, worst_index


def measure(case, settings) -> Measure:
    if case.scene.valve is None:
        return Measure.not_applicable("needs [valve]")
    speeds = case.rule_speeds("seating_velocity")
    try:
        case.needs_linkage()
    except NotApplicable:
        theta = lash_crossing_angles(case, "down")
        if np.all(np.isnan(theta)):
            return Measure.not_applicable("the valve never opens")
        d = case.lift.derivatives(np.where(np.isfinite(theta), theta, 0.0))
        v = np.abs(case.scene.follower.ratio * d[1])[:, None] * (speeds * RPM)[None, :]
        angle = np.broadcast_to(np.degrees(theta)[:, None], v.shape)
        return Measure.of(v, angle, speeds, settings, note="rigid (no [linkage]): the valve's velocity at the seat")
    figures = case.elastic(speeds)
    v = -figures["seating_velocity_m_s"]
    angle = np.full(v.shape, np.nan)
    i = worst_index(v, "max")
    if i is not None and not case.sampling:
        r, j = np.unravel_index(i, v.shape)
        angle[r, j] = case.elastic_event_angle(float(speeds[j]), "seat", "hardest")
    return Measure.of(v, angle, speeds, settings, note="elastic linkage (sweep engine); NaN: no seat impact",
                      speed_exact=not case.sampling)  # the elastic seating velocity has no monotony in the speed
