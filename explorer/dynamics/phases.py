"""The phase-transition rules of the elastic valve (model.py), written once for every solver that
steps phase by phase (exact, taylor; reference.py's start uses phase_of_state too).

Phases (PHASE_CODES): seated, contact (linkage loaded), flight (separated), stuck (held above the
seat by friction at v = 0). The solvers find *when* an event happens, each its own way; what
happens *then* is decided here, in plain floats:
  lift-off / release   a valve at rest whose net force leaves the friction band  release_from_rest
  separation           contact -> flight (the linkage force falls to 0)        AFTER_CROSSING
  re-contact           flight -> contact (the gap closes)                      AFTER_CROSSING
  velocity zero        with friction: the valve sticks, or the friction flips  velocity_zero
  seat                 rebound v -> -e v, or rest; the chatter's Zeno sum      seat_rebound
The start state (s, v) given by a caller is classified by phase_of_state.
"""

from __future__ import annotations

import math

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


def release_from_rest(which: str, resting: int, S: float, S1: float, k: float, c: float, lash: float, s: float,
                      W0: float, R: float) -> tuple[int, float, bool]:
    """A valve held at rest (PHASE_CODES seated or stuck) whose net force has just left the
    friction band, `which` = "up" or "down": (the moving phase, friction sign, lift-off?)."""
    x = S - lash - s
    touching = x >= 0.0 and k * x + c * S1 > 0.0
    seated = resting == PHASE_CODES["seated"]
    if which == "up" and seated and not touching and c * S1 > 0.0 and W0 + R > 0.0:
        # only the linkage can lift a seated valve, so it touches. With damping it can lift the
        # valve the instant its gap closes (the dashpot's c S' alone beats the preload), and the
        # gap recomputed there may round to a hair below zero: that is contact
        touching = True
    phase = PHASE_CODES["contact"] if touching else PHASE_CODES["flight"]
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
