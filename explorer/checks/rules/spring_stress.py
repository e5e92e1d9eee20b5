"""Valve-spring shear stress at full lift (Wahl-corrected by default) against the wire's static
allowable (a share of its minimum tensile strength S_ut = A/d^m); the installed height's stress in
the note."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure
from . import _spring


def measure(case, settings) -> Measure:
    try:
        d, _ = _spring.geometry(case)
        tau1, tau2, angle = _spring.stresses(case, settings["correction"])
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    w = _spring.wire(settings["wire"])
    s_ut = w.ultimate_tensile_strength(d)
    limit, source = (settings["fail"], "the rule's fail setting") if settings["fail"] is not None else \
        (w.allowable_share * s_ut, f"{w.allowable_share:.0%} of S_ut {s_ut / 1e6:.4g} MPa ({w.name}, ASTM {w.astm}): "
                                   f"{w.source}")
    return Measure.of(tau2[:, None], np.full((case.n, 1), angle), None, settings, fail=limit, limit_source=source,
                      note=f"{settings['correction']} correction; installed {float(np.ravel(tau1)[0]) / 1e6:.4g} MPa, "
                           f"full lift {float(np.ravel(tau2)[0]) / 1e6:.4g} MPa")
