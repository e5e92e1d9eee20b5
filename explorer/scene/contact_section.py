"""The [contact] section of a scene (explorer.mechanics.contact.ContactSpec); which followers the
contact statics cover is their gear's to say (explorer.gears.base.Gear.check_contact)."""

from __future__ import annotations

import math

from ..core.errors import InputError, echo
from ..core.ranges import FRICTION_COEFFICIENT
from ..gears.registry import gear
from ..mechanics.contact import ALLOWABLE, STEEL_E, STEEL_NU, WIDTH_RULE_K, ContactSpec


def parse_contact_section(table, fields) -> ContactSpec:
    """[contact] -> ContactSpec; called with table None when the effect runs without the section."""
    file = fields.get("source", "<memory>")
    follower = fields.get("follower")
    owner = gear(follower.type) if follower is not None else None
    if "contact" in fields.get("effects", ()) and owner is not None:
        owner.check_contact(follower, file)
    if table is None:
        return ContactSpec()
    if owner is not None and "contact" in owner.rejected:  # the trip gear: no cam and roller
        raise InputError(file, "contact", owner.rejected["contact"])
    table.reject_unknown((
        "friction_angle", "friction_coefficient", "youngs_modulus", "poisson_ratio", "roller_youngs_modulus",
        "roller_poisson_ratio", "width", "valve", "width_rule_k", "engine", "allowable_stress",
        "sliding_friction", "tip_friction",
    ))
    if table.has("friction_angle") and table.has("friction_coefficient"):
        raise table.error("friction_coefficient", "give friction_angle or friction_coefficient, not both")
    if table.has("friction_coefficient"):
        mu = table.number("friction_coefficient", minimum=FRICTION_COEFFICIENT[0], maximum=FRICTION_COEFFICIENT[1])
        rho = math.atan(mu)
    else:
        rho = table.quantity("friction_angle", "angle", 0.0)
        if not 0.0 <= rho < 0.5 * math.pi:
            raise table.error("friction_angle", f"must lie in [0 deg, 90 deg), got {echo(table.raw('friction_angle'))}")
    e_cam = table.quantity("youngs_modulus", "pressure", STEEL_E, positive=True)
    nu_cam = table.number("poisson_ratio", STEEL_NU, minimum=-1.0, maximum=0.5, open_minimum=True, open_maximum=True)
    if table.has("allowable_stress") and table.has("width_rule_k"):
        # the width rule is seed 004's for its cast-iron allowables; a scene's own allowable sizes
        # the width by the Hertz stress (explorer.mechanics.contact.hertz_width)
        raise table.error("width_rule_k", "give allowable_stress (the width is then the one its Hertz stress "
                                          "needs) or width_rule_k (seed 004's width rule), not both")
    valve = table.string("valve", "exhaust", choices=tuple(WIDTH_RULE_K))
    engine = table.string("engine", "large-gas", choices=tuple(ALLOWABLE))
    return ContactSpec(
        friction_angle=rho,
        youngs_modulus=e_cam,
        poisson_ratio=nu_cam,
        roller_youngs_modulus=table.quantity("roller_youngs_modulus", "pressure", e_cam, positive=True),
        roller_poisson_ratio=table.number("roller_poisson_ratio", nu_cam, minimum=-1.0, maximum=0.5,
                                          open_minimum=True, open_maximum=True),
        width=table.quantity("width", "length", positive=True) if table.has("width") else None,
        valve=valve,
        width_rule_k=table.quantity("width_rule_k", "pressure", WIDTH_RULE_K[valve], positive=True),
        engine=engine,
        allowable_stress=table.quantity("allowable_stress", "pressure", ALLOWABLE[engine], positive=True),
        allowable_source=("given" if table.has("allowable_stress") else "engine" if table.has("engine") else "default"),
        sliding_friction=table.number("sliding_friction", 0.0, minimum=0.0, maximum=1.0),
        tip_friction=table.number("tip_friction", 0.0, minimum=0.0, maximum=1.0),
    )
