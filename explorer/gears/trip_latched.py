"""The trip gear's latched phase in the effects 'forces', 'contact' and 'elastic' (its variants of
those effects: explorer.gears.trip_gear.TripGear.effects).

While the latch carries the valve - from the pick-up, where the latch has run through its
over-travel s_o (valve.lash), to the trip - the gear is a positive drive: the latch lift X(theta)
([lift], valve-referred) moves the valve, s = X - s_o. From the trip on the valve closes by itself
(explorer.gears.trip: spring, loads, friction, dashpot) and the latch carries nothing. The
generic effects, fed the trip gear's lift curve, would treat that free closing as driven; here
each of them is restricted to what the latch does.

forces   Over the carried window the latch transmits
             F = M p + F0 + k s + D + R sgn(v) - B,      p = w^2 X'',  v = w X'
         i.e. forces.load_parts on the latch law, F = w^2 A + G, less the buffer's upward force
         B on the valve along the rigid latch motion (trip.LatchedBuffer: 0 for a check-valve
         air pocket while the valve rises - it vents; with inlet = "orifice" the pocket sucks,
         B < 0, until it opens at s = stroke; a pocket or oil cushion the latch lowers the valve
         into pushes back, B > 0; column latch_buffer_force_N). Its minimum and maximum, refined
         on the analytic law and the pocket's dense solution (pieces cut where the buffer opens,
         closes or vents), say whether the valve stays on the latch: a latch that decelerates
         harder than spring and loads can follow before the trip throws the valve off (F < 0).
         Without the buffer that happens above the throw-off speed w^2 = min G / (-A) over the
         window: forces.float_speed with the window as the only "open" stretch (jump_speed_rpm
         leaves B out: it depends on the speed through the pocket's flow). The pick-up is an
         impact (the latch meets the resting spindle with w X' after the over-travel: the lash
         effect's impact_velocity_opening_m_s, the gear effect's latch_pickup_*); the forces
         effect gives the rigid force just after it, the finite peak of the impact needs the
         elastic linkage. Camshaft (eccentric) torque by power balance, T = F v / w = F X'
         (frictionless latch drive), and the work per stroke, the integral of T over the window
         (Gauss-Legendre on each smooth piece, the buffer's share integrated with the pocket's
         ODE), which equals the gain of kinetic and spring energy plus the work against D, R and
         the buffer after the pick-up (a test). work_per_stroke_J and mean_power_W leave out the
         pick-up impulse: the latch's speed times the impulse M v_p, i.e. M v_p^2
         (pickup_impulse_work_J; half of it the valve's kinetic energy, half lost in the impact).
         Outside the window the latch force, its inertia and friction parts and the torque are 0
         (nothing transmitted - as forces.rigid_train_forces reports a seated valve); the spring
         force follows the valve; the required spring force and the margin are the seat's while
         the valve is shut (-W: hold it down against the closing loads) and, while it closes
         freely (no latch to stay on), the spring force that closes it: Trinks' rule (seed 003)
         P_f = (p/g - 1) G_v + W_s = M p - W + R with p = 2 s_trip / t^2 for the wanted closing
         time t = [gear.trip] closing_time from the lift at the trip (explorer.mechanics.springs.
         trinks_closing_force; here with every closing load W, not the valve's weight alone), and
         without a wanted time its limit t -> infinity, R - W: the spring must at least overcome
         the friction beyond the closing loads, or the valve hangs open (the closing model refuses
         such a scene). No NaN: every sample has a requirement.
contact  No cam surface: the latch face bears on the spindle's catch (face square to the spindle).
         To trip, the governor-set trip gear pulls the latch out sideways against the friction
         mu F_trip ([gear.trip] latch_friction) and, over the engagement latch_depth d, does the
         work mu F_trip d; the face's bearing pressure is F / (latch_width d).
elastic  The latch drives the valve through the linkage (stiffness k, damping c, referred to the
         valve; lash = the over-travel). The scene's solver runs from the latch's lowest point,
         the valve at rest on its seat, to the trip instant, which ends its time grid (the
         solvers' public solve()). The pick-up impact excites the linkage: the valve may leave the
         latch and land on it again. At the trip the latch lets go: the elastic valve state (s, v)
         starts the free closing (trip.simulate_closing with the scene's buffer and the pocket
         density the rigid latched phase left), which runs to the seat. The linkage force is 0
         from the trip on. The linear linkage model cannot carry the buffer's nonlinear force
         while the latch drives; where the rigid latched phase has one (B above) the run warns
         with its largest size (elastic_trip.buffer_force_left_out_N).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..dynamics import solvers
from ..dynamics.model import EVENT_KINDS, PHASE_CODES, Drive, LinkageModel
from ..effects.elastic import elastic_jerk, solve_reporting
from ..effects.elastic_events import separated_angle_deg
from ..effects.forces import rigid_mass_summary
from ..mechanics.forces import (Pieces, TrainLoads, float_speed, friction_direction, load_parts, loss_report,
                                minimise_on_pieces, velocity_zeros)
from ..mechanics.forces import loss_intervals as intervals_of
from ..result import EffectOutput, Event
from .trip import simulate_closing

TWO_PI = 2.0 * math.pi
GAUSS_NODES = 32  # per smooth piece: the latch laws are trigonometric/polynomial, 32 nodes reach rounding
_INSIDE = 1e-11  # rad: one-sided limits at the pick-up and the trip (as forces._INSIDE)


def trip_lift_of(ctx):
    """The TripLift of a trip scene (the pipeline's, or built from the scene)."""
    return ctx.lift if hasattr(ctx.lift, "closing") else ctx.gear.build_lift(ctx.scene)


def carried(lift, theta) -> np.ndarray:
    """True where the latch carries the valve: pick-up <= phi < trip (an instant belongs to the
    state after its event, as in ClosingSolution.state)."""
    phi = np.mod(np.asarray(theta, dtype=float) - lift.start, TWO_PI)
    return (phi >= lift.phi_pick) & (phi < lift.phi_trip)


def buffer_force(lift, theta) -> np.ndarray:
    """B, the buffer's upward force on the valve along the rigid latch motion (0 outside the
    carried window and without a buffer)."""
    theta = np.asarray(theta, dtype=float)
    latched = getattr(lift, "latched", None)
    return np.zeros(theta.shape) if latched is None else latched.state(theta)["force"]


class _LatchAndBuffer:
    """Lift-like view for forces.minimise_on_pieces: the latch's derivatives and, as a fifth
    row, the buffer force B at the same angles."""

    def __init__(self, lift):
        self.lift = lift

    def derivatives(self, theta):
        theta = np.asarray(theta, dtype=float)
        d = self.lift.latch.derivatives(theta)
        return np.concatenate([d, buffer_force(self.lift, theta)[None]], axis=0)


def carried_pieces(lift, n_grid: int = 4096):
    """forces.Pieces of one revolution: the carried window split where the latch law, the
    friction direction or the buffer's state changes (is_open True), and the rest of the
    revolution as one piece (is_open False: the latch carries nothing there)."""
    latch = lift.latch
    latched = getattr(lift, "latched", None)
    buffer_cuts = latched.cuts() if latched is not None else np.zeros(0)
    inner = np.mod(np.concatenate([np.asarray(latch.breakpoints(), dtype=float), velocity_zeros(latch, n_grid),
                                   buffer_cuts]) - lift.start, TWO_PI)
    inner = inner[(inner > lift.phi_pick + 1e-12) & (inner < lift.phi_trip - 1e-12)]
    cuts = np.unique(np.concatenate([[lift.phi_pick], inner, [lift.phi_trip]]))
    starts = lift.start + np.append(cuts[:-1], lift.phi_trip)
    ends = lift.start + np.append(cuts[1:], lift.phi_pick + TWO_PI)
    d = latch.derivatives(np.mod(0.5 * (starts + ends), TWO_PI))
    return Pieces(start=starts, end=ends, is_open=np.arange(starts.size) < starts.size - 1,
                  direction=friction_direction(d[1], d[2]))


def _force(lift, d, direction, loads, omega):
    """(latch force F = w^2 A + G - B, its inertia part w^2 A) for derivatives d; a fifth row of d,
    if present, is the buffer force B (_LatchAndBuffer)."""
    a_coef, g_part, _ = load_parts(d, direction, loads, 1.0, lift.overtravel)
    force = omega**2 * a_coef + g_part
    if d.shape[0] > 4:
        force = force - d[4]
    return force, omega**2 * a_coef


def latch_force(lift, theta, loads, omega: float) -> dict[str, np.ndarray]:
    """Per sample: the rigid latch force F, its inertia, friction and buffer (B, upward on the
    valve) parts, the camshaft torque T = F dX/dtheta, and the carried mask; all 0 where the latch
    does not carry the valve."""
    theta = np.asarray(theta, dtype=float)
    d = _LatchAndBuffer(lift).derivatives(theta)
    direction = friction_direction(d[1], d[2])
    force, inertia = _force(lift, d, direction, loads, omega)
    on = carried(lift, theta)
    return {
        "carried": on,
        "force": np.where(on, force, 0.0),
        "inertia": np.where(on, inertia, 0.0),
        "friction": np.where(on, loads.friction * direction, 0.0),
        "buffer": np.where(on, d[4], 0.0),
        "torque": np.where(on, force * d[1], 0.0),
    }


def window_limits(lift, loads, omega: float, pieces) -> tuple[float, float]:
    """(latch force just after the pick-up, latch force just before the trip): one-sided limits,
    with the friction direction of the first and last carried piece."""
    n_open = int(np.count_nonzero(pieces.is_open))
    drive = _LatchAndBuffer(lift)
    out = []
    for th, k in ((lift.start + lift.phi_pick + _INSIDE, 0), (lift.start + lift.phi_trip - _INSIDE, n_open - 1)):
        d = drive.derivatives(np.array([np.mod(th, TWO_PI)]))
        out.append(float(_force(lift, d, float(pieces.direction[k]), loads, omega)[0][0]))
    return out[0], out[1]


def latch_work(lift, loads, omega: float, pieces) -> float:
    """Work the latch does on the valve from the pick-up to the trip, integral of T dtheta (J): the
    rigid part by Gauss-Legendre on each smooth piece, the buffer's (integral of -B ds) from the
    pocket's ODE (LatchedBuffer.work). The pick-up impulse's work M v_p^2 is not in it."""
    x, wts = np.polynomial.legendre.leggauss(GAUSS_NODES)
    total = 0.0
    for i in np.nonzero(pieces.is_open)[0]:
        a, b = pieces.start[i], pieces.end[i]
        th = 0.5 * (b - a) * x + 0.5 * (a + b)
        d = lift.latch.derivatives(np.mod(th, TWO_PI))
        force = _force(lift, d, float(pieces.direction[i]), loads, omega)[0]
        total += 0.5 * (b - a) * float(np.sum(wts * force * d[1]))
    latched = getattr(lift, "latched", None)
    return float(total + (latched.work if latched is not None else 0.0))


def latch_force_extremes(lift, loads, omega: float, pieces, n_grid: int = 4096) -> dict:
    """Smallest and largest latch force over the carried window with their cam angles (rad),
    refined on the analytic law and the buffer's dense solution (forces.minimise_on_pieces): the
    one source of the forces effect's and the gear effect's extremes."""
    drive = _LatchAndBuffer(lift)

    def force(d, direction):
        return _force(lift, d, direction, loads, omega)[0]

    f_min, th_min = minimise_on_pieces(drive, pieces, force, n_grid=n_grid)
    neg_max, th_max = minimise_on_pieces(drive, pieces, lambda d, direction: -force(d, direction), n_grid=n_grid)
    return {"min": f_min, "min_theta": th_min, "max": -neg_max, "max_theta": th_max}


def buffer_extremes(lift, pieces, n_grid: int = 4096) -> dict:
    """Smallest (most suction) and largest buffer force B over the carried window, with cam angles
    (rad; None where the buffer exerts nothing)."""
    drive = _LatchAndBuffer(lift)
    b_min, th_min = minimise_on_pieces(drive, pieces, lambda d, direction: d[4], n_grid=n_grid)
    neg_max, th_max = minimise_on_pieces(drive, pieces, lambda d, direction: -d[4], n_grid=n_grid)
    b_min, b_max = min(b_min, 0.0), max(-neg_max, 0.0)
    return {"min": b_min, "min_theta": th_min if b_min < 0.0 else None,
            "max": b_max, "max_theta": th_max if b_max > 0.0 else None}


def loss_intervals(lift, loads, omega: float, pieces, n_grid: int = 4096) -> list[tuple[float, float]]:
    """Where the latch force (buffer included) is <= 0 in the carried window: (loss, regain) cam
    angles, by the one definition of explorer.mechanics.forces.loss_intervals (the pick-up counts as the
    valve having been seated, the trip as its end)."""
    drive = _LatchAndBuffer(lift)

    def force_of(t, direction):
        return _force(lift, drive.derivatives(np.mod(t, TWO_PI)), direction, loads, omega)[0]

    return intervals_of(pieces, force_of, n_grid)


# --------------------------------------------------------------------------------------------
# forces
# --------------------------------------------------------------------------------------------


def free_closing_requirement(scene, lift, loads) -> float:
    """The spring force (N) the released valve needs: Trinks' rule P_f = M p + R - W (seed 003,
    explorer.mechanics.springs.trinks_closing_force with every closing load W in the place of the
    valve's weight G_v = M g) for closing from the lift at the trip within [gear.trip]
    closing_time, p = 2 s_trip / t^2; without a wanted closing time its limit p -> 0, R - W."""
    t_wanted = scene.gear.part("trip")["closing_time"]
    s_trip = float(lift.latch.derivatives(np.array([lift.trip_angle]))[0, 0] - lift.overtravel)
    p = 2.0 * s_trip / t_wanted**2 if t_wanted is not None else 0.0
    return loads.mass * p + loads.friction - loads.closing


def trip_forces_effect(ctx) -> EffectOutput:
    scene, w = ctx.scene, ctx.omega
    lift = trip_lift_of(ctx)
    loads = TrainLoads.from_scene(scene)
    s = np.asarray(ctx.columns["rigid_valve_lift_m"], dtype=float)
    parts = latch_force(lift, ctx.theta, loads, w)
    on, force, torque = parts["carried"], parts["force"], parts["torque"]
    seated = ~on & (s <= 0.0)
    spring = loads.preload + loads.rate * s
    # F = spring + inertia + friction + closing - B: the spring force that keeps F >= 0; seated: the
    # force that holds the valve down; released: the force that closes it (free_closing_requirement)
    required = np.where(on, -(parts["inertia"] + parts["friction"] + loads.closing - parts["buffer"]),
                        np.where(seated, -loads.closing, free_closing_requirement(scene, lift, loads)))
    margin = spring - required
    columns = {
        "spring_force_N": spring,
        "inertia_force_N": parts["inertia"],
        "friction_force_N": parts["friction"],
        "closing_load_N": np.full_like(s, loads.closing),
        "latch_buffer_force_N": parts["buffer"],  # B, upward on the valve: the latch carries -B
        "contact_force_N": force,
        "linkage_force_N": force,  # rigid: the linkage carries the latch force
        "follower_force_N": force,  # the latch law is valve-referred (ratio 1)
        "required_spring_force_N": required,
        "spring_margin_N": margin,
        "camshaft_torque_Nm": torque,
    }

    n_grid = max(4096, scene.solver.steps_per_revolution)
    pieces = carried_pieces(lift, n_grid)
    latch, so = lift.latch, lift.overtravel
    ext = latch_force_extremes(lift, loads, w, pieces, n_grid)
    f_min, th_min, f_max, th_max = ext["min"], ext["min_theta"], ext["max"], ext["max_theta"]
    jump = float_speed(latch, loads, 1.0, so, pieces, n_grid)
    f_pick, f_trip = window_limits(lift, loads, w, pieces)
    work = latch_work(lift, loads, w, pieces)
    mass = scene.valve.mass
    v_pick = w * float(latch.derivatives(np.array([lift.theta_of(lift.phi_pick)]))[1, 0])
    i_t = int(np.argmax(torque))
    latch_block: dict[str, Any] = {
        "pickup_cam_angle_deg": math.degrees(lift.theta_of(lift.phi_pick)),
        "trip_cam_angle_deg": math.degrees(lift.trip_angle),
        "carried_angle_deg": math.degrees(lift.phi_trip - lift.phi_pick),
        "force_after_pickup_N": f_pick,
        "force_at_trip_N": f_trip,
        # integral of T dtheta over the window; without the pick-up impulse's work (next key)
        "work_per_stroke_J": work,
        "mean_power_W": work * w / TWO_PI,
        # the latch's speed times the impulse M v_p: half the valve's kinetic energy, half lost
        "pickup_impulse_work_J": mass * v_pick**2,
        "valve_stays_on_latch": bool(f_min > 0.0),
    }
    latched = lift.latched
    if latched is not None:
        b_ext = buffer_extremes(lift, pieces, n_grid)
        b_trip = float(buffer_force(lift, np.array([np.mod(lift.trip_angle - _INSIDE, TWO_PI)]))[0])
        trip_part = scene.gear.part("trip")
        latch_block["buffer"] = trip_part["buffer"]
        if latched.buffer.has_state:
            latch_block["buffer_inlet"] = latched.buffer.inlet
        latch_block.update(
            min_buffer_force_N=b_ext["min"],
            min_buffer_force_cam_angle_deg=math.degrees(b_ext["min_theta"]) if b_ext["min_theta"] is not None else None,
            max_buffer_force_N=b_ext["max"],
            max_buffer_force_cam_angle_deg=math.degrees(b_ext["max_theta"]) if b_ext["max_theta"] is not None else None,
            buffer_force_at_trip_N=b_trip,
            buffer_work_J=latched.work,  # integral of -B ds, part of work_per_stroke_J
        )
    summary: dict[str, Any] = {
        "min_contact_force_N": f_min,
        "min_contact_force_cam_angle_deg": math.degrees(th_min),
        "max_contact_force_N": f_max,
        "max_contact_force_cam_angle_deg": math.degrees(th_max),
        "max_follower_force_N": f_max,
        "max_spring_force_N": float(spring.max()),
        "min_spring_margin_N": float(np.min(margin)),
        # the speed at which the latch's deceleration would throw the valve off before the trip
        # (spring and loads only: the buffer force depends on the speed through the pocket's flow)
        "jump_speed_rpm": jump.rpm if math.isfinite(jump.omega) else None,
        "jump_cam_angle_deg": math.degrees(jump.theta) if math.isfinite(jump.theta) else None,
        "valve_floats": bool(math.isfinite(jump.omega) and w >= jump.omega),
        "friction_N": loads.friction,
        "closing_loads_N": loads.closing,
        **rigid_mass_summary(scene),  # the M of the latch force (the forces effect's keys)
        "max_camshaft_torque_Nm": float(torque[i_t]),
        "max_camshaft_torque_cam_angle_deg": float(np.degrees(ctx.theta[i_t])),
        "min_camshaft_torque_Nm": float(torque[on].min()) if on.any() else 0.0,
        "latch": latch_block,
    }
    warnings: list[str] = []
    events: list[dict] = []
    b_min = float(buffer_force(lift, np.array([th_min]))[0])
    if jump.static_loss:
        warnings.append(f"the spring and closing loads do not hold the valve on the latch even at standstill "
                        f"(cam angle {math.degrees(jump.theta):.2f} deg)")
    elif f_min <= 0.0 and b_min > 0.0 and f_min + b_min > 0.0:
        warnings.append(
            f"the buffer pushes the valve off the latch before the trip: as the latch lowers the valve into the "
            f"dashpot its upward force reaches {b_min:.4g} N and the latch force falls to {f_min:.4g} N at cam "
            f"angle {math.degrees(th_min):.2f} deg")
    elif f_min <= 0.0:
        warnings.append(
            f"the latch throws the valve off before the trip: its deceleration needs more than spring and loads "
            f"supply, the rigid latch force falls to {f_min:.4g} N at cam angle {math.degrees(th_min):.2f} deg"
            + (f" (throw-off speed {jump.rpm:.6g} rpm)" if math.isfinite(jump.omega) else ""))
    intervals = loss_intervals(lift, loads, w, pieces, n_grid) if f_min < 0.0 else []
    summary["contact_loss_cam_angles_deg"] = [[math.degrees(a), math.degrees(b)] for a, b in intervals]
    events.extend(loss_report(intervals, w, f_min, th_min)[0])
    return EffectOutput(columns=columns, summary=summary, events=tuple(Event.of(e) for e in events),
                        warnings=tuple(warnings))


# --------------------------------------------------------------------------------------------
# contact
# --------------------------------------------------------------------------------------------


def trip_contact_effect(ctx) -> EffectOutput:
    scene, w = ctx.scene, ctx.omega
    lift = trip_lift_of(ctx)
    trip = scene.gear.part("trip")
    mu, width, depth = trip["latch_friction"], trip["latch_width"], trip["latch_depth"]
    loads = TrainLoads.from_scene(scene)
    pieces = carried_pieces(lift, max(4096, scene.solver.steps_per_revolution))
    _, f_trip = window_limits(lift, loads, w, pieces)
    # the forces effect's latch force (0 outside the carried window); a valve thrown off (F < 0)
    # does not bear on the latch
    bearing = np.maximum(np.asarray(ctx.columns["contact_force_N"], dtype=float), 0.0)
    f_max = max(float(ctx.summary["max_contact_force_N"]), 0.0)
    columns = {"latch_release_friction_N": mu * bearing}
    summary: dict[str, Any] = {
        "contact_follower_type": scene.follower.type,
        "latch_friction_coefficient": mu,
        "latch_force_at_trip_N": f_trip,
        "latch_release_friction_force_N": mu * max(f_trip, 0.0),
        # the governor may trip anywhere in the window: the largest pull it can meet
        "max_latch_release_friction_force_N": mu * f_max,
    }
    if width is not None:
        area = width * depth
        columns["latch_bearing_pressure_Pa"] = bearing / area
        summary.update(
            latch_width_m=width,
            latch_depth_m=depth,
            latch_contact_area_m2=area,
            latch_bearing_pressure_at_trip_Pa=max(f_trip, 0.0) / area,
            max_latch_bearing_pressure_Pa=f_max / area,
            max_latch_bearing_pressure_cam_angle_deg=ctx.summary["max_contact_force_cam_angle_deg"],
            latch_release_friction_work_J=mu * max(f_trip, 0.0) * depth,
        )
    return EffectOutput(columns=columns, summary=summary)


# --------------------------------------------------------------------------------------------
# elastic
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TripElasticMotion:
    """The elastic latched phase and the free closing after it, at the requested angles."""

    columns: dict  # s, v, a, j, force, contact, phase, deviation: arrays shaped like theta
    solution: Any  # DynamicsSolution of the latched phase at `nodes`
    nodes: np.ndarray  # s, absolute times of the latched run (latch bottom ... trip instant)
    closing: Any  # ClosingSolution from the elastic state at the trip (None: valve on its seat)
    state_at_trip: tuple[float, float]  # (s, v) handed over to the closing
    force_at_trip: float  # N, linkage force just before the latch lets go
    on_latch_at_trip: bool
    events: tuple
    warnings: tuple


def elastic_trip_motion(scene, lift, theta, method: str = solvers.DEFAULT, options: dict | None = None) -> TripElasticMotion:
    """Elastic valve motion of a trip gear at the cam angles theta (any order): the linkage model
    driven by the latch from its lowest point (valve at rest on the seat) to the trip instant, then
    the free closing from the elastic state there."""
    w = scene.drive.omega
    period = TWO_PI / w
    model = LinkageModel.from_scene(scene)
    drive = Drive(lift.latch, 1.0, w)
    theta = np.asarray(theta, dtype=float)
    phi = np.mod(theta - lift.start, TWO_PI)
    before = phi < lift.phi_trip
    t0 = lift.start / w
    t_before = t0 + phi[before] / w
    t_trip = t0 + lift.phi_trip / w
    nodes = np.unique(np.concatenate([[t0], t_before, [t_trip]]))
    sol, warnings = solve_reporting(model, drive, nodes, method, dict(options or {}), scene.source)
    warnings = list(warnings) + list(sol.stats.get("warnings", []))
    jerk_nodes = np.asarray(sol.jerk if sol.jerk is not None else elastic_jerk(model, drive(nodes), sol), dtype=float)
    if sol.phase is not None:
        phase_nodes = np.asarray(sol.phase)
    else:
        resting = (sol.v == 0.0) & (sol.a == 0.0)
        phase_nodes = np.where(sol.contact, PHASE_CODES["contact"],
                               np.where(resting, np.where(sol.s <= 0.0, PHASE_CODES["seated"], PHASE_CODES["stuck"]),
                                        PHASE_CODES["flight"]))

    shape = theta.shape
    out = {k: np.zeros(shape) for k in ("s", "v", "a", "j", "force", "deviation")}
    out["contact"] = np.zeros(shape, dtype=bool)
    out["phase"] = np.zeros(shape, dtype=np.int64)
    i = np.searchsorted(nodes, t_before)
    for key, values in (("s", sol.s), ("v", sol.v), ("a", sol.a), ("j", jerk_nodes), ("force", sol.linkage_force),
                        ("contact", sol.contact), ("phase", phase_nodes)):
        out[key][before] = np.asarray(values)[i]
    # Schenker's curve S - lash - W/k while the latch drives (0 where the valve is shut or tripped)
    S = drive(t_before)[0]
    sb, vb = out["s"][before], out["v"][before]
    W = model.preload + model.closing_load + model.spring_rate * sb + model.friction * np.where(vb < 0.0, -1.0, 1.0)
    out["deviation"][before] = np.where(sb > 0.0, sb - (S - model.lash - W / model.stiffness), 0.0)

    s_e, v_e = float(sol.s[-1]), float(sol.v[-1])
    f_e, on_e = float(sol.linkage_force[-1]), bool(sol.contact[-1])
    events: list[dict] = []

    def stamp(t_abs: float) -> dict:
        tt = math.fmod(t_abs, period)
        return {"time_s": tt, "cam_angle_deg": math.degrees(w * tt) % 360.0}

    for ev in sol.events:
        if ev["kind"] in EVENT_KINDS and ev["time_s"] < t_trip:
            item = {"kind": ev["kind"], **stamp(ev["time_s"])}
            if "velocity_m_s" in ev:
                item["velocity_m_s"] = float(ev["velocity_m_s"])
            events.append(item)
    events.append({"kind": "release", **stamp(t_trip), "lift_m": s_e, "velocity_m_s": v_e, "linkage_force_N": f_e,
                   "on_latch": on_e})

    closing = None
    after = ~before
    if s_e > 0.0 or v_e > 0.0:
        t_max = (TWO_PI - lift.phi_trip) / w
        latched = getattr(lift, "latched", None)
        # the pocket as the rigid latched phase left it (the elastic valve is microns off that path)
        closing = simulate_closing(lift.closing.model, s_e, v_e, t_max,
                                   density=latched.density_at_trip if latched is not None else None, file=scene.source)
        t_free = (phi[after] - lift.phi_trip) / w
        st = closing.state(t_free)
        shut = closing.seated & (t_free >= closing.seat_time) if closing.seated else np.zeros(t_free.shape, bool)
        for key in ("s", "v", "a", "j"):
            out[key][after] = np.where(shut, 0.0, st[key])
        resting = (st["v"] == 0.0) & (st["a"] == 0.0)
        out["phase"][after] = np.where(shut, PHASE_CODES["seated"],
                                       np.where(resting, PHASE_CODES["stuck"], PHASE_CODES["flight"]))
        for e in closing.events:
            item = {"kind": e["kind"], **stamp(t_trip + e["t"]), "lift_m": float(e["s"])}
            if "v" in e:
                item["velocity_m_s"] = float(e["v"])
            events.append(item)
        if closing.hang:
            warnings.append("the tripped valve hangs open: spring and closing loads do not overcome the friction "
                            "from the elastic state at the trip")
        elif not closing.seated:
            warnings.append(f"the tripped valve has not seated within {t_max * 1e3:.4g} ms, before the latch's next "
                            "stroke: the motion shown is not periodic")
    elif any(e["kind"] == "lift-off" for e in events):
        n_seat = sum(e["kind"] == "seat" for e in events)
        warnings.append(f"the valve is on its seat at the trip: the latch lifted it and set it down again before the "
                        f"trip ({n_seat} seating(s) in the latched phase): no free closing")
    else:
        warnings.append("the valve is on its seat at the trip: the latch never lifted it (linkage too soft?)")
    events.sort(key=lambda e: e["time_s"])
    return TripElasticMotion(columns=out, solution=sol, nodes=nodes, closing=closing, state_at_trip=(s_e, v_e),
                             force_at_trip=f_e, on_latch_at_trip=on_e, events=tuple(events), warnings=tuple(warnings))


def latched_float(events, phi_of, phi_trip: float, omega: float) -> dict:
    """The trip gear's float, in the elastic models' keys: the valve is free by design after the
    trip, so only its flights off the latch before it count. `events`: the run's (kind, time_s,
    cam_angle_deg) dicts; phi_of(cam angle rad) the angle from the pick-up stroke's start, the
    latched phase being phi < phi_trip. Walked in phi order: the valve is open from a lift-off (the
    latch lifting it off its seat) to the next seat impact; a separation while open is float (one
    after a seat impact is the rebound's, as valve_periods has it), its flight lasting to the next
    re-contact or seat impact, or to the trip; a separation while already flying starts none."""
    walk = sorted(((phi_of(math.radians(e["cam_angle_deg"])), e["kind"], e["cam_angle_deg"]) for e in events),
                  key=lambda item: item[0])
    first, count, flight, is_open, flying = None, 0, 0.0, False, None
    for phi, kind, angle in (item for item in walk if item[0] < phi_trip):
        if kind in ("seat", "re-contact") and flying is not None:
            flight += phi - flying
            flying = None
        if kind == "lift-off":
            is_open = True
        elif kind == "seat":
            is_open = False
        elif kind == "separation" and is_open:
            count += 1
            first = angle if first is None else first
            flying = phi if flying is None else flying
    if flying is not None:  # off the latch at the trip: its flight ends there
        flight += phi_trip - flying
    return {"first_separation_deg": first, "float_separations": count, "float_flight_time_s": flight / omega}


def trip_elastic_effect(ctx) -> EffectOutput:
    scene, w = ctx.scene, ctx.omega
    lift = trip_lift_of(ctx)
    method = scene.solver.method
    motion = elastic_trip_motion(scene, lift, ctx.theta, method, dict(scene.solver.options))
    c = motion.columns
    model = LinkageModel.from_scene(scene)
    n = ctx.theta.size
    period = TWO_PI / w
    phi = np.mod(ctx.theta - lift.start, TWO_PI)
    latched = phi < lift.phi_trip
    separated = latched & (c["s"] > 0.0) & ~c["contact"]
    force = c["force"]
    events = list(motion.events)

    # the rigid gear at the same instant: latch state at the trip, its latch force, its closing
    x = lift.latch.derivatives(np.array([lift.trip_angle]))[:, 0]
    s_r, v_r = float(x[0] - lift.overtravel), float(w * x[1])
    loads = TrainLoads.from_scene(scene)
    _, f_rigid = window_limits(lift, loads, w, carried_pieces(lift, max(4096, scene.solver.steps_per_revolution)))
    rigid = lift.closing
    s_e, v_e = motion.state_at_trip
    cl = motion.closing
    seated = cl is not None and cl.seated
    i_peak = int(np.argmax(force))
    # the grid may miss a short carried window: the force just before the trip counts as well
    peak, peak_angle = float(force[i_peak]), float(np.degrees(ctx.theta[i_peak]))
    if motion.force_at_trip > peak:
        peak, peak_angle = motion.force_at_trip, math.degrees(lift.trip_angle)
    # the buffer's force along the rigid latched phase, which the linear linkage model leaves out
    warnings = list(motion.warnings)
    left_out = 0.0
    if lift.latched is not None:
        pieces = carried_pieces(lift, max(4096, scene.solver.steps_per_revolution))
        b_ext = buffer_extremes(lift, pieces, max(4096, scene.solver.steps_per_revolution))
        left_out = max(0.0, -b_ext["min"], b_ext["max"])
        if left_out > 0.0:
            worst = b_ext["min_theta"] if -b_ext["min"] >= b_ext["max"] else b_ext["max_theta"]
            kind = "suction" if -b_ext["min"] >= b_ext["max"] else "push"
            warnings.append(
                f"the elastic linkage model leaves out the dashpot's force while the latch carries the valve: "
                f"{kind} up to {left_out:.4g} N (rigid latch motion, cam angle {math.degrees(worst):.2f} deg); the "
                f"'forces' effect includes it")
    trip_summary: dict[str, Any] = {
        "lift_at_trip_m": s_e,
        "rigid_lift_at_trip_m": s_r,
        "lift_at_trip_difference_m": s_e - s_r,
        # with the pick-up vibration died out the valve lags the latch by the linkage's compression
        "static_compression_at_trip_m": f_rigid / model.stiffness,
        "velocity_at_trip_m_s": v_e,
        "rigid_velocity_at_trip_m_s": v_r,
        "velocity_at_trip_difference_m_s": v_e - v_r,
        "linkage_force_at_trip_N": motion.force_at_trip,
        "rigid_latch_force_at_trip_N": f_rigid,
        "on_latch_at_trip": motion.on_latch_at_trip,
        "separations_before_trip": sum(e["kind"] == "separation" for e in events),
        "peak_linkage_force_cam_angle_deg": peak_angle,
        # the largest |B| of the rigid latched phase, not in the elastic run (warning)
        "buffer_force_left_out_N": left_out,
        "closing_time_s": cl.seat_time if seated else None,
        "rigid_closing_time_s": rigid.seat_time,
        "closing_time_difference_s": (cl.seat_time - rigid.seat_time) if seated else None,
        "seating_velocity_m_s": abs(cl.seat_velocity) if seated else None,
        "rigid_seating_velocity_m_s": abs(rigid.seat_velocity),
        "seating_velocity_difference_m_s": (abs(cl.seat_velocity) - abs(rigid.seat_velocity)) if seated else None,
        "seat_cam_angle_deg": (math.degrees(lift.trip_angle + w * cl.seat_time) % 360.0) if seated else None,
        "apex_lift_m": float(cl.apex) if cl is not None else None,
        "rigid_apex_lift_m": float(rigid.apex),
    }
    kinds = EVENT_KINDS + ("release",)
    floats = latched_float(events, lambda th: float(np.mod(th - lift.start, TWO_PI)), lift.phi_trip, w)
    stats = {k: v for k, v in motion.solution.stats.items() if k != "warnings"}
    summary = {
        "elastic_method": method,
        "elastic_natural_period_s": model.natural_period(),
        "elastic_steps_per_natural_period": model.natural_period() / (period / n),
        "lift_off_compression_m": (model.seated_resistance + model.friction) / model.stiffness,
        "max_deviation_m": float(np.abs(c["deviation"]).max()),
        "peak_linkage_force_N": peak,
        "peak_camshaft_back_pressure_N": peak,
        # off the latch before the trip (after it the valve is free by design): between the events
        # and the latched phase's ends (the pick-up stroke's start, the trip), exactly
        "separated_angle_deg": separated_angle_deg(
            ctx.time, separated, [(e["time_s"], e["kind"]) for e in events]
            + [(math.fmod(np.mod(lift.start + phi_end, TWO_PI) / w, period), "latch") for phi_end in (0.0, lift.phi_trip)],
            period),
        "elastic_max_valve_lift_m": float(c["s"].max()),
        "elastic_max_valve_velocity_m_s": float(c["v"].max()),
        "elastic_min_valve_velocity_m_s": float(c["v"].min()),
        "elastic_max_valve_accel_m_s2": float(c["a"].max()),
        "elastic_min_valve_accel_m_s2": float(c["a"].min()),
        "elastic_event_counts": {kind: sum(e["kind"] == kind for e in events) for kind in kinds},
        **floats,
        "elastic_solver": stats,
        "elastic_trip": trip_summary,
    }
    columns = {
        "valve_lift_m": c["s"],
        "valve_velocity_m_s": c["v"],
        "valve_accel_m_s2": c["a"],
        "valve_jerk_m_s3": c["j"],
        "linkage_force_N": force,
        "camshaft_back_pressure_N": force,  # the latch law is valve-referred (ratio 1)
        "deviation_from_drive_m": c["deviation"],
        "valve_in_contact": c["contact"].astype(float),
        "valve_phase": c["phase"].astype(float),
    }
    return EffectOutput(columns=columns, summary=summary, events=tuple(Event.of(e) for e in events),
                        warnings=tuple(warnings))
