"""The direct-acting bucket tappet (follower.type = "bucket-tappet"): the cam works on the flat (or
slightly crowned) face of a tappet that slides in its bore on the valve's axis and sits on the
valve (ratio 1) -- most DOHC engines. The geometry is explorer.gears.flat_face (synthesis of the
cam as the face's envelope, analysis of a [cam] contour, the radius of curvature rho = Rb + s + s'',
the contact's offset on the face ds/dtheta, the crown's closed forms, Hertz); this module wires it
into the scene, the effects, the sweeps, the exports and the design rules.

[follower]    type = "bucket-tappet", base_radius (the cam's base circle; no roller, no offset in
              the cam plane: the tappet's axis passes through the camshaft's centre)
[gear.tappet] face_diameter, face_radius (absent: a flat face), offset (the lobe's centre from the
              tappet's axis along the camshaft: turns the tappet), cam_width, face_margin
              (explorer.gears.modern_spec; docs/theory/modern-gears.md lists units and ranges)
[lift]        the valve-referred lift (= the tappet's, lash included): a closed-form law (the cam
              is synthesised) or law = "contour" with a [cam] contour (analysis)
[contact]     sliding_friction: mu of the cam on the face (the face slides: every gear figure of
              the contact statics includes it); friction_angle keeps its meaning (the bore's)

Figures. Kinematics: pressure angle (0 for a flat face; atan(s'/y) for a crown), the contact's
offset on the face, the cam's radius of curvature. Contact: the generic statics on the geometry
below (normal force, camshaft torque with the face friction, Hertz of the generic line contact),
plus the face's own Hertz stress (the line contact over the lobe's width, or the crown's ellipse),
the sliding and entrainment velocities and the face friction. Gear report: the face diameter the
contact needs against the given one, the cam's smallest radius of curvature.

Contact statics (explorer.gears.train_statics.cam_forces: virtual work with Coulomb friction on
the face, the bore frictionless): the tappet moves along its axis u = +y, the cam pushes with
N (n + mu sigma t), sigma = sign of the cam's sliding past the face; so
    N = F / (n.u + mu sigma t.u),   T = N (X x n + mu sigma X x t).
For the generic statics (explorer.mechanics.contact.contact_loads: N = ratio F / cos(alpha) with
the guide friction of [contact] friction_angle on top, T = N torque_arm) the face friction enters
as ratio = cos(alpha) / (n.u + mu sigma t.u) (exactly 1 for a flat face, whose tangent is across
the axis) and torque_arm = X x n + mu sigma X x t (flat: ds/dtheta + mu (Rb + s)). The same numbers
the design rules' case computes (ratio_g / cos a).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..lift.contours.cam_profile import CamGeometry, CutFor
from ..lift.curves import law_lift
from ..lift.registry import law_spec
from ..mechanics.contact import ContactGeometry, ContactSpec, effective_modulus
from ..mechanics.gear_contact import GearContact
from ..mechanics.tribology import SurfaceMotion
from ..result import EffectOutput
from .base import Gear
from .common import section, spec_of
from .contour_follow import cam_contour
from .envelope import _rotate_to_cam
from .flat_face import AXIS, BucketTappetGear, Tappet, TappetKinematics, analyse_bucket, synthesise_bucket
from .modern_spec import _tappet as tappet_keys

TWO_PI = 2.0 * math.pi
CHECK_STEPS = 3600  # the load-time check's grid (cusp, face): explorer.gears.flat_face.BucketTappetGear.check


@dataclass(frozen=True)
class BucketLift:
    """The valve-referred lift of a bucket tappet (its law's, or the motion over a given contour),
    remembering its gear (`.gear`: the views, the contact and the exports read it)."""

    gear: BucketTappetGear

    def derivatives(self, theta) -> np.ndarray:
        return self.gear.lift.derivatives(theta)

    def breakpoints(self) -> np.ndarray:
        return np.asarray(self.gear.lift.breakpoints())


@dataclass(frozen=True)
class BucketCam:
    """The cam to make (explorer.lift.contours.cam_profile.CamProfile): the face's envelope, cut
    for this tappet's face (cut_for). A crown's centre path is the crown centre, contact + Rf n
    (a translating roller's pitch curve with roller radius Rf, curvature 1/(rho + Rf)); a flat face
    has no centre to trace: its centre path is the contour itself, which the exports leave out."""

    gear: BucketTappetGear
    name: str
    source: str

    @property
    def cut_for(self) -> CutFor:
        return CutFor("bucket-tappet", "face", self.gear.tappet.face_radius)

    def at(self, theta):
        theta = np.asarray(theta, dtype=float)
        k = self.gear.kinematics(theta)
        curvature = 1.0 / k.surface.radius
        normal = _rotate_to_cam(theta, k.surface.normal)
        rf = self.gear.tappet.face_radius
        if self.gear.tappet.crowned:
            pitch, pitch_curvature = k.surface.contour + rf * normal, 1.0 / (k.surface.radius + rf)
        else:
            pitch, pitch_curvature = k.surface.contour.copy(), curvature.copy()
        return CamGeometry(theta=theta, pitch=pitch, contour=k.surface.contour, normal=normal,
                           pitch_curvature=pitch_curvature, contour_curvature=curvature, pressure_angle=k.pressure_angle)

    def breakpoints(self) -> np.ndarray:
        return np.mod(np.asarray(self.gear.lift.breakpoints(), dtype=float), TWO_PI)


def face_geometry(k: TappetKinematics, base_radius: float, face_radius: float, mu: float) -> ContactGeometry:
    """The ContactGeometry of the face on the cam with the face friction mu folded in (module
    docstring): ratio = cos(alpha) / (n.u + mu sigma t.u), torque_arm = X x n + mu sigma X x t."""
    s = k.surface
    x, n, t = s.contact, s.normal, s.tangent
    sigma = np.sign(k.velocities.sliding)
    along_n = n @ AXIS
    along_t = t @ AXIS
    drive = along_n + mu * sigma * along_t
    with np.errstate(divide="ignore"):
        ratio = np.where(drive > 0.0, along_n / np.where(drive > 0.0, drive, 1.0), np.inf)
    arm = (x[:, 0] * n[:, 1] - x[:, 1] * n[:, 0]) + mu * sigma * (x[:, 0] * t[:, 1] - x[:, 1] * t[:, 0])
    return ContactGeometry(
        pressure_angle=k.pressure_angle, ratio=ratio, torque_arm=arm, body_arm=arm.copy(),
        body_radius=np.hypot(x[:, 0], x[:, 1]), contour_radius=s.radius, counter_radius=face_radius,
        roller_diameter=None,
    )


class BucketTappet(Gear):
    type = "bucket-tappet"
    description = "direct-acting bucket tappet: a flat or crowned face sliding on the cam, ratio 1 (DOHC)"
    parts = MappingProxyType({"tappet": tappet_keys})
    linkage_ratio = True  # the tappet sits on the valve: follower.ratio stays 1
    batch_sweeps = True  # one lift for every run, a constant ratio 1 to the valve
    columns = MappingProxyType({
        "kinematics": ("pressure_angle_deg", "contour_radius_m", "contact_offset_m"),
        "contact": ("face_hertz_stress_Pa", "face_friction_force_N", "sliding_velocity_m_s", "entrainment_velocity_m_s"),
    })

    # -- 3. checks at load -----------------------------------------------------------------------
    def takes_law(self, law) -> bool:
        return law.closed_form or law.from_contour

    def law_refusal(self, law) -> str:
        return (f"a bucket tappet's cam is synthesised from a closed-form lift law or analysed from a [cam] contour "
                f"(law = \"contour\"), not from law \"{law.name}\"")

    def check(self, spec, fields) -> None:
        super().check(spec, fields)
        file, follower = fields.get("source", "<memory>"), fields["follower"]
        if law_spec(fields["lift"].law).gear_made:
            raise InputError(file, "lift.law", f"the {self.type} gear needs a lift law (the valve-referred lift) or "
                             "law = \"contour\"")
        if follower.roller_radius != 0.0:
            raise InputError(file, "follower.roller_radius", "a bucket tappet has no roller (its face is [gear.tappet] "
                             "face_radius); leave roller_radius out")
        if follower.offset != 0.0:
            raise InputError(file, "follower.offset", "a bucket tappet's axis passes through the camshaft's centre; its "
                             "offset along the camshaft is gear.tappet.offset")
        if law_spec(fields["lift"].law).from_contour and fields.get("cam") is None:
            raise InputError(file, "cam", "missing section: lift.law = \"contour\" needs the [cam] contour")

    def tappet(self, spec, base_radius: float) -> Tappet:
        p = spec.part("tappet")
        return Tappet(base_radius=base_radius, face_radius=p["face_radius"] or math.inf,
                      face_diameter=p["face_diameter"], offset=p["offset"], cam_width=p["cam_width"],
                      face_margin=p["face_margin"], file=spec.file)

    def make(self, spec, source) -> BucketTappetGear:
        """The tappet and its cam, checked over a revolution: a cusp (rho <= 0) names
        follower.base_radius and the cam angle, a face too small gear.tappet.face_diameter."""
        follower, lift = section(source, "follower"), section(source, "lift")
        tappet = self.tappet(spec, follower.base_radius)
        if law_spec(lift.law).from_contour:
            return analyse_bucket(tappet, cam_contour(section(source, "cam")), CHECK_STEPS)
        return synthesise_bucket(tappet, law_lift(lift), CHECK_STEPS)

    # -- 5. the lift -----------------------------------------------------------------------------
    def build_lift(self, scene) -> BucketLift:
        return BucketLift(self.make(spec_of(self, scene), scene))

    def _gear(self, ctx) -> BucketTappetGear:
        lift = ctx.lift if hasattr(ctx.lift, "gear") else self.build_lift(ctx.scene)
        return lift.gear

    # -- 6. figures ------------------------------------------------------------------------------
    def kinematics(self, ctx, d) -> tuple[dict, dict]:
        """Pressure angle (0 for a flat face), the cam's radius of curvature at the contact and the
        contact's offset from the tappet's axis (ds/dtheta for a flat face)."""
        k = self._gear(ctx).kinematics(ctx.theta)
        columns = {
            "pressure_angle_deg": np.degrees(k.pressure_angle),
            "contour_radius_m": k.surface.radius,
            "contact_offset_m": k.contact_offset,
        }
        i = int(np.argmin(k.surface.radius))
        j = int(np.argmax(np.abs(k.contact_offset)))
        summary = {
            "min_contour_radius_m": float(k.surface.radius[i]),
            "min_contour_radius_cam_angle_deg": float(np.degrees(ctx.theta[i])),
            "max_contact_offset_m": float(np.abs(k.contact_offset[j])),
            "max_contact_offset_cam_angle_deg": float(np.degrees(ctx.theta[j])),
        }
        return columns, summary

    def contact_geometry(self, ctx) -> ContactGeometry:
        spec = ctx.scene.contact if ctx.scene.contact is not None else ContactSpec()
        gear = self._gear(ctx)
        geometry = face_geometry(gear.kinematics(ctx.theta), gear.tappet.base_radius, gear.tappet.face_radius,
                                 spec.sliding_friction)
        if "pressure_angle_deg" in ctx.columns and "contour_radius_m" in ctx.columns:
            geometry = replace(geometry, from_columns=True)  # the kinematics' columns are these
        return geometry

    def contact_figures(self, ctx, geometry, columns) -> tuple[dict, dict]:
        """The face's own Hertz stress (line contact over the lobe's width, or the crown's ellipse:
        BucketTappetGear.hertz_stress), the face friction, and the sliding and entrainment
        velocities at the face (m/s) for the tribology."""
        spec = ctx.scene.contact if ctx.scene.contact is not None else ContactSpec()
        gear = self._gear(ctx)
        k = gear.kinematics(ctx.theta)
        normal = np.asarray(columns["cam_normal_force_N"], dtype=float)
        w = ctx.omega
        sliding, entrainment = w * k.velocities.sliding, w * k.velocities.entrainment
        loaded = np.where(np.isfinite(normal), np.maximum(normal, 0.0), 0.0)
        friction = spec.sliding_friction * loaded
        out = {
            "face_friction_force_N": friction,
            "sliding_velocity_m_s": sliding,
            "entrainment_velocity_m_s": entrainment,
        }
        theta_deg = np.degrees(ctx.theta)
        summary: dict[str, Any] = {
            "face_sliding_friction": spec.sliding_friction,
            "max_abs_sliding_velocity_m_s": float(np.max(np.abs(sliding))),
            "min_entrainment_velocity_m_s": float(np.min(entrainment)),
            "max_entrainment_velocity_m_s": float(np.max(entrainment)),
            "max_face_friction_power_W": float(np.max(friction * np.abs(sliding))),
        }
        t = gear.tappet
        if t.crowned or t.cam_width is not None:
            e_star = effective_modulus(spec.youngs_modulus, spec.poisson_ratio, spec.roller_youngs_modulus,
                                       spec.roller_poisson_ratio)
            sigma = gear.hertz_stress(k, loaded, e_star)
            out["face_hertz_stress_Pa"] = sigma
            i = int(np.argmax(sigma))
            summary.update(max_face_hertz_stress_Pa=float(sigma[i]), max_face_hertz_stress_cam_angle_deg=float(theta_deg[i]),
                           face_hertz_utilisation=float(sigma[i] / spec.allowable_stress))
            if t.crowned and t.cam_width is not None:
                summary["crown_edge_loaded"] = bool(np.any(gear.edge_loaded(k, np.maximum(loaded, 1e-300), e_star) & (loaded > 0.0)))
        return out, summary

    def cam_contact(self, scene, lift, theta) -> GearContact:
        """The face slides on the cam (SurfaceMotion of both surfaces past the contact); the
        tappet translates (not oscillating); for the face-width rule the contact's offset on the
        face, its reach (BucketTappetGear.face_reach: the lobe's width and offset included), the
        face's half-width and its margin."""
        gear = lift.gear if hasattr(lift, "gear") else self.build_lift(scene).gear
        spec = scene.contact if scene.contact is not None else ContactSpec()
        k = gear.kinematics(np.asarray(theta, dtype=float))
        geometry = face_geometry(k, gear.tappet.base_radius, gear.tappet.face_radius, spec.sliding_friction)
        motion = SurfaceMotion(k.velocities.first, k.velocities.second)
        d = gear.tappet.face_diameter
        # a crown touches the cam in an ellipse, not the line the generic rule assumes
        stress = (lambda normal, e_star: gear.hertz_stress(k, normal, e_star)) if gear.tappet.crowned else None
        return GearContact(geometry, motion, oscillating=False, pitch_radius=None, face_offset=k.contact_offset,
                           face_half_width=None if d is None else 0.5 * d, face_reach=gear.face_reach(k),
                           face_margin=gear.tappet.face_margin, stress=stress)

    # -- 8. the 'gear' effect --------------------------------------------------------------------
    def report(self, ctx) -> EffectOutput:
        """The face the contact needs against the given one, the cam's size and curvature."""
        gear = self._gear(ctx)
        t = gear.tappet
        k = gear.kinematics(ctx.theta)
        need, at = gear.face_diameter_needed(k)
        i = int(np.argmin(k.surface.radius))
        summary = {
            "face": "crowned" if t.crowned else "flat",
            "face_radius_m": t.face_radius if t.crowned else None,
            "face_diameter_m": t.face_diameter,
            "face_diameter_needed_m": need,
            "face_diameter_needed_cam_angle_deg": math.degrees(at) % 360.0,
            "face_margin_m": t.face_margin,
            "lobe_offset_m": t.offset,
            "cam_width_m": t.cam_width,
            "cam_max_radius_m": float(np.max(np.hypot(k.surface.contour[:, 0], k.surface.contour[:, 1]))),
            "min_cam_radius_of_curvature_m": float(k.surface.radius[i]),
            "min_cam_radius_of_curvature_cam_angle_deg": float(np.degrees(ctx.theta[i])),
            "max_pressure_angle_deg": float(np.degrees(np.max(np.abs(k.pressure_angle)))),
        }
        return EffectOutput(summary=summary)

    # -- 9. the cam to make ----------------------------------------------------------------------
    def cam_profile(self, scene, lift=None) -> BucketCam:
        gear = lift.gear if lift is not None and hasattr(lift, "gear") else self.build_lift(scene).gear
        return BucketCam(gear, scene.name, scene.source)


GEAR = BucketTappet()
