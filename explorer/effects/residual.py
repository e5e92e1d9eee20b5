"""Residual vibration figures of one elastic run: how far the valve strays from the lift the cam
is made for, and how strongly it vibrates in the dwell after the rise. Computed by the elastic
effect into its summary, so that a sweep over speed holds them as columns
(explorer.studies.sweep_engine) and `explorer residual` is that sweep; the sweep's compiled path
computes the same figures (explorer.dynamics.exact_kernel, from residual_reference below).
Definition and oracles: docs/theory/residual.md.

  residual_deviation_m  largest |s - s_ref| over the revolution, s_ref the lift the cam is made
                        for: a polydyne cam's wanted valve lift (explorer.lift.polydyne; then it
                        vanishes at the design speed), else the rigid valve lift max(ratio L - lash, 0)
  residual_amplitude_m  the amplitude of the valve's free vibration about its static equilibrium
                        in the dwell after the rise, sqrt(z^2 + (v/wn)^2) with z = s - s_eq
                        measured from that equilibrium (explorer.dynamics.free_vibration), at the
                        first output sample in that dwell (explorer.lift.dwell.dwell_after_rise:
                        the top dwell of a rise-dwell-return cam, else the base circle after the
                        event). Undefined (summary: null; sweep row: NaN) when the lift has no
                        such dwell, or no output sample falls in it.
"""

from __future__ import annotations

import math

import numpy as np

from ..dynamics.free_vibration import free_amplitude
from ..lift.dwell import dwell_after_rise


def reference_lift(lift, ratio: float, lash: float, theta, order: int = 1) -> np.ndarray:
    """(order + 1, N) valve lift the cam is meant to give, per radian, at cam angles theta."""
    wanted = getattr(lift, "wanted_valve_lift", None)
    if wanted is not None:
        return wanted(theta, order)
    d = lift.derivatives(theta)[: order + 1] * ratio
    is_open = d[0] - lash > 0.0
    d[0] -= lash
    return np.where(is_open, d, 0.0)


def reference_parts(lift, ratio: float, theta) -> tuple[np.ndarray, int, float, bool]:
    """residual_reference's parts that do not depend on the lash (a tolerance study draws a new
    lash every run): (a polydyne's wanted valve lift at theta, or ratio * L at theta; the dwell's
    first sample or -1; the valve-referred drive in the dwell ratio * L, NaN without a dwell; True
    when the lash is still to be taken off the first: lash_reference)."""
    theta = np.asarray(theta, dtype=float)
    if getattr(lift, "wanted_valve_lift", None) is not None:  # the wanted lift has no lash in it
        d, less_lash = np.ascontiguousarray(reference_lift(lift, ratio, 0.0, theta, 1)[0]), False
    else:
        d, less_lash = lift.derivatives(theta)[0] * ratio, True
    dwell = dwell_after_rise(lift)
    i = dwell.first_sample(theta) if dwell is not None else None
    if i is None:
        return d, -1, math.nan, less_lash
    return d, i, ratio * dwell.lift, less_lash


def lash_reference(d, lash: float) -> np.ndarray:
    """The rigid valve lift max(d - lash, 0) from d = ratio * L (reference_lift's floats)."""
    return np.ascontiguousarray(np.where(d - lash > 0.0, d - lash, 0.0))


def residual_reference(lift, ratio: float, lash: float, theta) -> tuple[np.ndarray, int, float]:
    """What the figures take from the lift at the output angles theta (one revolution from 0):
    (s_ref at theta, the dwell's first sample or -1, the valve-referred drive in the dwell
    ratio * L, NaN without a dwell)."""
    d, i, S, less_lash = reference_parts(lift, ratio, theta)
    return (lash_reference(d, lash) if less_lash else d), i, S


def residual_figures(lift, ratio: float, model, theta, s, v) -> dict:
    """The summary entries (module doc) from the run's valve lift s and velocity v at angles theta
    (the LinkageModel `model`: its stiffness where the dwell is, for one that changes). The
    amplitude is None where it is undefined (a summary figure is never NaN; a sweep row reads
    it as NaN, effects/elastic_events.elastic_row, as the compiled path gives it)."""
    ref, i, S = residual_reference(lift, ratio, model.lash, theta)
    deviation = float(np.max(np.abs(np.asarray(s) - ref)))
    amplitude = None  # undefined (no dwell, or no output sample in it): JSON null, as every summary figure
    if i >= 0:
        k = model.stiffness if model.stiffness_profile is None else float(model.stiffness_at(
            np.array([theta[i] / model.stiffness_profile.omega]))[0])
        amplitude = free_amplitude(float(s[i]), float(v[i]), S, k, model.lash, model.seated_resistance,
                                   model.spring_rate, model.friction, model.oscillating_mass)
    return {"residual_deviation_m": deviation, "residual_amplitude_m": amplitude}
