"""What a gear's drawing is to the viewers: the base class every gear's view derives from (GearView,
with its numbered contract). The views are listed in explorer/view/gear_views.py.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Mapping


class GearView:
    """Base class of a gear's drawing (trimesh, z up, metres, real dimensions; the conventions of
    explorer.view.drawing: the gear in the x-z plane, shafts along y).

    To draw a gear you write one subclass and register it under the gear's follower type. It must:

    1. Lay the drawing out: `layout(scene, result, lift)` -> drawing.Layout, every dimension of the
       drawing, with the valve group (valve, spring, seat) where the gear's valve end is (the
       translating roller's layout, moved: explorer.view.gear_parts.gear_layout).
    2. Build its parts: `parts(scene, result, lay, lift, contour_samples, only)` -> {name: trimesh},
       each in its own frame (a rotating part: origin on its axis; fixed parts may be in the world
       frame), the valve group included (drawing.valve_group); `only` limits the names built.
    3. Pose them: `poses(scene, result, magnification, lay, lift)` -> {name: (positions (N, 3),
       wxyz (N, 4))}, one pose per step of result.columns for every part of `parts`. Linkage parts
       follow the rigid kinematics; the valve follows the displayed lift
       (drawing.displayed_valve_lift: magnified deviation). A roller's spin is looped
       (drawing.loop_spin) so that a replayed revolution does not jump at 360 -> 0.
    4. Colour them: `colors` maps each of its part names to (r, g, b), 0-255 (the viewers look a
       part's colour up by name; a name the translating roller's drawing has keeps that colour).
    5. Say whether parts other than the cam change with the cam's lift (`parts_follow_cam`: levers
       drawn from the gear's geometry): a viewer then rebuilds them when the lift changes.
    6. Import trimesh and the drawing kit only: the view layer is imported by the viewers alone.
    7. Say which of its parts the masses of an elastic train carry (`train_stations(scene)`: a
       tuple of stations from the cam to the valve, each a tuple of part names; () when the
       drawing shows no train's masses: its rigid poses stand). explorer.view.train_motion lays
       the train's elements on the stations.
    8. Pose those parts from the masses' motion (`train_poses(scene, result, motion, rigid, lay,
       lift)` -> {name: (positions, wxyz)}; `motion` a train_motion.TrainMotion with one
       displayed valve-referred travel per station, and the displayed plunger travel when there
       is an adjuster; `rigid` the poses of item 3): the parts of each station where its
       displayed travel puts them, the adjuster's plunger (a part of `parts` when the scene has
       [hla]) at its displayed travel. What it returns replaces those parts' poses of item 3.
    """

    colors: Mapping[str, tuple[int, int, int]] = MappingProxyType({})  # item 4
    parts_follow_cam: bool = False  # item 5

    def layout(self, scene, result=None, lift=None):
        raise NotImplementedError

    def parts(self, scene, result=None, lay=None, lift=None, contour_samples: int = 720, only=None) -> dict:
        raise NotImplementedError

    def poses(self, scene, result, magnification: float = 1.0, lay=None, lift=None) -> dict:
        raise NotImplementedError

    def train_stations(self, scene) -> tuple[tuple[str, ...], ...]:  # item 7
        return ()

    def train_poses(self, scene, result, motion, rigid, lay=None, lift=None) -> dict:  # item 8
        return {}
