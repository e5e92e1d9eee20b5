"""The rigid figures of a sweep's runs (forces: min_contact_force_N, float_speed_rpm; contact:
max_camshaft_torque_Nm) for many speeds at once.

When the runs of a chunk differ in the camshaft speed only (a speed sweep, or the speed axis of a
map), everything but w^2 is shared: the lift at the samples of its smooth pieces and on the
scene's grid, A and G of the rigid contact force F = w^2 A + G, the float speed, the contact
geometry and the torque factors. Then
- the refined minimum contact force of every speed is explorer.mechanics.forces.min_contact_forces
  (the same floats as min_contact_force run by run, which `simulate`'s forces effect calls);
- the peak camshaft torque of every speed is explorer.effects.contact.peak_torques (the contact
  effect's per-sample product T = c(F) F, equal to its max_camshaft_torque_Nm to 1e-9 relative:
  the factor c is formed once instead of per speed).
The caller groups the runs (sweep_engine.speed_groups: equal in every varied key but the speed); a
run alone is a group of one, computed the same way. A group is one scene and its speeds (no scene
built per run: speeds_of gives Drive.omega of each rpm).
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from ..core.memo import remember
from ..effects.contact import peak_torques, torque_factors
from ..effects.pipeline import Context, figures
from ..mechanics.forces import (TrainLoads, float_speed, grid_load_parts, min_contact_forces, sampled_parts,
                                smooth_pieces)

RIGID = ("min_contact_force_N", "float_speed_rpm", "max_camshaft_torque_Nm")


def speeds_of(scene, rpms) -> np.ndarray:
    """Camshaft speeds (rad/s) of the scene at each of `rpms`: Drive.omega's arithmetic
    (rpm * 2 pi / 60, in that order) on the array, the floats a scene built with each rpm has
    (tests/test_sweep_engine.py checks them against Drive.omega) without a scene per run
    (dataclasses.replace was 10 % of a 1000-speed sweep)."""
    return np.asarray(rpms, dtype=float) * 2.0 * math.pi / 60.0


def rigid_over_speeds(scene, omegas, names, shared, group=None) -> dict[str, np.ndarray]:
    """{name: value per run} of the rigid names asked for, for the scene at the camshaft speeds
    `omegas` (rad/s; the runs of a group differ in speed only). `group`: a hashable key of the
    scene's values other than the speed within one sweep (its varied values but drive.rpm), under
    which the torque factors are kept across the sweep's chunks; None: made for this call."""
    if shared.lift is None:
        shared.lift = scene.gear_plugin.build_lift(scene)
    lift = shared.lift
    omegas = np.asarray(omegas, dtype=float)
    out: dict[str, np.ndarray] = {}
    ratio, lash = scene.follower.ratio, scene.valve.lash
    if "min_contact_force_N" in names or "float_speed_rpm" in names:
        loads = TrainLoads.from_scene(scene)
        n_grid = max(4096, scene.solver.steps_per_revolution)
        pieces = remember(shared.of("forces pieces"), (ratio, lash, n_grid), lambda: smooth_pieces(lift, ratio, lash, n_grid))
        # the open pieces' samples and A, G there: the same for every chunk of the sweep and for
        # the float speed (made once, as the pieces)
        parts = remember(shared.of("forces samples"), (ratio, lash, n_grid, loads),
                         lambda: sampled_parts(lift, loads, ratio, lash, pieces, n_grid))
        f_min, _ = min_contact_forces(lift, loads, omegas, ratio, lash, pieces, n_grid, parts)
        out["min_contact_force_N"] = f_min  # +inf: the valve never opens, as effects.forces.forces_row writes it
        jump = remember(shared.of("forces jumps"), (ratio, lash, n_grid, loads),
                        lambda: float_speed(lift, loads, ratio, lash, pieces, n_grid, parts))
        out["float_speed_rpm"] = np.full(omegas.size, jump.rpm if math.isfinite(jump.omega) else math.nan)
    if "max_camshaft_torque_Nm" in names:
        # speed-independent: made once per distinct loads, lash and grid (as the pieces above)
        n = scene.solver.steps_per_revolution
        lash = scene.valve.lash if scene.valve is not None else 0.0
        key = (TrainLoads.from_scene(scene), ratio, lash, n)
        theta, a_coef, g_part, is_open = remember(shared.of("contact grid"), key, lambda: grid_load_parts(scene, lift))
        def factors():
            # the kinematics' geometry columns at the first speed (the pipeline's run of that
            # effect alone): the factors do not depend on the speed (torque_factors; the same
            # floats at any speed for every gear with a contact, checked in tests/test_sweep_kernel.py),
            # so a group's chunks share them
            kinematics = figures(scene, shared, effects=("kinematics",))
            ctx = Context(scene, theta, kinematics.columns["time_s"], lift, kinematics.columns, MappingProxyType({}))
            return torque_factors(ctx)

        push, pull = factors() if group is None else remember(shared.of("torque factors"), (key, group), factors)
        out["max_camshaft_torque_Nm"] = peak_torques(a_coef, g_part, is_open, push, pull, omegas, compiled=True)
    return out
