"""`exact` solver (the default): piecewise-exact stepping of the elastic valve linkage.

Its parts: exact_grid.py (the grid of steps and the drive's polynomials over it),
exact_steps.py (a phase's ODE over a step: Taylor tables, forcing, one step's expansion),
modal.py (the propagator over many steps), exact_phase.py (one phase at a time: a valve at rest,
or moving window by window, up to its next event), exact_events.py (event functions, bounds, the
search in one step, root polish), exact_output.py (acceleration, jerk, force and the output
times), phases.py (what happens at an event, shared with the other solvers), series.py (Hermite
and Taylor helpers); this module: the event loop and what each event does.

Each moving phase is a linear ODE with constant coefficients,
    m s'' + c s' + K s = kc (S(t) - lash) + cc S'(t) - F0,
  contact: m = M1, c = damping, K = k + rate, kc = k, cc = c, F0 = preload + closing + R sign(v)
  flight:  m = M,  c = 0,       K = rate,     kc = cc = 0,  F0 = the same
and a valve at rest (seated, or stuck by friction) has s = const. Over every step the drive S is
replaced by the quintic Hermite polynomial through S, S', S'' at both ends (taken from the analytic
drive; steps end at the drive's breakpoints, so jumps of S'' fall on step ends). With polynomial
forcing the response over a step is known in closed form; it is carried as its Taylor series in
the step variable u = tau/h, whose coefficients follow exactly from the ODE,
    m (n+2)(n+1) a[n+2] + c h (n+1) a[n+1] + K h^2 a[n] = h^2 f[n]        (a[n] = s^(n) h^n / n!),
i.e. the matrix exponential of the augmented system (the "phi functions" of exponential
integrators) as a power series. Steps are at most 0.5 / rho long (rho: the phase's fastest rate,
the natural frequency), so 9-17 terms reach 1e-19 and no digits are lost to the cancellation
between particular and homogeneous solution that the textbook closed form suffers when
omega_n h is small. Longer steps (very stiff linkages) are split. There is no stability limit
and no tuning knob: the only error is the interpolation of S, O(h^6) (a drive feature narrower
than the output step, e.g. a bump, is seen only through that interpolation).

From step to step the state follows x[i+1] = Phi(h) x[i] + g[i]. In modal coordinates
(s, (v + alpha s)/beta) Phi is a damped rotation for any step length, so this recurrence is
solved in closed form for the whole grid at once (modal.py): the powers of the eigenvalue and the
cumulative sums of the drive's forcing are computed once per phase kind, and a phase is then a
few vector operations on slices, whatever its length (no Python loop over steps, no per-phase
cumulative sum). The module needs numpy only (fast to import).

Cost (issue 4's speed target): a solve is a fixed part -- the drive at the nodes, the step
polynomials, per phase kind the modal powers and the sums of the drive's forcing as far as its
phases reach -- plus, per phase, one window of vector operations (states, event values, bounds:
~20 numpy calls) and two single steps in plain Python (the phase's first partial step, where the
event that began it sits on its zero, and the step where the next event lies). Everything at the
scale of one step is plain-float Python: numpy's overhead on tiny arrays would dominate. At the
default 3600 steps per revolution the time is mostly that overhead, not arithmetic (a tenth of
the steps saves only 10-25 %): ~0.9 ms for a revolution with 3 events, ~1.3 ms with 11, and
0.25-0.35 ms more right after unrelated work has evicted the caches (benchmarks/bench_dynamics.py
measures that way, alternating with scipy).

Events are roots of the closed forms, per step:
  seated -> lift-off    linkage force k (S - lash) + c S' exceeds preload + closing + friction
  contact -> separation linkage force k (S - lash - s) + c (S' - v) falls to 0
  flight -> re-contact  gap S - lash - s closes (with damping: and the force would be positive)
  any -> seat           s = 0 moving down: rebound v -> -e v
  velocity zero         (only with friction) the friction force flips, or the valve sticks
No crossing inside a step is missed. A step is cleared only by a rigorous bound: the event
function e is at most the larger end value plus h^2/8 sup e''. sup e'' is bounded first for a
whole window of steps from node values and the ODE (cheap), then for the steps this does not
clear from each one's own left-node values, and for the few left from the step's own Taylor
coefficients (values and slopes at both ends and a signed bound of e''). Steps still not
cleared are sampled at 8 points, recursively, and the first sign change is polished to machine
precision (Newton steps from the secant point inside the bracket, or the Illinois variant of
regula falsi), returning the first representable instant past the zero so that the next phase
starts on its own side. At a phase start the function that began it sits on its
zero: its leading Taylor terms against the positive part of the rest clear an initial stretch
analytically (e(w) <= w^k (e_k + sum max(e_n, 0) w^(n-k))).

Chattering seat impacts (e > 0) are followed until the next bounce would rise less than
`zeno_height`; the remaining infinitely many bounces are summed as a geometric series (durations
2 v e^n / A, A the net deceleration on the seat) and the valve stays seated from that
accumulation instant on.

Output: s, v, a, jerk (the closed-form third derivative within the phase), linkage force and
phase at the requested times; the valve starts at rest on its seat at t[0] unless
initial_state = (s, v) is given.
"""

from __future__ import annotations

import numpy as np

from . import exact_output
from .exact_phase import PhaseStepper
from .model import DynamicsSolution, LinkageModel
from .phases import (AFTER_CROSSING, CONTACT, SEATED, STUCK, phase_of_state, release_from_rest, rest_force,
                     seat_rebound, velocity_zero)

MAX_SAME_TIME = 60  # events at one instant before the phase logic is declared looping
LAST_U = 1.0 - 1e-16  # the largest position within a step an advance lands on (the node after is the next step's)


class _Solver(PhaseStepper):
    """The event loop: a phase is stepped (PhaseStepper) up to its next event; the event decides
    the next phase (phases.py) and is recorded."""

    def __init__(self, model: LinkageModel, drive, t: np.ndarray, initial_state, zeno_height: float,
                 max_events: int, chunk: int, hmin: float):
        super().__init__(model, drive, t, chunk, hmin)
        self.zeno_height = zeno_height
        self.max_events = max_events
        self.initial_state = initial_state
        self.events: list[dict] = []

    def _advance(self, j: int, u: float, dt: float, s_star: float):
        """Position dt later; nodes passed on the way are recorded seated at s_star."""
        t_new = self.time(j, u) + dt
        j0 = j
        while j < self.h.size and self.nodes[j + 1] <= t_new:
            j += 1
        start = j0 + (1 if u > 0.0 else 0)
        if j >= self.h.size:
            self._record_static(start, j, s_star, SEATED)
            return j, 0.0
        u_new = max(0.0, min((t_new - self.nodes[j]) / self.h[j], LAST_U))
        self._record_static(start, j + (1 if u_new > 0.0 else 0), s_star, SEATED)
        return j, u_new

    def _event(self, kind: str, j: int, u: float, v: float | None = None, **extra) -> None:
        ev = {"kind": kind, "time_s": self.time(j, u)}
        if v is not None:
            ev["velocity_m_s"] = float(v)
        ev.update(extra)
        self.events.append(ev)

    # ---------------------------------------------------------------- main loop
    def run(self) -> None:
        if self.initial_state is None:
            phase, s, v, sigma = SEATED, 0.0, 0.0, 1.0
        else:
            s, v = (float(x) for x in self.initial_state)
            phase, sigma = self._phase_at(0, 0.0, s, v)
        j, u = 0, 0.0
        release = self.initial_state is not None and v == 0.0
        same_time, last_time = 0, None
        while True:
            self.stats["phases"] += 1
            if len(self.events) > self.max_events:
                raise RuntimeError(f"exact solver: more than {self.max_events} events; the motion does not settle")
            if phase in (SEATED, STUCK):
                res = self._run_static(j, u, s, phase)
                if res is None:
                    break
                which, j, u = res
                if j < self.h.size and u >= 1.0:
                    j, u = j + 1, 0.0
                S, S1 = self._drive_at(j, u)
                phase, sigma, lifts = release_from_rest(which, phase, S, S1, self.k, self.c, self.lash, s, self.W0, self.R)
                if lifts:
                    self._event("lift-off", j, u, 0.0)
                v = 0.0
                release = True
            else:
                res = self._run_moving(phase, j, u, s, v, sigma, release)
                release = False
                if res is None:
                    break
                which, j, u, s, v = res
                if j < self.h.size and u >= 1.0:
                    j, u = j + 1, 0.0
                phase, s, v, sigma, j, u = self._handle(which, phase, j, u, s, v, sigma)
            t_now = self.time(j, u)
            same_time = same_time + 1 if t_now == last_time else 0
            last_time = t_now
            if same_time > MAX_SAME_TIME:
                raise RuntimeError(f"exact solver: events repeat at t = {t_now!r} s without progress")

    def _phase_at(self, j: int, u: float, s: float, v: float):
        """Phase and friction sign of a valve given at (s, v)."""
        S, S1 = self._drive_at(j, u)
        return phase_of_state(S, S1, self.k, self.c, self.lash, s, v, self.W0, self.rate, self.R)

    def _handle(self, which: str, phase: int, j: int, u: float, s: float, v: float, sigma: float):
        """The phase after the event `which` (the rules: phases.py), with this solver's bookkeeping."""
        m_phase = self.M1 if phase == CONTACT else self.M
        if which in AFTER_CROSSING:
            self._event(which, j, u, v)
            switch = 0.5 * (self.M - self.M1) * v * v
            self.stats["mass_switch_energy_J"] += switch if which == "separation" else -switch
            return AFTER_CROSSING[which], s, v, sigma, j, u
        S, S1 = self._drive_at(j, u)  # (the mass switches above need no drive)
        if which == "velocity-zero":
            self.stats["velocity_reversals"] += 1
            phase, sign = velocity_zero(phase, S, S1, self.k, self.c, self.lash, s, self.W0, self.rate, self.R)
            if sign is None:
                self.stats["sticks"] += 1
                return phase, s, 0.0, sigma, j, u
            return phase, s, 0.0, sign, j, u
        # seat impact
        impact = min(v, 0.0)
        self._event("seat", j, u, impact)
        self.stats["impact_energy_loss_J"] += 0.5 * m_phase * (1.0 - self.e * self.e) * impact * impact
        if -self.e * impact <= 0.0:
            return SEATED, 0.0, 0.0, 1.0, j, u
        force = rest_force(S, S1, self.k, self.c, self.lash, 0.0)
        kind, rebound, m_rest, dt = seat_rebound(impact, self.e, force, self.M, self.M1, self.W0, self.R,
                                                 self.zeno_height)
        if dt is not None:  # the rest of the chatter, summed
            self.stats["zeno"] += 1
            self.stats["impact_energy_loss_J"] += 0.5 * m_rest * rebound * rebound
            self.events[-1]["zeno_accumulation_s"] = self.time(j, u) + dt
            j, u = self._advance(j, u, dt, 0.0)
            return SEATED, 0.0, 0.0, 1.0, j, u
        return kind, 0.0, rebound, 1.0, j, u

    def solution(self, t_req: np.ndarray, inverse) -> DynamicsSolution:
        """The results at the output times (inverse: node of each output time, None: one each)."""
        return exact_output.solution(t_req, inverse, self.out_s, self.out_v, self.out_sigma, self.out_phase, self.Dn,
                                     self.is_out, self.lins, self.k, self.c, self.lash, self.W0, self.R, self.events,
                                     self.stats)


def solve(
    model: LinkageModel,
    drive,
    t: np.ndarray,
    initial_state: tuple[float, float] | None = None,
    zeno_height: float = 1e-12,
    max_events: int = 100_000,
    chunk: int = 512,
) -> DynamicsSolution:
    """Piecewise-exact solution at the output times t (sorted).

    initial_state: (s, v) at t[0]; default: at rest on the seat.
    zeno_height: seat chatter ends (in closed form) once a rebound would rise less than this (m).
    max_events: guard against a motion that never settles (raises RuntimeError).
    chunk: fewest steps propagated and scanned at once at the start of a moving phase (then twice
      the last phase of its kind, growing 8x while no event is found).
    """
    t_req, t_nodes, inverse, hmin = exact_output.output_nodes(t)
    solver = _Solver(model, drive, t_nodes, initial_state, zeno_height, max_events, chunk, hmin)
    solver.run()
    return solver.solution(t_req, inverse)
