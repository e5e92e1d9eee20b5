"""The table of gear drawings: one view per follower type, the visual facts of a gear (its parts,
their poses per step and their colours), for the browser explorer and the rerun recordings alike
(explorer.view.parts is the entry they call). The gear layer names nothing of this: a gear's view
is registered here, beside it, keyed by the gear's follower type.

Adding a gear's drawing: one GearView subclass (explorer/view/base.py lists, numbered, what it must
provide) in its own module (explorer/view/<follower_type>.py) and one line of VIEWS (or
`register_view(type, view)`).
"""

from __future__ import annotations

from ..core.plugins import Registration, Registry
from .base import GearView


VIEWS: Registry[GearView] = Registry("gear view", {
    "translating-roller": "explorer.view.translating_roller:VIEW",
    "pivoted-roller": "explorer.view.pivoted_roller:VIEW",
    "rocking-cam": "explorer.view.rocking_cam:VIEW",
    "rolling-lever": "explorer.view.rolling_lever:VIEW",
    "trip": "explorer.view.trip_gear:VIEW",
    "bucket-tappet": "explorer.view.bucket_tappet:VIEW",
    "finger-follower": "explorer.view.finger_follower:VIEW",
    "rocker-arm": "explorer.view.rocker_arm:VIEW",
})


def register_view(follower_type: str, view: GearView, *, replace: bool = False) -> Registration:
    """Add the drawing of a gear (one call; `.undo()` removes it again)."""
    return VIEWS.register(follower_type, view, replace=replace)


def view_of(scene) -> GearView:
    """The drawing of the scene's gear."""
    return VIEWS[scene.follower.type]
