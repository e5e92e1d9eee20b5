"""Effect `forces`: the rigid valve-train loads of a scene (explorer.mechanics.forces holds the physics)."""

from __future__ import annotations

import math

import numpy as np

from ..core.memo import remember
from ..mechanics.forces import (TrainLoads, contact_loss_intervals, float_speed, loss_report, max_contact_force,
                                min_contact_force, rigid_train_forces, side_extremes, smooth_pieces)
from ..mechanics.moving_mass import rigid_mass
from ..result import EffectOutput, Event


def forces_effect(ctx) -> EffectOutput:
    scene, w = ctx.scene, ctx.omega
    loads = TrainLoads.from_scene(scene)
    ratio = scene.follower.ratio
    lash = scene.valve.lash
    c = ctx.columns
    columns = rigid_train_forces(c["rigid_valve_lift_m"], c["rigid_valve_velocity_m_s"], c["rigid_valve_accel_m_s2"],
                                 loads, ratio)
    n_grid = max(4096, scene.solver.steps_per_revolution)
    pieces = smooth_pieces(ctx.lift, ratio, lash, n_grid)
    f_min, f_theta = min_contact_force(ctx.lift, loads, w, ratio, lash, pieces, n_grid)
    jump = float_speed(ctx.lift, loads, ratio, lash, pieces, n_grid)
    sides = side_extremes(ctx.lift, loads, w, ratio, lash, pieces, n_grid)
    f_max, f_max_theta = max_contact_force(ctx.lift, loads, w, ratio, lash, pieces, n_grid)
    is_open = np.asarray(c["rigid_valve_lift_m"]) > 0.0

    summary: dict = {
        "min_contact_force_N": f_min if math.isfinite(f_min) else None,
        "min_contact_force_cam_angle_deg": math.degrees(f_theta) if math.isfinite(f_min) else None,
        # refined as the minimum is; None when the valve never opens
        "max_contact_force_N": f_max if math.isfinite(f_max) else None,
        "max_contact_force_cam_angle_deg": math.degrees(f_max_theta) if math.isfinite(f_max) else None,
        # virtual work through the rigid lever (valve travel = ratio x follower travel): F_f = ratio F_v
        "max_follower_force_N": ratio * f_max if math.isfinite(f_max) else None,
        "max_spring_force_N": float(columns["spring_force_N"].max()),
        # over the open valve: the spring's reserve against the inertia (a seated valve's margin is
        # its seat load, another figure); None when the valve never opens
        "min_spring_margin_N": float(columns["spring_margin_N"][is_open].min()) if is_open.any() else None,
        "jump_speed_rpm": jump.rpm if math.isfinite(jump.omega) else None,
        "jump_cam_angle_deg": math.degrees(jump.theta) if math.isfinite(jump.theta) else None,
        "valve_floats": bool(math.isfinite(jump.omega) and w >= jump.omega),
        "friction_N": loads.friction,
        "closing_loads_N": loads.closing,
        # the mass M of F = M p + ...: valve.mass and every part moving with it, referred to the valve
        **rigid_mass_summary(scene),
        # Schenker's judgement of the lift curve: spring force needed on each side and his optimum
        "opening_side": sides["opening"],
        "closing_side": sides["closing"],
        "optimum_deceleration_difference_m_s2": 2.0 * loads.friction / loads.mass,
    }
    p1, p2 = sides["opening"]["peak_deceleration_m_s2"], sides["closing"]["peak_deceleration_m_s2"]
    summary["deceleration_difference_m_s2"] = (p2 - p1) if p1 is not None and p2 is not None else None
    f1, f2 = sides["opening"]["required_spring_force_N"], sides["closing"]["required_spring_force_N"]
    summary["wasted_spring_force_N"] = abs(f2 - f1) if f1 is not None and f2 is not None else None

    warnings: list[str] = []
    events: list[Event] = []
    if jump.static_loss:
        warnings.append(
            f"valve float at any speed: the spring and closing loads do not hold the valve on the cam "
            f"even at standstill (cam angle {math.degrees(jump.theta):.2f} deg)"
        )
    intervals = contact_loss_intervals(ctx.lift, loads, w, ratio, lash, pieces, n_grid) if f_min < 0.0 else []
    summary["contact_loss_cam_angles_deg"] = [[math.degrees(a), math.degrees(b)] for a, b in intervals]
    loss_events, phrase = loss_report(intervals, w, f_min, f_theta)
    events.extend(Event.of(e) for e in loss_events)
    if not jump.static_loss and summary["valve_floats"]:
        # one set of angles, those of this speed; the float speed's own angle is named as such
        warnings.append(
            f"valve float: {scene.drive.rpm:.6g} rpm is at or above the float (jump) speed {jump.rpm:.6g} rpm "
            f"(at which contact is first lost, at cam angle {math.degrees(jump.theta):.2f} deg); at "
            f"{scene.drive.rpm:.6g} rpm " + (phrase or f"the least rigid contact force is {f_min:.4g} N at cam angle "
                                                     f"{math.degrees(f_theta):.2f} deg")
        )
    seat_force = loads.preload + loads.closing
    if seat_force < 0.0:
        warnings.append(
            f"valve lifts off its seat: opening loads exceed the preload by {-seat_force:.4g} N "
            f"(closing loads {loads.closing:.4g} N, preload {loads.preload:.4g} N)"
        )
    # [spring_design] adds its block to this summary through the pipeline (the effect table's sections)
    return EffectOutput(columns=columns, summary=summary, events=tuple(events), warnings=tuple(warnings))


def rigid_mass_summary(scene) -> dict:
    """rigid_mass_kg (the M the rigid forces use, TrainLoads.from_scene's) and its shares by part
    (kg at the valve: valve.mass, each part of the train, the spring's third where it is masses)."""
    rigid = rigid_mass(scene)
    return {"rigid_mass_kg": rigid.total, "rigid_mass_parts_kg": rigid.shares()}


def forces_figures(ctx, cache) -> EffectOutput:
    """The forces effect's figures for sweeps: its columns, the refined minimum contact force at
    this speed and the float speed (kept across the runs: it does not depend on the speed, nor do
    the lift's smooth pieces); the side figures and loss intervals, which no row holds, are left out."""
    scene, w = ctx.scene, ctx.omega
    loads = TrainLoads.from_scene(scene)
    ratio, lash = scene.follower.ratio, scene.valve.lash
    c = ctx.columns
    n_grid = max(4096, scene.solver.steps_per_revolution)
    columns = rigid_train_forces(c["rigid_valve_lift_m"], c["rigid_valve_velocity_m_s"], c["rigid_valve_accel_m_s2"],
                                 loads, ratio)
    pieces = remember(cache.of("forces pieces"), (ratio, lash, n_grid),
                      lambda: smooth_pieces(ctx.lift, ratio, lash, n_grid))
    f_min, _ = min_contact_force(ctx.lift, loads, w, ratio, lash, pieces, n_grid)
    jump = remember(cache.of("forces jumps"), (ratio, lash, n_grid, loads),
                    lambda: float_speed(ctx.lift, loads, ratio, lash, pieces, n_grid))
    return EffectOutput(columns=columns, summary={"min_contact_force_N": f_min if math.isfinite(f_min) else None,
                                                  "jump_speed_rpm": jump.rpm if math.isfinite(jump.omega) else None})


def forces_row(result) -> dict[str, float]:
    """A sweep row's forces figures: the refined minimum contact force (+inf: the valve never opens,
    no contact to lose) and the float speed (NaN: it never floats)."""
    f_min, jump = result.summary.get("min_contact_force_N"), result.summary.get("jump_speed_rpm")
    return {"min_contact_force_N": math.inf if f_min is None else float(f_min),
            "float_speed_rpm": math.nan if jump is None else float(jump)}
