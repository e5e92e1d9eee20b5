"""Effect `elastic` with the spring as a body (spring.elements > 0, issue #15).

The valve, the spring cut into N masses (chain.py), the linkage one-sided at the cam side and an
elastic seat one-sided at the valve, solved over one revolution from the lowest drive position
(where the valve rests on its seat, in static equilibrium) by the scene's solver's chain
function (explorer/dynamics/solvers.py: chain_entry; exact and scipy have one).

Columns: those of the massless elastic effect (valve_lift_m, ..., linkage_force_N,
camshaft_back_pressure_N, deviation_from_drive_m, valve_in_contact, valve_phase), and
  spring_force_retainer_N   the spring's force on the retainer, with its surge (dynamic)
  spring_force_static_N     preload + rate * lift: what the massless spring would push
  surge_force_N             their difference
  seat_force_N              the elastic seat's force on the valve
  coil_<j>_displacement_m   coil j (1 next to the retainer) in the lift direction
Summary: the spring's modal frequencies (ends held) and the cam orders that excite them (the
drive's harmonics nearest to each), surge amplitude, first separation, clash warnings.
"""

from __future__ import annotations

import math

import numpy as np

from ..dynamics.chain import CHAIN_EVENT_KINDS, FRICTION_EVENT_KINDS, ChainModel, continuous_frequencies
from ..result import EffectOutput
from .chain_run import chain_run
from .elastic_events import float_report, linkage_outputs, not_at_rest, output_order, revolution_events


def exciting_orders(frequencies_hz: np.ndarray, omega: float, drive_values: np.ndarray, count: int = 3) -> list:
    """Per mode: its frequency as a cam order (f / camshaft frequency) and the drive's acceleration
    harmonics at the integer orders around it (the cam orders that excite it), amplitudes in m/s^2.

    The acceleration, not the displacement: a mode driven through its base feels m times the base's
    acceleration (m z'' + c z' + k z = -m y''), which is also what `explorer spectrum` reports. Each
    is (k omega)^2 times the displacement's Fourier amplitude (exact for a periodic drive: the FFT
    of the sampled displacement, smooth, aliases far less than that of an acceleration with jumps)."""
    f_cam = omega / (2.0 * math.pi)
    S = np.asarray(drive_values, dtype=float)
    spectrum = np.abs(np.fft.rfft(S)) * 2.0 / S.size
    out = []
    for f in frequencies_hz[:count]:
        order = f / f_cam
        near = [int(math.floor(order)), int(math.ceil(order))]
        near = sorted({k for k in near if 1 <= k < spectrum.size})
        out.append({"frequency_Hz": float(f), "cam_order": float(order),
                    "exciting_accel_m_s2": {str(k): float((k * omega) ** 2 * spectrum[k]) for k in near}})
    return out


def chain_elastic_effect(ctx) -> EffectOutput:
    scene = ctx.scene
    omega = ctx.omega
    model = ChainModel.from_scene(scene)
    ratio = scene.follower.ratio
    n = ctx.time.size
    run = chain_run(ctx)
    period, D, i0, t_run = run.period, run.D, run.i0, run.t_run
    sol = run.solve(model, run.drive, t_run, **run.options)
    rotate, _ = output_order(n, i0)

    s, v, a, jerk = rotate(sol.s), rotate(sol.v), rotate(sol.a), rotate(sol.jerk)
    force = rotate(sol.linkage_force)
    contact = rotate(sol.contact) > 0.5
    phase = rotate(sol.phase)
    retainer = rotate(sol.retainer_force)
    static = model.static_retainer_force(s)
    W = model.preload + model.closing_load + model.spring_rate * s
    open_valve = s > 0.0
    deviation = np.where(open_valve, s - (D[0] - model.lash - W / model.stiffness), 0.0)
    separated = open_valve & ~contact

    warnings = []
    # with friction the valve's stops (stick, turn, release) are listed and counted too
    kinds = CHAIN_EVENT_KINDS + (FRICTION_EVENT_KINDS if model.friction > 0.0 else ())
    events = revolution_events(sol.events, kinds, float(t_run[0]), period, omega)
    clashes = [e for e in events if e.kind == "coil-clash"]
    if clashes:
        warnings.append(f"coil clash: the spring reaches its solid height {len(clashes)} time(s), first at "
                        f"{clashes[0]['cam_angle_deg']:.2f} deg (the model goes on without the coils' contact)")
    motion, columns = linkage_outputs(s, v, a, jerk, force, ratio * force, deviation, contact, separated, events, kinds,
                                      ctx.time, period)
    floats, float_warnings = float_report(ctx, s, events, period)
    warnings.extend(float_warnings)
    # (the elastic seat's phase, code 0: the valve on its seat; the run starts there at rest)
    warnings.extend(not_at_rest(int(sol.phase[-1]) == 0, math.degrees(omega * float(t_run[0])) % 360.0))
    freqs = model.spring_modal_frequencies()
    summary = {
        "elastic_method": scene.solver.method,
        "elastic_model": f"valve + spring of {model.elements} masses, elastic seat"
                         + (f", Coulomb friction {model.friction:g} N" if model.friction > 0.0 else ""),
        "spring_mass_kg": model.spring_mass,
        "spring_elements": model.elements,
        "spring_modal_frequencies_Hz": [float(f) for f in freqs[:5]],
        # the continuous spring's (j/2) sqrt(k/m_s), ends held, beside the chain's: their
        # difference is the chain's discretisation (spring_surge, 8 masses: -0.5 % at the first
        # mode, -12 % at the fifth)
        "spring_continuous_frequencies_Hz": [float(f) for f in continuous_frequencies(
            min(5, freqs.size), model.spring_rate, model.spring_mass)],
        "spring_modes_cam_orders": exciting_orders(freqs, omega, D[0]),
        "surge_amplitude_N": float(np.max(np.abs(retainer - static))),
        "peak_spring_force_retainer_N": float(retainer.max()),
        **motion,
        **floats,
        "elastic_solver": dict(sol.stats),
    }
    columns.update({
        "valve_phase": phase,
        "spring_force_retainer_N": retainer,
        "spring_force_static_N": static,
        "surge_force_N": retainer - static,
        "seat_force_N": rotate(sol.seat_force),
    })
    for j in range(model.elements):
        columns[f"coil_{j + 1}_displacement_m"] = rotate(sol.coils[j])
    return EffectOutput(columns=columns, summary=summary, events=tuple(events), warnings=tuple(warnings))
