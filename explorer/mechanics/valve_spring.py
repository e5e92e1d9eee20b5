"""Helical valve-spring strength: shear stress with the curvature correction at the installed and
full-lift heights, the fatigue safety factor (Goodman, with Zimmerli's endurance data), coil-bind
margin. Pure functions, SI (Pa, m, N).

Shear stress in the wire of a helical compression spring (mean coil diameter D, wire d, index
C = D/d) under an axial force F:
    tau = K 8 F D / (pi d^3)
with K the curvature (and direct-shear) correction: Wahl's K_W = (4C - 1)/(4C - 4) + 0.615/C
(A. M. Wahl, Mechanical Springs, 1944), Bergstraesser's K_B = (4C + 2)/(4C - 3) (Shigley's choice
since its 8th edition; within ~1 % of Wahl's), or the direct-shear factor K_s = 1 + 0.5/C alone
(Norton's for the mean stress).

Fatigue (Shigley, Mechanical Engineering Design, sec. "Fatigue loading of helical compression
springs"): the force cycles between the installed preload F1 and the full-lift force F2, so
tau_a = K 8 F_a D/(pi d^3) and tau_m = K 8 F_m D/(pi d^3) with F_a = (F2 - F1)/2 and
F_m = (F2 + F1)/2. Zimmerli's data (wires under 10 mm, any of the usual steels, 10^7 cycles):
S_sa = 241 MPa, S_sm = 379 MPa unpeened; 398 and 534 MPa shot-peened. The Goodman line through
(S_sm, S_sa) to the torsional modulus of rupture S_su = 0.67 S_ut meets the alternating axis at
    S_se = S_sa / (1 - S_sm / S_su),
and the load line from the origin through (tau_m, tau_a) meets the Goodman line at the safety factor
    n_f = 1 / (tau_a / S_se + tau_m / S_su).

Coil bind: the spring is installed at L1 = L0 - F1/k (free length L0, rate k) and compressed by the
valve's lift h to L2 = L1 - h; the margin to the solid height L_s is L2 - L_s.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.errors import InputError

ZIMMERLI = {  # (S_sa, S_sm), Pa: Zimmerli (1957), as Shigley quotes them
    False: (241e6, 379e6),  # unpeened
    True: (398e6, 534e6),  # shot-peened
}
TORSIONAL_RUPTURE = 0.67  # S_su / S_ut (Shigley)


def wahl_factor(index) -> np.ndarray:
    """K_W = (4C - 1)/(4C - 4) + 0.615/C."""
    c = np.asarray(index, dtype=float)
    return (4.0 * c - 1.0) / (4.0 * c - 4.0) + 0.615 / c


def bergstrasser_factor(index) -> np.ndarray:
    """K_B = (4C + 2)/(4C - 3)."""
    c = np.asarray(index, dtype=float)
    return (4.0 * c + 2.0) / (4.0 * c - 3.0)


def direct_shear_factor(index) -> np.ndarray:
    """K_s = 1 + 0.5/C (direct shear only, no curvature)."""
    return 1.0 + 0.5 / np.asarray(index, dtype=float)


CORRECTIONS = {"wahl": wahl_factor, "bergstrasser": bergstrasser_factor, "direct-shear": direct_shear_factor}


def shear_stress(force, coil_diameter: float, wire_diameter: float, correction: str = "wahl") -> np.ndarray:
    """tau = K 8 F D / (pi d^3) (Pa) with K the named correction of C = D/d."""
    if not (coil_diameter > wire_diameter > 0.0):
        raise InputError("<arguments>", "spring.coil_diameter", "the mean coil diameter must exceed the wire diameter")
    k = CORRECTIONS[correction](coil_diameter / wire_diameter)
    return k * 8.0 * np.asarray(force, dtype=float) * coil_diameter / (math.pi * wire_diameter**3)


def goodman_endurance(s_sa: float, s_sm: float, s_su: float) -> float:
    """S_se = S_sa / (1 - S_sm / S_su): the Goodman line through Zimmerli's point, at tau_m = 0."""
    if not s_sm < s_su:
        raise InputError("<arguments>", "spring.wire", f"Zimmerli's mean strength {s_sm / 1e6:.4g} MPa reaches the "
                         f"torsional rupture strength {s_su / 1e6:.4g} MPa: no Goodman line")
    return s_sa / (1.0 - s_sm / s_su)


def goodman_safety_factor(tau_a, tau_m, s_se: float, s_su: float) -> np.ndarray:
    """n_f = 1 / (tau_a/S_se + tau_m/S_su) (a load line through the origin)."""
    return 1.0 / (np.asarray(tau_a, dtype=float) / s_se + np.asarray(tau_m, dtype=float) / s_su)


def installed_length(free_length: float, preload: float, rate: float) -> float:
    """L1 = L0 - F1/k."""
    if not rate > 0.0:
        raise InputError("<arguments>", "spring.rate", "the installed length needs a spring rate > 0")
    return free_length - preload / rate


def coil_bind_margin(free_length: float, solid_height: float, preload, rate, lift) -> np.ndarray:
    """L0 - F1/k - h - L_s: the space left between the coils at the lift h (< 0: coil bind)."""
    return free_length - np.asarray(preload, dtype=float) / np.asarray(rate, dtype=float) \
        - np.asarray(lift, dtype=float) - solid_height
