"""Opening velocity at the end of the lash ramp: the valve's lift per cam angle, ratio L'(theta),
at the lash take-up (rigid kinematics; the same at every speed)."""

from __future__ import annotations

import numpy as np

from ..case import lash_crossing_angles
from ..rule import Measure


def measure(case, settings) -> Measure:
    if case.scene.valve is None:
        return Measure.not_applicable("needs [valve] (the lash)")
    theta = lash_crossing_angles(case, "up")
    if np.all(np.isnan(theta)):
        return Measure.not_applicable("the valve never opens (the lift never exceeds the lash)")
    d = case.lift.derivatives(np.where(np.isfinite(theta), theta, 0.0))
    rate = np.where(np.isfinite(theta), case.scene.follower.ratio * d[1], np.nan)
    return Measure.of(rate[:, None], np.degrees(theta)[:, None], None, settings,
                      note="rigid: ratio x dL/dtheta at the take-up")
