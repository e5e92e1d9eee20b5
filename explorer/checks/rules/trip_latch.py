"""Trip-gear latch hold: the latch's throw-off speed (its forces effect's float speed of the latched
window: above it the valve leaves the latch before the trip) less the highest operating speed.
Judged for the scenes whose forces effect reports a latch (the trip gear's variant); the nominal
design only (the latch law is rebuilt for every draw: tolerances are not propagated)."""

from __future__ import annotations

import math

import numpy as np

from ...effects.pipeline import simulate
from ..case import RPM
from ..rule import Measure


def measure(case, settings) -> Measure:
    if case.scene.gear_plugin.effect("forces") is None:  # only a gear's own forces report a latch
        return Measure.not_applicable("the gear has no latch")
    if case.scene.valve is None or case.scene.spring is None:
        return Measure.not_applicable("needs [valve] and [spring]")
    summary = simulate(case.scene.with_changes(effects=("forces",))).summary
    if not isinstance(summary.get("latch"), dict):
        return Measure.not_applicable("the gear has no latch")
    jump = summary.get("jump_speed_rpm")
    high = float(case.speeds.max())
    value = math.inf if jump is None else (jump - high) * RPM
    angle = summary.get("jump_cam_angle_deg")
    out = np.full((case.n, 1), value)
    return Measure.of(out, np.full((case.n, 1), math.nan if angle is None else angle), None, settings,
                      note="throw-off speed without the dashpot's force" + ("" if jump is None else f": {jump:.6g} rpm"))
