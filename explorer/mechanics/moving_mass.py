"""The rigid train's one mass referred to the valve: what the rigid forces multiply the valve's
acceleration by (the forces effect, the sweep engine's rigid figures, the design rules).

In a rigid train every part moves with the valve at a fixed ratio, so the train is one degree of
freedom and its kinetic energy is that of one mass M at the valve (Thomson, Theory of Vibration
with Applications, 5th ed., sect. 2.4 "Rayleigh method: effective mass", p. 24):

    T = 1/2 m_v v^2 + sum 1/2 m_i (v / r_i)^2 + sum 1/2 J_j (v / a_j)^2 = 1/2 M v^2,
    M = m_v + sum m_i / r_i^2 + sum J_j / a_j^2 (+ the spring's share)

with r_i the valve's travel per travel of part i and a_j the arm from a rocker's pivot to the
valve (LinkageElement.referred_mass: the same reduction the train model of the elastic effect
makes, explorer/dynamics/train.py). The force at the cam, referred to the valve, is then
M p + the loads: the cam's joint carries the inertia of every part, the joints nearer the valve
less, so the cam's contact is the one a rigid train loses first.

The spring: its coils move from rest at the seat to the retainer's velocity, in proportion along
the spring while it deforms quasi-statically, so its kinetic energy is 1/2 (m_s / 3) v^2: one
third of its mass (Rayleigh's value; Thomson, ibid., Example 2.4-1). A scene gives valve.mass
with that share in it, except where it models the spring as masses (spring.elements > 0: the
chain carries the coils itself, and valve.mass is the valve and retainer alone: the scene loader
says so); there the rigid train adds m_s / 3. (The chain's own quasi-static shape, masses
m_s / (N + 1) with half of one at the retainer, gives m_s (1/3 + 1/(6 (N+1)^2)): tests.) The
rigid figures take the continuous spring's third, which does not depend on how finely the
elastic model cuts the spring.

A hydraulic lash adjuster's plunger holds the lever's pivot still in a rigid train (the plunger
moves only with the oil's compression and leak, the elastic effect's): it adds nothing.

Which parts there are is the gear's (explorer.gears.base.Gear.moving_parts: by default the scene's
[[linkage.elements]] and the spring's share, train_parts below); this module sums them
(rigid_mass), in one order, so every consumer gets the same float.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class ReferredMass:
    """A moving part of the rigid train, referred to the valve."""

    name: str
    mass: float  # kg at the valve (m / r^2, J / a^2, m_s / 3)


@dataclass(frozen=True)
class RigidMass:
    """The rigid train's mass at the valve: valve.mass plus the other parts, each referred to it."""

    valve: float  # kg, the scene's valve.mass
    parts: tuple[ReferredMass, ...] = ()

    @property
    def others(self) -> float:
        """kg, the parts' sum (0.0 without parts: then total is valve.mass's float itself)."""
        return math.fsum(p.mass for p in self.parts)

    @property
    def total(self) -> float:
        return self.of_valve(self.valve)

    def of_valve(self, valve_mass):
        """The total for another valve.mass (a float or a sweep's array of draws): valve_mass + the
        parts, the one sum every consumer makes (a float equal to `total` at the scene's value)."""
        return valve_mass + self.others if self.parts else valve_mass

    def shares(self) -> dict[str, float]:
        """name -> kg at the valve, the valve first (what the summary shows)."""
        return {"valve": self.valve, **{p.name: p.mass for p in self.parts}}


def train_parts(scene) -> tuple[ReferredMass, ...]:
    """The scene's parts beyond valve.mass: each [[linkage.elements]] part (mass / ratio^2 or
    inertia / arm^2), and a third of the spring's mass when the spring is modelled as masses
    (spring.elements > 0, valve.mass then leaves it out)."""
    linkage, spring = scene.linkage, scene.spring
    parts = [ReferredMass(e.name, e.referred_mass) for e in (linkage.elements if linkage is not None else ())]
    if spring is not None and spring.elements > 0 and spring.mass > 0.0:
        parts.append(ReferredMass("spring", spring.mass / 3.0))  # Rayleigh's third (module docstring)
    return tuple(parts)


def rigid_mass(scene) -> RigidMass:
    """The scene's rigid-train mass: valve.mass and the gear's moving parts (Gear.moving_parts)."""
    return RigidMass(scene.valve.mass, tuple(scene.gear_plugin.moving_parts(scene)))
