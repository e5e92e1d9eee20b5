"""Effect `elastic`: the valve driven through the elastic linkage (Schenker 1902, section 3).

The linkage model (dynamics/model.py) is solved over one revolution with the scene's solver
method. The columns valve_lift_m, valve_velocity_m_s, valve_accel_m_s2 and valve_jerk_m_s3
replace the rigid ones (which stay available as rigid_valve_*), and the effect adds
  linkage_force_N           compressive force in the linkage at the valve (0 when unloaded)
  camshaft_back_pressure_N  Schenker's "Rueckdruck": that force referred to the follower
                            (times the lever ratio, by virtual work), i.e. the load on the cam
                            along the follower's travel; W + p M1 while the valve moves in contact
  deviation_from_drive_m    s - (S - lash - W/k), the valve's distance from Schenker's (S - W/k)
                            curve with W = preload + rate s + friction sign(v) + closing loads;
                            0 while the valve is closed
Jerk: the exact solver returns the closed form's third derivative (derivative of the phase's
ODE right-hand side); for other solvers it is computed the same way from their s, v, a and the
analytic drive: M1 j = k (S' - v) + c (S'' - a) - rate v in contact, M j = -rate v in flight,
0 at rest. It jumps where the acceleration jumps (events, S'' jumps).

Stiffness that changes along the cycle: a lift curve may carry its own elasticity
(`linkage_stiffness`: theta -> (k, dk/dtheta), the rolling lever's, which follows the changing
ratio). It is then put in series with [linkage] stiffness (the rest of the chain) as k(t), and
only the solvers that accept k(t) can run it (explorer/dynamics/solvers.py, varying_stiffness; the scene loader says so).

Periodic start: the solvers start with the valve at rest on its seat, so the revolution is
solved from the angle where the drive is lowest (the valve surely rests there) and the arrays
are rotated back; a warning says when the valve has not come back to rest one revolution later.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..core.errors import InputError
from ..dynamics import solvers as registry
from ..dynamics.model import EVENT_KINDS, PHASE_CODES, Drive, LinkageModel, StiffnessProfile
from ..dynamics.solvers import solve
from ..result import EffectOutput
from .chain_elastic import chain_elastic_effect
from .elastic_events import float_report, linkage_outputs, not_at_rest, output_order, revolution_events
from .residual import residual_figures


# The exact and taylor solvers split every output step into pieces of at most 0.5 / rho (rho the
# fastest rate of the linkage), scipy takes steps of that order: a slow revolution of a stiff,
# light linkage spans millions of natural periods (rpm = 1e-9 asked for 3.5 PiB of nodes), and a
# feather-light valve bounces through as many events (a 0.1 g valve on the rolling lever: 180 000
# steps, 26 s). The shipped scenes need a few thousand; the output grid itself is the scene's
# choice (solver.steps_per_revolution) and is not counted.
MAX_SOLVER_NODES = 100_000
REFERENCE_REVOLUTION_S = 0.1  # a revolution at 600 rpm: which key a refusal blames (check_resolution)


def _rates(model) -> dict[str, float]:
    """The linkage's rates (1/s): the contact phase's oscillation or, overdamped, its fast real
    root ("damped"); the flight's (the spring against the valve alone)."""
    alpha = 0.5 * model.damping / model.oscillating_mass
    w2 = (model.stiffness + model.spring_rate) / model.oscillating_mass
    contact = ("damped", alpha + math.sqrt(alpha * alpha - w2)) if alpha * alpha > w2 else ("contact", math.sqrt(w2))
    return dict([contact, ("flight", math.sqrt(model.spring_rate / model.mass))])


def _steps(rate: float, span: float) -> float:
    """Solver steps to resolve a rate (1/s) over span seconds: the exact and taylor solvers' pieces
    of at most 0.5 / rate."""
    return rate * span / 0.5


def fastest_rate(model) -> float:
    """rho (1/s): the linkage's fastest rate in contact (overdamped: the fast real root) or flight."""
    return max(_rates(model).values())


# The entries that set each rate, with a typical valve train's value and whether the rate grows
# with the entry (+1) or falls (-1): a refusal names the entry furthest from its typical value
# (in decades), the one a user most likely mistyped or pushed too far.
_TYPICAL = {"linkage.stiffness": ("stiffness", 1e7, +1), "spring.rate": ("spring_rate", 5e4, +1),
            "valve.mass": ("oscillating_mass", 0.1, -1), "linkage.damping": ("damping", 50.0, +1)}
_SET_BY = {"contact": ("linkage.stiffness", "spring.rate", "valve.mass"),
           "damped": ("linkage.damping", "valve.mass"), "flight": ("spring.rate", "valve.mass")}
_SLOWER = {"linkage.stiffness": "a softer linkage (linkage.stiffness)", "spring.rate": "a softer spring (spring.rate)",
           "valve.mass": "a heavier valve (valve.mass)", "linkage.damping": "less damping (linkage.damping)"}


def _blamed(model, rate: str) -> str:
    """The entry of those setting `rate` furthest from a typical valve train's (_TYPICAL)."""
    def decades(key):
        field, typical, sign = _TYPICAL[key]
        value = float(getattr(model, field))
        return sign * math.log10(value / typical) if value > 0.0 and math.isfinite(value) else math.inf
    return max(_SET_BY[rate], key=decades)


def check_resolution(model, t, method: str, file: str) -> None:
    """InputError when resolving the linkage's vibration over the times t would take more than
    MAX_SOLVER_NODES steps. The steps are the linkage's fastest rate times the revolution's time:
    the refusal names drive.rpm when the linkage would fit the budget over a revolution at 600 rpm
    (a slow revolution), else the linkage's entry furthest from a typical train's (_blamed); its
    reason gives the rate, the revolution's time and both remedies."""
    if registry.solver(method).fixed_step or len(t) < 2:  # a fixed-step scheme takes only the output grid
        return
    rates = _rates(model)
    fastest = max(rates, key=rates.__getitem__)
    span = float(t[-1] - t[0])
    nodes = _steps(rates[fastest], span)
    if not nodes <= MAX_SOLVER_NODES:  # also NaN
        rate = rates[fastest]
        shown = f"decay rate {rate:.3g} 1/s" if fastest == "damped" else f"{rate / (2.0 * math.pi):.3g} Hz"
        steps = f"{math.ceil(nodes):,}" if math.isfinite(nodes) else "unboundedly many"
        entry = _blamed(model, fastest)
        slower = " or ".join(_SLOWER[k] for k in (entry, *(k for k in _SET_BY[fastest] if k != entry)))
        if _steps(rate, REFERENCE_REVOLUTION_S) <= MAX_SOLVER_NODES:
            key, advice = "drive.rpm", f"a higher drive.rpm, or {slower}"
        else:
            key, advice = entry, f"{slower}, or a higher drive.rpm"
        raise InputError(file, key, f"resolving the linkage's vibration ({shown}) over a revolution of {span:.3g} s "
                         f"needs about {steps} solver steps (at most {MAX_SOLVER_NODES:,}): {advice}")


def solve_reporting(model, drive, t, method: str, options: dict, file: str = "<memory>") -> tuple:
    """(solution, warnings): solve(), a fixed-step scheme beyond its stability limit (the 1902
    scheme) run anyway with a warning, a resolution beyond the step budget refused naming `file`
    (also the gears' own elastic runs)."""
    check_resolution(model, t, method, file)
    warnings: list[str] = []
    info = registry.solver(method)
    try:
        return solve(model, drive, t, method=method, **options), warnings
    except ValueError as exc:
        if info.stability_error is None or not isinstance(exc, info.stability_error):
            raise
        warnings.append(f"{exc} The results below are those of the unstable scheme.")
        return solve(model, drive, t, method=method, **info.unstable_options(), **options), warnings


def elastic_jerk(model: LinkageModel, drive_values: np.ndarray, sol) -> np.ndarray:
    """Jerk from the phase ODEs (for solvers that do not return one)."""
    if sol.jerk is not None:
        return np.asarray(sol.jerk, dtype=float)
    S1, S2 = drive_values[1], drive_values[2]
    if sol.phase is not None:
        phase = np.asarray(sol.phase)
        moving_contact = phase == PHASE_CODES["contact"]
        flight = phase == PHASE_CODES["flight"]
    else:
        resting = (sol.v == 0.0) & (sol.a == 0.0)
        moving_contact = sol.contact & ~resting
        flight = ~sol.contact & ~resting
    if model.stiffness_profile is not None:  # k(t): d/dt [k (S - lash - s)] has a k' term
        k, dk = model.stiffness_profile(sol.t)
        spring_part = dk * (drive_values[0] - model.lash - sol.s) + k * (S1 - sol.v)
    else:
        spring_part = model.stiffness * (S1 - sol.v)
    contact_jerk = (spring_part + model.damping * (S2 - sol.a)
                    - model.spring_rate * sol.v) / model.oscillating_mass
    flight_jerk = -model.spring_rate * sol.v / model.mass
    return np.where(moving_contact, contact_jerk, np.where(flight, flight_jerk, 0.0))


def linkage_model(scene, lift, omega: float) -> LinkageModel:
    """The scene's linkage model; with the lift's own elasticity (a rolling lever) k(t) in series
    with [linkage] stiffness, `stiffness` then being the largest k (the solvers' step bounds)."""
    model = LinkageModel.from_scene(scene)
    own = getattr(lift, "linkage_stiffness", None)
    if own is None:
        return model
    profile = StiffnessProfile(own, omega, series=scene.linkage.stiffness)
    return replace(model, stiffness=profile.bounds()[1], stiffness_profile=profile)


def elastic_effect(ctx) -> EffectOutput:
    scene = ctx.scene
    if scene.linkage.elements or scene.hla is not None:  # a train of parts, an adjuster (#25)
        from .train_elastic import train_elastic_effect  # numba, scipy: only for a train of parts or [hla]

        return train_elastic_effect(ctx)
    if scene.spring.elements > 0:  # the spring as a body: its own model and solvers (issue #15)
        return chain_elastic_effect(ctx)
    omega = ctx.omega
    model = linkage_model(scene, ctx.lift, omega)
    ratio = scene.follower.ratio
    drive = Drive(ctx.lift, ratio, omega)
    n = ctx.time.size
    period = 2.0 * math.pi / omega
    D = drive(ctx.time)
    # start at the lowest drive position, where the valve rests on its seat, and run one
    # revolution plus one step (to see whether the motion has come back to rest)
    i0 = int(np.argmin(D[0]))
    t_run = np.concatenate([ctx.time[i0:], ctx.time[:i0] + period])
    t_run = np.append(t_run, ctx.time[i0] + period)
    method = scene.solver.method
    sol, warnings = solve_reporting(model, drive, t_run, method, dict(scene.solver.options), scene.source)
    warnings.extend(sol.stats.get("warnings", []))

    rotate, back = output_order(n, i0)

    s, v, a = rotate(sol.s), rotate(sol.v), rotate(sol.a)
    force = rotate(sol.linkage_force)
    contact = np.zeros(n, bool)
    contact[back] = np.asarray(sol.contact)[:n]
    # the exact solver returns the jerk; the others get it from the ODE (one more drive evaluation)
    jerk = rotate(sol.jerk if sol.jerk is not None else elastic_jerk(model, drive(t_run), sol))
    phase = None
    if sol.phase is not None:
        phase = np.empty(n, dtype=np.int64)
        phase[back] = np.asarray(sol.phase)[:n]
    warnings.extend(not_at_rest(sol.s[-1] == 0.0 and sol.v[-1] == 0.0, math.degrees(omega * t_run[0]) % 360.0))

    # Schenker's curve S - lash - W/k, with W the resistance the valve feels
    W = model.preload + model.closing_load + model.spring_rate * s + model.friction * np.where(v < 0.0, -1.0, 1.0)
    open_valve = s > 0.0
    k_t = model.stiffness_at(ctx.time)
    deviation = np.where(open_valve, s - (D[0] - model.lash - W / k_t), 0.0)
    back_pressure = ratio * force
    separated = open_valve & ~contact

    events = revolution_events(sol.events, EVENT_KINDS, float(t_run[0]), period, omega)
    motion, columns = linkage_outputs(s, v, a, jerk, force, back_pressure, deviation, contact, separated, events,
                                      EVENT_KINDS, ctx.time, period)

    stats = {k: v for k, v in sol.stats.items() if k != "warnings"}
    if model.stiffness_profile is not None:
        stats["stiffness_min_N_m"], stats["stiffness_max_N_m"] = model.stiffness_profile.bounds()
    floats, float_warnings = float_report(ctx, s, events, period)
    warnings.extend(float_warnings)
    summary = {
        "elastic_method": method,
        "elastic_natural_period_s": model.natural_period(),
        "elastic_steps_per_natural_period": model.natural_period() / (period / n),
        "lift_off_compression_m": (model.seated_resistance + model.friction) / _stiffness_at_lift_off(model, events),
        **motion,
        **floats,
        **residual_figures(ctx.lift, ratio, model, ctx.theta, s, v),
        "elastic_solver": stats,
    }
    if phase is not None:
        columns["valve_phase"] = phase.astype(float)
    return EffectOutput(columns=columns, summary=summary, events=tuple(events), warnings=tuple(warnings))


def _stiffness_at_lift_off(model: LinkageModel, events) -> float:
    """k where the valve lifts (the first lift-off; the constant k, or k(t) there)."""
    if model.stiffness_profile is None:
        return model.stiffness
    lift_offs = [e.time_s for e in events if e.kind == "lift-off"]
    return float(model.stiffness_at(np.array(lift_offs[:1] or [0.0]))[0])
