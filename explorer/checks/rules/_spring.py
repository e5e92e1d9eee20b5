"""What the valve-spring rules share: the wire geometry, the forces at the installed and
full-lift heights per draw, the wire's strength."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ...mechanics.materials import SPRING_WIRES
from ...mechanics.valve_spring import shear_stress


def geometry(case) -> tuple[float, float]:
    """(wire diameter d, mean coil diameter D) of [spring], or NotApplicable."""
    sp = case.scene.spring
    if sp is None or sp.wire_diameter is None or sp.coil_diameter is None:
        raise NotApplicable("needs the spring's wire geometry: [spring] wire_diameter, coil_diameter, active_coils, "
                            "shear_modulus")
    return sp.wire_diameter, sp.coil_diameter


def full_lift(case) -> tuple[np.ndarray, float]:
    """(the valve's largest lift per draw (N,), the cam angle in degrees where it is reached)."""
    top = case.scene.follower.ratio * case.derivs[0]
    i = int(np.argmax(top))  # the same angle for every lash: the lash only shifts the lift
    lash = case.param("valve.lash") if case.scene.valve is not None else 0.0
    lift = np.ravel(top[i] - np.asarray(lash, dtype=float))
    return np.maximum(lift, 0.0), float(case.theta_deg[i])


def forces(case) -> tuple[np.ndarray, np.ndarray, float]:
    """(installed force F1, full-lift force F2) per draw (N,) and the angle of full lift."""
    lift, angle = full_lift(case)
    preload = np.broadcast_to(np.ravel(np.asarray(case.param("spring.preload"), dtype=float)), (case.n,))
    rate = np.broadcast_to(np.ravel(np.asarray(case.param("spring.rate"), dtype=float)), (case.n,))
    lift = np.broadcast_to(lift, (case.n,))
    return preload, preload + rate * lift, angle


def stresses(case, correction: str):
    """(tau at installed height, tau at full lift) per draw, Pa, and the angle of full lift."""
    d, D = geometry(case)
    f1, f2, angle = forces(case)
    return shear_stress(f1, D, d, correction), shear_stress(f2, D, d, correction), angle


def wire(name: str):
    return SPRING_WIRES[name]
