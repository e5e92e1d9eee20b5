"""The gear registry: one frozen entry per follower type that is a gear.

What the generic code asks of a gear is looked up here, never branched on by type:
  lift      "module:function", scene -> the valve-referred lift curve (lift.build_lift)
  effects   effect name -> "module:function", the gear's variant of that effect, which the
            pipeline (explorer.effects.pipeline) runs instead of the generic one (the trip gear's latch
            drives only from the pick-up to the trip, so forces, contact and elastic are its own)
  meshes    module with gear_layout, gear_parts and gear_poses (explorer.view.parts)
  rejected  [section] -> why the gear takes no such section (the scene loader's error)
  lift_reads "module:function", scene -> the sweep keys (explorer.studies.sweep_spec.SWEEP_KEYS)
            whose values the gear's lift reads, () when none (the gear's geometry alone makes it),
            None when it may read any (the speed, the train's loads): a sweep builds a lift that
            reads none once and shares it across its runs (explorer.studies.sweep_engine)

Adding a gear: its own modules and one line of GEARS. Import-light: names only, standard
library only (scene.py reads GEAR_TYPES while validating follower.type); the functions are
imported when used.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Callable, Mapping

_NONE: Mapping[str, str] = MappingProxyType({})


@dataclass(frozen=True)
class GearEntry:
    lift: str = "explorer.gears.build:build_gear_lift"
    effects: Mapping[str, str] = field(default_factory=lambda: _NONE)
    meshes: str = "explorer.view.gear_parts"
    rejected: Mapping[str, str] = field(default_factory=lambda: _NONE)
    lift_reads: str = "explorer.gears.build:gear_lift_reads"


_TRIP = "explorer.effects.trip"

GEARS: Mapping[str, GearEntry] = MappingProxyType({
    "pivoted-roller": GearEntry(),
    "rocking-cam": GearEntry(),
    "rolling-lever": GearEntry(),
    "trip": GearEntry(
        effects=MappingProxyType({
            "forces": f"{_TRIP}:trip_forces_effect",  # the latch drives only from the pick-up to the trip
            "contact": f"{_TRIP}:trip_contact_effect",  # a latch on the spindle, no cam surface
            "elastic": f"{_TRIP}:trip_elastic_effect",  # latch drives until the trip, then the valve closes freely
        }),
        rejected=MappingProxyType({
            "contact": "the trip gear has no cam and roller: its latch keys are latch_friction, "
                       "latch_width and latch_depth in [gear.trip]",
        }),
    ),
})


def resolve(target: str) -> Any:
    """The object a "module:name" string names (imported now)."""
    module, _, attr = target.partition(":")
    return getattr(importlib.import_module(module), attr)


def gear(follower_type: str) -> GearEntry | None:
    """The registry entry of a follower type; None when it is not a gear."""
    return GEARS.get(follower_type)


def effect_variant(follower_type: str, effect: str) -> str | None:
    """The "module:function" of the gear's own variant of an effect, or None (the generic one)."""
    entry = GEARS.get(follower_type)
    return None if entry is None else entry.effects.get(effect)


def lift_reads(scene) -> tuple[str, ...] | None:
    """The sweep keys whose values the scene's gear lift reads (the entry's lift_reads): () for a
    scene that is not a gear (its lift is the cam's alone), None when it may read any."""
    entry = GEARS.get(scene.follower.type)
    return () if entry is None else resolve(entry.lift_reads)(scene)


def lift_builder(follower_type: str) -> Callable | None:
    entry = GEARS.get(follower_type)
    return None if entry is None else resolve(entry.lift)


def meshes_module(follower_type: str):
    entry = GEARS.get(follower_type)
    return None if entry is None else importlib.import_module(entry.meshes)
