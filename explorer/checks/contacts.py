"""How each follower type supplies its cam contact to the rules: one line per type in CONTACTS,
naming a provider `(scene, lift, theta) -> GearContact` (explorer.mechanics.gear_contact, the
narrow interface) as "module:function" (or the function itself). A type without a line has no cam contact the rules can judge (the contact and
tribology rules then say so); a new gear adds its line, its provider may live in its own module.

The providers below build each existing gear's contact from its public geometry (the same
ContactGeometry the `contact` effect uses) and add the surface motion:
- rollers (translating, pivoted lever, rocking cam) roll without slipping: both surfaces pass
  the contact at the contour's arc-length rate, the pitch curve's times (rho_p - r)/rho_p
  (explorer.mechanics.tribology.rolling_roller_motion), with the pitch curve traced in the frame
  of the body that carries the contour (the camshaft; the rocking cam about its pivot);
- the rolling lever's faces roll on each other: the contact runs along face A (a spiral
  rho = rho_c + k w about its pivot) at sqrt(k^2 + rho^2) per radian of rolling swing w.
"""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Mapping

import numpy as np

from ..mechanics.gear_contact import GearContact, NotApplicable

_C = "explorer.checks.contacts"

CONTACTS: Mapping[str, str] = MappingProxyType({
    "translating-roller": f"{_C}:translating_roller",
    "pivoted-roller": f"{_C}:pivoted_roller",
    "rocking-cam": f"{_C}:rocking_cam",
    "rolling-lever": f"{_C}:rolling_lever",
})


def gear_contact(scene, lift, theta) -> GearContact:
    """The follower type's GearContact on the angles theta, or NotApplicable with the reason."""
    import importlib

    target = CONTACTS.get(scene.follower.type)
    if target is None:
        raise NotApplicable(f"follower type {scene.follower.type!r} has no cam contact the rules judge "
                            "(its own rules judge it)")
    if callable(target):  # a provider given as the function itself
        return target(scene, lift, theta)
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)(scene, lift, theta)


def translating_roller(scene, lift, theta) -> GearContact:
    from ..lift.contours.translating import profile_from_derivatives
    from ..mechanics.contact import ContactGeometry, camshaft_torque, contact_point_radius
    from ..mechanics.tribology import rolling_roller_motion

    f = scene.follower
    if not f.roller_radius > 0.0:
        raise NotApplicable("a knife-edge follower (roller_radius 0): no contact radius to judge")
    d = lift.derivatives(theta)
    profile = profile_from_derivatives(theta, d, f.base_radius, f.roller_radius, f.offset)
    alpha = profile.pressure_angle
    arm = camshaft_torque(1.0, alpha, d[0], f.base_radius, f.roller_radius, f.offset)
    geometry = ContactGeometry(
        pressure_angle=alpha, ratio=np.full(alpha.shape, f.ratio), torque_arm=arm, body_arm=arm,
        body_radius=contact_point_radius(alpha, d[0], f.base_radius, f.roller_radius, f.offset),
        contour_radius=profile.contour_radius, counter_radius=f.roller_radius, roller_diameter=2.0 * f.roller_radius,
    )
    rp = f.base_radius + f.roller_radius
    speed = np.hypot(math.sqrt(rp * rp - f.offset**2) + d[0], d[1] - f.offset)  # |dP/dtheta|, P the pitch point
    motion = rolling_roller_motion(speed, profile.pitch_radius, f.roller_radius)
    return GearContact(geometry, motion, oscillating=False, pitch_radius=profile.pitch_radius)


def pivoted_roller(scene, lift, theta) -> GearContact:
    from ..mechanics.tribology import rolling_roller_motion

    gear = lift.gear
    geometry = gear.contact_geometry(theta)
    px, py = gear.pitch(theta)  # the roller centre in the cam frame, jets in theta
    speed = np.hypot(px.c[1], py.c[1])
    pitch_radius = np.asarray(geometry.contour_radius, dtype=float) + gear.roller_radius
    motion = rolling_roller_motion(speed, pitch_radius, gear.roller_radius)
    return GearContact(geometry, motion, oscillating=True, pitch_radius=pitch_radius)


def rocking_cam(scene, lift, theta) -> GearContact:
    from ..gears.jet import Jet
    from ..mechanics.tribology import rolling_roller_motion

    gear = lift.gear
    geometry = gear.contact_geometry(theta)
    phi, _ = gear.contact_angle(theta)  # the contact's body angle on the pitch curve, jets in theta
    rho = gear.contour.radius(Jet.variable(phi.c[0]))  # pitch radius about the pivot, jets in phi
    speed = np.hypot(rho.c[0], rho.c[1]) * np.abs(phi.c[1])  # |dP/dtheta| in the rocking body's frame
    pitch_radius = np.asarray(geometry.contour_radius, dtype=float) + gear.roller_radius
    motion = rolling_roller_motion(speed, pitch_radius, gear.roller_radius)
    return GearContact(geometry, motion, oscillating=True, pitch_radius=pitch_radius)


def rolling_lever(scene, lift, theta) -> GearContact:
    from ..mechanics.tribology import SurfaceMotion

    gear = lift.gear
    geometry = gear.contact_geometry(theta)
    swing = gear.rolling_swing(theta)  # w and dw/dtheta
    w = np.maximum(swing.c[0], 0.0)
    rho = gear.law.rho(w)
    rate = np.where(swing.c[0] > 0.0, -np.hypot(gear.law.growth, rho) * np.abs(swing.c[1]), 0.0)
    return GearContact(geometry, SurfaceMotion(rate, rate.copy()), oscillating=True, pitch_radius=None)
