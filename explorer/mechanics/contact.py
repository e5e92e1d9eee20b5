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
(exhaust) kgf/cm^2. The width rule belongs to those cast-iron allowables: it sizes a roller only
while the allowable is seed 004's (the engine's, or the default). A scene that gives its own
allowable_stress (a modern hardened pair, several times seed 004's) is sized by it: the required
width is the one at which the peak Hertz stress equals that allowable, b = N E* (1/r1 + 1/r2) /
(pi sigma^2) at the worst angle (the finger follower's 1500 MPa pair needs 2.3 mm where the 1902
rule asks 12.9 mm). A rolling lever has no roller: it is sized as seed 004 says rolling levers
are, by the Hertz allowable, whichever allowable that is.

The trip gear has no cam surface: its latch lifts the valve spindle directly and lets go. Its
contact statics are the latch face's (explorer.gears.trip_latched, its variant of this effect in
its gear): the latch force at the release, the friction the trip must overcome to pull
the latch out, the face's bearing pressure; their keys are in [gear.trip] (latch_friction,
latch_width, latch_depth), not in [contact].

Scene section [contact] (all optional):
    friction_angle        rho of the follower guide (default 0 deg), or
    friction_coefficient  mu = tan(rho)
    youngs_modulus, poisson_ratio                cam material (default steel: 210 GPa, 0.3)
    roller_youngs_modulus, roller_poisson_ratio  roller material (default: as the cam)
    width                 contact width b (default: the required width, hertz_width)
    valve                 "exhaust" (default) or "intake": picks the width-rule k
    width_rule_k          k of b = P/(k D) (default 40 kgf/cm^2 exhaust, 10 kgf/cm^2 intake); not
                          with allowable_stress (which sizes the width by the Hertz stress instead)
    engine                "large-gas" (default, 3500 kgf/cm^2) or "diesel" (4000 kgf/cm^2)
    allowable_stress      explicit allowable contact stress (replaces the engine's)
    sliding_friction      mu of a face or pad sliding on the cam (default 0; read by the gears
                          whose follower slides on the cam: docs/theory/modern-gears.md)
    tip_friction          mu of a valve pad sliding on the valve tip (default 0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np

from ..core.errors import InputError, echo
from ..core.units import AT

STEEL_E = 210e9  # Pa
STEEL_NU = 0.3
ALLOWABLE = {"large-gas": 3500.0 * AT, "diesel": 4000.0 * AT}  # Pa, seed 004
WIDTH_RULE_K = {"intake": 10.0 * AT, "exhaust": 40.0 * AT}  # Pa (kgf/cm^2), seed 004

# Where ContactSpec.allowable_stress comes from: seed 004's large-gas figure because the scene named
# none ("default"), seed 004's figure for the [contact] engine the scene named ("engine"), or the
# scene's own [contact] allowable_stress ("given"). It decides the required width (hertz_width) and
# what the warnings and the hertz_stress rule call the allowable.
AllowableSource = Literal["default", "engine", "given"]


@dataclass(frozen=True)
class ContactSpec:
    friction_angle: float = 0.0  # rad, follower guide
    youngs_modulus: float = STEEL_E  # Pa, cam
    poisson_ratio: float = STEEL_NU
    roller_youngs_modulus: float = STEEL_E  # Pa
    roller_poisson_ratio: float = STEEL_NU
    width: float | None = None  # m; None: the required width (hertz_width)
    valve: str = "exhaust"
    width_rule_k: float = WIDTH_RULE_K["exhaust"]  # Pa
    engine: str = "large-gas"
    allowable_stress: float = ALLOWABLE["large-gas"]  # Pa
    allowable_source: AllowableSource = "default"  # see AllowableSource
    sliding_friction: float = 0.0  # mu of a face or pad sliding on the cam (the gears of #24; rollers take none)
    tip_friction: float = 0.0  # mu of a valve pad sliding on the valve tip




# --- formulas -------------------------------------------------------------------------------------


def effective_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """E* of two elastic bodies in contact: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2."""
    for key, e, nu in (("youngs_modulus", e1, nu1), ("roller_youngs_modulus", e2, nu2)):
        if not (math.isfinite(e) and e > 0.0):
            raise InputError("<arguments>", key, f"must be greater than zero, got {echo(e)}")
        if not (-1.0 < nu < 0.5):
            raise InputError("<arguments>", key.replace("youngs_modulus", "poisson_ratio"),
                             f"must lie in (-1, 0.5), got {echo(nu)}")
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
        raise InputError("<arguments>", "contact.width_rule_k", f"must be greater than zero, got {echo(k)}")
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


class ContactModel(Protocol):
    """A gear's geometry with contact statics (PivotedRollerGear, RockingCamGear, RollingLeverGear):
    the ContactGeometry at cam angles theta (rad)."""

    def contact_geometry(self, theta) -> ContactGeometry: ...


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


def allowable_label(spec: ContactSpec) -> str:
    """Where the allowable contact stress comes from, for a warning."""
    if spec.allowable_source == "given":
        return "[contact] allowable_stress"
    if spec.allowable_source == "engine":
        return f"[contact] engine = {spec.engine!r}, seed 004"
    return f"seed 004's {spec.engine!r} default of 1902 cast iron: no [contact] allowable_stress given"


def self_locking_worst(margin, lift_rate) -> int:
    """Index of the smallest self-locking margin while the cam lifts the follower (lift_rate > 0:
    dL/dtheta, or the follower's velocity at a positive speed). Only there can the guide lock: on
    the closing flank the spring drives the follower down and the cam only holds it back. A cam
    that never lifts: the whole revolution. The contact effect's summary and the self_locking
    rule both take it."""
    lifting = np.asarray(lift_rate, dtype=float) > 0.0
    if not lifting.any():
        lifting = np.ones_like(lifting)
    return int(np.argmin(np.where(lifting, margin, np.inf)))


# hertz_width's rules (the summary's required_cam_width_rule) in words, for notes and tables
WIDTH_RULE_WORDS = {
    "P/(k D)": "seed 004's width rule b = P/(k D)",
    "hertz allowable": "the width at which the Hertz stress reaches the allowable",
}


def hertz_width(normal, geometry: ContactGeometry, spec: ContactSpec, e_star: float) -> tuple[float, str]:
    """Required contact width and the rule that gave it: seed 004's b = P/(k D) on the largest
    normal force for a roller judged by seed 004's allowables (the engine's or the default);
    otherwise (a roller under the scene's own allowable_stress, or rolling faces) the width at
    which the peak Hertz stress equals the allowable, b = N E* / (pi sigma^2 R*) at its worst angle."""
    finite = np.where(np.isfinite(normal), normal, np.nan)
    if geometry.roller_diameter is not None and spec.allowable_source != "given":
        max_normal = float(np.nanmax(finite)) if np.isfinite(finite).any() else 0.0
        return width_rule(max_normal, geometry.roller_diameter, spec.width_rule_k), "P/(k D)"
    with np.errstate(divide="ignore", invalid="ignore"):
        curvature = 1.0 / np.asarray(geometry.counter_radius, dtype=float) + 1.0 / np.asarray(geometry.contour_radius)
        need = np.maximum(finite, 0.0) * e_star * np.maximum(curvature, 0.0) / (math.pi * spec.allowable_stress**2)
    need = np.where(np.isfinite(need), need, np.nan)
    return (float(np.nanmax(need)) if np.isfinite(need).any() else 0.0), "hertz allowable"


# --- the effect -------------------------------------------------------------------------------------


