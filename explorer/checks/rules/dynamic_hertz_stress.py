"""Contact (Hertz) stress under the elastic train's cam force: the hertz_stress rule's pressure
(the same contact, width, material and allowable) with the normal force N of the force the cam
carries in one elastic revolution of the nominal design at each speed (the contact effect's
dynamic_hertz_stress_Pa), not the rigid train's. The two differ where the train is elastic: at a
landing after a float the cam takes several times the rigid load (valve_float_demo at 4000 rpm:
1942 N against 828 N); below the float speed the linkage's vibration adds to it.

The tolerance draws are not propagated: a draw's elastic force needs its own revolution at every
speed (the sweep engine gives its figures, not its force at every angle); hertz_stress judges them
on the rigid train."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..case import reduce_angles
from ..rule import Measure
from .hertz_stress import allowable, model_note, stress


def measure(case, settings) -> Measure:
    try:
        contact = case.contact()
        case.needs_train()
        case.needs_linkage()
    except NotApplicable as exc:
        return Measure.not_applicable(str(exc))
    if case.sampling:
        return Measure.not_applicable("judged on the nominal design (an elastic revolution per speed); the "
                                      "draws' contact stress is hertz_stress's, on the rigid train")
    width, how = case.width
    if not width > 0.0:
        return Measure.not_applicable("no contact width (the cam carries no load at the scene's speed)")
    speeds = case.rule_speeds("dynamic_hertz_stress")
    value = np.full((1, speeds.size), np.nan)
    angle = np.full_like(value, np.nan)
    for j, rpm in enumerate(speeds):
        force = case.elastic_cam_force(float(rpm))
        if force is None:  # the elastic run was refused at this speed: no verdict there
            continue
        sigma = stress(case, contact, width, case.normal(force))
        value[0, j], angle[0, j] = reduce_angles(sigma, "max", case.theta_deg)
    limit, source = allowable(case, settings)
    return Measure.of(value, angle, speeds, settings, fail=limit, limit_source=source,
                      note=model_note(case, contact, width, how, "elastic train, nominal design"))
