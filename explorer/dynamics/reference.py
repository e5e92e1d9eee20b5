"""`scipy` solver: the linkage model integrated by scipy.integrate.solve_ivp, phase by phase.

This is the converged reference the other solvers are measured against. The motion is split
into phases with smooth right-hand sides, each integrated by solve_ivp up to the next event:
  rest     valve held (on the seat, or stuck by friction at v = 0): no ODE; the release instant
           is a root of the net force, found on a probe grid and polished with Brent's method
  contact  M1 s'' = k (S - lash - s) + c (S' - s') - W(s) - friction*d      (d = direction)
  flight   M  s'' = -W(s) - friction*d
Event functions end a phase: separation (linkage force falls to 0), re-contact (gap closes),
seat (s = 0 moving down), and velocity zero when there is friction (its sign flips, the RHS
jumps, and the valve may stick). Each phase also ends at the drive's breakpoints, where S''
may jump, so every solve_ivp call sees a smooth problem and keeps its full order.

solve_ivp finds events only by sign changes between two steps: a double crossing inside one step
(a short flight, a brief re-contact) is missed silently. max_step is therefore bounded by a
fraction of the contact natural period, the fastest time scale of the model.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from ..core.roots import root_in

from .model import PHASE_CODES, DynamicsSolution, Drive, LinkageModel
from .phases import phase_of_state, rebound_rest_speed, seat_speed, touching, velocity_zero
from .tabulated import TabulatedDrive

REST, CONTACT, FLIGHT = "rest", "contact", "flight"
IMPLICIT_METHODS = ("Radau", "BDF", "LSODA")
SEAT_TOLERANCE = 1e-12  # m: an event this close to the seat while moving down is a seat impact
MAX_EVENTS = 100_000  # a guard against endless event loops (a bug, not physics)


def static_resistance(model: LinkageModel, s):
    """W(s) without friction: preload + rate*s + closing loads (N, + closes the valve)."""
    return model.preload + model.spring_rate * s + model.closing_load


def linkage_force(model: LinkageModel, S, Sd, s, v, k=None):
    """Compressive linkage force k*(S - lash - s) + c*(S' - v), unclipped (negative = would pull).
    k: the stiffness at that instant when it changes along the cycle (default: the model's)."""
    return (model.stiffness if k is None else k) * (S - model.lash - s) + model.damping * (Sd - v)


def contact_acceleration(model: LinkageModel, S, Sd, s, v, d, k=None):
    return (linkage_force(model, S, Sd, s, v, k) - static_resistance(model, s) - model.friction * d) / model.oscillating_mass


def flight_acceleration(model: LinkageModel, s, d):
    return -(static_resistance(model, s) + model.friction * d) / model.mass


def rest_net_force(model: LinkageModel, S, Sd, s_rest, k=None):
    """Net force on a valve held at rest at s_rest, friction excluded: linkage (if touching) - W."""
    x = S - model.lash - s_rest
    push = np.where(x >= 0.0, np.maximum(0.0, (model.stiffness if k is None else k) * x + model.damping * Sd), 0.0)
    return push - static_resistance(model, s_rest)


class _DriveCache:
    """S and S' at one time, remembered: solve_ivp asks the RHS and the event functions for the
    same instant several times, and each lift evaluation costs tens of microseconds."""

    def __init__(self, drive: Drive):
        self.lift, self.ratio, self.omega = drive.lift, drive.ratio, drive.omega
        self.t = math.nan
        self.S = self.Sd = self.Sdd = 0.0

    def __call__(self, t: float):
        if t != self.t:
            d = self.lift.derivatives(np.array([self.omega * t]))
            w, r = self.omega, self.ratio
            self.t, self.S, self.Sd, self.Sdd = t, r * float(d[0, 0]), r * w * float(d[1, 0]), r * w * w * float(d[2, 0])
        return self.S, self.Sd


class _VaryingCache(_DriveCache):
    """The same, with the linkage stiffness k(t) and dk/dt of the instant (a lever whose ratio
    changes); a class of its own so that the constant-stiffness path pays nothing for it."""

    def __init__(self, drive: Drive, profile):
        super().__init__(drive)
        self.profile = profile
        self.k = self.kd = 0.0

    def __call__(self, t: float):
        if t != self.t:
            super().__call__(t)
            k = self.profile(np.array([t]))
            self.k, self.kd = float(k[0, 0]), float(k[1, 0])
        return self.S, self.Sd

    def stiffness(self, t: float) -> float:
        self(t)
        return self.k


def _phase_functions(model: LinkageModel, cache: _DriveCache, phase: str, d: float, friction_events: bool, band: float,
                     watchers: bool = True):
    """RHS, Jacobian, terminal event functions and their watchers of one moving phase.

    A watcher is a non-terminal event on the derivative of a terminal event function: it marks
    each extremum of the function. An extremum beyond the surface means the function crossed it
    twice inside one step, which solve_ivp's sign test cannot see; `solve` then goes back to the
    first crossing. (Returns rhs, jac, events, names, watch: watcher index -> event index.)

    Each event fires a hair (`band`, in metres; times k for the force, omega_n for the velocity)
    beyond its surface. A phase starts exactly on the surface it came through, and solve_ivp
    counts a zero after its first (tiny) step as a crossing; the band keeps it from firing the
    event it has just crossed, at a cost of ~1e-15 m.
    """
    k, c, lash = model.stiffness, model.damping, model.lash
    rate, m1, m = model.spring_rate, model.oscillating_mass, model.mass
    w0 = model.preload + model.closing_load + model.friction * d

    if phase == CONTACT and model.stiffness_profile is not None:  # k = k(t), cache.k

        def rhs(t, y):
            S, Sd = cache(t)
            return [y[1], (cache.k * (S - lash - y[0]) + c * (Sd - y[1]) - w0 - rate * y[0]) / m1]

        def jacobian_of(t, y):
            cache(t)
            return np.array([[0.0, 1.0], [-(cache.k + rate) / m1, -c / m1]])

        def separation(t, y):
            S, Sd = cache(t)
            return cache.k * (S - lash - y[0]) + c * (Sd - y[1]) + cache.k * band

        separation.terminal, separation.direction = True, -1.0

        def separation_slope(t, y):
            S, Sd = cache(t)
            x = S - lash - y[0]
            a = (cache.k * x + c * (Sd - y[1]) - w0 - rate * y[0]) / m1
            return cache.kd * x + cache.k * (Sd - y[1]) + c * (cache.Sdd - a)

        events = [separation]
        names = ["separation"]
        slopes = [separation_slope]
    elif phase == CONTACT:

        def rhs(t, y):
            S, Sd = cache(t)
            return [y[1], (k * (S - lash - y[0]) + c * (Sd - y[1]) - w0 - rate * y[0]) / m1]

        jacobian = np.array([[0.0, 1.0], [-(k + rate) / m1, -c / m1]])

        force_band = k * band

        def separation(t, y):
            S, Sd = cache(t)
            return k * (S - lash - y[0]) + c * (Sd - y[1]) + force_band

        separation.terminal, separation.direction = True, -1.0

        def separation_slope(t, y):
            S, Sd = cache(t)
            a = (k * (S - lash - y[0]) + c * (Sd - y[1]) - w0 - rate * y[0]) / m1
            return k * (Sd - y[1]) + c * (cache.Sdd - a)

        events = [separation]
        names = ["separation"]
        slopes = [separation_slope]
    else:

        def rhs(t, y):
            return [y[1], -(w0 + rate * y[0]) / m]

        jacobian = np.array([[0.0, 1.0], [-rate / m, 0.0]])

        if c > 0.0:
            # with damping the linkage lets go while still compressed (k x + c (S' - v) = 0 at
            # x > 0), so the gap alone may never cross zero again: contact resumes where the
            # linkage would push, min(x, x + (c/k)(S' - v)) rising through 0 (in metres)
            varying = model.stiffness_profile is not None

            def recontact(t, y):
                S, Sd = cache(t)
                x = S - lash - y[0]
                return min(x, x + c / (cache.k if varying else k) * (Sd - y[1])) - band

            def recontact_slope(t, y):
                S, Sd = cache(t)
                if Sd - y[1] >= 0.0:  # the gap is the smaller
                    return Sd - y[1]
                kk = cache.k if varying else k
                a = -(w0 + rate * y[0]) / m
                slope = Sd - y[1] + c / kk * (cache.Sdd - a)
                return slope - c * cache.kd / (kk * kk) * (Sd - y[1]) if varying else slope
        else:

            def recontact(t, y):
                return cache(t)[0] - lash - y[0] - band

            def recontact_slope(t, y):
                return cache(t)[1] - y[1]

        recontact.terminal, recontact.direction = True, 1.0

        events = [recontact]
        names = ["re-contact"]
        slopes = [recontact_slope]

    if phase != CONTACT or model.stiffness_profile is None:

        def jacobian_of(t, y):
            return jacobian

    def seat(t, y):
        return y[0] + band

    seat.terminal, seat.direction = True, -1.0

    def seat_slope(t, y):
        return y[1]

    events.append(seat)
    names.append("seat")
    slopes.append(seat_slope)
    if friction_events:

        speed_band = d * band * math.sqrt((k + rate) / m1)

        def velocity_zero(t, y):
            return y[1] + speed_band

        velocity_zero.terminal, velocity_zero.direction = True, -d
        events.append(velocity_zero)
        names.append("velocity-zero")
    watch = {}
    if not watchers:
        return rhs, jacobian_of, events, names, watch
    for i, slope in enumerate(slopes):
        slope.terminal, slope.direction = False, -events[i].direction  # extremum on the far side
        watch[len(events) + i] = i
    return rhs, jacobian_of, events + slopes, names, watch


def _missed_crossing(sol, functions, watch: dict, t_seg: float):
    """(time, event index) of the earliest event crossed twice inside one step, or None.

    A watcher fired at an extremum of event function g; if g there lies beyond its surface
    (g < 0 for a falling event, > 0 for a rising one), g crossed the surface inside the step
    that holds the extremum. The crossing is polished with Brent's method on the dense output."""
    best = None
    for w, i in watch.items():
        g, direction = functions[i], functions[i].direction
        for te, ye in zip(sol.t_events[w], sol.y_events[w]):
            if te >= t_seg or (best is not None and te >= best[0]):
                continue
            if g(te, ye) * direction > 0.0:  # beyond the surface at the extremum
                ts = sol.sol.ts
                k = max(int(np.searchsorted(ts, te, side="right")) - 1, 0)
                lo = float(ts[k]) if ts[k] < te else float(ts[max(k - 1, 0)])

                def along(tt):
                    return g(tt, sol.sol(tt))

                f_lo = along(lo)
                if f_lo * direction < 0.0:  # the event value (g at te, > 0 by direction) closes the bracket
                    root = root_in(along, lo, float(te), fa=f_lo, fb=float(g(te, ye)), xtol=1e-15, maxiter=200)
                    best = (float(root), i)
    return best


def initial_phase(model: LinkageModel, S: float, Sd: float, s: float, v: float, k=None) -> tuple[str, float]:
    """Phase and friction direction of a valve given at (s, v) with the drive at (S, S') (seated
    and stuck are both REST here, with direction 0)."""
    code, direction = phase_of_state(S, Sd, model.stiffness if k is None else k, model.damping, model.lash, s, v,
                                     model.seated_resistance, model.spring_rate, model.friction)
    if code in (PHASE_CODES["seated"], PHASE_CODES["stuck"]):
        return REST, 0.0
    return (CONTACT if code == PHASE_CODES["contact"] else FLIGHT), direction


def _release(model: LinkageModel, drive: Drive, s_rest: float, t0: float, t1: float, probe: float):
    """First time in [t0, t1] at which a valve held at s_rest starts to move, and the direction.

    Up: net force exceeds friction (the seat can only push up, so on the seat this is the only
    way out). Down (held above the seat by friction alone): net force below -friction.
    Returns (t1 or later, 0) when it stays held. Probes windows of growing length so a short rest
    costs little; inside the first bracket the root is polished with Brent's method.
    """
    mu = model.friction
    can_fall = s_rest > 0.0

    varying = model.stiffness_profile is not None

    def margin(tt):
        D = drive(tt)
        net = rest_net_force(model, D[0], D[1], s_rest, model.stiffness_at(tt) if varying else None)
        up = net - mu
        return up, (-net - mu) if can_fall else np.full_like(up, -np.inf)

    def scalar(tt, which):
        up, down = margin(np.array([tt]))
        return float(up[0] if which > 0 else down[0])

    up, down = margin(np.array([t0]))
    if up[0] > 0.0:
        return t0, 1
    if down[0] > 0.0:
        return t0, -1
    start, width = t0, 256 * probe
    breaks = drive.breakpoints(t0, t1)
    while start < t1:
        stop = min(t1, start + width)
        grid = np.unique(np.concatenate([np.arange(start, stop, probe), [stop], breaks[(breaks > start) & (breaks < stop)]]))
        up, down = margin(grid)
        hit = np.nonzero((up > 0.0) | (down > 0.0))[0]
        if hit.size:
            j = int(hit[0])
            which = 1 if up[j] > 0.0 else -1
            if j == 0:
                return float(grid[0]), which
            return _first_positive(lambda tt: scalar(tt, which), float(grid[j - 1]), float(grid[j])), which
        start, width = stop, 4 * width
    return math.inf, 0


def _first_positive(f, a: float, b: float) -> float:
    """The earliest time in (a, b] where f > 0, given f(a) <= 0 < f(b), to machine precision.

    Brent's method when f(a) < 0 strictly; when f(a) == 0 (a net force that stays exactly zero
    until the drive starts moving, common on a base circle) only bisection on the sign finds
    where f leaves zero."""
    fa = f(a)
    if fa < 0.0:
        a = root_in(f, a, b, fa=fa, fb=f(b), xtol=1e-15, maxiter=200)
        if f(a) > 0.0:
            return a
    for _ in range(200):  # bisection on the predicate f > 0: a stays where f <= 0, b where f > 0
        mid = 0.5 * (a + b)
        if mid <= a or mid >= b:
            break
        if f(mid) > 0.0:
            b = mid
        else:
            a = mid
    return b


def solve(
    model: LinkageModel,
    drive: Drive,
    t: np.ndarray,
    scipy_method: str = "DOP853",
    rtol: float = 1e-10,
    atol: float = 1e-13,
    max_step_fraction: float = 0.25,
    initial_state: tuple[float, float] | None = None,
    rest_height: float = 1e-12,
    watch_extrema: bool = True,
    tabulate: int | None = None,
) -> DynamicsSolution:
    """Integrate the model over the output times t (sorted); the valve starts at rest on its seat
    at t[0] unless initial_state = (s, v) is given.

    scipy_method: any solve_ivp method (DOP853 default; RK45, RK23, Radau, BDF, LSODA).
    max_step_fraction: largest solve_ivp step as a fraction of the contact natural period.
    rest_height: restitution e > 0 gives infinitely many ever smaller seat bounces in finite
    time (Zeno); a rebound that would rise less than this (m) ends the bouncing.
    watch_extrema: also watch the extrema of the event functions, which catches an event crossed
    twice inside one step (a short flight); False is plain solve_ivp event detection.
    tabulate: evaluate the drive (and k(t)) once at this many nodes per output step and use
    Hermite tables between them (explorer.dynamics.tabulated) instead of one analytic evaluation
    per instant; default: 4 when the stiffness changes along the cycle (a gear's k(t) costs a
    millisecond an instant), else off.
    """
    t = np.asarray(t, dtype=float)
    n = t.size
    if n == 0 or np.any(np.diff(t) < 0.0):
        raise ValueError("output times must be a non-empty, sorted array")
    t_end = float(t[-1])
    period = model.natural_period()
    max_step = max_step_fraction * period
    probe = min(period / 4.0, float(np.min(np.diff(t))) if n > 1 else period / 4.0) or period / 4.0
    breaks = drive.breakpoints(float(t[0]), t_end)
    varying = model.stiffness_profile is not None
    if tabulate is None:
        tabulate = 4 if varying else 0
    if tabulate:
        spacing = min(float(np.min(np.diff(t))) if n > 1 else max_step, max_step) / tabulate
        cache = TabulatedDrive(drive, model.stiffness_profile, float(t[0]), t_end, spacing)
    else:
        cache = _VaryingCache(drive, model.stiffness_profile) if varying else _DriveCache(drive)

    def k_now(tt: float):
        """k at one instant (None: the model's constant)."""
        return cache.stiffness(tt) if varying else None
    # event hysteresis: far above the rounding of lift differences, far below any accuracy asked for
    scale = float(np.abs(drive(np.linspace(t[0], t_end, 257))[0]).max()) + abs(model.lash) + 1e-3
    band = 64 * np.finfo(float).eps * scale
    friction_events = model.friction > 0.0
    rest_speed = rebound_rest_speed(model.seated_resistance, model.friction, model.mass, rest_height)

    out = {name: np.zeros(n) for name in ("s", "v", "a", "f", "j")}
    in_contact = np.zeros(n, dtype=bool)
    phase_out = np.zeros(n, dtype=np.int64)
    events: list[dict] = []
    stats = {"method": scipy_method, "rtol": rtol, "atol": atol, "max_step_s": max_step, "nfev": 0, "njev": 0,
             "steps": 0, "ivp_calls": 0, "rest_phases": 0, "double_crossings": 0}
    filled = 0  # outputs t[:filled] are done

    def fill_rest(s_rest: float, upto: float) -> None:
        nonlocal filled
        j = int(np.searchsorted(t, upto, side="right")) if math.isfinite(upto) else n
        if j > filled:
            tt = t[filled:j]
            D = drive(tt)
            x = D[0] - model.lash - s_rest
            k = model.stiffness_at(tt) if varying else model.stiffness
            force = np.where(x >= 0.0, np.maximum(0.0, k * x + model.damping * D[1]), 0.0)
            out["s"][filled:j] = s_rest
            out["f"][filled:j] = force
            in_contact[filled:j] = force > 0.0
            phase_out[filled:j] = PHASE_CODES["seated" if s_rest == 0.0 else "stuck"]
            filled = j

    tcur = float(t[0])
    if initial_state is None:
        phase, s, v, d = REST, 0.0, 0.0, 0.0
    else:
        s, v = (float(x) for x in initial_state)
        phase, d = initial_phase(model, *cache(tcur), s, v, k_now(tcur))

    same_time_events = 0
    while tcur < t_end or filled < n:
        if len(events) > MAX_EVENTS:
            raise RuntimeError(f"more than {MAX_EVENTS} events: the phase logic is looping")
        if phase == REST:
            stats["rest_phases"] += 1
            released, direction = _release(model, drive, s, tcur, t_end, probe)
            fill_rest(s, released)
            if not math.isfinite(released) or released > t_end:
                break
            if s == 0.0:
                events.append({"kind": "lift-off", "time_s": released, "velocity_m_s": 0.0})
            tcur, v, d = released, 0.0, float(direction)
            S0, Sd0 = cache(tcur)
            k0 = k_now(tcur)
            pushes = touching(S0, Sd0, model.stiffness if k0 is None else k0, model.damping, model.lash, s)
            phase = CONTACT if pushes else FLIGHT
            continue

        later = breaks[breaks > tcur]
        t_stop = min(t_end, float(later[0])) if later.size else t_end
        if t_stop <= tcur:  # nothing left to integrate (outputs end here)
            t_stop = t_end
        rhs, jac, event_functions, names, watch = _phase_functions(model, cache, phase, d, friction_events, band,
                                                                   watch_extrema)
        options = dict(method=scipy_method, rtol=rtol, atol=atol, max_step=max_step, events=event_functions, dense_output=True)
        if scipy_method in IMPLICIT_METHODS:
            options["jac"] = jac
        if t_stop > tcur:
            sol = solve_ivp(rhs, (tcur, t_stop), [s, v], **options)
            if sol.status < 0:
                raise RuntimeError(f"solve_ivp failed at t = {tcur:.9g} s: {sol.message}")
            stats["nfev"] += int(sol.nfev)
            stats["njev"] += int(sol.njev)
            stats["ivp_calls"] += 1
            stats["steps"] += len(sol.sol.ts) - 1 if sol.sol is not None else 0
            t_seg = float(sol.t[-1])
            y_end = sol.y[:, -1]
            fired = [names[i] for i in range(len(names)) if sol.t_events[i].size] if sol.status == 1 else []
            missed = _missed_crossing(sol, event_functions, watch, t_seg)
            if missed is not None:
                t_seg, i = missed
                y_end, fired = sol.sol(t_seg), [names[i]]
                stats["double_crossings"] += 1
        else:
            sol, t_seg, y_end, fired = None, tcur, np.array([s, v]), []
        # outputs reached in this phase
        j = int(np.searchsorted(t, t_seg, side="right"))
        if j > filled and sol is not None:
            tt = t[filled:j]
            y = sol.sol(tt)
            D = drive(tt)
            out["s"][filled:j], out["v"][filled:j] = y[0], y[1]
            if phase == CONTACT:
                k, dk = model.stiffness_profile(tt) if varying else (model.stiffness, 0.0)
                a = contact_acceleration(model, D[0], D[1], y[0], y[1], d, k)
                force = np.maximum(0.0, linkage_force(model, D[0], D[1], y[0], y[1], k))
                out["f"][filled:j] = force
                in_contact[filled:j] = force > 0.0
                # d/dt of the contact equation: the jerk in closed form from the state
                out["j"][filled:j] = (dk * (D[0] - model.lash - y[0]) + k * (D[1] - y[1]) + model.damping * (D[2] - a)
                                      - model.spring_rate * y[1]) / model.oscillating_mass
            else:
                a = flight_acceleration(model, y[0], d)
                out["j"][filled:j] = -model.spring_rate * y[1] / model.mass
            out["a"][filled:j] = a
            phase_out[filled:j] = PHASE_CODES[phase]
            filled = j

        same_time_events = same_time_events + 1 if fired and t_seg == tcur else 0
        if same_time_events > 50:
            raise RuntimeError(f"events repeat at t = {tcur:.17g} s without progress ({fired})")
        tcur = t_seg
        s, v = float(y_end[0]), float(y_end[1])
        if not fired:
            continue
        S0, Sd0 = cache(tcur)
        k0 = k_now(tcur)
        k_here = model.stiffness if k0 is None else k0
        if s <= SEAT_TOLERANCE and v < 0.0 and "seat" not in fired:
            # the valve reaches the seat in the same instant as another event (zero lash on the
            # base circle: gap and lift close together); the seat, being rigid, decides
            fired = ["seat"]
        if "seat" in fired:
            if s < 0.0:  # the event fired a hair below the seat: the speed at s = 0, by energy
                a_here = contact_acceleration(model, S0, Sd0, s, v, d, k0) if phase == CONTACT else flight_acceleration(model, s, d)
                v = seat_speed(v, s, a_here)
            s = 0.0
            events.append({"kind": "seat", "time_s": tcur, "velocity_m_s": v})
            v = -model.restitution * v
            if v <= rest_speed:  # includes e = 0
                phase, v = REST, 0.0
            else:
                d = 1.0
                phase = CONTACT if touching(S0, Sd0, k_here, model.damping, model.lash, 0.0, v) else FLIGHT
        elif "separation" in fired:
            events.append({"kind": "separation", "time_s": tcur, "velocity_m_s": v})
            phase = FLIGHT
        elif "re-contact" in fired:
            events.append({"kind": "re-contact", "time_s": tcur, "velocity_m_s": v})
            phase = CONTACT
        elif "velocity-zero" in fired:
            v = 0.0
            code = PHASE_CODES["contact"] if phase == CONTACT else PHASE_CODES["flight"]
            _, sign = velocity_zero(code, S0, Sd0, k_here, model.damping, model.lash, s, model.seated_resistance,
                                    model.spring_rate, model.friction)
            if sign is None:
                phase = REST  # stuck: friction holds the valve
            else:
                d = sign
    return DynamicsSolution(
        t=t, s=out["s"], v=out["v"], a=out["a"], linkage_force=out["f"], contact=in_contact,
        events=tuple(events), stats=stats, jerk=out["j"], phase=phase_out,
    )
