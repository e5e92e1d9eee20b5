"""Contact (Hertz) stress: the largest peak pressure of the line contact over the operating range,
sigma = sqrt(N E* (1/r1 + 1/r2) / (pi b)) with N the cam's normal force of the rigid train
(explorer.mechanics.contact's statics) and b the contact width, against the allowable of the
material pair. A gear whose contact is no line contact (a crowned face: an ellipse) gives its own
pressure (GearContact.stress), which the rule judges instead."""

from __future__ import annotations

import math

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ...mechanics.materials import CONTACT_MATERIALS
from ..case import reduce_angles
from ..rule import Measure


def allowable(case, settings) -> tuple[float, str]:
    """(allowable Pa, its source) from the settings: an explicit fail limit, a named material or
    the scene's [contact] allowable."""
    if settings["fail"] is not None:
        return settings["fail"], "the rule's fail setting"
    material = settings["material"]
    if material != "scene":
        m = CONTACT_MATERIALS[material]
        return m.allowable, f"{m.name}: {m.source}"
    spec = case.contact_spec
    if spec.allowable_source == "given":
        return spec.allowable_stress, "[contact] allowable_stress"
    m = CONTACT_MATERIALS[spec.engine]
    if spec.allowable_source == "default":  # the 1902 default: say so, and how to name a modern one
        return m.allowable, (f"no [contact] allowable_stress given: seed 004's {spec.engine!r} default of 1902 cast "
                             f"iron, {m.source} (a modern hardened pair: [contact] allowable_stress, or the rule's "
                             "material setting)")
    return m.allowable, f"[contact] engine = {spec.engine!r}: {m.source}"


def stress(case, contact, width: float, normal: np.ndarray) -> np.ndarray:
    """The peak contact pressure (Pa) for cam normal forces `normal` (..., n) at the check's angles:
    the gear's own contact (contact.stress: an ellipse) or the line contact of width `width`; 0
    where unloaded, inf where a loaded concave flank is tighter than the roller."""
    if contact.stress is not None:
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
            return np.where(normal > 0.0, contact.stress(normal, case.e_star), 0.0)
    g = contact.geometry
    with np.errstate(divide="ignore"):
        curvature = 1.0 / np.asarray(g.counter_radius, dtype=float) + 1.0 / np.asarray(g.contour_radius, dtype=float)
    curvature = np.broadcast_to(curvature, case.theta.shape)
    with np.errstate(invalid="ignore", over="ignore"):
        sigma = np.sqrt(normal * case.e_star * np.maximum(curvature, 0.0) / (math.pi * width))
    return np.where((normal > 0.0) & (curvature <= 0.0), np.inf, np.where(normal > 0.0, sigma, 0.0))


def model_note(case, contact, width: float, how: str, train: str) -> str:
    return (f"{train}; the gear's own contact (a Hertz ellipse); E* {case.e_star / 1e9:.4g} GPa"
            if contact.stress is not None else
            f"{train}; contact width {width * 1e3:.4g} mm ({how}); E* {case.e_star / 1e9:.4g} GPa")


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
        case.needs_train()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    width, how = case.width
    if not width > 0.0:
        return Measure.not_applicable("no contact width (the cam carries no load at the scene's speed)")
    speeds = case.rule_speeds("hertz_stress", ends=True)
    value = np.empty((case.n, speeds.size))
    angle = np.empty_like(value)
    for rows, force, _ in case.blocks(speeds):
        w, a = reduce_angles(stress(case, contact, width, case.normal(force)), "max", case.theta_deg)
        value[rows], angle[rows] = w, a
    limit, source = allowable(case, settings)
    return Measure.of(value, angle, speeds, settings, fail=limit, limit_source=source,
                      note=model_note(case, contact, width, how, "rigid train"))
