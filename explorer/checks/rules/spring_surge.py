"""Spring surge: over the operating range, how close a surge frequency of the spring (its modes
with both ends held: the chain's when the scene cuts it into masses, else the continuous
spring's f_j = (j/2) sqrt(k/m_s)) comes to a strong harmonic of the cam (order n at speed w:
n w; strong: an amplitude of the drive acceleration's spectrum at least `strength` times the
largest), as a share of the surge frequency. The spectrum is the sweep's
(explorer.studies.spectrum: FFT of ratio w^2 L''); its shape does not depend on the speed."""

from __future__ import annotations

import math

import numpy as np

from ...dynamics.chain import chain_frequencies, continuous_frequencies
from ...studies.spectrum import MAX_ORDERS, acceleration_spectrum
from ..case import RPM
from ..rule import Measure


def surge_frequencies(spring, rate, modes: int) -> np.ndarray:
    """The first `modes` surge frequencies (rad/s) per rate (N, modes)."""
    rate = np.ravel(np.asarray(rate, dtype=float))
    if spring.elements > 0:
        base = np.asarray(chain_frequencies(spring.elements, 1.0, spring.mass), dtype=float)[:modes]
    else:
        base = 2.0 * math.pi * np.asarray(continuous_frequencies(modes, 1.0, spring.mass), dtype=float)
    return np.sqrt(rate)[:, None] * base[None, :]  # every mode scales with sqrt(k)


def measure(case, settings) -> Measure:
    sp = case.scene.spring
    if sp is None or not sp.mass > 0.0 or not sp.rate > 0.0:
        return Measure.not_applicable("needs the spring's mass ([spring] mass, or density with its wire geometry)")
    modes = int(settings["modes"])
    omega_s = surge_frequencies(sp, case.param("spring.rate"), modes)  # (N, modes)
    lo, hi = float(case.speeds.min()) * RPM, float(case.speeds.max()) * RPM
    orders = int(min(MAX_ORDERS, math.ceil(float(omega_s.max()) / lo) + 2))
    spectrum = acceleration_spectrum(case.scene, case.lift, orders=orders)
    amp = spectrum.amplitude
    strong = spectrum.orders[amp >= settings["strength"] * amp.max()].astype(float) if amp.max() > 0 else np.zeros(0)
    if strong.size == 0:
        return Measure.not_applicable("the cam's drive has no harmonics")
    # distance of n w from w_s over [lo, hi]: 0 where w_s/n lies inside the range, else at the nearer end
    res = omega_s[:, :, None] / strong[None, None, :]  # the resonant speeds, (N, modes, orders)
    nearest = np.clip(res, lo, hi)
    dist = np.abs(strong[None, None, :] * nearest - omega_s[:, :, None]) / omega_s[:, :, None]
    flat = dist.reshape(case.n, -1)
    k = np.argmin(flat, axis=1)
    value = flat[np.arange(case.n), k]
    j, o = np.unravel_index(k[0], dist.shape[1:])
    where = float(nearest[0, j, o]) / RPM
    # the 15-20 x screen of f1 against the camshaft's frequency is spring_frequency's (closed form)
    note = (f"mode {j + 1} ({omega_s[0, j] / (2 * math.pi):.4g} Hz) nearest to order {int(strong[o])} at "
            f"{where:.6g} rpm; strong orders: {', '.join(str(int(x)) for x in strong[:20])}"
            f"{'...' if strong.size > 20 else ''}")
    speeds = None if case.sampling else np.array([where])
    return Measure.of(value[:, None], np.full((case.n, 1), np.nan), speeds, settings, note=note)
