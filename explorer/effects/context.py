"""What an effect is handed (Context) and what it may ask of the scene's gear (GearHooks).

The effects sit below the gears (tests/test_layers.py): they never import a gear, they call the
hooks of the gear the scene names (Scene.gear_plugin, explorer/gears/base.py implements them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping, Protocol

import numpy as np

from ..lift.curves import LiftCurve
from ..mechanics.contact import ContactGeometry
from ..result import EffectOutput


class GearHooks(Protocol):
    """The effects' view of a gear (explorer.gears.base.Gear, items 5 to 8 and 10)."""

    type: str
    batch_sweeps: bool
    columns: Mapping[str, tuple[str, ...]]

    def build_lift(self, scene) -> LiftCurve: ...

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

    scene: Any  # explorer.scene.scene.Scene (the layer above: not imported here)
    theta: np.ndarray  # rad, 0 <= theta < 2 pi, one revolution
    time: np.ndarray  # s, theta / omega
    lift: LiftCurve
    columns: Mapping[str, np.ndarray]  # computed so far
    summary: Mapping[str, Any]  # computed so far

    @property
    def omega(self) -> float:
        return self.scene.drive.omega

    @property
    def gear(self) -> GearHooks:
        """The scene's gear (its follower type's plug-in)."""
        return self.scene.gear_plugin


def sample_grid(scene) -> tuple[np.ndarray, np.ndarray]:
    """(theta, time): the scene's samples of one revolution, steps_per_revolution equal steps from 0,
    the one grid every effect, run and sweep computes on."""
    n = scene.solver.steps_per_revolution
    theta = np.arange(n) * (2.0 * np.pi / n)
    return theta, theta / scene.drive.omega
