"""Tribology of a lubricated cam contact along the profile: surface and entrainment velocities,
the minimum film thickness of an elastohydrodynamic (EHL) line contact, the film parameter
(lambda ratio) and Blok's flash temperature. Pure functions on numpy arrays, SI throughout.

Surface motion (the narrow interface a gear supplies, SurfaceMotion): per cam angle, the
velocity of each surface *relative to the contact point*, along the common tangent, per unit
camshaft speed (m/rad; multiply by omega for m/s):

    u_cam = omega * cam_rate,   u_follower = omega * follower_rate
    entrainment (mean rolling) velocity  u_e = (u_cam + u_follower) / 2
    sliding velocity                     u_s =  u_cam - u_follower

Closed forms for the followers the project has or is getting:
- a roller that rolls without slipping: both surfaces pass the contact at the speed the contact
  point runs along the cam contour. The contour is the pitch curve offset by the roller radius
  r, so its arc length per cam angle is the pitch curve's times (rho_p - r)/rho_p
  (rho_p: signed pitch-curve radius): u_e = omega |T| (rho_p - r)/rho_p, u_s = 0. For a
  translating roller without offset |T| = sqrt((R_p + L)^2 + L'^2).
- a flat face square to a translating follower (no offset): the contact lies at x = L' on the
  face, so it runs along the face at omega L'' and along the cam at omega rho, rho = R_b + L + L'':
      u_cam = -omega (R_b + L + L''),  u_follower = -omega L''
      u_e = -omega (R_b + L + 2 L'')/2,  u_s = -omega (R_b + L)
  (signs for a cam turning counter-clockwise; only their relation matters). u_e passes through
  zero where R_b + L + 2 L'' = 0, near the nose of most flat-tappet cams: the film is then
  carried by squeeze alone, which the steady formulas below do not see.

Film thickness of a line contact (both formulas isothermal, fully flooded, Newtonian, smooth
surfaces; u the entrainment speed, w the load per unit length, R the reduced radius
1/R = 1/R1 + 1/R2, E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2), eta0 the viscosity at the inlet
temperature and ambient pressure, alpha the pressure-viscosity coefficient):
- Dowson & Higginson (Elasto-Hydrodynamic Lubrication, 1966; SI edition 1977):
      h_min / R = 2.65 U^0.70 G^0.54 W^-0.13
- Pan & Hamrock (ASME J. Tribol. 111 (1989) 246-251; Hamrock, Schmid & Jacobson, Fundamentals of
  Fluid Film Lubrication, 2nd ed. 2004, rectangular conjunctions):
      h_min / R = 1.714 W^-0.128 U^0.694 G^0.568
with U = eta0 u / (E' R), G = alpha E', W = w / (E' R).

Film parameter lambda = h_min / sqrt(Rq1^2 + Rq2^2) (composite rms roughness): below ~1 the
asperities carry the load (boundary lubrication), 1-3 mixed, above ~3 a full film (Hamrock,
Schmid & Jacobson, ch. on film parameter).

Blok's flash temperature (H. Blok, Proc. General Discussion on Lubrication, IMechE 1937): the
frictional heat mu w |u1 - u2| per unit length, released over a Hertzian (semi-elliptic) band of
semi-width b, partitioned so that both surfaces reach the same peak temperature, each surface a
half-space passing the band fast (Peclet number u b / kappa >> 1):
      theta_f = 1.11 mu w |u1 - u2| / (sqrt(2 b) (B1 sqrt|u1| + B2 sqrt|u2|)),   B = sqrt(k rho c)
The 1.11 belongs with the band's full width 2b: the same peak is 0.786/sqrt(b) with the
semi-width (tests/test_tribology.py integrates the moving heat source and finds 0.786).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.errors import InputError
from ..lift.contours.translating import pitch_geometry

# Thermal contact coefficient sqrt(k rho c) of martensitic steels, the average ISO/TR 13989-1
# uses when the material's own is unknown: 13.6 N/(mm s^0.5 K) (k 41-52 W/(m K), rho c about
# 3.8 N/(mm^2 K)); in SI, W s^0.5 / (m^2 K).
STEEL_THERMAL_COEFFICIENT = 13.6e3
FILM_MODELS = ("dowson-higginson", "pan-hamrock")


# --- surface motion ---------------------------------------------------------------------------


@dataclass(frozen=True)
class SurfaceMotion:
    """Velocities of the two surfaces relative to the contact point, along the common tangent,
    per unit camshaft speed (m/rad), per cam angle."""

    cam_rate: np.ndarray
    follower_rate: np.ndarray

    def entrainment(self, omega=1.0) -> np.ndarray:
        """u_e = omega (cam_rate + follower_rate) / 2 (m/s); omega broadcasts (e.g. speeds x 1)."""
        return omega * (0.5 * (self.cam_rate + self.follower_rate))

    def sliding(self, omega=1.0) -> np.ndarray:
        """u_s = omega (cam_rate - follower_rate) (m/s)."""
        return omega * (self.cam_rate - self.follower_rate)


def rolling_roller_motion(pitch_speed, pitch_radius, roller_radius: float) -> SurfaceMotion:
    """A roller rolling without slip on a cam: both surfaces pass the contact at the contour's
    arc-length rate |dP/dtheta| (rho_p - r)/rho_p, with |dP/dtheta| the pitch curve's (roller
    centre's path in the body frame of the cam) and rho_p its signed radius (> 0 convex)."""
    speed = np.asarray(pitch_speed, dtype=float)
    rho = np.asarray(pitch_radius, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(np.isfinite(rho), (rho - roller_radius) / rho, 1.0)
    rate = -speed * factor
    return SurfaceMotion(rate, rate.copy())


def translating_roller_motion(d, base_radius: float, roller_radius: float, offset: float = 0.0) -> SurfaceMotion:
    """Translating roller (explorer.lift.contours.translating's conventions): the pitch curve's
    tangent T = (y, L' - e) with y = sqrt(Rp^2 - e^2) + L, its radius from pitch_geometry."""
    rp = base_radius + roller_radius
    y = math.sqrt(rp * rp - offset * offset) + np.asarray(d[0], dtype=float)
    speed = np.hypot(y, np.asarray(d[1], dtype=float) - offset)
    _, pitch_radius = pitch_geometry(d, base_radius, roller_radius, offset)
    return rolling_roller_motion(speed, pitch_radius, roller_radius)


def flat_face_motion(d, base_radius: float) -> SurfaceMotion:
    """Flat face square to a translating follower through the cam centre (a bucket tappet):
    cam_rate = -(R_b + L + L''), follower_rate = -L'' (module docstring)."""
    lift, second = np.asarray(d[0], dtype=float), np.asarray(d[2], dtype=float)
    return SurfaceMotion(-(base_radius + lift + second), -second)


def flat_face_radius(d, base_radius: float) -> np.ndarray:
    """Radius of curvature of a flat-faced follower's cam, rho = R_b + L + L'' (> 0 everywhere,
    else the cam has a cusp)."""
    return base_radius + np.asarray(d[0], dtype=float) + np.asarray(d[2], dtype=float)


def zero_crossings(theta, values, mask=None) -> np.ndarray:
    """Angles (same unit as theta) where `values` changes sign between neighbouring samples (the
    periodic wrap included), linearly interpolated; only pairs of samples both in `mask`."""
    th = np.asarray(theta, dtype=float)
    v = np.asarray(values, dtype=float)
    nxt = np.roll(v, -1)
    ok = np.isfinite(v) & np.isfinite(nxt)
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        ok &= m & np.roll(m, -1)
    i = np.nonzero(ok & (np.sign(v) * np.sign(nxt) < 0.0))[0]
    if i.size == 0:
        return np.zeros(0)
    period = th[-1] - th[0] + (th[1] - th[0]) if th.size > 1 else 0.0
    t0 = th[i]
    t1 = np.where(i + 1 < th.size, th[np.minimum(i + 1, th.size - 1)], th[0] + period)
    frac = v[i] / (v[i] - nxt[i])
    return t0 + frac * (t1 - t0)


# --- contact mechanics of a line contact ---------------------------------------------------------


def reduced_modulus(e1: float, nu1: float, e2: float, nu2: float) -> float:
    """E' = 2 / ((1 - nu1^2)/E1 + (1 - nu2^2)/E2) (Hamrock's and Dowson-Higginson's; twice E*)."""
    return 2.0 / ((1.0 - nu1**2) / e1 + (1.0 - nu2**2) / e2)


def reduced_radius(r1, r2) -> np.ndarray:
    """R with 1/R = 1/r1 + 1/r2 (signed radii, > 0 convex, inf flat); inf where both are flat,
    <= 0 where the contact is not conformal-convex (no Hertzian line contact)."""
    with np.errstate(divide="ignore"):
        curvature = 1.0 / np.asarray(r1, dtype=float) + 1.0 / np.asarray(r2, dtype=float)
        return np.where(curvature > 0.0, 1.0 / np.where(curvature > 0.0, curvature, 1.0), -np.inf)


def hertz_half_width(load_per_length, radius, e_prime: float) -> np.ndarray:
    """Semi-width b of a line contact: b = sqrt(8 w R / (pi E'))  (= sqrt(4 w R / (pi E*)))."""
    w = np.maximum(np.asarray(load_per_length, dtype=float), 0.0)
    return np.sqrt(8.0 * w * np.asarray(radius, dtype=float) / (math.pi * e_prime))


# --- EHL film ----------------------------------------------------------------------------------


def film_dowson_higginson(u, load_per_length, radius, e_prime: float, viscosity: float, alpha: float) -> np.ndarray:
    """Minimum film thickness h_min (m) of an EHL line contact, Dowson & Higginson:
    h_min = 2.65 R U^0.70 G^0.54 W^-0.13 (module docstring). u: entrainment speed (its size
    counts; 0 gives 0), load_per_length w > 0, radius R > 0."""
    U, G, W, R = _groups(u, load_per_length, radius, e_prime, viscosity, alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        return 2.65 * R * U**0.70 * G**0.54 * W**-0.13


def film_pan_hamrock(u, load_per_length, radius, e_prime: float, viscosity: float, alpha: float) -> np.ndarray:
    """Minimum film thickness h_min (m) of an EHL line contact, Pan & Hamrock (1989):
    h_min = 1.714 R W^-0.128 U^0.694 G^0.568."""
    U, G, W, R = _groups(u, load_per_length, radius, e_prime, viscosity, alpha)
    with np.errstate(divide="ignore", invalid="ignore"):
        return 1.714 * R * W**-0.128 * U**0.694 * G**0.568


FILM_FUNCTIONS = {"dowson-higginson": film_dowson_higginson, "pan-hamrock": film_pan_hamrock}


def _groups(u, w, r, e_prime, viscosity, alpha):
    R = np.asarray(r, dtype=float)
    U = viscosity * np.abs(np.asarray(u, dtype=float)) / (e_prime * R)
    W = np.asarray(w, dtype=float) / (e_prime * R)
    return U, alpha * e_prime, W, R


def composite_roughness(rq1: float, rq2: float) -> float:
    """sqrt(Rq1^2 + Rq2^2), the rms roughness of the gap between two surfaces."""
    return math.hypot(rq1, rq2)


def film_parameter(h_min, rq1: float, rq2: float) -> np.ndarray:
    """lambda = h_min / sqrt(Rq1^2 + Rq2^2)."""
    sigma = composite_roughness(rq1, rq2)
    if not sigma > 0.0:
        raise InputError("<arguments>", "lubricant.cam_roughness", "the composite roughness must be greater than zero")
    return np.asarray(h_min, dtype=float) / sigma


# --- flash temperature ---------------------------------------------------------------------------


BLOK_COEFFICIENT = 1.11


def blok_flash_temperature(mu: float, load_per_length, u1, u2, half_width, b1: float = STEEL_THERMAL_COEFFICIENT,
                           b2: float = STEEL_THERMAL_COEFFICIENT) -> np.ndarray:
    """Blok's flash temperature rise (K) of a line contact (module docstring):
    1.11 mu w |u1 - u2| / (sqrt(2 b) (B1 sqrt|u1| + B2 sqrt|u2|)); 0 where nothing slides or
    nothing is loaded."""
    w = np.maximum(np.asarray(load_per_length, dtype=float), 0.0)
    a1, a2 = np.abs(np.asarray(u1, dtype=float)), np.abs(np.asarray(u2, dtype=float))
    slide = np.abs(np.asarray(u1, dtype=float) - np.asarray(u2, dtype=float))
    den = np.sqrt(2.0 * np.asarray(half_width, dtype=float)) * (b1 * np.sqrt(a1) + b2 * np.sqrt(a2))
    with np.errstate(divide="ignore", invalid="ignore"):
        out = BLOK_COEFFICIENT * mu * w * slide / den
    return np.where((slide > 0.0) & (w > 0.0) & (den > 0.0), out, 0.0)


# --- the [lubricant] section ---------------------------------------------------------------------


@dataclass(frozen=True)
class LubricantSpec:
    """[lubricant]: the oil and the surfaces it separates (SI)."""

    viscosity: float  # Pa s, dynamic, at the contact inlet's temperature and ambient pressure
    pressure_viscosity: float = 2.0e-8  # 1/Pa, alpha of Barus' law (mineral oils: 1-3e-8 1/Pa)
    cam_roughness: float | None = None  # m, Rq of the cam
    follower_roughness: float | None = None  # m, Rq of the roller or face
    friction_coefficient: float | None = None  # of the contact (Blok's heat source)
    temperature: float | None = None  # K, bulk temperature of the surfaces (Blok's flash adds to it)
    cam_thermal_coefficient: float = STEEL_THERMAL_COEFFICIENT  # sqrt(k rho c), W s^0.5/(m^2 K)
    follower_thermal_coefficient: float = STEEL_THERMAL_COEFFICIENT
    film: str = "dowson-higginson"  # the film thickness formula

    @property
    def has_roughness(self) -> bool:
        return self.cam_roughness is not None and self.follower_roughness is not None


def parse_lubricant_section(table, fields) -> LubricantSpec | None:
    """[lubricant] -> LubricantSpec (None without the section)."""
    if table is None:
        return None
    table.reject_unknown(("viscosity", "pressure_viscosity", "cam_roughness", "follower_roughness",
                          "friction_coefficient", "temperature", "cam_thermal_coefficient",
                          "follower_thermal_coefficient", "film"))
    rough = [k for k in ("cam_roughness", "follower_roughness") if table.has(k)]
    if len(rough) == 1:
        other = "follower_roughness" if rough[0] == "cam_roughness" else "cam_roughness"
        raise table.error(other, "missing key: the film parameter needs the roughness (Rq) of both surfaces")
    return LubricantSpec(
        viscosity=table.quantity("viscosity", "viscosity", positive=True),
        pressure_viscosity=table.quantity("pressure_viscosity", "pressure_viscosity", 2.0e-8, positive=True),
        cam_roughness=table.quantity("cam_roughness", "length", positive=True) if rough else None,
        follower_roughness=table.quantity("follower_roughness", "length", positive=True) if rough else None,
        friction_coefficient=table.number("friction_coefficient", minimum=0.0, maximum=1.0, open_minimum=True)
        if table.has("friction_coefficient") else None,
        temperature=table.quantity("temperature", "temperature", positive=True) if table.has("temperature") else None,
        cam_thermal_coefficient=table.number("cam_thermal_coefficient", STEEL_THERMAL_COEFFICIENT, minimum=1.0,
                                             maximum=1e6),
        follower_thermal_coefficient=table.number("follower_thermal_coefficient", STEEL_THERMAL_COEFFICIENT,
                                                  minimum=1.0, maximum=1e6),
        film=table.string("film", "dowson-higginson", choices=FILM_MODELS),
    )
