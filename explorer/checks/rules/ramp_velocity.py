"""Opening velocity at the end of the lash ramp: the lift per cam angle at the lash take-up
(rigid kinematics; the same at every speed), of the follower the cam drives -- the lifter side.

The trade's figure (below about 0.002 in/deg for a solid tappet: camprofiledesigns.com, 'cam talk')
is a lobe's: a lobe is designed and ground to the tappet's lift ("to manufacture a lobe profile the
lift data must be presented at the tappet ... tappet lift, not valve lift", same page), the valve's
being the tappet's times the rocker ratio. So the figure and the limit are the lifter's: dL/dtheta
where the scene's lift is the follower's (follower.ratio makes the valve's); where [lift] is the
valve's (the lever gears), the valve's ds/dtheta over the gear's kinematic ratio at the take-up
(Gear.lifter_ratio: valve travel per travel of the lifter, the roller centre, the pad crown); a gear
with no follower between cam and valve is judged at the valve and says so."""

from __future__ import annotations

import numpy as np

from ..case import lash_crossing_angles
from ..rule import Measure


def measure(case, settings) -> Measure:
    if case.scene.valve is None:
        return Measure.not_applicable("needs [valve] (the lash)")
    theta = lash_crossing_angles(case, "up")
    if np.all(np.isnan(theta)):
        return Measure.not_applicable("the valve never opens (the lift never exceeds the lash)")
    at = np.where(np.isfinite(theta), theta, 0.0)
    d = case.lift.derivatives(at)
    side = case.scene.gear_plugin.lifter_ratio(case.scene, case.lift, at)
    if side is None:  # the lift is the follower's own
        name, rate = "lifter", d[1]
        note = "rigid: the follower's dL/dtheta at the take-up (the valve's is follower.ratio x it)"
    else:
        name, ratio = side
        rate = case.scene.follower.ratio * d[1] / ratio
        note = (f"rigid: the valve's ds/dtheta at the take-up over the gear's ratio there ({float(ratio[0]):.4g}, "
                f"valve travel per {name} travel)" if name != "valve" else
                "rigid: the valve's ds/dtheta at the take-up (the gear has no follower between cam and valve: "
                "the lobe figure is judged at the valve)")
    rate = np.where(np.isfinite(theta), rate, np.nan)
    return Measure.of(rate[:, None], np.degrees(theta)[:, None], None, settings, note=note, qualifier=f"{name} side")
