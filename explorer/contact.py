"""Cam-roller contact statics and sizing (seed 004): normal force, pressure angle, self-locking,
camshaft torque, Hertz line-contact stress, the historic width rule - for the translating roller
and the seeds' other gears (pivoted roller lever, eccentric-driven rocking cam, rolling lever).

One statics for every gear. Each gear describes its contact by a ContactGeometry (per cam angle):
the pressure angle alpha between the contact normal and the direction in which the driven point
(roller centre, or the valve lever's point of the rolling faces) travels to open the valve; the
instantaneous ratio q = valve travel per travel of that point; the camshaft torque per newton of
normal force; and the radii of curvature of the two surfaces. The driven point must be pushed
along its travel with P = q F (F the valve-side contact force of the forces effect, which holds
the train's masses; the linkage itself is massless).

Statics of the driven point (seed 004: the roller's travel treated as a straight guide, "radial
roller travel"). The free roller passes the contact force along the contact normal, tilted by alpha
from the travel; the guide (for a lever: the pivot, lumped into the same guide friction) pushes
back sideways with N |sin alpha| and its friction mu = tan(rho) acts along the travel against the
motion:
    N (cos alpha - mu |sin alpha| sgn v) = P   ->   N = P cos rho / cos(|alpha| + rho sgn v).
While the cam lifts the follower (v > 0) this blows up at |alpha| + rho = 90 deg: self-locking
(seed 004: "bei alpha + rho = 90 deg tritt Selbstsperrung ein"); the margin 90 - rho - |alpha| says
how far off that is. The force on the cam acts along the normal, so the torque the shaft supplies
is N times the moment arm of that line (about the camshaft; for a rocking cam or rolling lever
about its pivot, carried to the eccentric shaft by the four-bar's ratio dchi/dtheta). Geometry,
not virtual work: the tests check T w = F v without friction, and T w >= F v with it.
A rolling lever's faces roll without sliding, so its friction angle stands for the pivots'
friction lumped the same way; its margin says how far the frictionless normal is from square to
the travel (circular faces, k = 0, would have alpha = 90 deg and could drive only by friction).

Hertz line contact between two cylinders of signed radii r1, r2 (> 0 convex, < 0 concave):
sigma_max = sqrt(N E* / (pi b R*)), 1/R* = 1/r1 + 1/r2, 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2.
Seed 004's allowables: 3500 kgf/cm^2 for large gas engines, about 4000 kgf/cm^2 for Diesel
engines; and the width rule b = P/(k D) with the roller diameter D, k = 10 (intake) or up to 40
(exhaust) kgf/cm^2. A rolling lever has no roller: it is sized as seed 004 says rolling levers
are, by the Hertz allowable (the width at which the peak stress equals it).

The trip gear has no cam surface: its latch lifts the valve spindle directly and lets go. Its
contact statics are the latch face's (explorer.gears.trip_effects, its variant of this effect in
the gear registry): the latch force at the release, the friction the trip must overcome to pull
the latch out, the face's bearing pressure; their keys are in [gear.trip] (latch_friction,
latch_width, latch_depth), not in [contact].

Scene section [contact] (all optional):
    friction_angle        rho of the follower guide (default 0 deg), or
    friction_coefficient  mu = tan(rho)
    youngs_modulus, poisson_ratio                cam material (default steel: 210 GPa, 0.3)
    roller_youngs_modulus, roller_poisson_ratio  roller material (default: as the cam)
    width                 contact width b (default: the width rule's width)
    valve                 "exhaust" (default) or "intake": picks the width-rule k
    width_rule_k          k of b = P/(k D) (default 40 kgf/cm^2 exhaust, 10 kgf/cm^2 intake)
    engine                "large-gas" (default, 3500 kgf/cm^2) or "diesel" (4000 kgf/cm^2)
    allowable_stress      explicit allowable contact stress (replaces the engine's)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .gears.registry import effect_variant, gear
from .result import EffectOutput
from .ranges import FRICTION_COEFFICIENT
from .units import AT

STEEL_E = 210e9  # Pa
STEEL_NU = 0.3
ALLOWABLE = {"large-gas": 3500.0 * AT, "diesel": 4000.0 * AT}  # Pa, seed 004
WIDTH_RULE_K = {"intake": 10.0 * AT, "exhaust": 40.0 * AT}  # Pa (kgf/cm^2), seed 004


@dataclass(frozen=True)
class ContactSpec:
    friction_angle: float = 0.0  # rad, follower guide
    youngs_modulus: float = STEEL_E  # Pa, cam
    poisson_ratio: float = STEEL_NU
    roller_youngs_modulus: float = STEEL_E  # Pa
    roller_poisson_ratio: float = STEEL_NU
    width: float | None = None  # m; None: the width rule's width
    valve: str = "exhaust"
    width_rule_k: float = WIDTH_RULE_K["exhaust"]  # Pa
    engine: str = "large-gas"
    allowable_stress: float = ALLOWABLE["large-gas"]  # Pa


ROLLER_TYPES = ("translating-roller", "pivoted-roller", "rocking-cam")  # a cam surface on a roller
CONTACT_TYPES = ROLLER_TYPES + ("rolling-lever",)  # + two faces rolling on each other


def check_follower(follower, file: str) -> None:
    """The follower types the contact statics cover; a roller where the width rule needs one."""
    if effect_variant(follower.type, "contact") is not None:  # the gear's own statics (the trip gear's latch)
        return
    if follower.type not in CONTACT_TYPES:
        raise InputError(file, "follower.type", f"effect 'contact' does not model follower type {follower.type!r}")
    if follower.type in ROLLER_TYPES and follower.roller_radius <= 0.0:
        raise InputError(file, "follower.roller_radius",
                         "effect 'contact' needs a roller (roller_radius > 0) for the Hertz stress and the width rule")


def parse_contact_section(table, fields) -> ContactSpec:
    """[contact] -> ContactSpec; called with table None when the effect runs without the section."""
    file = fields.get("source", "<memory>")
    follower = fields.get("follower")
    if "contact" in fields.get("effects", ()) and follower is not None:
        check_follower(follower, file)
    if table is None:
        return ContactSpec()
    entry = gear(follower.type) if follower is not None else None
    if entry is not None and "contact" in entry.rejected:  # the trip gear: no cam and roller
        raise InputError(file, "contact", entry.rejected["contact"])
    table.reject_unknown((
        "friction_angle", "friction_coefficient", "youngs_modulus", "poisson_ratio", "roller_youngs_modulus",
        "roller_poisson_ratio", "width", "valve", "width_rule_k", "engine", "allowable_stress",
    ))
    if table.has("friction_angle") and table.has("friction_coefficient"):
        raise table.error("friction_coefficient", "give friction_angle or friction_coefficient, not both")
    if table.has("friction_coefficient"):
        mu = table.number("friction_coefficient", minimum=FRICTION_COEFFICIENT[0], maximum=FRICTION_COEFFICIENT[1])
        rho = math.atan(mu)
    else:
        rho = table.quantity("friction_angle", "angle", 0.0)
        if not 0.0 <= rho < 0.5 * math.pi:
            raise table.error("friction_angle", f"must lie in [0 deg, 90 deg), got {table.raw('friction_angle')!r}")
    e_cam = table.quantity("youngs_modulus", "pressure", STEEL_E, positive=True)
    nu_cam = table.number("poisson_ratio", STEEL_NU, minimum=-1.0, maximum=0.5, open_minimum=True, open_maximum=True)
    valve = table.string("valve", "exhaust", choices=tuple(WIDTH_RULE_K))
    engine = table.string("engine", "large-gas", choices=tuple(ALLOWABLE))
    return ContactSpec(
        friction_angle=rho,
        youngs_modulus=e_cam,
        poisson_ratio=nu_cam,
        roller_youngs_modulus=table.quantity("roller_youngs_modulus", "pressure", e_cam, positive=True),
        roller_poisson_ratio=table.number("roller_poisson_ratio", nu_cam, minimum=-1.0, maximum=0.5,
                                          open_minimum=True, open_maximum=True),
        width=table.quantity("width", "length", positive=True) if table.has("width") else None,
        valve=valve,
        width_rule_k=table.quantity("width_rule_k", "pressure", WIDTH_RULE_K[valve], positive=True),
        engine=engine,
        allowable_stress=table.quantity("allowable_stress", "pressure", ALLOWABLE[engine], positive=True),
    )


# --- formulas -------------------------------------------------------------------------------------


def effective_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """E* of two elastic bodies in contact: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2."""
    for key, e, nu in (("youngs_modulus", e1, nu1), ("roller_youngs_modulus", e2, nu2)):
        if not (math.isfinite(e) and e > 0.0):
            raise InputError("<arguments>", key, f"must be greater than zero, got {e!r}")
        if not (-1.0 < nu < 0.5):
            raise InputError("<arguments>", key.replace("youngs_modulus", "poisson_ratio"),
                             f"must lie in (-1, 0.5), got {nu!r}")
    return 1.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2)


def hertz_line_stress(force, width: float, roller_radius, contour_radius, e_star: float) -> np.ndarray:
    """Peak Hertz pressure of a line contact, sigma = sqrt(F E* / (pi b R*)), 1/R* = 1/r + 1/rho_c.

    Both radii are signed (> 0 convex, < 0 concave, inf flat): the roller's (or the driven face's)
    and the contour's; force <= 0 gives 0 (no contact)."""
    force = np.asarray(force, dtype=float)
    with np.errstate(divide="ignore"):
        curvature = 1.0 / np.asarray(roller_radius, dtype=float) + 1.0 / np.asarray(contour_radius, dtype=float)
    loaded = np.maximum(force, 0.0)
    with np.errstate(invalid="ignore"):
        sigma = np.sqrt(loaded * e_star * curvature / (math.pi * width))
    # a concave flank tighter than the roller cannot carry it (the envelope would interfere)
    return np.where(curvature > 0.0, sigma, np.where(loaded > 0.0, np.inf, 0.0))


def roller_normal_force(follower_force, pressure_angle, follower_velocity, friction_angle: float) -> np.ndarray:
    """Normal force between cam and roller for the axial follower force P (> 0 pushes the follower
    off the cam). Guide friction opposes the follower's motion. Self-locked samples (the cam cannot
    lift the follower) give inf. P <= 0 (contact would need tension) is passed through frictionless."""
    p = np.asarray(follower_force, dtype=float)
    alpha = np.abs(np.asarray(pressure_angle, dtype=float))
    v = np.sign(np.asarray(follower_velocity, dtype=float))
    mu = math.tan(friction_angle)
    denominator = np.cos(alpha) - mu * np.sin(alpha) * v
    with np.errstate(divide="ignore", invalid="ignore"):
        n_loaded = np.where(denominator > 0.0, p / denominator, np.inf)
        n_free = p / np.cos(alpha)
    return np.where(p > 0.0, n_loaded, np.where(p < 0.0, n_free, 0.0))


def camshaft_torque(normal_force, pressure_angle, follower_lift, base_radius: float, roller_radius: float,
                    offset: float) -> np.ndarray:
    """Torque the camshaft supplies: the roller's push acts on the cam along the contact normal
    through the roller centre q = (e, y0 + L), so T = N (e cos alpha + y sin alpha)."""
    rp = base_radius + roller_radius
    y = math.sqrt(rp * rp - offset * offset) + np.asarray(follower_lift, dtype=float)
    alpha = np.asarray(pressure_angle, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.asarray(normal_force) * (offset * np.cos(alpha) + y * np.sin(alpha))


def contact_point_radius(pressure_angle, follower_lift, base_radius: float, roller_radius: float,
                         offset: float) -> np.ndarray:
    """Distance of the contact point from the cam centre: roller centre moved by r along -normal."""
    rp = base_radius + roller_radius
    y = math.sqrt(rp * rp - offset * offset) + np.asarray(follower_lift, dtype=float)
    alpha = np.asarray(pressure_angle, dtype=float)
    return np.hypot(offset + roller_radius * np.sin(alpha), y - roller_radius * np.cos(alpha))


def width_rule(roller_force: float, roller_diameter: float, k: float) -> float:
    """Seed 004: cam width b = P / (k D) (any consistent units; SI: N, m, Pa -> m)."""
    if not roller_diameter > 0.0:
        raise InputError("<arguments>", "follower.roller_radius", "the width rule needs a roller (diameter > 0)")
    if not k > 0.0:
        raise InputError("<arguments>", "contact.width_rule_k", f"must be greater than zero, got {k!r}")
    return max(0.0, float(roller_force)) / (k * roller_diameter)


# --- the contact of each gear ------------------------------------------------------------------------


@dataclass(frozen=True)
class ContactGeometry:
    """What the statics need from a gear's geometry, per cam angle (arrays of the grid's shape).

    The driven point is the roller centre (or, for a rolling lever, the valve lever's point of the
    rolling faces); the cam body is the cam (the rocking cam, the rolling lever) turning about its
    pivot, which for a rotating cam is the camshaft."""

    pressure_angle: np.ndarray  # rad, contact normal vs the driven point's opening travel (signed)
    ratio: np.ndarray  # valve travel per travel of the driven point: P = ratio x valve force
    torque_arm: np.ndarray  # m, camshaft torque per newton of normal force
    body_arm: np.ndarray  # m, moment about the cam body's pivot per newton of normal force
    body_radius: np.ndarray  # m, distance of the contact point from the cam body's pivot
    contour_radius: np.ndarray  # m, signed radius of the cam surface at the contact (> 0 convex)
    counter_radius: np.ndarray | float  # m, signed radius of the driven surface (the roller's radius)
    roller_diameter: float | None  # m, D of the width rule b = P/(k D); None: size by the Hertz allowable
    from_columns: bool = False  # pressure angle and contour radius already are kinematics columns


def translating_geometry(ctx) -> ContactGeometry:
    """Translating roller: the kinematics' geometry columns when the cam provides them, otherwise
    the exact closed forms of explorer.geometry.translating. The roller centre q = (e, y0 + L)."""
    c, f = ctx.columns, ctx.scene.follower
    if "pressure_angle_deg" in c and "contour_radius_m" in c:
        alpha, contour_radius, reused = np.radians(c["pressure_angle_deg"]), np.asarray(c["contour_radius_m"]), True
    else:
        from .geometry.translating import profile_from_derivatives

        profile = profile_from_derivatives(ctx.theta, ctx.lift.derivatives(ctx.theta), f.base_radius, f.roller_radius,
                                           f.offset)
        alpha, contour_radius, reused = profile.pressure_angle, profile.contour_radius, False
    lift = np.asarray(c["follower_lift_m"])
    arm = camshaft_torque(1.0, alpha, lift, f.base_radius, f.roller_radius, f.offset)
    return ContactGeometry(
        pressure_angle=alpha, ratio=np.full(alpha.shape, f.ratio), torque_arm=arm, body_arm=arm,
        body_radius=contact_point_radius(alpha, lift, f.base_radius, f.roller_radius, f.offset),
        contour_radius=contour_radius, counter_radius=f.roller_radius, roller_diameter=2.0 * f.roller_radius,
        from_columns=reused,
    )


def gear_geometry(ctx) -> ContactGeometry:
    """The gear's own contact geometry (explorer.gears: pivoted.py, rocking.py, rolling.py)."""
    lift = ctx.lift
    if not hasattr(lift, "gear"):
        from .lift import build_lift

        lift = build_lift(ctx.scene)
    return lift.gear.contact_geometry(ctx.theta)


def contact_geometry(ctx) -> ContactGeometry:
    check_follower(ctx.scene.follower, ctx.scene.source)
    if ctx.scene.follower.type == "translating-roller":
        return translating_geometry(ctx)
    return gear_geometry(ctx)


def contact_loads(geometry: ContactGeometry, valve_force, velocity, friction_angle: float) -> dict[str, np.ndarray]:
    """Normal force, camshaft torque, tangential force on the cam body and self-locking margin for
    the valve-side contact force F (forces effect) and the driven point's velocity (its sign)."""
    alpha = np.asarray(geometry.pressure_angle, dtype=float)
    travel_force = geometry.ratio * np.asarray(valve_force, dtype=float)
    normal = roller_normal_force(travel_force, alpha, velocity, friction_angle)
    with np.errstate(invalid="ignore"):
        torque = normal * geometry.torque_arm
        tangential = normal * geometry.body_arm / geometry.body_radius
    return {
        "cam_normal_force_N": normal,
        "cam_tangential_force_N": tangential,
        "camshaft_torque_Nm": torque,
        "self_locking_margin_deg": 90.0 - math.degrees(friction_angle) - np.degrees(np.abs(alpha)),
    }


def hertz_width(normal, geometry: ContactGeometry, spec: ContactSpec, e_star: float) -> tuple[float, str]:
    """Required contact width and the rule that gave it: seed 004's b = P/(k D) on the largest
    normal force for a roller; for rolling faces the width at which the peak Hertz stress equals
    the allowable, b = N E* / (pi sigma^2 R*) at its worst angle."""
    finite = np.where(np.isfinite(normal), normal, np.nan)
    if geometry.roller_diameter is not None:
        max_normal = float(np.nanmax(finite)) if np.isfinite(finite).any() else 0.0
        return width_rule(max_normal, geometry.roller_diameter, spec.width_rule_k), "P/(k D)"
    with np.errstate(divide="ignore", invalid="ignore"):
        curvature = 1.0 / np.asarray(geometry.counter_radius, dtype=float) + 1.0 / np.asarray(geometry.contour_radius)
        need = np.maximum(finite, 0.0) * e_star * np.maximum(curvature, 0.0) / (math.pi * spec.allowable_stress**2)
    need = np.where(np.isfinite(need), need, np.nan)
    return (float(np.nanmax(need)) if np.isfinite(need).any() else 0.0), "hertz allowable"


# --- the effect -------------------------------------------------------------------------------------


def contact_effect(ctx) -> EffectOutput:
    scene = ctx.scene
    spec: ContactSpec = scene.contact if scene.contact is not None else ContactSpec()
    geometry = contact_geometry(ctx)
    c = ctx.columns
    alpha, contour_radius = np.asarray(geometry.pressure_angle), np.asarray(geometry.contour_radius)
    rho = spec.friction_angle
    columns = contact_loads(geometry, c["contact_force_N"], c["follower_velocity_m_s"], rho)
    normal, torque, margin = columns["cam_normal_force_N"], columns["camshaft_torque_Nm"], columns["self_locking_margin_deg"]

    finite_normal = np.where(np.isfinite(normal), normal, np.nan)
    max_normal = float(np.nanmax(finite_normal)) if np.isfinite(finite_normal).any() else 0.0
    e_star = effective_modulus(spec.youngs_modulus, spec.poisson_ratio, spec.roller_youngs_modulus, spec.roller_poisson_ratio)
    required_width, rule = hertz_width(normal, geometry, spec, e_star)
    width = spec.width if spec.width is not None else required_width
    if width > 0.0:
        sigma = hertz_line_stress(normal, width, geometry.counter_radius, contour_radius, e_star)
    else:
        sigma = np.zeros_like(normal)
    columns["hertz_stress_Pa"] = sigma
    if not geometry.from_columns:  # reuse the kinematics' geometry columns when they exist; add them otherwise
        columns["pressure_angle_deg"] = np.degrees(alpha)
        columns["contour_radius_m"] = contour_radius

    theta_deg = np.degrees(ctx.theta)
    i_alpha = int(np.argmax(np.abs(alpha)))
    i_margin = int(np.argmin(margin))
    finite_torque = np.where(np.isfinite(torque), torque, np.nan)
    i_torque = int(np.nanargmax(finite_torque)) if np.isfinite(finite_torque).any() else 0
    i_sigma = int(np.argmax(np.where(np.isfinite(sigma), sigma, -1.0)))
    convex = contour_radius > 0.0
    summary = {
        "contact_follower_type": scene.follower.type,
        "max_pressure_angle_deg": float(np.degrees(np.abs(alpha[i_alpha]))),
        "max_pressure_angle_cam_angle_deg": float(theta_deg[i_alpha]),
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
        "hertz_utilisation": float(sigma[i_sigma] / spec.allowable_stress),
        "required_cam_width_m": required_width,
        "required_cam_width_rule": rule,
        "width_rule_k_Pa": spec.width_rule_k,
        "valve_kind": spec.valve,
        "engine": spec.engine,
    }
    warnings: list[str] = []
    if margin[i_margin] <= 0.0:
        warnings.append(
            f"self-locking: pressure angle {summary['max_pressure_angle_deg']:.3f} deg + friction angle "
            f"{math.degrees(rho):.3f} deg reaches 90 deg at cam angle {theta_deg[i_margin]:.2f} deg "
            f"(margin {margin[i_margin]:.3f} deg)"
        )
    if not np.isfinite(normal).all():
        warnings.append("contact: the cam cannot lift the follower where it is self-locked (infinite normal force)")
    if sigma[i_sigma] > spec.allowable_stress:
        warnings.append(
            f"contact stress: Hertz {sigma[i_sigma] / 1e6:.4g} MPa at cam angle {theta_deg[i_sigma]:.2f} deg exceeds "
            f"the allowable {spec.allowable_stress / 1e6:.4g} MPa ({spec.engine}, seed 004) for width {width * 1e3:.4g} mm"
        )
    if spec.width is not None and spec.width < required_width:
        warnings.append(
            f"cam width {spec.width * 1e3:.4g} mm is below the required {required_width * 1e3:.4g} mm ({rule})"
            if rule != "P/(k D)" else
            f"cam width {spec.width * 1e3:.4g} mm is below the width rule b = P/(k D) = {required_width * 1e3:.4g} mm"
        )
    return EffectOutput(columns=columns, summary=summary, warnings=tuple(warnings))
