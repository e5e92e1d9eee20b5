"""The table of gears: one line per follower type (explorer.gears.base.Gear lists, numbered, what a
gear must provide). The scene loader reads it for follower.type and the [gear] section; everyone
else asks the scene's gear (Scene.gear_plugin). Adding a gear: its module and one line of GEARS
(or `register_gear(gear)`); its drawing is a line of explorer/view/gear_views.py.

The gears are written as references ("module:GEAR"), imported when a scene first uses one: loading
a translating-roller scene imports no lever, eccentric or dashpot.
"""

from __future__ import annotations

from ..core.plugins import Registration, Registry
from .base import Gear

GEARS: Registry[Gear] = Registry("gear", {
    "translating-roller": "explorer.gears.translating_roller:GEAR",
    "pivoted-roller": "explorer.gears.pivoted_roller:GEAR",
    "rocking-cam": "explorer.gears.rocking_cam:GEAR",
    "rolling-lever": "explorer.gears.rolling_lever:GEAR",
    "trip": "explorer.gears.trip_gear:GEAR",
    "bucket-tappet": "explorer.gears.bucket_tappet:GEAR",
    "finger-follower": "explorer.gears.finger_follower:GEAR",
    "rocker-arm": "explorer.gears.rocker_arm:GEAR",
})

DEFAULT = "translating-roller"  # the follower.type of a scene that names none


def register_gear(gear: Gear, *, replace: bool = False) -> Registration:
    """Add a gear to the table (one call; `.undo()` removes it again)."""
    return GEARS.register(gear.type, gear, replace=replace)


def gear(follower_type: str) -> Gear:
    """The gear of a follower type (KeyError naming the known ones)."""
    return GEARS[follower_type]


def gear_types() -> tuple[str, ...]:
    return GEARS.names()
