"""Face width left on a flat-faced (or crowned) follower: the face's half-width less how far the
contact reaches from the follower's axis and less half the gear's face margin,
    half-width - max reach - face_margin / 2 = (face_diameter - face_diameter_needed) / 2,
the gear's own reach (GearContact.face_reach: on a bucket tappet's flat face the contact line's far
end sqrt(s'^2 + (|e| + b/2)^2) with the lobe's offset e and width b, explorer.gears.flat_face.
BucketTappetGear.face_reach) and margin, so the rule and the gear's report (face_diameter_needed_m)
say the same. The margin is included: it is the designer's allowance for the face's edge (chamfer,
wear, the tappet's turning), and a face the gear's load check accepts passes the fail limit 0.

The cam is the same in every run (the tolerance draws vary no key of the face's geometry, and the
lift is the tappet's, lash included): one figure for every draw and speed, broadcast over the
draws by the checks (explorer.checks.run)."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..rule import Measure


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    reach = contact.reach()
    if reach is None or contact.face_half_width is None:
        return Measure.not_applicable("the follower is not flat-faced (no face offset and width supplied)")
    i = int(np.argmax(reach))
    half_margin = 0.5 * contact.face_margin
    value = contact.face_half_width - reach[i] - half_margin
    note = f"contact reaches {reach[i] * 1e3:.4g} mm of the {contact.face_half_width * 1e3:.4g} mm half-width"
    if contact.face_margin:
        note += f", less half the face margin ({half_margin * 1e3:.4g} mm)"
    return Measure.of([[value]], [[case.theta_deg[i]]], None, settings, note=note)
