"""Effect 'gear': what is particular to each of the seeds' other gears, along the cycle.

pivoted-roller and rocking-cam: lever angle and valve ratio; pivoted-roller also the cam's size
and seed 004's instant-centre check of the lever's velocity.
rocking-cam also: the swing, equal eccentric arcs against unequal swings, and the opening/closing
symmetry about the eccentric's dead centre (why Schenker's 2R/M asymmetry is out of reach); with
[gear.target] the contour fitted to a wanted lift and open angle against the written one.
rolling-lever: lever angles, rolling ratio, pick-up and release, valve-referred stiffness.
trip: latch lift, buffer force and pressure, the closing (apex, cushion, seat), the latch's
pick-up impact, Trinks' closing-force rule, and the same valve closed by each buffer.

The contact statics of the roller gears and the rolling lever (pressure angle referred to the
lever, self-locking margin, normal force, camshaft torque, Hertz stress, cam width) are the
'contact' effect's (explorer.mechanics.contact), computed from each gear's `contact_geometry`.
"""

from __future__ import annotations

import math

import numpy as np

from ..result import EffectOutput, Event

TWO_PI = 2.0 * math.pi


def gear_effect(ctx) -> EffectOutput:
    scene = ctx.scene
    spec = scene.gear
    if spec is None:
        from ..core.errors import InputError

        raise InputError(scene.source, "effects", "effect 'gear' needs a gear follower type and its [gear] section")
    lift = ctx.lift
    if not hasattr(lift, "gear") and not hasattr(lift, "closing"):
        from ..gears.build import build_gear_lift

        lift = build_gear_lift(scene)
    handler = {"pivoted-roller": _pivoted, "rocking-cam": _rocking, "rolling-lever": _rolling, "trip": _trip}[spec.type]
    columns, summary, events, warnings = handler(ctx, lift)
    summary = {"type": spec.type, **summary}
    return EffectOutput(columns=columns, summary={"gear": summary}, events=tuple(Event.of(e) for e in events),
                        warnings=tuple(warnings))


# --------------------------------------------------------------------------------------------


def _pivoted(ctx, lift):
    from ..gears.pivoted import PivotedRollerGear

    gear = lift.gear
    g = gear.geometry(ctx.theta)
    ic = PivotedRollerGear.instant_centre_rate(gear.pivot, g.roller_centre, g.normal_ground)
    columns = {
        "lever_angle_deg": np.degrees(g.lever_angle),
        "lever_ratio": g.ratio,
    }
    convex = g.contour_radius[g.contour_radius > 0.0]
    summary = {
        "rest_lever_angle_deg": math.degrees(gear.rest_angle),
        "lever_swing_deg": float(np.degrees(g.lever_angle.max() - g.lever_angle.min())),
        "min_lever_ratio": float(g.ratio.min()),
        "max_lever_ratio": float(g.ratio.max()),
        "cam_max_radius_m": float(np.max(np.hypot(g.contour[:, 0], g.contour[:, 1]))),
        "min_convex_contour_radius_m": float(convex.min()) if convex.size else None,
        # seed 004's velocity construction against the analytic chain rule: a built-in self-check
        "instant_centre_check_rad": float(np.max(np.abs(ic - g.lever_rate))),
    }
    return columns, summary, [], []


def _rocking(ctx, lift):
    from ..gears.rocking import swing_increments

    gear = lift.gear
    d = gear.contact_details(ctx.theta)
    w = gear.contour.sense * (d["rocking_angle"] - gear.closed_end)
    columns = {
        "rocking_angle_deg": np.degrees(d["rocking_angle"]),
        "rocking_swing_deg": np.degrees(w),
        "lever_angle_deg": np.degrees(d["lever_angle"]),
        "lever_ratio": d["ratio"],
    }
    sym = symmetry_report(ctx.scene, lift)
    closed_dc = [c for c in gear.drive.dead_centres() if abs(np.angle(np.exp(1j * (c - gear.dead_centre)))) > 1e-9][0]
    start = gear.dead_centre - float(np.mod(gear.dead_centre - closed_dc, TWO_PI))
    theta_eq, increments = swing_increments(gear, start, gear.dead_centre, 12)
    chis = gear.drive.angle(np.array([closed_dc, gear.dead_centre]))
    summary = {
        "swing_deg": float(np.degrees(abs(chis[1] - chis[0]))),
        "eccentric_dead_centre_deg": math.degrees(gear.dead_centre),
        "eccentric_closed_dead_centre_deg": math.degrees(closed_dc),
        "flank_angles_deg": [math.degrees(a) for a in lift.breakpoints()],
        # seed 004: 12 equal eccentric arcs from the closed to the open dead centre give unequal swings
        "swing_per_equal_eccentric_arc_deg": [float(np.degrees(abs(x))) for x in increments],
        "min_lever_ratio": float(d["ratio"].min()),
        "max_lever_ratio": float(d["ratio"].max()),
        "symmetry": sym,
    }
    warnings = []
    if "target" in ctx.scene.gear.parts:
        # [gear.target]: the fitted flank next to the written one; which of the two is simulated
        # is `use` (build.make_gear), so `gear` here is the fitted one when use = "fitted"
        from ..gears.build import rocking_target
        from ..gears.rocking import target_report

        spec = ctx.scene.gear
        given, fit, fitted = rocking_target(spec, ctx.scene)
        lash = ctx.scene.valve.lash if ctx.scene.valve is not None else 0.0
        summary["target"], warnings = target_report(given, fit, fitted, spec.part("target"), spec.part("rocking_cam"),
                                                    lash, ctx.theta)
    return columns, summary, [], warnings


def symmetry_report(scene, lift) -> dict:
    """Opening and closing about the eccentric's dead centre: half-durations, the linkage's
    prediction of their difference (mirror images about the line O -> rod pin), and the largest
    decelerations p1 (opening) and p2 (closing), with Schenker's 2R/M for comparison."""
    from ..mechanics.kinematics import lash_crossings

    gear = lift.gear
    lash = scene.valve.lash if scene.valve else 0.0
    ups, downs = lash_crossings(lift, 1.0, lash)
    out: dict = {}
    if ups.size != 1 or downs.size != 1:
        return out
    w = scene.drive.omega
    td = gear.dead_centre
    open_half = float(np.mod(td - ups[0], TWO_PI))
    close_half = float(np.mod(downs[0] - td, TWO_PI))
    chi_open = float(gear.drive.angle(np.array([ups[0]]))[0])
    chi_dead = float(gear.drive.angle(np.array([td]))[0])
    predicted = 2.0 * float(np.angle(np.exp(1j * (gear.rod_pin_angle(np.array([chi_open]))[0]
                                                    - gear.rod_pin_angle(np.array([chi_dead]))[0]))))
    u = np.linspace(0.0, max(open_half, close_half), 2001)
    p_open = w**2 * lift.derivatives(np.mod(td - u[u <= open_half], TWO_PI))[2]
    p_close = w**2 * lift.derivatives(np.mod(td + u[u <= close_half], TWO_PI))[2]
    p1, p2 = float(p_open.min()), float(p_close.min())
    out.update(
        opening_half_deg=math.degrees(open_half),
        closing_half_deg=math.degrees(close_half),
        timing_asymmetry_deg=math.degrees(close_half - open_half),
        timing_asymmetry_from_linkage_deg=math.degrees(predicted),
        peak_deceleration_opening_m_s2=p1,
        peak_deceleration_closing_m_s2=p2,
        deceleration_difference_m_s2=p2 - p1,
    )
    if scene.valve is not None:
        out["schenker_2R_over_M_m_s2"] = 2.0 * scene.loads.friction / scene.valve.mass
    return out


def _rolling(ctx, lift):
    gear = lift.gear
    theta = ctx.theta
    w = gear.rolling_swing(theta)
    beta = gear.valve_lever_angle(w)
    alpha = gear.drive.angle(theta)
    contact = (w.c[0] > 0.0)
    ratio = np.where(contact, gear.law.ratio(w.c[0]), 0.0)
    columns = {
        "rolling_lever_angle_deg": np.degrees(alpha),
        "valve_lever_angle_deg": np.degrees(np.where(contact, beta.c[0], gear.rest)),
        "rolling_ratio": ratio,
        "rolling_contact_radius_m": np.where(contact, gear.law.rho(w.c[0]), 0.0),
    }
    k = gear.stiffness(theta)
    summary: dict = {}
    warnings = []
    lift_values = lift.derivatives(theta)[0]
    i_max = int(np.argmax(lift_values))
    if "lever" in k or "rod" in k:
        total = k.get("total", k.get("lever", k.get("rod")))
        columns["valve_referred_stiffness_N_m"] = np.where(contact, total, np.nan)
        summary["valve_referred_stiffness_at_max_lift_N_m"] = float(total[i_max])
        if "lever" in k:
            summary["lever_stiffness_at_max_lift_N_m"] = float(k["lever"][i_max])
        if "rod" in k:
            summary["rod_stiffness_at_max_lift_N_m"] = float(k["rod"][i_max])
        if "lever" in k and "rod" in k:
            # Schenker: most of the elasticity sits in the rolling lever
            summary["share_of_compliance_in_lever"] = float(k["total"][i_max] / k["lever"][i_max])
        link = ctx.scene.linkage
        if link is not None:  # the elastic effect's k(t): the gear's in series with the rest of the chain
            chain = 1.0 / (1.0 / total[contact] + 1.0 / link.stiffness)
            summary["linkage_stiffness_in_contact_N_m"] = [float(chain.min()), float(chain.max())]
    marks = lift.breakpoints()
    omega = ctx.omega
    picks = []
    for m in marks:
        virtual = gear.virtual_lift(np.array([m]))
        picks.append({"cam_angle_deg": math.degrees(m), "velocity_m_s": float(omega * virtual.c[1][0]),
                      "ratio": float(gear.law.ratio(0.0))})
    events = []
    for p in picks:
        kind = "rolling-contact" if p["velocity_m_s"] > 0 else "rolling-release"
        events.append({"kind": kind, "time_s": math.radians(p["cam_angle_deg"]) / omega, **p})
    summary.update(
        pick_up_ratio=float(gear.law.ratio(0.0)),
        max_rolling_ratio=float(gear.law.ratio(gear.max_rolling_swing())),
        swing_deg=float(np.degrees(np.ptp(alpha))),
        rolling_swing_deg=math.degrees(gear.max_rolling_swing()),
        pick_up=picks,
        eccentric_dead_centres_deg=[math.degrees(a) for a in gear.drive.dead_centres()],
    )
    return columns, summary, events, warnings


def _trip(ctx, lift):
    from ..mechanics.kinematics import lash_crossings
    from ..gears.build import closing_model, make_buffer
    from ..gears.trip import compare_buffers, peak_buffer_force

    scene, spec = ctx.scene, ctx.scene.gear
    trip = spec.part("trip")
    omega = ctx.omega
    columns = lift.columns(ctx.theta)
    sol = lift.closing
    # while the latch carries the valve it transmits the rigid-train force (the forces effect's, one function)
    from ..mechanics.forces import TrainLoads
    from .trip import carried_pieces, latch_force, latch_force_extremes

    loads = TrainLoads.from_scene(scene)
    latch = latch_force(lift, ctx.theta, loads, omega)
    columns["latch_force_N"] = latch["force"]
    n_grid = max(4096, scene.solver.steps_per_revolution)
    extremes = latch_force_extremes(lift, loads, omega, carried_pieces(lift, n_grid), n_grid)
    s_trip = float(lift.latch.derivatives(np.array([lift.trip_angle]))[0, 0] - lift.overtravel)
    v_trip = float(omega * lift.latch.derivatives(np.array([lift.trip_angle]))[1, 0])
    ups, _ = lash_crossings(lift.latch, 1.0, lift.overtravel)
    v_pick = float(omega * lift.latch.derivatives(ups)[1, 0]) if ups.size else 0.0
    mass = scene.valve.mass
    events = [{"kind": "trip", "time_s": lift.trip_angle / omega, "cam_angle_deg": math.degrees(lift.trip_angle),
               "lift_m": s_trip, "velocity_m_s": v_trip}]
    for e in sol.events:
        if e["kind"] == "seat":
            continue
        th = lift.theta_of(lift.phi_trip + omega * e["t"])
        events.append({"kind": e["kind"], "time_s": th / omega, "cam_angle_deg": math.degrees(th), "lift_m": float(e["s"])})
    if lift.latched is not None:  # the buffer opening, closing or venting while the latch carries the valve
        for e in lift.latched.events:
            th = lift.theta_of(e["phi"])
            events.append({"kind": e["kind"], "time_s": th / omega, "cam_angle_deg": math.degrees(th), "latched": True})
    buffers = {"none": None}
    densities = {}
    for name in ("air", "oil"):
        if f"{name}_dashpot" in spec.parts:
            buffers[name] = make_buffer(spec, name)
            if name == "air":  # the pocket as the latched phase leaves it at the trip
                densities[name] = lift.density_at_trip(buffers[name])
    t_max = (TWO_PI - lift.phi_trip) / omega
    table = compare_buffers(closing_model(spec, scene), buffers, s_trip, v_trip, t_max, densities, scene.source)
    summary = {
        "trip_angle_deg": math.degrees(lift.trip_angle),
        "lift_at_trip_m": s_trip,
        "velocity_at_trip_m_s": v_trip,
        "apex_lift_m": sol.apex,
        "closing_time_s": sol.seat_time,
        "seating_velocity_m_s": abs(sol.seat_velocity),
        "seat_cam_angle_deg": math.degrees(lift.theta_of(lift.phi_seat)),
        "buffer": trip["buffer"],
        "max_buffer_force_N": peak_buffer_force(sol),
        # refined on the analytic law (the forces effect's, one function)
        "max_latch_force_N": extremes["max"],
        "min_latch_force_N": extremes["min"],
        "rebounds": sum(1 for e in sol.events if e["kind"] == "rebound"),
        # the latch meets the resting valve with its own velocity after the over-travel (Schenker)
        "latch_overtravel_m": lift.overtravel,
        "latch_pickup_velocity_m_s": v_pick,
        "latch_pickup_impulse_N_s": mass * v_pick,
        "latch_pickup_energy_J": 0.5 * mass * v_pick**2,
        "buffer_comparison": table,
    }
    # Trinks' closing-force rule (seed 003) for the lift at the trip and a wanted closing time
    from ..mechanics.springs import TRINKS_G, trinks_closing_force

    weight = trip["valve_weight"] if trip["valve_weight"] is not None else mass * TRINKS_G
    t_wanted = trip["closing_time"] if trip["closing_time"] is not None else sol.seat_time
    if s_trip > 0.0:
        summary["trinks"] = {
            "closing_time_s": t_wanted,
            "lift_m": s_trip,
            "valve_weight_N": weight,
            "required_spring_force_N": trinks_closing_force(s_trip, t_wanted, weight, scene.loads.friction),
            "spring_force_at_trip_N": scene.spring.preload + scene.spring.rate * s_trip,
        }
    warnings = []
    if trip["closing_time"] is not None and sol.seat_time > trip["closing_time"]:
        warnings.append(f"the tripped valve takes {sol.seat_time * 1e3:.4g} ms to close, more than the wanted "
                        f"{trip['closing_time'] * 1e3:.4g} ms")
    return columns, summary, events, warnings
