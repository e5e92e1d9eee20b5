"""Seat bounce: how often the valve lands again after its first seat impact in a revolution
(elastic linkage, sweep engine), counted when its largest bounce (the highest lift after a seat
impact before the cam opens the valve again: effects/elastic_events.valve_periods) rises above
`min_height`. A valve that does not land at all in the revolution (held off its seat: float, a
pumped-up lash adjuster) fails: it never seats, which is worse than any bounce (inf)."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure, worst_index


def measure(case, settings) -> Measure:
    try:
        case.needs_linkage()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    speeds = case.rule_speeds("seat_bounce")
    fig = case.elastic(speeds)
    impacts = fig["seat_impacts"]
    high = fig["largest_bounce_m"] > settings["min_height"]
    bounces = np.where(np.isnan(impacts), np.nan, np.where(high, np.maximum(impacts - 1.0, 0.0), 0.0))
    never = impacts == 0.0  # no landing in the whole revolution: the valve stays off its seat
    bounces = np.where(never, np.inf, bounces)
    angle = np.full(bounces.shape, np.nan)
    i = worst_index(bounces, "max")
    if i is not None and not case.sampling and 0 < bounces.ravel()[i] < np.inf:
        r, j = np.unravel_index(i, bounces.shape)
        angle[r, j] = case.elastic_event_angle(float(speeds[j]), "seat", "second")
    return Measure.of(bounces, angle, speeds, settings,
                      note=(f"every landing after the first is counted once the largest bounce rises above "
                            f"{settings['min_height'] * 1e6:.3g} um"
                            + ("; inf: the valve does not land in the revolution (held off its seat)"
                               if bool(np.any(never)) else "")),
                      speed_exact=not case.sampling)
