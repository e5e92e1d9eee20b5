"""Entrainment reversal: the cam angles where the entrainment velocity u_e = omega (u_cam +
u_follower)/2 passes through zero while the valve is open (the contact loaded). The steady EHL
film formulas give no film there (squeeze alone carries the load): a flat tappet's nose. The
angles do not depend on the speed (u_e is proportional to omega)."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ...mechanics.tribology import zero_crossings
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    if contact.motion is None:
        return Measure.not_applicable(contact.motion_note or "the gear supplies no surface motion")
    if case.scene.valve is None:
        return Measure.not_applicable("needs [valve] (the lash: where the contact is loaded)")
    rate = contact.motion.entrainment(1.0)
    nxt = np.roll(rate, -1)
    crossing = np.sign(rate) * np.sign(nxt) < 0.0  # as zero_crossings counts them
    idx = np.nonzero(crossing)[0]
    level = case.scene.follower.ratio * case.derivs[0]
    lash = np.atleast_2d(np.asarray(case.param("valve.lash"), dtype=float))  # (N or 1, 1)
    inside = (level[idx][None, :] - lash > 0.0) & (level[(idx + 1) % rate.size][None, :] - lash > 0.0)
    count = inside.sum(axis=1).astype(float)
    count = np.broadcast_to(count, (case.n,)) if count.size == 1 else count
    nominal = level - (case.scene.valve.lash if case.scene.valve is not None else 0.0) > 0.0
    angles = zero_crossings(case.theta_deg, rate, mask=nominal).tolist()
    first = angles[0] if angles else np.nan
    details = (f"entrainment velocity passes through zero at cam angles {', '.join(f'{a:.2f}' for a in angles)} deg",) \
        if angles else ()
    return Measure.of(count[:, None], np.full((case.n, 1), first), None, settings, details=details,
                      note="loaded: valve open")
