"""The translating roller follower: a roller (or knife edge, roller_radius = 0) on a follower that
slides along a straight axis at `offset` from the cam centre, driving the valve through a lever
of constant ratio (follower.ratio). The most common follower, and the gear of every scene that
names no other.

Its keys are the [follower] section's own (base_radius, roller_radius, offset, ratio); it takes
every lift law with a builder or a closed form, and the analysis of a [cam] contour. Its figures:
pressure angle and radii of curvature in the kinematics (closed forms of
explorer.lift.contours.translating, with the validity checks of explorer.lift.validity), the contact statics of the roller on
the cam, and the cam to make (exports).
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np

from ..core.plugins import resolve
from ..lift.registry import law_spec, scene_lift
from ..mechanics.contact import ContactGeometry, camshaft_torque, contact_point_radius
from ..mechanics.gear_contact import GearContact, NotApplicable
from ..mechanics.tribology import rolling_roller_motion
from .base import Gear

# The cam's geometry, imported when first used (core.plugins.resolve): a scene loads without the
# contour analysis, the curvature columns and the exports' cam, which a run or an export needs
# (arcs, parametric and the closed forms are the better part of a scene load's imports).
_CONTOUR_LIFT = "explorer.lift.contours.lift_from_contour:contour_lift"
_GEOMETRY_COLUMNS = "explorer.effects.contour:geometry_columns"
_TRANSLATING = "explorer.lift.contours.translating:"
_CAM_PROFILE = "explorer.lift.contours.cam_profile:"


class TranslatingRoller(Gear):
    type = "translating-roller"
    description = "roller (or knife edge) on a follower sliding along a straight axis, constant lever ratio"
    contact_roller = True
    roller_envelope = True
    analyses_contours = True
    columns = MappingProxyType({"kinematics": ("pressure_angle_deg", "pitch_radius_m", "contour_radius_m")})
    batch_sweeps = True

    def check(self, spec, fields) -> None:
        super().check(spec, fields)
        lift = fields["lift"]
        if law_spec(lift.law).from_contour and fields.get("cam") is not None:
            # every follower-dependent check of the contour, at load time
            self.contour_lift(fields["cam"], fields["follower"], fields.get("source", "<memory>"))

    def takes_law(self, law) -> bool:
        return law.closed_form or law.builder is not None or (law.from_contour and self.analyses_contours)

    def contour_lift(self, cam, follower, file: str):
        return resolve(_CONTOUR_LIFT)(cam, follower, file)

    def build_lift(self, scene):
        if law_spec(scene.lift.law).from_contour:
            return self.contour_lift(scene.cam, scene.follower, scene.source)
        return scene_lift(scene)

    def kinematics(self, ctx, d) -> tuple[dict, dict]:
        """Pressure angle and radii of curvature (closed forms); InputError when the cam fails the
        validity checks of every cam (explorer.lift.validity: finite, lift range, pressure angle,
        undercut; a measured table's lift may dip below the base circle by its `dip_allowance`)."""
        return resolve(_GEOMETRY_COLUMNS)(ctx.scene, ctx.theta, d, getattr(ctx.lift, "dip_allowance", 0.0), ctx.lift)

    def contact_geometry(self, ctx) -> ContactGeometry:
        """The kinematics' geometry columns when the cam provides them, otherwise the exact closed
        forms of explorer.lift.contours.translating. The roller centre q = (e, y0 + L)."""
        c, f = ctx.columns, ctx.scene.follower
        if "pressure_angle_deg" in c and "contour_radius_m" in c:
            alpha, contour_radius, reused = np.radians(c["pressure_angle_deg"]), np.asarray(c["contour_radius_m"]), True
        else:
            profile = resolve(_TRANSLATING).profile_from_derivatives(ctx.theta, ctx.lift.derivatives(ctx.theta),
                                                                     f.base_radius, f.roller_radius, f.offset)
            alpha, contour_radius, reused = profile.pressure_angle, profile.contour_radius, False
        lift = np.asarray(c["follower_lift_m"])
        arm = camshaft_torque(1.0, alpha, lift, f.base_radius, f.roller_radius, f.offset)
        return ContactGeometry(
            pressure_angle=alpha, ratio=np.full(alpha.shape, f.ratio), torque_arm=arm, body_arm=arm,
            body_radius=contact_point_radius(alpha, lift, f.base_radius, f.roller_radius, f.offset),
            contour_radius=contour_radius, counter_radius=f.roller_radius, roller_diameter=2.0 * f.roller_radius,
            from_columns=reused,
        )

    def cam_contact(self, scene, lift, theta) -> GearContact:
        """The roller rolls without slipping: both surfaces pass the contact at the contour's
        arc-length rate, the pitch curve's times (rho_p - r)/rho_p
        (explorer.mechanics.tribology.rolling_roller_motion)."""
        f = scene.follower
        if not f.roller_radius > 0.0:
            raise NotApplicable("a knife-edge follower (roller_radius 0): no contact radius to judge")
        d = lift.derivatives(theta)
        profile = resolve(_TRANSLATING).profile_from_derivatives(theta, d, f.base_radius, f.roller_radius, f.offset)
        alpha = profile.pressure_angle
        arm = camshaft_torque(1.0, alpha, d[0], f.base_radius, f.roller_radius, f.offset)
        geometry = ContactGeometry(
            pressure_angle=alpha, ratio=np.full(alpha.shape, f.ratio), torque_arm=arm, body_arm=arm,
            body_radius=contact_point_radius(alpha, d[0], f.base_radius, f.roller_radius, f.offset),
            contour_radius=profile.contour_radius, counter_radius=f.roller_radius, roller_diameter=2.0 * f.roller_radius,
        )
        rp = f.base_radius + f.roller_radius
        speed = np.hypot(math.sqrt(rp * rp - f.offset**2) + d[0], d[1] - f.offset)  # |dP/dtheta|, P the pitch point
        motion = rolling_roller_motion(speed, profile.pitch_radius, f.roller_radius)
        return GearContact(geometry, motion, oscillating=False, pitch_radius=profile.pitch_radius)

    def cam_profile(self, scene, lift=None):
        """The cam to make (a TranslatingCam); InputError for an undercut cam (its contour folds:
        nothing to make)."""
        f = scene.follower
        cam, translating = resolve(_CAM_PROFILE), resolve(_TRANSLATING)
        src = cam.TranslatingCam(lift if lift is not None else self.build_lift(scene), f.base_radius, f.roller_radius,
                                 f.offset, scene.name, scene.source, f.type)
        theta = cam.angles_with(7200, src.breakpoints())
        g = src.at(theta)
        with np.errstate(divide="ignore"):
            rho = 1.0 / g.pitch_curvature
        i = translating.find_undercut(rho, f.roller_radius)
        if i is not None:
            raise translating.undercut_error(float(theta[i]), float(rho[i]), f.roller_radius, scene.source)
        return src


GEAR = TranslatingRoller()
