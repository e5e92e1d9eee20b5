"""Effect `contact`: the contact statics of a scene's gear (explorer.mechanics.contact holds the
physics; the gear gives its contact geometry and may add figures of its own)."""

from __future__ import annotations

import math
from dataclasses import replace
from types import MappingProxyType

import numpy as np

from ..mechanics.contact import (ContactGeometry, ContactSpec, allowable_label, contact_loads, effective_modulus,
                                 hertz_line_stress, hertz_width, self_locking_worst)
from ..result import EffectOutput


def contact_geometry(ctx) -> ContactGeometry:
    """The contact geometry of the scene's gear over ctx.theta (explorer.gears.base.Gear, item 6)."""
    ctx.gear.check_contact(ctx.scene.follower, ctx.scene.source)
    return ctx.gear.contact_geometry(ctx)


# The effect that gives the cam's dynamic load, referred to the valve, as linkage_force_N: the
# elastic effect in every form (one mass, the spring chain, the train of parts: its cam contact's
# force). When a scene has it, the statics run a second time on that force (the `dynamic_` figures):
# the cam carries the elastic train's force, not the rigid train's (beyond the float speed the
# rigid one is even negative where the elastic valve still presses on the cam after a rebound).
DYNAMIC_SOURCE = ("elastic", "linkage_force_N")
# The figures of the statics that scale with the force and that a designer judges: the normal force,
# the camshaft torque and every Hertz stress (the gear's own: the tip's, the face's, ...).
DYNAMIC_FIGURES = ("cam_normal_force_N", "camshaft_torque_Nm")
DYNAMIC_STRESSES = "hertz_stress_Pa"  # each column ending so


def _dynamic(name: str) -> bool:
    return name in DYNAMIC_FIGURES or name.endswith(DYNAMIC_STRESSES)


def _statics(ctx, geometry: ContactGeometry, spec: ContactSpec, e_star: float, width: float | None,
             force) -> tuple[dict, dict, float, str]:
    """(columns, the gear's summary, the width, its rule) of the contact statics for the valve-side
    contact force `force` (on ctx.theta); `width` None: the scene's width, else the width rule's
    for these loads."""
    alpha, contour_radius = np.asarray(geometry.pressure_angle), np.asarray(geometry.contour_radius)
    columns = contact_loads(geometry, force, ctx.columns["follower_velocity_m_s"], spec.friction_angle)
    normal = columns["cam_normal_force_N"]
    required_width, rule = hertz_width(normal, geometry, spec, e_star)
    if width is None:
        width = spec.width if spec.width is not None else required_width
    if width > 0.0:
        sigma = hertz_line_stress(normal, width, geometry.counter_radius, contour_radius, e_star)
    else:
        sigma = np.zeros_like(normal)
    columns["hertz_stress_Pa"] = sigma
    if not geometry.from_columns:  # reuse the kinematics' geometry columns when they exist; add them otherwise
        columns["pressure_angle_deg"] = np.degrees(alpha)
        columns["contour_radius_m"] = contour_radius
    gear_columns, gear_summary = ctx.gear.contact_figures(ctx, geometry, MappingProxyType(columns))
    columns.update(gear_columns)
    return columns, gear_summary, width, (required_width, rule)


def _contact(ctx) -> tuple[ContactSpec, ContactGeometry, float]:
    """The scene's [contact] (or the defaults), its gear's contact geometry and E*."""
    spec: ContactSpec = ctx.scene.contact if ctx.scene.contact is not None else ContactSpec()
    e_star = effective_modulus(spec.youngs_modulus, spec.poisson_ratio, spec.roller_youngs_modulus, spec.roller_poisson_ratio)
    return spec, contact_geometry(ctx), e_star


def contact_effect(ctx) -> EffectOutput:
    scene = ctx.scene
    spec, geometry, e_star = _contact(ctx)
    columns, gear_summary, width, (required_width, rule) = _statics(ctx, geometry, spec, e_star, None,
                                                                  ctx.columns["contact_force_N"])
    alpha, contour_radius = np.asarray(geometry.pressure_angle), np.asarray(geometry.contour_radius)
    rho = spec.friction_angle
    normal, torque, margin = columns["cam_normal_force_N"], columns["camshaft_torque_Nm"], columns["self_locking_margin_deg"]
    sigma = columns["hertz_stress_Pa"]

    finite_normal = np.where(np.isfinite(normal), normal, np.nan)
    max_normal = float(np.nanmax(finite_normal)) if np.isfinite(finite_normal).any() else 0.0
    theta_deg = np.degrees(ctx.theta)
    i_alpha = int(np.argmax(np.abs(alpha)))
    i_margin = self_locking_worst(margin, ctx.columns["follower_velocity_m_s"])
    finite_torque = np.where(np.isfinite(torque), torque, np.nan)
    i_torque = int(np.nanargmax(finite_torque)) if np.isfinite(finite_torque).any() else 0
    i_sigma = int(np.argmax(np.where(np.isfinite(sigma), sigma, -1.0)))
    convex = contour_radius > 0.0
    peak_alpha, peak_at = float(np.degrees(np.abs(alpha[i_alpha]))), float(theta_deg[i_alpha])
    # where the contact's pressure angles are the kinematics' own column (geometry.from_columns: a
    # translating roller), the kinematics' extremum refined between the samples
    # (effects/contour.geometry_extremes) is the figure: one pressure angle under both names, not a
    # sampled one beside an exact one (>=: the column's degrees back from radians, to rounding)
    exact = ctx.summary.get("max_abs_pressure_angle_deg")
    if geometry.from_columns and exact is not None and exact >= peak_alpha * (1.0 - 1e-12):
        peak_alpha, peak_at = float(exact), float(ctx.summary["max_abs_pressure_angle_at_deg"])
    summary = {
        "contact_follower_type": scene.follower.type,
        "max_pressure_angle_deg": peak_alpha,
        "max_pressure_angle_cam_angle_deg": peak_at,
        "friction_angle_deg": math.degrees(rho),
        "min_self_locking_margin_deg": float(margin[i_margin]),
        "min_self_locking_margin_cam_angle_deg": float(theta_deg[i_margin]),
        "max_cam_normal_force_N": max_normal,
        "max_camshaft_torque_Nm": float(finite_torque[i_torque]) if np.isfinite(finite_torque).any() else None,
        "max_camshaft_torque_cam_angle_deg": float(theta_deg[i_torque]),
        "min_camshaft_torque_Nm": float(np.nanmin(finite_torque)) if np.isfinite(finite_torque).any() else None,
        "max_hertz_stress_Pa": float(sigma[i_sigma]),
        "max_hertz_stress_cam_angle_deg": float(theta_deg[i_sigma]),
        "max_hertz_stress_convex_Pa": float(np.max(np.where(convex, sigma, 0.0))),
        "max_hertz_stress_concave_Pa": float(np.max(np.where(~convex, sigma, 0.0))),
        "hertz_width_m": width,
        "hertz_width_from_rule": spec.width is None,
        "effective_modulus_Pa": e_star,
        "hertz_allowable_Pa": spec.allowable_stress,
        "hertz_allowable_source": spec.allowable_source,
        "hertz_utilisation": float(sigma[i_sigma] / spec.allowable_stress),
        "required_cam_width_m": required_width,
        "required_cam_width_rule": rule,
        **gear_summary,
    }
    # seed 004's width rule b = P/(k D) and its engines' allowables: named only where they act (the
    # width rule sizes the width; no allowable of the scene's own), not as 1902 defaults
    # beside a modern gear's Hertz figures
    if rule == "P/(k D)":
        summary.update({"width_rule_k_Pa": spec.width_rule_k, "valve_kind": spec.valve})
    if spec.allowable_source != "given":
        summary["engine"] = spec.engine
    warnings: list[str] = []
    if margin[i_margin] <= 0.0:
        warnings.append(
            f"self-locking: pressure angle {math.degrees(abs(alpha[i_margin])):.3f} deg + friction angle "
            f"{math.degrees(rho):.3f} deg reaches 90 deg at cam angle {theta_deg[i_margin]:.2f} deg while the cam "
            f"lifts the follower (margin {margin[i_margin]:.3f} deg)"
        )
    if not np.isfinite(normal).all():
        warnings.append("contact: the cam cannot lift the follower where it is self-locked (infinite normal force)")
    if sigma[i_sigma] > spec.allowable_stress:
        warnings.append(
            f"contact stress: Hertz {sigma[i_sigma] / 1e6:.4g} MPa at cam angle {theta_deg[i_sigma]:.2f} deg exceeds "
            f"the allowable {spec.allowable_stress / 1e6:.4g} MPa ({allowable_label(spec)}) for width "
            f"{width * 1e3:.4g} mm"
        )
    # the gear's own contact stresses (a crowned face's ellipse, a valve tip's): judged against the
    # same allowable, named by their column
    for name, values in columns.items():
        if name != "hertz_stress_Pa" and name.endswith(DYNAMIC_STRESSES):
            warnings.extend(_beyond(name, np.asarray(values, dtype=float), theta_deg, spec, ""))
    summary.update(_governing(columns, spec, ""))
    if spec.width is not None and spec.width < required_width:
        warnings.append(
            f"cam width {spec.width * 1e3:.4g} mm is below the required {required_width * 1e3:.4g} mm ({rule})"
            if rule != "P/(k D)" else
            f"cam width {spec.width * 1e3:.4g} mm is below the width rule b = P/(k D) = {required_width * 1e3:.4g} mm"
        )
    effect, column = DYNAMIC_SOURCE
    if effect in ctx.done:
        dynamic, dynamic_summary, dynamic_warnings = dynamic_statics(ctx, geometry, spec, e_star, width,
                                                                     ctx.columns[column])
        columns.update(dynamic)
        summary.update(dynamic_summary)
        warnings.extend(dynamic_warnings)
    return EffectOutput(columns=columns, summary=summary, warnings=tuple(warnings))


def dynamic_statics(ctx, geometry: ContactGeometry, spec: ContactSpec, e_star: float, width: float,
                    force) -> tuple[dict, dict, list[str]]:
    """The statics on the elastic train's cam force `force` (valve-referred, >= 0): the same
    geometry, friction and contact width as the rigid statics (the width is the design's, not one
    the rule would give for these loads), the gear's own figures computed on that force (its
    ctx sees it as contact_force_N). Columns `dynamic_<name>` for each DYNAMIC_FIGURES column and
    Hertz stress, and per column its largest value (max_dynamic_<name>) and cam angle; the
    governing stress's utilisation (the largest Hertz column's) and a warning for each column
    beyond the allowable."""
    force = np.asarray(force, dtype=float)
    dctx = replace(ctx, columns=MappingProxyType({**ctx.columns, "contact_force_N": force}))
    statics, _, _, _ = _statics(dctx, geometry, spec, e_star, width, force)
    theta_deg = np.degrees(ctx.theta)
    columns: dict[str, np.ndarray] = {}
    summary: dict = {"dynamic_contact_force_from": f"{DYNAMIC_SOURCE[1]} of the {DYNAMIC_SOURCE[0]} effect"}
    for name, values in statics.items():
        if not _dynamic(name):
            continue
        values = np.asarray(values, dtype=float)
        columns[f"dynamic_{name}"] = values
        finite = np.where(np.isfinite(values), values, -np.inf)
        i = int(np.argmax(finite))
        stem = name.rpartition("_")[0]
        summary[f"max_dynamic_{name}"] = float(values[i]) if np.isfinite(values[i]) else None
        summary[f"max_dynamic_{stem}_cam_angle_deg"] = float(theta_deg[i]) if np.isfinite(values[i]) else None
    summary.update(_governing(columns, spec, "dynamic_"))
    summary["dynamic_hertz_utilisation"] = summary.pop("dynamic_governing_hertz_utilisation")
    warnings = []
    for name, values in columns.items():
        if name.endswith(DYNAMIC_STRESSES):
            warnings.extend(_beyond(name, values, theta_deg, spec, "under the elastic train's force: "))
    return columns, summary, warnings


def _governing(columns, spec: ContactSpec, prefix: str) -> dict:
    """The largest of the Hertz stress columns (the line contact's and the gear's own: a crowned
    face, a valve tip), which governs the design: its column and its ratio to the allowable."""
    stresses = {name: float(np.max(v))
                for name, v in columns.items() if name.startswith(prefix) and name.endswith(DYNAMIC_STRESSES)}
    name = max(stresses, key=stresses.get)
    return {f"{prefix}governing_hertz_stress": name,
            f"{prefix}governing_hertz_utilisation": stresses[name] / spec.allowable_stress}


def _beyond(name: str, values: np.ndarray, theta_deg: np.ndarray, spec: ContactSpec, how: str) -> list[str]:
    """A warning when the stress column `name` exceeds the allowable (none otherwise)."""
    i = int(np.argmax(values))
    if not values[i] > spec.allowable_stress:
        return []
    return [f"contact stress {how}{name} {values[i] / 1e6:.4g} MPa at cam angle {theta_deg[i]:.2f} deg exceeds the "
            f"allowable {spec.allowable_stress / 1e6:.4g} MPa ({allowable_label(spec)})"]


def contact_figures(ctx, cache) -> EffectOutput:
    """The contact effect's figures for sweeps: the rigid statics (a sweep row holds the rigid peak
    camshaft torque: the compiled sweep computes it at every speed from the rigid forces), without
    the dynamic pass, whose figures no row holds."""
    spec, geometry, e_star = _contact(ctx)
    columns, _, _, _ = _statics(ctx, geometry, spec, e_star, None, ctx.columns["contact_force_N"])
    torque = columns["camshaft_torque_Nm"]
    finite = np.where(np.isfinite(torque), torque, np.nan)
    peak = float(np.nanmax(finite)) if np.isfinite(finite).any() else None
    return EffectOutput(columns=columns, summary={"max_camshaft_torque_Nm": peak})


def contact_row(result) -> dict[str, float]:
    """A sweep row's contact figure: the peak camshaft torque (NaN: none finite)."""
    torque = result.summary.get("max_camshaft_torque_Nm")
    return {"max_camshaft_torque_Nm": math.nan if torque is None else float(torque)}


# --- the peak camshaft torque at many speeds at once -------------------------------------------

BLOCK_CELLS = 2_000_000  # speeds x samples per block (16 MB of float64)



def torque_factors(ctx) -> tuple[np.ndarray, np.ndarray]:
    """(c_push, c_pull) per sample of ctx.theta: the rigid camshaft torque is T = c F with c = c_push
    where the valve-side contact force F > 0, c_pull where F < 0, from this effect's own geometry
    and laws (explorer.mechanics.contact.contact_loads: T = N arm, N = ratio F / (cos a - mu sin a
    sign v) when pushing, ratio F / cos a when pulling; inf: self-locked). The geometry and the
    sign of the follower's velocity do not depend on the speed (ctx: the kinematics' columns at any
    one speed)."""
    geometry = contact_geometry(ctx)
    spec = ctx.scene.contact if ctx.scene.contact is not None else ContactSpec()
    alpha = np.abs(np.asarray(geometry.pressure_angle, dtype=float))
    v = np.sign(np.asarray(ctx.columns["follower_velocity_m_s"], dtype=float))
    arm = np.asarray(geometry.ratio, dtype=float) * np.asarray(geometry.torque_arm, dtype=float)
    denominator = np.cos(alpha) - math.tan(spec.friction_angle) * np.sin(alpha) * v
    with np.errstate(divide="ignore", invalid="ignore"):
        push = np.where(denominator > 0.0, arm / denominator, np.inf)
        pull = arm / np.cos(alpha)
    return push, pull


def peak_torques(a_coef, g_part, is_open, push, pull, omegas, compiled: bool = False) -> np.ndarray:
    """max_camshaft_torque_Nm (N m) at each speed of `omegas` (rad/s) from F = w^2 A + G on the
    scene's grid (explorer.mechanics.forces.grid_load_parts) and the torque factors: the largest
    finite torque (closed samples carry no force: 0 there; NaN where none is finite). `compiled`:
    the same floats from one compiled loop (mechanics/sweep_loops.py: ahead of time or numba; the
    compiled sweep, whose elastic kernel is compiled the same way), else numpy in blocks (the browser's speed sweep, which must
    not load numba)."""
    w2 = np.asarray(omegas, dtype=float).ravel() ** 2
    a_coef, g_part, push, pull = a_coef[is_open], g_part[is_open], push[is_open], pull[is_open]
    if a_coef.size == 0:
        return np.zeros(w2.size)
    floor = 0.0 if not is_open.all() else -np.inf
    if compiled:
        from ..mechanics.sweep_loops import peak_torques as kernel  # compiled: the compiled sweep's path only

        out = kernel(w2, np.ascontiguousarray(a_coef), np.ascontiguousarray(g_part), np.ascontiguousarray(push),
                     np.ascontiguousarray(pull), floor)
        return np.where(np.isfinite(out), out, np.nan)
    out = np.full(w2.size, floor)
    block = max(1, BLOCK_CELLS // a_coef.size)
    for start in range(0, w2.size, block):
        end = min(w2.size, start + block)
        forces = w2[start:end, None] * a_coef[None, :] + g_part[None, :]
        with np.errstate(invalid="ignore"):
            torque = forces * np.where(forces > 0.0, push[None, :], pull[None, :])
        torque = np.where(np.isfinite(torque), torque, -np.inf)  # self-locked samples: no finite torque
        out[start:end] = np.maximum(out[start:end], torque.max(axis=1))
    return np.where(np.isfinite(out), out, np.nan)
