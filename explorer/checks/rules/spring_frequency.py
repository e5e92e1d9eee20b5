"""Spring frequency ratio: the spring's first natural frequency with both ends held (against flat
plates), f1 = (1/2) sqrt(k / m_a) with m_a the mass of the active coils, over the camshaft's
rotational frequency at the highest speed checked, n_top / 60.

The classic criterion of the spring books: Shigley's Mechanical Engineering Design, ch. 10,
"Critical frequency of helical springs", quoting Wolford and Smith -- the fundamental critical
frequency should be 15 to 20 times the frequency of the force or motion of the spring (after
Wahl, Mechanical Springs, 1944, who gives f = (1/2) sqrt(k g / W) for both ends fixed). It is the
closed form of the continuous spring even where the scene cuts the spring into masses (the chain's
first mode lies within about 0.5 % of it at 8 masses): the criterion is stated with it. It does
not replace spring_surge, which looks at the cam's harmonics themselves; a valve spring judged by
this rule alone would be judged against its own first order only.
"""

from __future__ import annotations

import math

import numpy as np

from ..case import RPM
from ..rule import Measure


def first_frequency(rate, mass):
    """f1 = (1/2) sqrt(k/m) (Hz): the first mode of a uniform spring, both ends fixed."""
    return 0.5 * np.sqrt(np.asarray(rate, dtype=float) / np.asarray(mass, dtype=float))


def measure(case, settings) -> Measure:
    sp = case.scene.spring
    if sp is None or not sp.mass > 0.0 or not sp.rate > 0.0:
        return Measure.not_applicable("needs the spring's mass ([spring] mass, or density with its wire geometry)")
    top = float(case.speeds.max())  # the ratio falls with the speed: the top speed is the worst
    f_cam = top * RPM / (2.0 * math.pi)  # Hz, the camshaft's rotational frequency
    f1 = np.broadcast_to(np.ravel(first_frequency(case.param("spring.rate"), sp.mass)), (case.n,))
    ratio = f1 / f_cam
    note = (f"f1 = (1/2) sqrt(k/m_active) = {f1[0]:.4g} Hz (k {float(np.ravel(case.param('spring.rate'))[0]) / 1e3:.4g} "
            f"N/mm, active mass {sp.mass * 1e3:.4g} g) over the camshaft's {f_cam:.4g} Hz at {top:.6g} rpm")
    return Measure.of(ratio[:, None], np.full((case.n, 1), np.nan), np.array([top]), settings, note=note)
