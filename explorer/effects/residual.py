"""Residual vibration figures of one elastic run: how far the valve strays from the lift the cam
is made for. Computed by the elastic effect into its summary, so that a sweep over speed holds
them as columns (explorer.studies.sweep_engine) and `explorer residual` is that sweep.

  residual_deviation_m  largest |s - s_ref| over the revolution, s_ref the lift the cam is made
                        for: a polydyne cam's wanted valve lift (explorer.lift.polydyne; then it
                        vanishes at the design speed), else the rigid valve lift max(ratio L - lash, 0)
  residual_amplitude_m  sqrt(e^2 + (e'/wn)^2), e = s - s_ref, wn^2 = (k + rate)/M1, at the first
                        output sample in the dwell after the rise (NaN: the lift names no dwell, or
                        no sample falls in it). While the valve stays in contact in the dwell,
                        M1 e'' + (k + rate) e = 0 there (the drive and s_ref are constant), so this
                        is the amplitude of the residual vibration at any instant of the dwell:
                        which sample is taken does not matter (the closed form's oracle, test).
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def reference_lift(lift, ratio: float, lash: float, theta, order: int = 1) -> np.ndarray:
    """(order + 1, N) valve lift the cam is meant to give, per radian, at cam angles theta."""
    wanted = getattr(lift, "wanted_valve_lift", None)
    if wanted is not None:
        return wanted(theta, order)
    d = lift.derivatives(theta)[: order + 1] * ratio
    is_open = d[0] - lash > 0.0
    d[0] -= lash
    return np.where(is_open, d, 0.0)


def dwell_sample(lift, theta) -> int | None:
    """Index of the first angle of theta (one revolution, increasing from 0) inside the dwell after
    the rise, or None (no dwell named by the lift, or none of theta in it)."""
    wanted = getattr(lift, "wanted", None)
    start = wanted.dwell_start() if wanted is not None else None
    if start is None:
        return None
    length = wanted.dwell
    x = np.mod(np.asarray(theta, dtype=float) - (lift.start + start), TWO_PI)  # angle since the dwell began
    inside = np.nonzero(x < length)[0]
    if inside.size == 0:
        return None
    return int(inside[np.argmin(x[inside])])


def residual_figures(lift, ratio: float, lash: float, omega: float, wn: float, theta, s, v) -> dict:
    """The summary entries (module doc) from the run's valve lift s and velocity v at angles theta."""
    ref = reference_lift(lift, ratio, lash, theta, 1)
    e = np.asarray(s) - ref[0]
    amplitude = math.nan
    i = dwell_sample(lift, theta)
    if i is not None:
        amplitude = math.hypot(float(e[i]), float(v[i] - omega * ref[1][i]) / wn)
    return {"residual_deviation_m": float(np.max(np.abs(e))), "residual_amplitude_m": amplitude}
