"""The elastic valve-linkage model and the one interface all its solvers share.

Model (Schenker 1902, section 3, generalised): the valve (mass M) is driven through a linkage of
stiffness k (and optional viscous damping c) referred to the valve, which can push but never
pull, after a clearance (lash). Resistance W = preload + rate*s + friction*sign(v) + closing loads.
  seated:      s = 0 until the linkage force k*(S - lash) exceeds W (lift-off)
  in contact:  M1 s'' = k (S - lash - s) + c (S' - s') - W      (linkage force > 0)
  separated:   M s''  = -W                                      (linkage would pull)
  seat:        s = 0 reached with v < 0: rebound with v -> -e v (e = restitution; 0 stays down)
S(t) = ratio * L(omega t) is the drive (roller path referred to the valve). M1 (Schenker's mass
without the spring's share) is used while the linkage is compressed, M otherwise.

A lever whose ratio changes with its position (the rolling lever) has a valve-referred stiffness
that changes along the cycle: k(t) from a StiffnessProfile. The contact equation keeps its form
with k(t) in place of k; the force is k(t) (S - lash - s) + c (S' - s'). Only the solvers whose
registry entry says varying_stiffness accept it: the exact solver's closed forms need constant
coefficients.

Every solver has the signature
    solve(model: LinkageModel, drive: Drive, t: np.ndarray, **options) -> DynamicsSolution
and is listed, with what it accepts, in explorer/dynamics/solvers.py, whose `solve()` dispatches on
the method name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from .phases import PHASE_CODES, phase_of_state, release_from_rest  # noqa: F401 (re-exported)

if TYPE_CHECKING:
    from ..lift.curves import LiftCurve

EVENT_KINDS = ("lift-off", "separation", "re-contact", "seat")
@dataclass(frozen=True)
class LinkageModel:
    mass: float  # M, kg: all moving masses referred to the valve
    oscillating_mass: float  # M1, kg: mass used while the linkage is compressed (= M if not given)
    stiffness: float  # k, N/m, referred to the valve
    damping: float = 0.0  # c, N*s/m, in parallel with k (acts only in contact)
    lash: float = 0.0  # m, clearance before the linkage takes load
    preload: float = 0.0  # N, spring force at closed valve
    spring_rate: float = 0.0  # N/m
    friction: float = 0.0  # N, Coulomb, opposes valve motion
    closing_load: float = 0.0  # N, sum of constant loads (+ closes the valve)
    restitution: float = 0.0  # seat impact, 0 <= e < 1
    # k(t) when the stiffness changes along the cycle (then `stiffness` is its largest value, which
    # sets the shortest natural period: the solvers' step bounds and stability limits)
    stiffness_profile: Any = None

    def stiffness_at(self, t) -> np.ndarray:
        """k at the times t (N/m): the profile's, or the constant stiffness."""
        if self.stiffness_profile is None:
            return np.full(np.shape(t), self.stiffness)
        return self.stiffness_profile(t)[0]

    @property
    def seated_resistance(self) -> float:
        """W0 = preload + closing loads: what the linkage must exceed to lift the valve."""
        return self.preload + self.closing_load

    def natural_period(self) -> float:
        """Tn of the contact phase, 2 pi sqrt(M1 / (k + rate))."""
        return 2.0 * math.pi * math.sqrt(self.oscillating_mass / (self.stiffness + self.spring_rate))

    @staticmethod
    def from_scene(scene) -> "LinkageModel":
        v, s, loads, link = scene.valve, scene.spring, scene.loads, scene.linkage
        return LinkageModel(
            mass=v.mass,
            oscillating_mass=v.oscillating_mass if v.oscillating_mass is not None else v.mass,
            stiffness=link.stiffness,
            damping=link.damping,
            lash=v.lash,
            preload=s.preload,
            spring_rate=s.rate,
            friction=loads.friction,
            closing_load=loads.closing_total,
            restitution=scene.seat.restitution,
        )


@dataclass(frozen=True)
class Drive:
    """Linkage end motion referred to the valve: S(t) = ratio * L(omega t), analytic derivatives."""

    lift: LiftCurve
    ratio: float
    omega: float  # rad/s

    def __call__(self, t) -> np.ndarray:
        """(4, N) array: S, dS/dt, d2S/dt2, d3S/dt3 at times t (s)."""
        t = np.asarray(t, dtype=float)
        d = self.lift.derivatives(self.omega * t)
        w = self.omega
        return np.stack([self.ratio * d[0], self.ratio * w * d[1], self.ratio * w**2 * d[2], self.ratio * w**3 * d[3]])

    def breakpoints(self, t0: float, t1: float) -> np.ndarray:
        """Times in [t0, t1] where a derivative of S may jump (segment joints of the lift)."""
        period = 2.0 * math.pi / self.omega
        base = np.asarray(self.lift.breakpoints(), dtype=float) / self.omega
        k0, k1 = math.floor(t0 / period) - 1, math.ceil(t1 / period) + 1
        times = (base[None, :] + period * np.arange(k0, k1 + 1)[:, None]).ravel()
        return np.sort(times[(times >= t0) & (times <= t1)])


@dataclass(frozen=True)
class StiffnessProfile:
    """Valve-referred stiffness along the cycle: `function(theta) -> (k, dk/dtheta)` (N/m, N/m/rad,
    analytic), periodic in the cam angle theta = omega t; optionally in series with a constant
    stiffness of the rest of the chain (valve spindle, valve lever)."""

    function: Any
    omega: float  # rad/s
    series: float = math.inf  # N/m

    def __call__(self, t) -> np.ndarray:
        """(2, N): k and dk/dt at the times t."""
        t = np.asarray(t, dtype=float)
        k, dk = (np.asarray(x, dtype=float) for x in self.function(self.omega * t))
        dk = self.omega * dk
        if math.isfinite(self.series):
            total = 1.0 / (1.0 / k + 1.0 / self.series)
            dk = dk * (total / k) ** 2
            k = total
        return np.stack([k, dk])

    def bounds(self) -> tuple[float, float]:
        """Smallest and largest k over a revolution (sampled; for step bounds and reports)."""
        return self._bounds

    @cached_property
    def _bounds(self) -> tuple[float, float]:
        # a gear's k(t) costs milliseconds at 4097 angles; the model, the solver and the report ask
        t = np.linspace(0.0, 2.0 * math.pi / self.omega, 4097)
        k = self(t)[0]
        return float(k.min()), float(k.max())


@dataclass(frozen=True)
class DynamicsSolution:
    t: np.ndarray  # s, the requested output times
    s: np.ndarray  # m, valve lift
    v: np.ndarray  # m/s
    a: np.ndarray  # m/s^2
    linkage_force: np.ndarray  # N, compressive force in the linkage (>= 0)
    contact: np.ndarray  # bool, linkage loaded at t
    events: tuple = ()  # dicts: kind (EVENT_KINDS), time_s, plus optional velocity_m_s
    stats: dict = field(default_factory=dict)  # solver facts: steps, rhs evaluations, warnings, ...
    # optional (None when a solver does not provide them):
    jerk: np.ndarray | None = None  # m/s^3, derivative of a within the phase at t (exact solver: closed form)
    phase: np.ndarray | None = None  # int codes PHASE_CODES: what the valve is doing at t
