"""Trip gear ("Ausklink-/Ausloesesteuerung", seeds 000 and 003): latch lift, release, free closing.

A latch, moved by an eccentric or cam (the scene's [lift] law, valve-referred), first travels
its over-travel s_o (the scene's valve.lash) before it catches the valve spindle: the valve is
picked up with the latch's finite velocity - an impact, worst in trip gears (Schenker, sec. 2).
The valve then rides on the latch until the trip angle, where the governor-set release frees it.
From there the valve moves on its own:
    M s'' = -(F0 + k s + W_close) - R sign(s') + F_buffer
(spring preload F0 and rate k, constant closing loads such as the valve weight, stuffing-box
friction R, the buffer force of an air or oil dashpot near the seat). It first coasts upward
(it was moving with the latch), stops, falls and seats. Closed forms exist for the free parts
(constant force: t = sqrt(2 h / p); spring: a cosine); with a buffer the motion is integrated
with scipy's DOP853 in segments split at every event (apex or reversal, where friction changes
sign; entry into the cushion; the seat; a check valve opening as the expanding air pocket falls
to ambient, after which the pocket vents at ambient density until the valve turns down again),
each event located to machine precision, with dense output for the lift curve.

The buffer already acts while the latch carries the valve (LatchedBuffer, along the rigid latch
motion from the pick-up): an orifice-fed air pocket sucks as the latch lifts the valve off its
seat, a pocket or oil cushion the latch lowers the valve into pushes back. The free closing
starts with the pocket density the latched phase leaves at the trip.

Trinks' rule (seed 003): for closing from rest over h in time t, p = 2 h / t^2 and the spring
force P_f = (p/g - 1) G_v + W_s (G_v valve weight, W_s stuffing-box friction); it lives in
explorer.mechanics.springs.trinks_closing_force and the tests check it against this closing model.

As a lift curve (valve-referred, lash = over-travel): L = latch lift X(theta) up to the trip;
L = s_o + s(t) while the valve closes freely; after the seat a monotone cubic that leaves s_o
with the seating velocity and reaches the latch's bottom lift with zero slope, then that bottom
value until the latch itself is back at its bottom (a virtual continuation below the lash
level: the valve stays shut, and the seating crossing is found exactly with its velocity);
then the latch again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from ..core.errors import InputError
from ..mechanics.forces import velocity_zeros
from ..mechanics.kinematics import lash_crossings
from .dashpot import AirDashpot, OilDashpot

TWO_PI = 2.0 * math.pi
MAX_SEGMENTS = 400
MAX_CLOSING_STEPS = 2_000_000  # the shipped trip scene takes a few thousand
MAX_CLOSING_EVALUATIONS = 60_000  # the shipped scenes take < 10 000; the refusal of a too-light valve then costs ~1 s, not ~5


@dataclass(frozen=True)
class ClosingModel:
    mass: float  # kg
    preload: float  # N, spring force at the seat
    rate: float  # N/m
    closing: float  # N, constant closing loads (valve weight, steam on the valve ...)
    friction: float  # N, Coulomb (stuffing box)
    buffer: AirDashpot | OilDashpot | None = None

    def closing_force(self, s):
        return self.preload + self.rate * s + self.closing

    def rhs(self, t, y, direction, engaged, vented=False):
        """Equation of motion in one segment. A closed air pocket uses the smooth continuations
        gauge_force and pocket_density_rate (its segment ends where a check valve opens); a vented
        one (check valve open, pocket expanding at ambient) exerts nothing and keeps its density."""
        s, v = y[0], y[1]
        fb, drho = 0.0, 0.0
        if self.buffer is not None and engaged and not vented:
            if self.buffer.has_state:
                fb, drho = self.buffer.gauge_force(y[2]), self.buffer.pocket_density_rate(s, v, y[2])
            else:
                fb = self.buffer.force(s, v)
        a = (-self.closing_force(s) - self.friction * direction + fb) / self.mass
        if len(y) > 2:
            return [v, a, drho]
        return [v, a]


@dataclass(frozen=True)
class Segment:
    t0: float
    t1: float
    direction: int  # sign of velocity in this segment (friction), 0 = stuck
    engaged: bool  # buffer acting
    sol: Any  # dense output (OdeSolution) or None for a stuck segment
    y0: tuple
    vented: bool = False  # check-valve air pocket expanding at ambient: no force, density held


@dataclass(frozen=True)
class ClosingSolution:
    model: ClosingModel
    segments: tuple[Segment, ...]
    events: tuple[dict, ...]
    seated: bool
    seat_time: float  # s after release (nan if not seated)
    seat_velocity: float  # m/s (<= 0)
    hang: bool  # stopped open: closing force below friction
    apex: float  # m, highest lift after release

    @property
    def has_state(self) -> bool:
        return self.model.buffer is not None and self.model.buffer.has_state

    def state(self, t) -> dict:
        """s, v, a, j (and buffer force, cushion density) at times t since release; a and j from the
        equation of motion at the interpolated state, not by differencing."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        starts = np.array([seg.t0 for seg in self.segments])
        # a time on a boundary belongs to the segment that starts there (state after the event)
        index = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.segments) - 1)
        m = self.model
        out = {k: np.zeros(t.shape) for k in ("s", "v", "a", "j", "buffer_force", "density")}
        for i, seg in enumerate(self.segments):
            mask = index == i
            if not np.any(mask):
                continue
            tt = np.clip(t[mask], seg.t0, seg.t1)
            if seg.sol is None:
                y = np.repeat(np.asarray(seg.y0, dtype=float)[:, None], tt.size, axis=1)
            else:
                y = seg.sol(tt)
            s, v = y[0], y[1]
            rho = y[2] if y.shape[0] > 2 else np.full(tt.shape, np.nan)
            fb = np.zeros(tt.shape)
            dfv = np.zeros(tt.shape)
            dfr = np.zeros(tt.shape)
            drho = np.zeros(tt.shape)
            if m.buffer is not None and seg.engaged and not seg.vented:
                fb = fb + m.buffer.force(s, v, rho)
                _, dfv_k, dfr_k = m.buffer.force_partials(s, v, rho)
                dfv, dfr = dfv + dfv_k, dfr + dfr_k
                if m.buffer.has_state:
                    drho = m.buffer.density_rate(s, v, rho)
            if seg.direction == 0:
                a = np.zeros(tt.shape)
                j = np.zeros(tt.shape)
            else:
                a = (-m.closing_force(s) - m.friction * seg.direction + fb) / m.mass
                j = (-m.rate * v + dfv * a + dfr * drho) / m.mass
            for key, val in (("s", s), ("v", v), ("a", a), ("j", j), ("buffer_force", fb), ("density", rho)):
                out[key][mask] = val
        return out


def simulate_closing(model: ClosingModel, s0: float, v0: float, t_max: float, *, density: float | None = None,
                     rtol: float = 1e-11, atol: float = 1e-14, file: str = "<memory>") -> ClosingSolution:
    """Free motion of the released valve from lift s0 (> 0) and velocity v0 until it seats, hangs
    or t_max passes. Segments are split at every event so each is smooth; events are located by
    solve_ivp's root finder on the dense output (to ~machine precision). density: the air
    pocket's density at the start when the valve is released inside the cushion (the latched
    phase's, LatchedBuffer.density_at_trip); default ambient."""
    buffer = model.buffer
    has_state = buffer is not None and buffer.has_state
    stroke = buffer.stroke if buffer is not None else -1.0
    rho_a = buffer.ambient_density if has_state else None
    check_valve = has_state and buffer.check_valve
    engaged = buffer is not None and s0 < stroke
    rho0 = density if (engaged and density is not None and math.isfinite(density)) else rho_a
    y = [s0, v0] + ([rho0] if has_state else [])
    t = 0.0
    direction = int(np.sign(v0))
    segments: list[Segment] = []
    events: list[dict] = []
    apex = s0
    # a characteristic time bounds the step, so sign-change event detection cannot skip a pair
    # of crossings: the free fall time from s0 and the spring's and cushion's periods
    net = max(model.closing_force(0.0) - model.friction, 1e-9)
    scales = [math.sqrt(2.0 * max(s0, 1e-6) * model.mass / net)]
    if model.rate > 0.0:
        scales.append(2.0 * math.pi * math.sqrt(model.mass / model.rate))
    if has_state:
        k_air = buffer.exponent * buffer.ambient_pressure * buffer.area / (buffer.stroke + buffer.clearance)
        scales.append(2.0 * math.pi * math.sqrt(model.mass / k_air))
    max_step = min(scales) / 40.0
    steps = t_max / max_step
    if not steps <= MAX_CLOSING_STEPS:  # a feather-light valve on a stiff spring: millions of steps (a hang)
        raise InputError(file, "valve.mass", f"the released valve's closing needs about {steps:.3g} solver steps "
                         f"(at most {MAX_CLOSING_STEPS:g}): a heavier valve, a softer spring or cushion, or a higher speed")

    # The step bound above misses stiffness (a feather-light valve on an air cushion): the
    # explicit integrator then creeps for ever. A budget of right-hand-side evaluations over the
    # whole closing ends that in one line (the shipped scene takes ~8000, its variants < 100 000).
    evaluations = [0]

    def spend():
        evaluations[0] += 1
        if evaluations[0] > MAX_CLOSING_EVALUATIONS:
            raise InputError(file, "valve.mass", f"the released valve's closing did not finish within "
                             f"{MAX_CLOSING_EVALUATIONS:g} solver evaluations: the valve is too light for its spring "
                             f"and cushion (a heavier valve, a softer spring or cushion)")

    def static_force(yy, eng):
        s, rho = yy[0], (yy[2] if len(yy) > 2 else None)
        return -model.closing_force(s) + (buffer.force(s, 0.0, rho) if (buffer is not None and eng) else 0.0)

    for _ in range(MAX_SEGMENTS):
        if t >= t_max:
            break
        if direction == 0:
            f = static_force(y, engaged)
            if abs(f) > model.friction:
                direction = 1 if f > 0.0 else -1
            elif (has_state and engaged and buffer.orifice_area > 0.0
                  and abs(model.closing_force(y[0])) > model.friction):
                # the pocket's pressure leaks towards ambient, so the force tends to -closing_force:
                # the valve slips once that exceeds the friction (else it hangs for good)
                # stuck on the cushion while air leaks: wait until the pressure lets it slide
                def stuck_rhs(tt, yy):
                    spend()
                    return [0.0, 0.0, buffer.density_rate(yy[0], 0.0, yy[2])]

                def slip(tt, yy):
                    return abs(static_force(yy, True)) - model.friction

                slip.terminal, slip.direction = True, 1
                # nothing fast happens while stuck (a monotone leak): no step bound needed
                sol = solve_ivp(stuck_rhs, (t, t_max), y, method="DOP853", rtol=rtol, atol=atol, events=[slip],
                                dense_output=True)
                segments.append(Segment(t, float(sol.t[-1]), 0, True, sol.sol, tuple(y)))
                t, y = float(sol.t[-1]), list(sol.y[:, -1])
                if sol.status != 1:
                    events.append({"kind": "hang", "t": t, "s": y[0]})
                    return ClosingSolution(model, tuple(segments), tuple(events), False, math.nan, 0.0, True, apex)
                events.append({"kind": "unstick", "t": t, "s": y[0]})
                continue
            else:
                events.append({"kind": "hang", "t": t, "s": y[0]})
                segments.append(Segment(t, t_max, 0, engaged, None, tuple(y)))
                return ClosingSolution(model, tuple(segments), tuple(events), False, math.nan, 0.0, True, apex)

        d, eng = direction, engaged
        # a check valve is open while the pocket expands at (or below) ambient: density held
        vent = bool(check_valve and eng and d > 0 and y[2] <= rho_a)
        if vent:
            y[2] = rho_a

        def rhs(tt, yy, d=d, eng=eng, vent=vent):
            spend()
            return model.rhs(tt, yy, d, eng, vent)

        def stop(tt, yy):  # velocity reverses
            return yy[1]

        stop.terminal, stop.direction = True, -d

        def seat(tt, yy):
            return yy[0]

        seat.terminal, seat.direction = True, -1
        evs = [stop, seat]
        if buffer is not None:
            def cushion(tt, yy):
                return yy[0] - stroke

            cushion.terminal = True
            cushion.direction = -1 if not eng else 1
            evs.append(cushion)
        if check_valve and eng and not vent and d > 0:
            def refill(tt, yy):  # the expanding pocket falls to ambient: the check valve opens
                return yy[2] - rho_a

            refill.terminal, refill.direction = True, -1
            evs.append(refill)
        sol = solve_ivp(rhs, (t, t_max), y, method="DOP853", rtol=rtol, atol=atol, events=evs, dense_output=True,
                        max_step=max_step)
        t_end = float(sol.t[-1])
        segments.append(Segment(t, t_end, d, eng, sol.sol, tuple(y), vent))
        y = list(sol.y[:, -1])
        t = t_end
        if sol.status != 1:
            break  # reached t_max
        fired = [k for k, te in enumerate(sol.t_events) if len(te) and te[-1] == t_end]
        kind = fired[0] if fired else None
        if kind == 1:  # seat
            y[0] = 0.0
            events.append({"kind": "seat", "t": t, "s": 0.0, "v": y[1]})
            return ClosingSolution(model, tuple(segments), tuple(events), True, t, float(y[1]), False, apex)
        if kind == 0:
            y[1] = 0.0
            apex = max(apex, y[0])
            # moving up it is an apex; moving down, only the cushion can stop it short of the seat
            events.append({"kind": "apex" if d > 0 else "rebound", "t": t, "s": y[0]})
            direction = 0
        elif kind == 3:
            y[2] = rho_a
            events.append({"kind": "dashpot-refill", "t": t, "s": y[0], "v": y[1]})
        elif kind == 2:
            if not eng:
                events.append({"kind": "dashpot-entry", "t": t, "s": y[0], "v": y[1]})
                engaged = True
                if has_state:
                    y[2] = rho_a  # the pocket closes with ambient air
            else:
                events.append({"kind": "dashpot-exit", "t": t, "s": y[0], "v": y[1]})
                engaged = False
    return ClosingSolution(model, tuple(segments), tuple(events), False, math.nan, 0.0, False, apex)


def peak_buffer_force(sol: ClosingSolution, samples: int = 2001) -> float:
    """Largest buffer force during a closing: each cushion segment sampled densely, ends included
    (an oil buffer's force jumps to c v^2 at the entry, which a sample grid alone would miss)."""
    peak = 0.0
    for seg in sol.segments:
        if seg.engaged and seg.t1 > seg.t0:
            t = np.linspace(seg.t0, seg.t1, samples)
            peak = max(peak, float(np.max(np.abs(sol.state(t)["buffer_force"]))))
    return peak


def compare_buffers(model: ClosingModel, buffers: dict, s0: float, v0: float, t_max: float,
                    densities: dict | None = None, file: str = "<memory>") -> list[dict]:
    """Close the same valve with each buffer (None = no buffer): seating velocity, closing time,
    largest buffer force and the number of rebounds, one row per buffer. densities: an air
    buffer's pocket density at the release (by name; default ambient)."""
    rows = []
    for name, buffer in buffers.items():
        rho0 = (densities or {}).get(name)
        sol = simulate_closing(replace(model, buffer=buffer), s0, v0, t_max, density=rho0, file=file)
        peak = peak_buffer_force(sol) if buffer is not None else 0.0
        rows.append({
            "buffer": name,
            "seated": sol.seated,
            "closing_time_s": sol.seat_time if sol.seated else None,
            "seating_velocity_m_s": abs(sol.seat_velocity) if sol.seated else None,
            "max_buffer_force_N": peak,
            "rebounds": sum(1 for e in sol.events if e["kind"] == "rebound"),
        })
    return rows


# --------------------------------------------------------------------------------------------
# The buffer while the latch carries the valve
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BufferPiece:
    phi0: float  # rad since the latch's start
    phi1: float
    mode: str  # "open" (valve above the stroke), "closed" (pocket shut / oil displaced), "vented"
    sol: Any  # air, closed: dense output in phi of [rho, work against the pocket]; else None
    density: float  # air: density at phi0 (the whole piece when vented); nan otherwise


@dataclass(frozen=True)
class LatchedBuffer:
    """The buffer along the rigid latch motion from the pick-up to the trip, s = X(theta) - s_o.

    The valve sat on its seat before the pick-up long enough for the pocket to settle to ambient
    (the orifice empties a seated pocket in milliseconds). From the pick-up the latch moves the
    valve, so the pocket density obeys drho/dt = density_rate(s, v, rho) with the latch's s(t),
    v(t): integrated with DOP853 (in the cam angle) on pieces split where the pocket opens or
    closes (s = stroke), where the latch turns and at the latch law's breakpoints, and where a
    check valve opens (event rho = rho_a). With a check valve the lift vents (no force); with
    "orifice" the lift sucks: B = (p - p_a) A < 0 pulls the valve down until the pocket opens at
    s = stroke (where the force drops to 0). An oil buffer acts only if the latch lowers the
    valve into its stroke: B = c v^2. B is the upward force on the valve; the latch carries -B."""

    buffer: Any
    latch: Any
    overtravel: float
    start: float
    omega: float
    phi_pick: float
    phi_trip: float
    pieces: tuple[BufferPiece, ...]
    events: tuple[dict, ...]  # kind ("dashpot-exit", "dashpot-entry", "dashpot-refill"), phi
    density_at_trip: float  # air pocket closed at the trip: its density; nan otherwise
    work: float  # J, the latch's work against the buffer over the window, integral of -B ds

    def cuts(self) -> np.ndarray:
        """Cam angles (rad, mod 2 pi) where the buffer force may jump or kink."""
        return np.mod(np.array([p.phi0 for p in self.pieces[1:]]) + self.start, TWO_PI)

    def state(self, theta) -> dict:
        """B (upward force on the valve, N), density (nan where no air pocket is closed) and the
        air pocket's gauge pressure at cam angles theta; 0 / nan outside the carried window. An instant
        on a piece boundary belongs to the piece that starts there."""
        theta = np.asarray(theta, dtype=float)
        phi = np.mod(theta - self.start, TWO_PI)
        force = np.zeros(theta.shape)
        density = np.full(theta.shape, np.nan)
        pressure = np.zeros(theta.shape)
        starts = np.array([p.phi0 for p in self.pieces])
        on = (phi >= self.phi_pick) & (phi < self.phi_trip)
        index = np.clip(np.searchsorted(starts, phi, side="right") - 1, 0, len(self.pieces) - 1)
        buffer, so, w = self.buffer, self.overtravel, self.omega
        for i, piece in enumerate(self.pieces):
            mask = on & (index == i)
            if not np.any(mask) or piece.mode == "open":
                continue
            if piece.mode == "vented":
                density[mask] = piece.density
                continue
            d = self.latch.derivatives(theta[mask])
            s, v = d[0] - so, w * d[1]
            if buffer.has_state:
                rho = piece.sol(np.clip(phi[mask], piece.phi0, piece.phi1))[0]
                density[mask] = rho
                force[mask] = buffer.force(s, v, rho)
                pressure[mask] = force[mask] / buffer.area
            else:  # oil: the force only (the cycle's pressure column is the air pocket's)
                force[mask] = buffer.force(s, v)
        return {"force": force, "density": density, "gauge_pressure": pressure}


def latched_buffer(buffer, latch, overtravel: float, start: float, omega: float, phi_pick: float,
                   phi_trip: float, n_grid: int = 4096, rtol: float = 1e-11) -> LatchedBuffer:
    """The buffer's state and force along the rigid latch motion over the carried window."""
    so, w = overtravel, omega
    ups, downs = lash_crossings(latch, 1.0, so + buffer.stroke, n_grid)
    inner = np.concatenate([ups, downs, np.asarray(latch.breakpoints(), dtype=float), velocity_zeros(latch, n_grid)])
    inner = np.mod(inner - start, TWO_PI)
    inner = np.unique(inner[(inner > phi_pick + 1e-12) & (inner < phi_trip - 1e-12)])
    cuts = list(np.concatenate([[phi_pick], inner, [phi_trip]]))
    air = buffer.has_state
    rho_a = buffer.ambient_density if air else math.nan
    rho = rho_a  # settled while the valve sat
    was_open = False
    pieces: list[BufferPiece] = []
    events: list[dict] = []
    work = 0.0

    def lift_at(phi):
        d = latch.derivatives(np.array([start + phi]))[:, 0]
        return float(d[0] - so), float(d[1])

    k = 0
    while k < len(cuts) - 1:
        a, b = float(cuts[k]), float(cuts[k + 1])
        s_mid, x1_mid = lift_at(0.5 * (a + b))
        if s_mid >= buffer.stroke:
            if not was_open and pieces:
                events.append({"kind": "dashpot-exit", "phi": a})
            pieces.append(BufferPiece(a, b, "open", None, math.nan))
            was_open, k = True, k + 1
            continue
        if was_open:
            events.append({"kind": "dashpot-entry", "phi": a})
            rho = rho_a  # the pocket closes with ambient air
        was_open = False
        if not air:  # oil: algebraic force, c v^2 while the latch lowers the valve; work by Gauss-Legendre
            x, wts = np.polynomial.legendre.leggauss(32)
            ph = 0.5 * (b - a) * x + 0.5 * (a + b)
            d = latch.derivatives(start + ph)
            work -= 0.5 * (b - a) * float(np.sum(wts * buffer.force(d[0] - so, w * d[1]) * d[1]))
            pieces.append(BufferPiece(a, b, "closed", None, math.nan))
            k += 1
            continue
        if buffer.check_valve and x1_mid >= 0.0 and rho <= rho_a:
            pieces.append(BufferPiece(a, b, "vented", None, rho_a))
            rho, k = rho_a, k + 1
            continue

        def rhs(phi, y):
            d = latch.derivatives(np.array([start + phi]))[:, 0]
            s, x1 = d[0] - so, d[1]
            return [buffer.pocket_density_rate(s, w * x1, y[0]) / w, -buffer.gauge_force(y[0]) * x1]

        evs = []
        if buffer.check_valve and x1_mid > 0.0:
            def refill(phi, y):
                return y[0] - rho_a

            refill.terminal, refill.direction = True, -1
            evs.append(refill)
        sol = solve_ivp(rhs, (a, b), [rho, 0.0], method="DOP853", rtol=rtol, atol=[1e-14, 1e-16],
                        events=evs or None, dense_output=True)
        end = float(sol.t[-1])
        pieces.append(BufferPiece(a, end, "closed", sol.sol, rho))
        rho, work = float(sol.y[0, -1]), work + float(sol.y[1, -1])
        if sol.status == 1:  # the check valve opened: the rest of the piece vents
            events.append({"kind": "dashpot-refill", "phi": end})
            rho = rho_a
            cuts[k] = end
            continue
        k += 1
    s_trip = lift_at(phi_trip)[0]
    rho_trip = rho if (air and s_trip < buffer.stroke) else math.nan
    return LatchedBuffer(buffer=buffer, latch=latch, overtravel=so, start=start, omega=w, phi_pick=phi_pick,
                         phi_trip=phi_trip, pieces=tuple(pieces), events=tuple(events), density_at_trip=rho_trip,
                         work=work)


# --------------------------------------------------------------------------------------------
# The trip gear as a lift curve
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class TripLift:
    """Valve-referred lift of a trip gear over one revolution (see module docstring)."""

    latch: Any  # LawLift: valve-referred latch lift, over-travel included
    overtravel: float  # s_o = valve.lash
    trip_angle: float  # rad
    omega: float  # rad/s
    closing: ClosingSolution
    start: float  # latch rise start (rad): phi = theta - start
    phi_pick: float
    phi_trip: float
    phi_seat: float
    phi_flat: float  # end of the cubic
    phi_join: float
    join_lift: float
    seat_slope: float  # dL/dphi at the seat
    marks: tuple[float, ...] = field(default=())
    latched: LatchedBuffer | None = None  # the buffer while the latch carries the valve (None: no buffer)

    def _phi(self, theta):
        return np.mod(np.asarray(theta, dtype=float) - self.start, TWO_PI)

    def density_at_trip(self, buffer) -> float:
        """The pocket density an air `buffer` has at the trip after the latched lift: the scene's own
        buffer's was integrated when the lift was built; another's (a comparison) is integrated now."""
        if self.latched is not None and buffer == self.closing.model.buffer:
            return self.latched.density_at_trip
        return latched_buffer(buffer, self.latch, self.overtravel, self.start, self.omega, self.phi_pick,
                              self.phi_trip).density_at_trip

    def derivatives(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        flat = theta.reshape(-1)
        phi = self._phi(flat)
        out = self.latch.derivatives(flat)
        w = self.omega
        free = (phi >= self.phi_trip) & (phi < self.phi_seat)
        if np.any(free):
            st = self.closing.state((phi[free] - self.phi_trip) / w)
            out[0][free] = self.overtravel + st["s"]
            out[1][free] = st["v"] / w
            out[2][free] = st["a"] / w**2
            out[3][free] = st["j"] / w**3
        cubic = (phi >= self.phi_seat) & (phi < self.phi_flat)
        if np.any(cubic):
            out[:, cubic] = self._hermite(phi[cubic])
        flat = (phi >= self.phi_flat) & (phi < self.phi_join)
        out[:, flat] = 0.0
        out[0][flat] = self.join_lift
        return out.reshape((4,) + theta.shape)

    def _hermite(self, phi):
        """Cubic from (phi_seat, s_o, seat slope) to (phi_flat, join lift, 0)."""
        span = self.phi_flat - self.phi_seat
        u = (phi - self.phi_seat) / span
        y0, y1, m0 = self.overtravel, self.join_lift, self.seat_slope * span
        # p(u) = y0 h00 + m0 h10 + y1 h01
        h = np.stack([
            [2 * u**3 - 3 * u**2 + 1, 6 * u**2 - 6 * u, 12 * u - 6, np.full_like(u, 12.0)],
            [u**3 - 2 * u**2 + u, 3 * u**2 - 4 * u + 1, 6 * u - 4, np.full_like(u, 6.0)],
            [-2 * u**3 + 3 * u**2, -6 * u**2 + 6 * u, -12 * u + 6, np.full_like(u, -12.0)],
        ])
        p = y0 * h[0] + m0 * h[1] + y1 * h[2]
        return p / span ** np.arange(4)[:, None]

    def breakpoints(self) -> np.ndarray:
        return np.unique(np.mod(np.array(self.marks), TWO_PI))

    # -- reports ----------------------------------------------------------------------------
    def theta_of(self, phi: float) -> float:
        return float(np.mod(phi + self.start, TWO_PI))

    def columns(self, theta) -> dict:
        """Latch lift, buffer force (upward on the valve) and cushion gauge pressure along the
        cycle: while the latch carries the valve (LatchedBuffer) and while it closes; 0 elsewhere."""
        theta = np.asarray(theta, dtype=float)
        phi = self._phi(theta)
        latch = self.latch.derivatives(theta)[0]
        force = np.zeros(theta.shape)
        pressure = np.zeros(theta.shape)
        if self.latched is not None:
            st = self.latched.state(theta)
            force, pressure = st["force"], st["gauge_pressure"]
        free = (phi >= self.phi_trip) & (phi < self.phi_seat)
        buffer = self.closing.model.buffer
        if np.any(free):
            st = self.closing.state((phi[free] - self.phi_trip) / self.omega)
            force[free] = st["buffer_force"]
            if isinstance(buffer, AirDashpot):
                rho = np.where(np.isfinite(st["density"]), st["density"], buffer.ambient_density)
                pressure[free] = np.where(st["buffer_force"] != 0.0, buffer.pressure(rho) - buffer.ambient_pressure, 0.0)
        return {"latch_lift_m": latch, "buffer_force_N": force, "buffer_gauge_pressure_Pa": pressure}


def build_trip_lift(latch, overtravel: float, trip_angle: float, omega: float, model: ClosingModel,
                    file: str = "<memory>") -> TripLift:
    start = latch.start
    ups, downs = lash_crossings(latch, 1.0, overtravel)
    if ups.size != 1 or downs.size != 1:
        raise InputError(file, "valve.lash", "the latch must pass the over-travel (valve.lash) once up and once down per revolution")
    phi_pick = float(np.mod(ups[0] - start, TWO_PI))
    phi_drop = float(np.mod(downs[0] - start, TWO_PI))
    phi_trip = float(np.mod(trip_angle - start, TWO_PI))
    if not phi_pick < phi_trip < phi_drop:
        raise InputError(
            file, "gear.trip.angle",
            f"the latch carries the valve only from {math.degrees(ups[0]):.2f} deg to {math.degrees(downs[0]):.2f} deg; "
            "the trip angle must lie between",
        )
    x = latch.derivatives(np.array([trip_angle]))[:, 0]
    s0, v0 = float(x[0] - overtravel), float(omega * x[1])
    t_max = (TWO_PI - phi_trip) / omega
    latched = None
    if model.buffer is not None:
        latched = latched_buffer(model.buffer, latch, overtravel, start, omega, phi_pick, phi_trip)
    sol = simulate_closing(model, s0, v0, t_max, density=latched.density_at_trip if latched is not None else None,
                           file=file)
    if sol.hang:
        raise InputError(file, "spring.preload", "the tripped valve hangs open: spring and closing loads do not overcome the friction")
    if not sol.seated:
        raise InputError(
            file, "gear.trip.angle",
            f"the tripped valve has not seated within {t_max * 1e3:.4g} ms, before the latch's next stroke "
            "(stronger spring, smaller buffer resistance or lower speed)",
        )
    phi_seat = phi_trip + omega * sol.seat_time
    phi_end = float(latch.rise + latch.dwell + latch.ret)
    phi_join = phi_end if phi_seat < phi_end - 1e-9 else TWO_PI
    join_lift = float(latch.derivatives(np.array([start + phi_join]))[0, 0])
    # the cubic is monotone (Fritsch-Carlson) when its span is at most 3 (s_o - join) / |slope|
    slope = abs(sol.seat_velocity / omega)
    span = phi_join - phi_seat
    if slope > 0.0:
        span = min(span, 3.0 * (overtravel - join_lift) / slope)
    phi_flat = phi_seat + span
    marks = [phi_trip, phi_seat, phi_flat, phi_join]
    marks += [phi_trip + omega * e["t"] for e in sol.events if e["kind"] != "seat"]
    latch_marks = np.mod(np.asarray(latch.breakpoints()) - start, TWO_PI)
    marks += [m for m in latch_marks if m <= phi_trip or m >= phi_join]
    lift = TripLift(
        latch=latch, overtravel=overtravel, trip_angle=trip_angle, omega=omega, closing=sol, start=start,
        phi_pick=phi_pick, phi_trip=phi_trip, phi_seat=phi_seat, phi_flat=phi_flat, phi_join=phi_join, join_lift=join_lift,
        seat_slope=sol.seat_velocity / omega, marks=tuple(float(np.mod(m + start, TWO_PI)) for m in marks),
        latched=latched,
    )
    return lift
