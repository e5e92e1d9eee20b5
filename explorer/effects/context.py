"""What an effect is handed (Context), the scene as the effects read it (SceneView), and what they
may ask of the scene's gear (GearHooks).

The effects sit below the gears and the scene (tests/test_layers.py): they never import a gear or
the scene loader; they read the scene through the Protocols here (explorer.scene.scene.Scene and
its sections implement them: tests/test_context_types.py holds the two together) and call the
hooks of the gear the scene names (Scene.gear_plugin, explorer/gears/base.py implements them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Mapping, Protocol

import numpy as np

from ..lift.curves import LiftCurve
from ..mechanics.contact import ContactGeometry, ContactSpec
from ..mechanics.springs import SpringDesign

if TYPE_CHECKING:  # imported when a scene has an [hla] section (the train's effect): not for every effect
    from ..dynamics.hla import HLA
from ..result import EffectOutput


# The scene's sections as the effects read them (read-only: the sections are frozen dataclasses of
# explorer.scene.scene). Only what the effects and the lower layers they hand a section to read.


class DriveView(Protocol):
    @property
    def rpm(self) -> float: ...  # rev/min

    @property
    def omega(self) -> float: ...  # rad/s


class FollowerView(Protocol):
    @property
    def type(self) -> str: ...  # the gear's name, for messages only (the effects ask gear_plugin)

    @property
    def base_radius(self) -> float: ...  # m

    @property
    def roller_radius(self) -> float: ...  # m

    @property
    def offset(self) -> float: ...  # m

    @property
    def ratio(self) -> float: ...  # valve travel per follower travel


class ValveView(Protocol):
    @property
    def mass(self) -> float: ...  # kg, referred to the valve

    @property
    def lash(self) -> float: ...  # m

    @property
    def oscillating_mass(self) -> float | None: ...  # kg


class SpringView(Protocol):
    @property
    def preload(self) -> float: ...  # N

    @property
    def rate(self) -> float: ...  # N/m

    @property
    def mass(self) -> float: ...  # kg, the active coils

    @property
    def elements(self) -> int: ...  # surge model's masses (0: massless)

    @property
    def damping_ratio(self) -> float: ...

    @property
    def solid_height(self) -> float | None: ...  # m


class LoadsView(Protocol):
    @property
    def friction(self) -> float: ...  # N, Coulomb

    @property
    def closing(self) -> Mapping[str, float]: ...  # N, + closes

    @property
    def closing_total(self) -> float: ...  # N


class LinkageView(Protocol):
    @property
    def stiffness(self) -> float: ...  # N/m, referred to the valve

    @property
    def damping(self) -> float: ...  # N*s/m

    @property
    def elements(self) -> tuple: ...  # the train's parts (explorer.scene.train_section.LinkageElement)

    @property
    def one_sided(self) -> bool: ...


class SeatView(Protocol):
    @property
    def restitution(self) -> float: ...

    @property
    def stiffness(self) -> float | None: ...  # N/m

    @property
    def damping(self) -> float: ...  # N*s/m


class SolverView(Protocol):
    @property
    def method(self) -> str: ...  # a name of explorer.dynamics.solvers.SOLVERS

    @property
    def steps_per_revolution(self) -> int: ...

    @property
    def options(self) -> Mapping[str, Any]: ...  # the method's own options, parsed


class HLAView(Protocol):
    @property
    def hla(self) -> HLA: ...

    @property
    def revolutions(self) -> int: ...


class SceneView(Protocol):
    """The scene as the effects read it (explorer.scene.scene.Scene implements it)."""

    @property
    def name(self) -> str: ...

    @property
    def source(self) -> str: ...  # the file, for messages

    @property
    def effects(self) -> tuple[str, ...]: ...

    @property
    def drive(self) -> DriveView: ...

    @property
    def follower(self) -> FollowerView: ...

    @property
    def valve(self) -> ValveView | None: ...

    @property
    def spring(self) -> SpringView | None: ...

    @property
    def loads(self) -> LoadsView: ...

    @property
    def linkage(self) -> LinkageView | None: ...

    @property
    def seat(self) -> SeatView: ...

    @property
    def solver(self) -> SolverView: ...

    @property
    def contact(self) -> ContactSpec | None: ...

    @property
    def spring_design(self) -> SpringDesign | None: ...

    @property
    def hla(self) -> HLAView | None: ...

    @property
    def gear_plugin(self) -> "GearHooks": ...

    @property
    def omega(self) -> float: ...  # rad/s


class GearHooks(Protocol):
    """The effects' view of a gear (explorer.gears.base.Gear, items 5 to 8 and 10)."""

    type: str
    batch_sweeps: bool
    columns: Mapping[str, tuple[str, ...]]

    def build_lift(self, scene: SceneView) -> LiftCurve: ...

    def effect(self, name: str) -> Callable[["Context"], EffectOutput] | None: ...

    def kinematics(self, ctx: "Context", d: np.ndarray) -> tuple[dict, dict]: ...

    def contact_geometry(self, ctx: "Context") -> ContactGeometry: ...

    def contact_figures(self, ctx: "Context", geometry: ContactGeometry, columns: Mapping) -> tuple[dict, dict]: ...

    def check_contact(self, follower, file: str) -> None: ...

    def report(self, ctx: "Context") -> EffectOutput: ...


@dataclass(frozen=True)
class Context:
    """Read-only inputs of an effect: the scene, the revolution's samples (cam angle, time), the
    lift curve, and the columns and summary of the effects run before it."""

    scene: SceneView  # explorer.scene.scene.Scene (the layer above: not imported here)
    theta: np.ndarray  # rad, 0 <= theta < 2 pi, one revolution
    time: np.ndarray  # s, theta / omega
    lift: LiftCurve
    columns: Mapping[str, np.ndarray]  # computed so far
    summary: Mapping[str, Any]  # computed so far
    done: tuple[str, ...] = ()  # the effects run before it, in order

    @property
    def omega(self) -> float:
        return self.scene.drive.omega

    @property
    def gear(self) -> GearHooks:
        """The scene's gear (its follower type's plug-in)."""
        return self.scene.gear_plugin


def sample_grid(scene: SceneView) -> tuple[np.ndarray, np.ndarray]:
    """(theta, time): the scene's samples of one revolution, steps_per_revolution equal steps from 0,
    the one grid every effect, run and sweep computes on."""
    n = scene.solver.steps_per_revolution
    theta = np.arange(n) * (2.0 * np.pi / n)
    return theta, theta / scene.drive.omega
