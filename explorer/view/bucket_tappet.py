"""The drawing of the bucket tappet (explorer.gears.bucket_tappet), as in a DOHC head: the cam on
top turning about the camshaft, the bucket below it sliding on the valve's axis, the contact point
on the face as a small sphere (it runs across the face by ds/dtheta), and the valve group under
the bucket (valve, spring, seat: explorer.view.drawing.valve_group), the valve opening downwards.

The cam, the bucket and the contact are explorer.view.modern_parts' (bucket_drawing,
bucket_poses: the gear's plane turned by BUCKET_FRAME = 180 deg, so the tappet's +y is the world's
-z); the valve group is the translating roller's layout (proportioned from the cam and the lift)
moved under the bucket: its stem top sits the lash below the face's underside, so the tappet
meets the valve where the lash is taken up.
"""

from __future__ import annotations

import math
from dataclasses import replace
from types import MappingProxyType

from ..effects.lift import build_lift
from . import translating_roller as stock
from .base import GearView
from .drawing import valve_group
from .gear_parts import valve_poses
from .modern_parts import BUCKET_FRAME, MODERN_PART_COLORS, bucket_drawing, bucket_poses

COLORS = MappingProxyType({name: MODERN_PART_COLORS[name] for name in ("cam", "camshaft", "tappet", "cam_contact")})
FACE_WALL = 0.06  # the face's thickness per face diameter (modern_parts.bucket_drawing's)
GEAR_PARTS = ("cam", "camshaft", "tappet", "cam_contact")


def _gear(scene, lift):
    lift = lift if lift is not None and hasattr(lift, "gear") else build_lift(scene)
    return lift, lift.gear


def layout(scene, result=None, lift=None):
    """The stock layout with the valve group moved under the bucket (x = 0, stem top the face's
    thickness and the lash below the face at zero lift)."""
    lift, gear = _gear(scene, lift)
    lay = stock.layout(scene, result)
    t = gear.tappet
    diameter = t.face_diameter or 1.6 * t.base_radius
    lash = scene.valve.lash if scene.valve is not None else 0.0
    top = -(t.base_radius + FACE_WALL * diameter + lash)
    dz = top - lay.stem_top_rest
    return replace(lay, valve_x=0.0, stem_top_rest=top, seat_z=lay.seat_z + dz, spring_seat_z=lay.spring_seat_z + dz,
                   pivot=(0.0, lay.pivot[1], lay.pivot[2] + dz))


class BucketTappetView(GearView):
    colors = COLORS

    def layout(self, scene, result=None, lift=None):
        return layout(scene, result, lift)

    def parts(self, scene, result=None, lay=None, lift=None, contour_samples: int = 720, only=None) -> dict:
        lift, gear = _gear(scene, lift)
        lay = lay or self.layout(scene, result, lift)
        parts = {}
        if only is None or any(name in only for name in GEAR_PARTS):
            drawing = bucket_drawing(gear, n=contour_samples, frame=BUCKET_FRAME)
            parts.update({name: drawing.parts[name] for name in GEAR_PARTS})
        parts.update(valve_group(lay))
        return {k: v for k, v in parts.items() if only is None or k in only}

    def poses(self, scene, result, magnification: float = 1.0, lay=None, lift=None) -> dict:
        import numpy as np

        lift, gear = _gear(scene, lift)
        lay = lay or self.layout(scene, result, lift)
        theta = np.radians(np.asarray(result.columns["cam_angle_deg"], dtype=float))
        poses = bucket_poses(gear, theta, frame=BUCKET_FRAME)
        poses.pop("valve")  # the valve group's own (displayed, possibly elastic and magnified)
        poses.update(valve_poses(scene, result, lay, magnification, -0.5 * math.pi))
        return poses


VIEW = BucketTappetView()
