"""Speed sweeps: the rigid contact margin of a scene versus camshaft speed, vectorised.

Accelerations scale with w^2 and the loads do not, so on the sampling grid the contact force is
F_i(w) = w^2 A_i + G_i (see explorer.mechanics.forces). The speed-independent arrays A, G are computed once;
the smallest contact force at each of many speeds is then one broadcast minimum over (speeds x
open samples), done in blocks to bound memory. Grid values (the exact, refined minimum at one
speed is explorer.mechanics.forces.min_contact_force; the exact float speed is explorer.mechanics.forces.float_speed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..effects.lift import build_lift
from ..mechanics.forces import RPM_PER_RAD_S, grid_load_parts

_BLOCK_CELLS = 2_000_000  # speeds x samples per block (16 MB of float64)


@dataclass(frozen=True)
class MarginSweep:
    rpm: np.ndarray  # rev/min
    min_contact_force: np.ndarray  # N, smallest rigid contact force over the open samples
    cam_angle_deg: np.ndarray  # where it occurs (nan when the valve never opens)

    def first_float_rpm(self) -> float | None:
        """Lowest swept speed whose margin is <= 0 (None if none): a grid bracket of the float speed."""
        hit = np.nonzero(self.min_contact_force <= 0.0)[0]
        return float(self.rpm[hit[0]]) if hit.size else None


def speed_parts(scene, lift=None, n: int | None = None):
    """(theta, A, G) on the open samples of the scene's grid: F = w^2 A + G."""
    lift = lift if lift is not None else build_lift(scene)
    theta, a_coef, g_part, is_open = grid_load_parts(scene, lift, n)
    return theta[is_open], a_coef[is_open], g_part[is_open]


def contact_margin_sweep(scene, rpms, lift=None, n: int | None = None) -> MarginSweep:
    """Smallest rigid contact force over one revolution for each speed in `rpms` (rev/min)."""
    rpm = np.asarray(rpms, dtype=float).ravel()
    if rpm.size == 0 or not np.all(np.isfinite(rpm)) or np.any(rpm <= 0.0):
        raise InputError(scene.source, "rpm", "sweep speeds must be finite and greater than zero")
    theta, a_coef, g_part = speed_parts(scene, lift, n)
    if theta.size == 0:
        nan = np.full(rpm.shape, np.nan)
        return MarginSweep(rpm, np.full(rpm.shape, np.inf), nan)
    w2 = (rpm / RPM_PER_RAD_S) ** 2
    out = np.empty(rpm.size)
    where = np.empty(rpm.size, dtype=np.intp)
    block = max(1, _BLOCK_CELLS // theta.size)
    for lo in range(0, rpm.size, block):
        hi = min(rpm.size, lo + block)
        forces = w2[lo:hi, None] * a_coef[None, :]
        forces += g_part[None, :]
        idx = np.argmin(forces, axis=1)
        where[lo:hi] = idx
        out[lo:hi] = forces[np.arange(hi - lo), idx]
    return MarginSweep(rpm, out, np.degrees(theta[where]))


def contact_margin_loop(scene, rpms, lift=None, n: int | None = None) -> MarginSweep:
    """The same sweep one speed at a time (the benchmark's baseline and the tests' reference)."""
    theta, a_coef, g_part = speed_parts(scene, lift, n)
    rpm = np.asarray(rpms, dtype=float).ravel()
    out = np.empty(rpm.size)
    angle = np.empty(rpm.size)
    for i, r in enumerate(rpm):
        forces = (r / RPM_PER_RAD_S) ** 2 * a_coef + g_part
        j = int(np.argmin(forces)) if forces.size else 0
        out[i] = forces[j] if forces.size else math.inf
        angle[i] = math.degrees(theta[j]) if forces.size else math.nan
    return MarginSweep(rpm, out, angle)
