"""Flash temperature (Blok): the largest contact temperature over the loaded contact, the bulk
temperature of [lubricant] plus Blok's flash of the sliding between the surfaces
(explorer.mechanics.tribology.blok_flash_temperature), with the semi-width of the Hertzian band
and the surfaces' velocities relative to the contact from the gear's surface motion."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ...mechanics.tribology import blok_flash_temperature, hertz_half_width, reduced_radius
from ..case import RPM, reduce_angles
from ..rule import Measure
from .film_parameter import e_prime, lubricated


def measure(case, settings) -> Measure:
    try:
        contact, lub = lubricated(case, need_friction=True)
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    g = contact.geometry
    width, how = case.width
    radius = np.broadcast_to(reduced_radius(g.counter_radius, g.contour_radius), case.theta.shape)
    ep = e_prime(case)
    speeds = case.rule_speeds("flash_temperature", ends=True)
    omega = (speeds * RPM)[:, None]
    u1 = omega * contact.motion.cam_rate[None, :]
    u2 = omega * contact.motion.follower_rate[None, :]
    value = np.empty((case.n, speeds.size))
    angle = np.empty_like(value)
    for rows, force, _ in case.blocks(speeds):
        w = case.normal(force) / width
        loaded = (w > 0.0) & (radius > 0.0)
        half = hertz_half_width(np.where(loaded, w, 0.0), np.where(radius > 0.0, radius, 0.0), ep)
        flash = blok_flash_temperature(lub.friction_coefficient, np.where(loaded, w, 0.0), u1[None], u2[None], half,
                                       lub.cam_thermal_coefficient, lub.follower_thermal_coefficient)
        temp = np.where(loaded, lub.temperature + flash, np.nan)
        wv, a = reduce_angles(temp, "max", case.theta_deg)
        value[rows], angle[rows] = wv, a
    rolling = bool(np.allclose(contact.motion.cam_rate, contact.motion.follower_rate))
    note = f"bulk {lub.temperature - 273.15:.4g} degC, mu {lub.friction_coefficient:g}, width {width * 1e3:.4g} mm ({how})"
    if rolling:
        note += "; pure rolling: no sliding, no flash"
    # At an angle where the load falls with the speed (A < 0) Blok's flash, ~ w^(3/4) omega^(1/2),
    # peaks inside the range (at omega^2 = G/(4|A|)): the draws' worst lies at their own speed there
    return Measure.of(value, angle, speeds, settings, note=note, speed_exact=not case.sampling or rolling)
