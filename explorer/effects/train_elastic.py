"""Effect `elastic` with the valve train as parts (issue #25: [[linkage.elements]], [hla]).

The train of dynamics/train.py -- the parts from the cam to the valve on their joints, the valve on
its elastic seat with its spring (massless, or a chain of masses), a hydraulic lash adjuster under
the lever -- solved by the scene's solver's chain function (exact or scipy: the same PhaseSystem)
from rest at the lowest drive position. With an adjuster, hla.revolutions revolutions in a row
(its plunger and chamber carry over from one to the next: pump-up and leak-down build up over
revolutions); the last is reported.

Columns: those of the spring-chain effect (valve_lift_m, ..., linkage_force_N: the cam contact's
force referred to the valve, camshaft_back_pressure_N, valve_phase, spring and seat forces, coils)
and, for each part <name> (its own travel: referred / ratio),
  part_<name>_displacement_m, part_<name>_velocity_m_s, part_<name>_accel_m_s2
for each joint <name> (cam: the cam contact, each part's cam-side joint by the part's name,
valve: the joint at the valve; plunger-stop),
  contact_<name>_force_N     its force along the travel of the part on its cam side (0 while open)
  contact_<name>_closed      1 while it carries load
and with an adjuster
  hla_plunger_travel_m       into its body, from its rest on the base circle (negative: extended)
  hla_chamber_pressure_Pa    gauge
  hla_check_valve_open       1 while the check valve refills the chamber
Events: lift-off, seat, separation and re-contact of the cam contact, contact-opens and
contact-closes of the other joints (with the joint's name), check-valve-open and -close, coil
clashes, and pump-up: the valve not back on its seat over the base circle of the last revolution.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..core.errors import InputError
from ..dynamics.hla import ATMOSPHERE
from ..dynamics.train import TrainModel
from ..result import EffectOutput, Event
from .chain_elastic import exciting_orders
from .chain_run import chain_run
from .elastic_events import float_report, linkage_outputs, not_at_rest, output_order

# how far (relative) the oil's secant modulus to hla.reference_pressure may sit from the secant to
# the chamber's peak before the run warns: the oil column's stiffness is off by as much, its own
# frequency by about half that. Half: a speed sweep's peaks span the static load's pressure to
# the float's (finger_hla_pumpup: 4.2 to 5.9 MPa, secants 188 to 252 MPa), which one reference
# cannot meet closer; the default 10 MPa there is +56 %
SECANT_TOLERANCE = 0.5

TRAIN_KINDS = ("lift-off", "separation", "re-contact", "seat", "contact-opens", "contact-closes", "coil-clash",
               "check-valve-open", "check-valve-close", "stick", "turn", "release", "pump-up")


def _event(ev: dict, period: float, omega: float) -> Event:
    """A solver's event (a dict of the phase system) as the result lists it: the time within the
    revolution, the cam angle, the joint (contact) and the impact speed or coil where known."""
    kind = ev["kind"]
    contact = ev.get("contact")
    if contact is not None and contact != "cam":
        kind = {"separation": "contact-opens", "re-contact": "contact-closes"}[kind]
    t_ev = math.fmod(ev["time_s"], period)  # the run's times are the output's plus whole revolutions
    values = {} if contact is None else {"contact": contact}
    values.update((key, ev[key]) for key in ("velocity_m_s", "element") if key in ev)
    return Event(kind, t_ev, math.degrees(omega * t_ev) % 360.0, values)


def train_elastic_effect(ctx) -> EffectOutput:
    scene = ctx.scene
    omega = ctx.omega
    model = TrainModel.from_scene(scene)
    section = scene.hla
    revolutions = section.revolutions if section is not None else 1
    ratio = scene.follower.ratio
    n = ctx.time.size
    run = chain_run(ctx, revolutions)
    drive, period, D, i0, t_run = run.drive, run.period, run.D, run.i0, run.t_run
    try:
        model.start_state(drive, float(t_run[0]))
    except ValueError as exc:  # no rest for the train on the base circle: its joints contradict each other
        raise InputError(scene.source, "linkage.elements", f"{exc}: check the joints' lash and contacts") from None
    sol = run.solve(model, drive, t_run, **run.options)
    rotate, _ = output_order(n, i0)
    last = slice((revolutions - 1) * n, revolutions * n)
    t_last = float(t_run[(revolutions - 1) * n])

    def col(values):
        return rotate(np.asarray(values, dtype=float)[last])

    s, v, a, jerk = col(sol.s), col(sol.v), col(sol.a), col(sol.jerk)
    force = col(sol.linkage_force)
    contact = col(sol.contact) > 0.5
    phase = col(sol.phase)
    c = model.chain
    W = c.preload + c.closing_load + c.spring_rate * s
    k_series = 1.0 / sum(1.0 / j.stiffness for j in model.joints)
    lash = sum(j.lash for j in model.joints)
    open_valve = s > 0.0
    deviation = np.where(open_valve, s - (D[0] - lash - W / k_series), 0.0)
    separated = open_valve & ~contact

    warnings: list[str] = []
    events = sorted((_event(e, period, omega) for e in sol.events if e["time_s"] >= t_last),
                    key=lambda e: e.time_s)
    motion, columns = linkage_outputs(s, v, a, jerk, force, ratio * force, deviation, contact, separated, events,
                                      TRAIN_KINDS, ctx.time, period)
    floats, float_warnings = float_report(ctx, s, events, period)
    warnings.extend(float_warnings)
    columns["valve_phase"] = phase
    columns["seat_force_N"] = col(sol.seat_force)
    retainer = col(sol.retainer_force)
    static = c.static_retainer_force(s)
    columns.update({"spring_force_retainer_N": retainer, "spring_force_static_N": static,
                    "surge_force_N": retainer - static})
    for j in range(c.elements):
        columns[f"coil_{j + 1}_displacement_m"] = col(sol.coils[j])
    elements = scene.linkage.elements
    for i, e in enumerate(elements):
        columns[f"part_{e.name}_displacement_m"] = col(sol.parts[i]) / e.ratio
        columns[f"part_{e.name}_velocity_m_s"] = col(sol.part_velocities[i]) / e.ratio
        columns[f"part_{e.name}_accel_m_s2"] = col(sol.part_accelerations[i]) / e.ratio
    # a joint's force along the travel of the part on its cam side (the cam's: the follower's)
    joint_ratio = ([e.ratio for e in elements] + [1.0]) if elements else [1.0]
    for j, jt in enumerate(model.all_joints):
        r = joint_ratio[j] if j < len(joint_ratio) else 1.0
        columns[f"contact_{jt.name.replace('-', '_')}_force_N"] = col(sol.joint_forces[jt.name]) * r
        columns[f"contact_{jt.name.replace('-', '_')}_closed"] = col(sol.joint_closed[jt.name])

    counts: dict = {}
    first: dict = {}
    for e in events:
        name = e.values.get("contact")
        if name is not None and e.kind in ("separation", "contact-opens"):
            counts[name] = counts.get(name, 0) + 1
            first.setdefault(name, e.cam_angle_deg)
    freqs = model.natural_frequencies(model.running_key())
    summary = {
        "elastic_method": scene.solver.method,
        "elastic_model": f"valve train of {len(model.parts)} parts"
                         + (f", spring of {c.elements} masses" if c.elements else "")
                         + (", hydraulic lash adjuster" if model.hla is not None else "") + ", elastic seat",
        "train_parts": [{"name": e.name, "referred_mass_kg": e.referred_mass, "ratio": e.ratio} for e in elements],
        "train_natural_frequencies_Hz": [float(f) for f in freqs[:6]],
        "train_modes_cam_orders": exciting_orders(freqs, omega, D[0]),
        "contact_openings": counts,
        "contact_first_opening_deg": first,
        **motion,
        **floats,
        "elastic_solver": dict(sol.stats),
    }
    clashes = [e for e in events if e.kind == "coil-clash"]
    if clashes:
        warnings.append(f"coil clash: the spring reaches its solid height {len(clashes)} time(s), first at "
                        f"{clashes[0].cam_angle_deg:.2f} deg (the model goes on without the coils' contact)")
    if model.hla is not None:
        block, more_events, more_warnings = _hla_report(model, sol, D, t_run, n, revolutions, i0, col, period, omega,
                                                         t_last, ctx.time)
        summary["hla"] = block
        events = sorted(events + more_events, key=lambda e: e.time_s)
        warnings.extend(more_warnings)
        p_rest = float(model.static_state(0.0)[0][model.plunger_index])
        columns["hla_plunger_travel_m"] = col(sol.plunger) - p_rest
        columns["hla_chamber_pressure_Pa"] = col(sol.chamber_pressure)
        columns["hla_check_valve_open"] = col(sol.check_open)
    if not summary.get("hla", {}).get("pump_up"):  # (pump-up has its own warning: the valve held off its seat)
        warnings.extend(not_at_rest(int(np.asarray(sol.phase)[-1]) == 0, math.degrees(omega * float(t_run[0])) % 360.0))
    return EffectOutput(columns=columns, summary=summary, events=tuple(events), warnings=tuple(warnings))


def _hla_report(model, sol, D, t_run, n, revolutions, i0, col, period, omega, t_last, time):
    """The adjuster's summary block, the pump-up event and the warnings."""
    h = model.hla
    p_rest = float(model.static_state(0.0)[0][model.plunger_index])
    S = np.asarray(D[0])
    base = S <= float(S.min()) + 1e-9 * max(float(S.max() - S.min()), 1e-12)
    base_run = np.roll(base, -i0)  # the base circle in run order (the run starts at output sample i0)
    per_rev = []
    for k in range(revolutions):
        idx = slice(k * n, (k + 1) * n)
        p = np.asarray(sol.plunger)[idx]
        s = np.asarray(sol.s)[idx]
        ph = np.asarray(sol.phase)[idx]
        on_base = base_run
        seated = bool(np.any(ph[on_base] == 0))
        per_rev.append({"revolution": k + 1, "plunger_travel_m": float(p[-1] - p[0]),
                        "plunger_extension_m": float(p_rest - p.min()),
                        "base_circle_min_lift_m": float(s[on_base].min()), "seated": seated})
    lastrev = per_rev[-1]
    pump_up = not lastrev["seated"] and lastrev["base_circle_min_lift_m"] > 0.0
    check = np.asarray(sol.check_open)[(revolutions - 1) * n:]
    P = np.asarray(sol.chamber_pressure)[(revolutions - 1) * n:]
    opens = [e for e in sol.events if e["kind"] == "check-valve-open" and e["time_s"] >= t_last]
    p_last = np.asarray(sol.plunger)[(revolutions - 1) * n:]
    block = {
        "revolutions": revolutions,
        "per_revolution": per_rev,
        "plunger_travel_per_revolution_m": lastrev["plunger_travel_m"],
        "lash_taken_up_m": float(p_rest - p_last.min()),
        "plunger_rest_m": p_rest,
        "chamber_pressure_min_Pa": float(P.min()),
        "chamber_pressure_max_Pa": float(P.max()),
        "check_valve_openings": len(opens),
        "check_valve_open_angle_deg": float(360.0 * np.count_nonzero(check) / check.size),
        "leak_conductance_m3_s_Pa": h.leak_conductance,
        "refill_conductance_m3_s_Pa": h.refill_conductance,
        "effective_bulk_modulus_Pa": h.effective_bulk_modulus,
        "oil_column_stiffness_N_m": h.oil_stiffness,
        "pump_up": pump_up,
        "pump_up_valve_lift_m": lastrev["base_circle_min_lift_m"] if pump_up else 0.0,
    }
    events, warnings = [], []
    if pump_up:
        # at the first output sample of the base circle (in cam angle) of the last revolution
        j = int(np.flatnonzero(base)[0])
        t_ev = float(time[j])
        events.append(Event("pump-up", t_ev, math.degrees(omega * t_ev) % 360.0,
                            {"valve_lift_m": block["pump_up_valve_lift_m"]}))
        warnings.append(f"pump-up: the adjuster has grown {1e3 * block['lash_taken_up_m']:.3f} mm while the valve "
                        f"floated; the valve stays {1e3 * block['pump_up_valve_lift_m']:.3f} mm off its seat over the "
                        f"base circle (revolution {revolutions} of {revolutions}): the cylinder's compression leaks there")
    # the linear chamber's one modulus is the secant to reference_pressure (dynamics/hla.py); with
    # air in the oil it depends on that pressure, so a peak far from it ran on the wrong stiffness
    peak = float(P.max())
    if h.aeration > 0.0 and peak > h.supply_pressure:
        at_peak = replace(h, reference_pressure=peak).effective_bulk_modulus
        block["secant_modulus_at_peak_Pa"] = at_peak
        used = h.effective_bulk_modulus
        if abs(used / at_peak - 1.0) > SECANT_TOLERANCE:
            warnings.append(f"the oil's modulus is the secant to hla.reference_pressure = {h.reference_pressure / 1e6:.3g} "
                            f"MPa ({used / 1e6:.0f} MPa), but the chamber peaks at {peak / 1e6:.3g} MPa, where the "
                            f"secant is {at_peak / 1e6:.0f} MPa ({100.0 * (used / at_peak - 1.0):+.0f} %): the oil "
                            "column's stiffness is off by as much; set reference_pressure near the peak")
    if float(P.min()) < -ATMOSPHERE:
        warnings.append(f"the adjuster's chamber falls to {P.min() / 1e6:.2f} MPa (gauge): below the oil's vapour "
                        "pressure, where it would cavitate; the model's oil does not (a linear chamber)")
    return block, events, warnings


def hla_row(result) -> dict[str, float]:
    """A sweep row's adjuster figures (the elastic effect's with [hla]: explorer/effects/registry.py,
    section_figures) from the run's summary block "hla"."""
    hla = result.summary.get("hla") or {}

    def figure(key: str) -> float:
        value = hla.get(key)
        return math.nan if value is None else float(value)

    return {"pump_up_valve_lift_m": figure("pump_up_valve_lift_m"), "hla_lash_taken_up_m": figure("lash_taken_up_m"),
            "hla_plunger_travel_per_revolution_m": figure("plunger_travel_per_revolution_m"),
            "hla_chamber_pressure_max_Pa": figure("chamber_pressure_max_Pa")}
