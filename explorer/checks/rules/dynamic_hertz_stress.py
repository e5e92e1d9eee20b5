"""Contact (Hertz) stress under the elastic train's cam force: the hertz_stress rule's pressure
(the same contact, width, material and allowable) with the normal force N of the force the cam
carries in one elastic revolution of the nominal design at each speed (the contact effect's
dynamic_hertz_stress_Pa), not the rigid train's. The two differ where the train is elastic: at a
landing after a float the cam takes several times the rigid load (valve_float_demo at 4000 rpm:
1942 N against 828 N); below the float speed the linkage's vibration adds to it.

Cost: an elastic revolution through `simulate` is some hundred times a compiled sweep run, so the
rule does not run every speed. The sweep engine's runs (which the other elastic rules share) give
each speed's peak cam force F_max; at each angle the stress grows with the force, so the stress at
F_max at the worst angle bounds that speed's stress from above. The speeds run in order of that
bound, highest first, until the worst found reaches the next bound: every speed not run is
certified below it (the bound is raised by BOUND_SLACK for the compiled engine's rounding against
simulate's, ~1e-13 relative). The Measure holds the speeds run.

The tolerance draws are not propagated: a draw's elastic force needs its own revolution at every
speed (the sweep engine gives its figures, not its force at every angle); hertz_stress judges them
on the rigid train."""

from __future__ import annotations

import numpy as np

from ...mechanics.gear_contact import NotApplicable
from ..case import reduce_angles
from ..rule import Measure
from .hertz_stress import allowable, model_note, stress

BOUND_SLACK = 1e-9  # relative: the sweep engine's peak force against simulate's (measured ~1e-13)


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
    peak = np.asarray(case.elastic(speeds)["peak_linkage_force_N"], dtype=float).reshape(-1)
    with np.errstate(invalid="ignore"):  # (one call for all the speeds: the gear's own stress is costly a call)
        bounds = np.max(stress(case, contact, width, case.normal(peak[:, None])), axis=1)
    bounds = np.where(np.isnan(bounds), np.inf, bounds) * (1.0 + BOUND_SLACK)  # a run the engine refused: run it
    run: dict[int, tuple[float, float]] = {}
    best = -np.inf
    for j in np.argsort(-bounds, kind="stable"):
        if bounds[j] <= best:  # this speed and every one after it are certified below the worst
            break
        force = case.elastic_cam_force(float(speeds[j]))
        if force is None:  # the elastic run was refused at this speed: no verdict there
            run[int(j)] = (np.nan, np.nan)
            continue
        value, angle = reduce_angles(stress(case, contact, width, case.normal(force)), "max", case.theta_deg)
        run[int(j)] = (float(value), float(angle))
        if not np.isnan(value):
            best = max(best, float(value))
    idx = np.array(sorted(run), dtype=int)
    limit, source = allowable(case, settings)
    note = model_note(case, contact, width, how, "elastic train, nominal design")
    if idx.size < speeds.size:
        note += (f"; {idx.size} of {speeds.size} speeds run, the others certified below the worst by the stress "
                 "at their peak cam force")
    return Measure.of([[run[j][0] for j in idx]], [[run[j][1] for j in idx]], speeds[idx], settings, fail=limit,
                      limit_source=source, note=note)
