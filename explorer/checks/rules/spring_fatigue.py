"""Valve-spring fatigue: Goodman's safety factor n_f = 1/(tau_a/S_se + tau_m/S_su) for the cycle
between the installed and the full-lift force, with Zimmerli's endurance data (peened or not) and
S_su = 0.67 S_ut (explorer.mechanics.valve_spring)."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ...mechanics.valve_spring import TORSIONAL_RUPTURE, ZIMMERLI, goodman_endurance, goodman_safety_factor
from ..rule import Measure
from . import _spring


def measure(case, settings) -> Measure:
    try:
        d, _ = _spring.geometry(case)
        tau1, tau2, angle = _spring.stresses(case, settings["correction"])
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    w = _spring.wire(settings["wire"])
    s_su = TORSIONAL_RUPTURE * w.ultimate_tensile_strength(d)
    s_sa, s_sm = ZIMMERLI[bool(settings["peened"])]
    s_se = goodman_endurance(s_sa, s_sm, s_su)
    tau_a, tau_m = 0.5 * (tau2 - tau1), 0.5 * (tau2 + tau1)
    n_f = goodman_safety_factor(tau_a, tau_m, s_se, s_su)
    peened = "peened" if settings["peened"] else "unpeened"
    return Measure.of(n_f[:, None], np.full((case.n, 1), angle), None, settings,
                      note=f"{w.name}: S_su {s_su / 1e6:.4g} MPa, Zimmerli {peened} S_se {s_se / 1e6:.4g} MPa; "
                           f"tau_a {float(np.ravel(tau_a)[0]) / 1e6:.4g}, tau_m {float(np.ravel(tau_m)[0]) / 1e6:.4g} MPa "
                           f"({settings['correction']})")
