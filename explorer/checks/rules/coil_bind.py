"""Coil bind: the fractional overrun to closure at full lift, xi = (L2 - Ls)/(L0 - L2), with the
spring installed at L1 = L0 - F1/k and compressed by the valve's lift to L2 (< 0: the coils go
solid).

xi is Shigley's (Mechanical Engineering Design, ch. 10, "Design of helical compression springs for
static service"): the force at solid F_s = (1 + xi) F_max, F_max the largest working force, and the
book designs for xi >= 0.15 (the warn limit). For a linear spring F_s = k (L0 - Ls) and F_max =
k (L0 - L2), so xi = F_s/F_max - 1 = (L2 - Ls)/(L0 - L2): the same figure in lengths (tested against
a Shigley ch. 10 exercise's xi = 0.42 in tests/test_checks.py)."""

from __future__ import annotations

import numpy as np

from ..rule import Measure
from . import _spring


def measure(case, settings) -> Measure:
    sp = case.scene.spring
    if sp is None or sp.free_length is None or sp.solid_height is None:
        return Measure.not_applicable("needs [spring] free_length and solid_height")
    if not sp.rate > 0.0:
        return Measure.not_applicable("needs a spring rate > 0")
    lift, angle = _spring.full_lift(case)
    preload = np.ravel(np.asarray(case.param("spring.preload"), dtype=float))
    rate = np.ravel(np.asarray(case.param("spring.rate"), dtype=float))
    l2 = sp.free_length - preload / rate - lift
    xi = (l2 - sp.solid_height) / (sp.free_length - l2)
    xi = np.broadcast_to(xi, (case.n,))
    gap = float(np.ravel(l2 - sp.solid_height)[0])
    return Measure.of(xi[:, None], np.full((case.n, 1), angle), None, settings,
                      note=f"{gap * 1e3:.4g} mm between the coils and solid at full lift")
