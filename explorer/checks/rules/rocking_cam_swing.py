"""Rocking-cam swing: how far the rocking cam swings beyond the swing at which its roller reaches
the top arc (explorer.gears.rocking: total_swing - top_arc_swing). Negative: the swing turns back on
the flank and the valve never gets the contour's full rise."""

from __future__ import annotations

import math

import numpy as np

from ..rule import Measure


def measure(case, settings) -> Measure:
    gear = getattr(case.lift, "gear", None)
    if gear is None or not hasattr(gear, "top_arc_swing") or not hasattr(gear, "total_swing"):
        return Measure.not_applicable("not a rocking cam")
    top = gear.top_arc_swing()
    excess = gear.total_swing() - top if math.isfinite(top) else -math.inf
    dwell = gear.full_lift_dwell() if math.isfinite(top) else 0.0
    return Measure.of(np.full((case.n, 1), excess), np.full((case.n, 1), math.degrees(gear.dead_centre) % 360.0),
                      None, settings, note=f"dwell at full lift {math.degrees(dwell):.4g} deg of shaft angle")
