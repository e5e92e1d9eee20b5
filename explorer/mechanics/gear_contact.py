"""What the design rules need to know of a gear's cam contact (explorer.checks): the narrow
interface a gear supplies, one object per grid of cam angles.

A gear supplies a GearContact through its `cam_contact(scene, lift, theta)` hook
(explorer.gears.base.Gear, item 6; the default raises NotApplicable: no cam contact the rules
judge). It holds:

1. `geometry`: the contact statics' ContactGeometry (explorer.mechanics.contact: pressure angle
   against the driven point's travel, the valve/driven-point ratio, torque arms, the signed
   radii of both surfaces). Gears already build it for the `contact` effect.
2. `motion`: the SurfaceMotion (explorer.mechanics.tribology): each surface's velocity relative to
   the contact point, per unit camshaft speed; None when the gear cannot say (the tribology
   rules then report "not applicable" with `motion_note`).
3. `oscillating`: True when the driven point travels on an arc (a lever, a rocker, a finger
   follower: pressure-angle limit ~35 deg), False for a straight guide (~30 deg).
4. `pitch_radius`: a roller follower's roller-centre path radius in the cam's frame (signed, > 0
   convex; undercut where 0 < pitch_radius <= roller radius); None without a roller.
5. `face_offset`, `face_half_width`: a flat-faced follower's contact position along its face
   from the follower axis (m, per angle) and the half-width of face available; None otherwise.
   `face_reach`: how far from the axis the contact reaches on the face (m, per angle; None:
   |face_offset|, a point contact in the cam plane) -- a flat face touching a lobe of width b
   offset e along the camshaft reaches sqrt(offset^2 + (|e| + b/2)^2), the gear's own formula
   (the one its face check uses); `face_margin`: the allowance the gear adds to the face's
   diameter (m, 0: none). The face_width rule judges face_half_width - max reach - face_margin/2.

Everything per angle is an array of the grid's shape; SI.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .contact import ContactGeometry
from .tribology import SurfaceMotion


@dataclass(frozen=True)
class GearContact:
    geometry: ContactGeometry
    motion: SurfaceMotion | None
    oscillating: bool
    pitch_radius: np.ndarray | None = None
    face_offset: np.ndarray | None = None
    face_half_width: float | None = None
    face_reach: np.ndarray | None = None  # None: |face_offset| (item 5)
    face_margin: float = 0.0
    motion_note: str = ""  # why motion is None
    # the gear's own peak contact pressure (normal force per angle, any leading axes; E*) -> Pa,
    # where a line contact over [contact] width does not describe the contact: a crowned face on
    # the cam is a Hertz ellipse, about twice the line contact's pressure (the hertz_stress rule)
    stress: Callable[[np.ndarray, float], np.ndarray] | None = None

    def reach(self) -> np.ndarray | None:
        """The contact's reach on a flat face (item 5): face_reach, or |face_offset|; None
        without a face."""
        if self.face_reach is not None:
            return np.asarray(self.face_reach, dtype=float)
        return None if self.face_offset is None else np.abs(np.asarray(self.face_offset, dtype=float))

    @property
    def roller_radius(self) -> float | None:
        """The roller's radius when the follower has a roller (pitch_radius given)."""
        if self.pitch_radius is None:
            return None
        return float(np.asarray(self.geometry.counter_radius, dtype=float).reshape(-1)[0])


class NotApplicable(Exception):
    """A scene has nothing a rule judges (no cam contact, no spring geometry, ...): the reason."""
