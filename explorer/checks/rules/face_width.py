"""Face width used by a flat-faced follower: the face's half-width less the largest contact offset
(ds/dtheta of a translating face) on either side."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    if contact.face_offset is None or contact.face_half_width is None:
        return Measure.not_applicable("the follower is not flat-faced (no face offset and width supplied)")
    offset = np.abs(np.asarray(contact.face_offset, dtype=float))
    i = int(np.argmax(offset))
    return Measure.of([[contact.face_half_width - offset[i]]], [[case.theta_deg[i]]], None, settings,
                      note=f"largest offset {offset[i] * 1e3:.4g} mm of {contact.face_half_width * 1e3:.4g} mm")
