"""The phase-transition rules of the elastic valve (model.py), written once: exact and taylor
take all of them; reference.py (scipy) and schenker1902.py take those that apply to them (the
start phase, touching, the stick at velocity zero, the seat speed of an event found a hair below
the seat, the rebound speed that ends the bouncing).

Phases (PHASE_CODES): seated, contact (linkage loaded), flight (separated), stuck (held above the
seat by friction at v = 0). Which events can end a phase, and the function whose sign change is
each event, are the tables moving_events and rest_events; each solver turns them into its own
functions (exact: linear rows in S, S', s, v; taylor: polynomials with k(t)) and finds *when* an
event happens its own way. What happens *then* is decided here, in plain floats:
  lift-off / release   a valve at rest whose net force leaves the friction band  release_from_rest
  separation           contact -> flight (the linkage force falls to 0)        AFTER_CROSSING
  re-contact           flight -> contact (the gap closes)                      AFTER_CROSSING
  velocity zero        with friction: the valve sticks, or the friction flips  velocity_zero
  seat                 rebound v -> -e v, or rest; the chatter's Zeno sum      seat_rebound
  (overshoot)          the seat speed of a landing found below the seat        seat_speed
The start state (s, v) given by a caller is classified by phase_of_state.

Two seat rules stay different, on purpose: the solvers that follow the chatter to its end
(exact, taylor) sum the Zeno tail (seat_rebound) and choose the phase after a rebound by the
linkage force at rest; reference and schenker1902 stop the bouncing below rebound_rest_speed and
choose it by the linkage force at the rebound speed (touching with v). Making them one would
change those solvers' results (the tests' converged reference among them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# DynamicsSolution.phase codes: on the seat, moving with the linkage loaded, moving with the linkage
# unloaded (separated), held above the seat by friction at v = 0
PHASE_CODES = {"seated": 0, "contact": 1, "flight": 2, "stuck": 3}
SEATED, CONTACT, FLIGHT, STUCK = (PHASE_CODES[k] for k in ("seated", "contact", "flight", "stuck"))


def phase_of_state(S: float, S1: float, k: float, c: float, lash: float, s: float, v: float, W0: float,
                   rate: float, R: float) -> tuple[int, float]:
    """PHASE_CODES phase and friction sign of a valve given at (s, v) with the drive at (S, S')
    and the linkage stiffness k there (the exact and taylor solvers' start from initial_state)."""
    x = S - lash - s
    force = k * x + c * (S1 - v)
    touching = x >= 0.0 and force > 0.0
    kind = PHASE_CODES["contact"] if touching else PHASE_CODES["flight"]
    if v != 0.0:
        return kind, math.copysign(1.0, v)
    net = (force if touching else 0.0) - W0 - rate * s
    if s <= 0.0 and net <= R:
        return PHASE_CODES["seated"], 1.0
    if abs(net) <= R:
        return PHASE_CODES["stuck"], 1.0
    return kind, (1.0 if net > 0.0 else -1.0)


@dataclass(frozen=True)
class EventRule:
    """An event that ends a phase: it fires at the first instant where the combination `comb` of
    its components becomes > 0 ("one": the single component; "min": all of them; "max": any).
    A component (quantity, sign, threshold) is sign * (quantity - threshold), the quantities:
      gap       S - lash - s               (the linkage's clearance is closed where > 0)
      force     k gap + c (S' - v)         (the linkage force, unclipped)
      lift      s
      velocity  v
      push      k (S - lash - s*) + c S'   (a valve at rest at s*: the linkage force on it)
    with s* the rest height for a valve at rest (gap is then S - lash - s*)."""

    kind: str
    comps: tuple[tuple[str, float, float], ...]
    comb: str = "one"


def moving_events(phase: int, damped: bool, friction: bool, sigma: float) -> tuple[EventRule, ...]:
    """The events of a moving valve (phase CONTACT or FLIGHT, friction sign sigma): the linkage
    lets go (separation) or takes hold again (re-contact; with damping it pushes only where the
    dashpot's part does not pull it back, min(gap, force)), the valve reaches the seat, and with
    friction its velocity reaches zero (stick or turn: velocity_zero)."""
    if phase == CONTACT:
        crossing = EventRule("separation", (("force", -1.0, 0.0),))
    elif damped:
        crossing = EventRule("re-contact", (("gap", 1.0, 0.0), ("force", 1.0, 0.0)), "min")
    else:
        crossing = EventRule("re-contact", (("gap", 1.0, 0.0),))
    events = (crossing, EventRule("seat", (("lift", -1.0, 0.0),)))
    if friction:
        events += (EventRule("velocity-zero", (("velocity", -sigma, 0.0),)),)
    return events


def rest_events(s_star: float, W0: float, rate: float, R: float, gap_check: bool) -> tuple[EventRule, ...]:
    """The events of a valve at rest at s_star (seated: 0): "up" where the linkage pushes harder
    than the spring, the loads and friction hold it (and its gap is closed), "down" (held above
    the seat by friction only) where the push falls below the loads less friction (or the gap
    opens). Without damping the gap's component is implied by the push's (k gap >= push there);
    gap_check=False leaves it out then."""
    # (the gap first: a resting valve's gap is mostly open, and a search that clears a step on
    # any component clears it on the first)
    thr_up = W0 + rate * s_star + R
    up = ((("gap", 1.0, 0.0),) if gap_check else ()) + (("push", 1.0, thr_up),)
    events = (EventRule("up", up, "min" if len(up) > 1 else "one"),)
    thr_dn = W0 + rate * s_star - R
    if s_star > 0.0 and thr_dn > 0.0:
        down = ((("gap", -1.0, 0.0),) if gap_check else ()) + (("push", -1.0, thr_dn),)
        events += (EventRule("down", down, "max" if len(down) > 1 else "one"),)
    return events


def touching(S: float, S1: float, k: float, c: float, lash: float, s: float, v: float = 0.0) -> bool:
    """The linkage touches a valve at (s, v) and pushes it: the gap x = S - lash - s is closed and
    k x + c (S' - v) > 0."""
    x = S - lash - s
    return x >= 0.0 and k * x + c * (S1 - v) > 0.0


def release_from_rest(which: str, resting: int, S: float, S1: float, k: float, c: float, lash: float, s: float,
                      W0: float, R: float) -> tuple[int, float, bool]:
    """A valve held at rest (PHASE_CODES seated or stuck) whose net force has just left the
    friction band, `which` = "up" or "down": (the moving phase, friction sign, lift-off?)."""
    pushes = touching(S, S1, k, c, lash, s)
    seated = resting == PHASE_CODES["seated"]
    if which == "up" and seated and not pushes and c * S1 > 0.0 and W0 + R > 0.0:
        # only the linkage can lift a seated valve, so it touches. With damping it can lift the
        # valve the instant its gap closes (the dashpot's c S' alone beats the preload), and the
        # gap recomputed there may round to a hair below zero: that is contact
        pushes = True
    phase = PHASE_CODES["contact"] if pushes else PHASE_CODES["flight"]
    return phase, (1.0 if which == "up" else -1.0), which == "up" and seated


# the phase after a crossing of the linkage's force or gap (the state itself is continuous)
AFTER_CROSSING = {"separation": FLIGHT, "re-contact": CONTACT}


def rest_force(S: float, S1: float, k: float, c: float, lash: float, s: float) -> float:
    """Linkage force on a valve at rest at s (v = 0): k x + c S' when the gap x is closed, >= 0."""
    x = S - lash - s
    return max(0.0, k * x + c * S1) if x >= 0.0 else 0.0


def velocity_zero(phase: int, S: float, S1: float, k: float, c: float, lash: float, s: float, W0: float,
                  rate: float, R: float) -> tuple[int, float | None]:
    """A moving valve (with friction R > 0) whose velocity has reached 0 at s: it sticks when the
    net force is within the friction band -- (STUCK, or SEATED at s <= 0; None: keep the friction
    sign) -- else it turns, (phase, the new friction sign)."""
    force = k * (S - lash - s) + c * S1 if phase == CONTACT else 0.0
    net = force - W0 - rate * s
    if abs(net) <= R:
        return (STUCK if s > 0.0 else SEATED), None
    return phase, (1.0 if net > 0.0 else -1.0)


def seat_rebound(impact: float, e: float, force: float, M: float, M1: float, W0: float, R: float,
                 zeno_height: float) -> tuple[int, float, float, float | None]:
    """The valve hits its seat at speed `impact` (<= 0) with the linkage force `force` there (at
    rest, rest_force): (phase after, rebound speed -e impact, mass the rebound moves with, Zeno
    time or None). It stays seated when it does not rebound; when the rebound would rise less than
    zeno_height against the net deceleration A on the seat, the rest of the chatter -- bounces
    of durations 2 v e^n / A -- is summed, 2 v / (A (1 - e)), after which it is seated."""
    rebound = -e * impact
    if rebound <= 0.0:
        return SEATED, rebound, M, None
    m_rest = M1 if force > 0.0 else M
    decel = (W0 + R - force) / m_rest
    if decel > 0.0 and rebound * rebound <= 2.0 * decel * zeno_height:
        return SEATED, rebound, m_rest, 2.0 * rebound / (decel * (1.0 - e))
    return (CONTACT if force > 0.0 else FLIGHT), rebound, m_rest, None


def seat_speed(v: float, s: float, acc: float) -> float:
    """A seat event found a hair below the seat (s < 0, moving down at v under the acceleration
    acc): the speed at s = 0, by energy (v^2 - 2 acc s, the work over the overshoot taken back)."""
    return -math.sqrt(max(v * v - 2.0 * acc * s, 0.0))


def rebound_rest_speed(W0: float, R: float, M: float, rest_height: float) -> float:
    """The solvers that do not sum the chatter (reference, schenker1902): a rebound slower than this
    would rise less than rest_height against the seated resistance W0 + R, and ends the bouncing
    (the Zeno tail of e > 0 dropped, where seat_rebound sums it)."""
    deceleration = (W0 + R) / M
    return math.sqrt(2.0 * deceleration * rest_height) if deceleration > 0.0 else 0.0
