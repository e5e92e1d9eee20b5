"""Film parameter along the profile: lambda = h_min / sqrt(Rq_cam^2 + Rq_follower^2) with h_min the
EHL line contact's minimum film ([lubricant] film: Dowson-Higginson or Pan-Hamrock) at the
entrainment velocity the gear's surface motion gives and the load per width of the rigid train,
the smallest over the loaded contact (explorer.mechanics.tribology)."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ...mechanics.tribology import FILM_FUNCTIONS, composite_roughness, reduced_modulus, reduced_radius
from ..case import RPM, reduce_angles
from ..rule import Measure


def lubricated(case, need_roughness=False, need_friction=False):
    """(contact, lubricant) or NotApplicable with the reason."""
    lub = case.scene.lubricant
    if lub is None:
        raise NotApplicable("needs [lubricant] (viscosity, pressure_viscosity, roughness of both surfaces)")
    if need_roughness and not lub.has_roughness:
        raise NotApplicable("needs [lubricant] cam_roughness and follower_roughness")
    if need_friction and (lub.friction_coefficient is None or lub.temperature is None):
        raise NotApplicable("needs [lubricant] friction_coefficient and temperature")
    contact = case.contact()
    if contact.motion is None:
        raise NotApplicable(contact.motion_note or "the gear supplies no surface motion")
    case.needs_train()
    return contact, lub


def e_prime(case) -> float:
    s = case.contact_spec
    return reduced_modulus(s.youngs_modulus, s.poisson_ratio, s.roller_youngs_modulus, s.roller_poisson_ratio)


def measure(case, settings) -> Measure:
    try:
        contact, lub = lubricated(case, need_roughness=True)
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    g = contact.geometry
    width, how = case.width
    radius = np.broadcast_to(reduced_radius(g.counter_radius, g.contour_radius), case.theta.shape)
    film = FILM_FUNCTIONS[lub.film]
    sigma = composite_roughness(lub.cam_roughness, lub.follower_roughness)
    ep = e_prime(case)
    mean_rate = contact.motion.entrainment(1.0)
    speeds = case.rule_speeds("film_parameter", ends=True)
    u = (speeds * RPM)[:, None] * mean_rate[None, :]  # (S, n)
    value = np.empty((case.n, speeds.size))
    angle = np.empty_like(value)
    # h ~ u^0.70 w^-0.13 (u ~ omega, w ~ F = omega^2 A + G at each angle) grows with the speed
    # wherever the static load G > 0, so a draw's thinnest film is at the range's lowest speed; where
    # G <= 0 < A (a contact loaded only above some speed) it may dip inside the range
    speed_exact = True
    for rows, force, _ in case.blocks(speeds):
        if case.sampling and speed_exact:
            a_coef, g_part, is_open = case.force_parts(rows)
            speed_exact = not bool(np.any(is_open & (g_part <= 0.0) & (a_coef > 0.0)))
        w = case.normal(force) / width
        loaded = (w > 0.0) & (radius > 0.0)
        finite = np.isfinite(w)  # an infinite normal force: the guide locks, no film
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            h = film(u[None, :, :], np.where(loaded & finite, w, 1.0), np.where(radius > 0.0, radius, 1.0), ep,
                     lub.viscosity, lub.pressure_viscosity)
        lam = np.where(loaded, np.where(finite, h / sigma, 0.0), np.nan)
        wv, a = reduce_angles(lam, "min", case.theta_deg)
        value[rows], angle[rows] = wv, a
    return Measure.of(value, angle, speeds, settings, speed_exact=speed_exact,
                      note=f"{lub.film} film, Rq {sigma * 1e6:.3g} um composite, width {width * 1e3:.4g} mm ({how}); "
                           f"viscosity {lub.viscosity:.4g} Pa s, alpha {lub.pressure_viscosity:.3g} 1/Pa")
