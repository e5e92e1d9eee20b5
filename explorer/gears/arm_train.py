"""What the end-pivot finger follower and the centre-pivot rocker (with or without the OHV lifter and
pushrod) share as gears: the valve-referred lift that carries its geometry, the kinematics' ratio
and its derivatives, the contact statics with friction at the cam and at the valve tip, the
sliding and entrainment velocities of both contacts, the Hertz stresses, the design rules' contact
and the cam to make. The geometry is explorer.gears.arm (ArmGear) and explorer.gears.pushrod
(PushrodTrain), built by explorer.gears.modern_spec from the [gear.*] keys; each gear module
(finger_follower, rocker_arm) is a subclass naming its parts.

The lift: [lift] is the wanted valve lift (valve-referred, lash included); the cam is synthesised
from it (Schenker's backwards construction), so the valve's lift, velocity, acceleration and jerk
are the law's, exactly, and the geometry gives the ratio (valve travel per travel of the cam-side
point: the roller's centre, a pad's crown, or the lifter) with its derivatives in the cam angle as
jets, the pressure angle and the cam's radius of curvature. With law = "contour" the cam is the
[cam] contour (arcs or points) and the geometry is analysed over it (explorer.gears.arm: the
roller's or curved pad's centre on the contour's offset, a flat pad's support function;
explorer.gears.pushrod: the lifter's lift): the valve's motion is then the geometry's
(ContourValveLift), with the same figures.

Contact statics (explorer.gears.train_statics, virtual work on the one-degree-of-freedom train):
the cam's normal force N per newton of valve force F and the camshaft torque per newton of N, with
the [contact] friction coefficients `sliding_friction` (a pad or a flat lifter on the cam; a roller
rolls) and `tip_friction` (the valve pad on the valve tip). The generic contact effect computes
N = ratio F / cos(alpha) and T = N arm from a ContactGeometry; this gear hands it
    ratio = (N/F) cos(alpha),   torque_arm = T/N
from the exact statics, so its columns are the exact ones wherever the valve pushes (F > 0; where
F < 0 the rigid train would need tension and the generic frictionless pull is kept). Without
friction ratio = the kinematic ratio exactly (the tests check both against T omega = F v).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from ..core.errors import InputError
from ..dynamics.solvers import varying_stiffness
from ..lift.contours.cam_profile import CamGeometry, CutFor
from ..lift.curves import law_lift
from ..lift.registry import closed_form_names, law_spec
from ..mechanics.contact import ContactGeometry, ContactSpec, effective_modulus, hertz_line_stress
from ..mechanics.gear_contact import GearContact
from ..mechanics.tribology import SurfaceMotion
from ..result import EffectOutput
from .arm import tip_stress
from .base import Gear, GearSpec
from .common import section, spec_of
from .contour_follow import cam_contour, dwell_floors, exact_dwell
from .modern_spec import build_modern_gear, parse_parts

TWO_PI = 2.0 * math.pi
MEMO_GRIDS = 4
# the kinematics' columns of every arm train; the pushrod train adds its own
KINEMATICS_COLUMNS = ("pressure_angle_deg", "contour_radius_m", "valve_ratio", "valve_ratio_d1", "valve_ratio_d2",
                      "arm_angle_deg")
CONTACT_COLUMNS = ("cam_contact_x_m", "cam_contact_y_m", "cam_friction_force_N", "cam_sliding_velocity_m_s",
                   "cam_entrainment_velocity_m_s", "tip_contact_x_m", "tip_contact_y_m", "tip_scrub_m",
                   "tip_scrub_velocity_m_s", "tip_normal_force_N", "tip_friction_force_N", "tip_sliding_velocity_m_s",
                   "tip_entrainment_velocity_m_s", "tip_hertz_stress_Pa")


@dataclass(frozen=True)
class TrainLift:
    """The valve-referred lift (the [lift] law) of an arm train, remembering its geometry (`gear`:
    an ArmGear or a PushrodTrain)."""

    gear: Any
    law: Any
    memo: dict = field(default_factory=dict, compare=False, repr=False)  # kinematics per grid (bounded)
    side_stiffness: float | None = None  # N/m, the arm's (lifter's and pushrod's) at its cam-side point

    @property
    def linkage_stiffness(self):
        """theta -> (k, dk/dtheta): the cam-side stiffness referred to the valve through the
        ratio i(theta) (valve travel per travel of the roller centre, pad crown or lifter; energy
        k_side dx^2 / 2 with dx = ds / i): k = k_side / i^2, dk/dtheta = -2 k_side i' / i^3 (i' of
        the exact jets); None without [gear.*] stiffness. The elastic effect puts it in series with
        [linkage] stiffness (the rest of the chain, at the valve)."""
        if self.side_stiffness is None:
            return None
        k_side = self.side_stiffness

        def of(theta):
            jet = self.gear.kinematics(np.asarray(theta, dtype=float)).ratio_jet
            i, di = np.abs(jet[0]), np.sign(jet[0]) * jet[1]
            return k_side / i**2, -2.0 * k_side * di / i**3

        return of

    def derivatives(self, theta) -> np.ndarray:
        return self.law.derivatives(theta)

    def kinematics(self, theta):
        """The geometry's kinematics over a grid of cam angles, kept for the last few grids (the
        kinematics, contact and gear effects of a run, and a sweep's runs, read the same grid)."""
        theta = np.asarray(theta, dtype=float)
        key = (theta.size, hash(theta.tobytes()))
        if key not in self.memo:
            if len(self.memo) >= MEMO_GRIDS:
                self.memo.pop(next(iter(self.memo)))
            self.memo[key] = self.gear.kinematics(theta)
        return self.memo[key]

    def breakpoints(self) -> np.ndarray:
        return np.asarray(self.law.breakpoints())


@dataclass(frozen=True)
class ContourValveLift:
    """The valve-referred lift of a train analysed over a given contour (a LiftCurve in place of
    the law): the geometry's valve travel with its exact derivatives (ArmGear / PushrodTrain
    .valve_lift), the breakpoints where the contour's curvature jumps (arc junctions, a cubic
    spline's knots) as the follower's motion over it found them."""

    gear: Any
    floors: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "floors", dwell_floors(self.gear.valve_lift))

    def derivatives(self, theta) -> np.ndarray:
        # the base circle's dwell exactly 0, as a law's (contour_follow.exact_dwell)
        return exact_dwell(self.gear.valve_lift(np.asarray(theta, dtype=float)), self.floors)

    def breakpoints(self) -> np.ndarray:
        return np.asarray(self.gear.motion.breakpoints(), dtype=float)


@dataclass(frozen=True)
class TrainCam:
    """The synthesised cam as the exports see it (explorer.lift.contours.cam_profile.CamProfile):
    the contact point turned into the cam's frame; the centre path is the roller's centre, a
    curved pad's or crowned lifter's centre of curvature (cut_for.radius), a flat one's the contour
    itself (which the exports leave out)."""

    gear: Any
    roller_radius: float  # 0: no roller
    name: str
    source: str
    law: Any
    cut_for: CutFor = CutFor("", "face", math.inf)

    def at(self, theta):
        theta = np.asarray(theta, dtype=float)
        k = self.gear.kinematics(theta)
        s = k.surface
        c, si = np.cos(theta), np.sin(theta)

        def to_cam(xy):
            return np.column_stack([c * xy[:, 0] + si * xy[:, 1], -si * xy[:, 0] + c * xy[:, 1]])

        normal = to_cam(s.normal)
        with np.errstate(divide="ignore"):
            curvature = 1.0 / s.radius
            centre = self.cut_for.radius if math.isfinite(self.cut_for.radius) else 0.0
            pitch_curvature = 1.0 / (s.radius + centre)
        return CamGeometry(theta=theta, pitch=s.contour + centre * normal, contour=s.contour, normal=normal,
                           pitch_curvature=pitch_curvature, contour_curvature=curvature,
                           pressure_angle=pressure_angle(k))

    def breakpoints(self) -> np.ndarray:
        return np.mod(np.asarray(self.law.breakpoints(), dtype=float), TWO_PI)


def pressure_angle(k) -> np.ndarray:
    """The pressure angle against the driven point's travel: the arm's (roller centre or the pad's
    point at the contact), or the lifter's (its axis)."""
    return k.pressure_angle if hasattr(k, "pressure_angle") else k.lifter_pressure_angle


class ArmTrainGear(Gear):
    """An arm train as a gear (module docstring); a subclass names `type`, `description`, `parts`,
    `optional_parts`, `arm_kind` (modern_spec's kind: "finger" or "rocker") and its columns."""

    arm_kind: str = ""
    linkage_ratio = True
    # the lift is the valve's (follower.ratio 1, no elasticity of its own on the lift): the compiled
    # batch path's linkage model is the elastic effect's, and the contact row's torque factors are
    # this gear's ContactGeometry (item 10)
    batch_sweeps = True

    # -- 2, 3: keys and geometry ------------------------------------------------------------------
    def parse(self, table, fields) -> GearSpec:
        file = fields.get("source", "<memory>")
        if table is None:
            raise InputError(file, "gear", f"missing section: follower.type '{self.type}' needs [gear]")
        parts = parse_parts(table, self.arm_kind)
        spec = GearSpec(type=self.type, parts=MappingProxyType({k: MappingProxyType(v) for k, v in parts.items()}),
                        file=file)
        self.check(spec, fields)
        self.make(spec, fields)
        return spec

    def takes_law(self, law) -> bool:
        """A closed form (the wanted valve lift: the cam is synthesised) or a [cam] contour (analysed)."""
        return law.closed_form or law.from_contour

    def law_refusal(self, law) -> str:
        return (f"the {self.type} gear synthesises its cam from one of the laws {', '.join(closed_form_names())} "
                f"(the wanted valve lift) or analyses a [cam] contour (law = \"contour\"), not law \"{law.name}\"")

    def check(self, spec, fields) -> None:
        super().check(spec, fields)
        file, law = fields.get("source", "<memory>"), law_spec(fields["lift"].law)
        if law.gear_made:
            raise InputError(file, "lift.law", f"the {self.type} gear needs a lift law (the wanted valve lift) or "
                             "law = \"contour\"")
        if law.from_contour and fields.get("cam") is None:
            raise InputError(file, "cam", "missing section: lift.law = \"contour\" needs the [cam] contour")
        if spec is not None and self.side_stiffness(spec) is not None and "elastic" in fields["effects"]:
            varying = varying_stiffness()
            if fields["solver"].method not in varying:
                raise InputError(spec.file, "solver.method", f"method \"{fields['solver'].method}\" needs a constant "
                                 f"linkage stiffness, but the {self.type}'s stiffness ([gear.*] stiffness) is referred to "
                                 "the valve through its changing ratio: use method = "
                                 + " or ".join(f'"{m}"' for m in varying))

    def make(self, spec, source):
        """The train's geometry with its synthesised cam, or analysed over the [cam] contour
        (law = "contour"), checked over a revolution (undercut or cusp, the arm through the cam,
        the pad off the valve tip, a dead point of the pushrod; a given contour: the follower
        following it round, its base circle follower.base_radius)."""
        follower, lift = section(source, "follower"), section(source, "lift")
        if law_spec(lift.law).from_contour:
            return build_modern_gear(self.arm_kind, spec.parts, base_radius=follower.base_radius,
                                     roller_radius=follower.roller_radius, lift=None,
                                     contour=cam_contour(section(source, "cam")), file=spec.file)
        return build_modern_gear(self.arm_kind, spec.parts, base_radius=follower.base_radius,
                                 roller_radius=follower.roller_radius, lift=law_lift(lift), file=spec.file)

    # -- 5: the lift -------------------------------------------------------------------------------
    def build_lift(self, scene) -> TrainLift:
        spec = spec_of(self, scene)
        gear = self.make(spec, scene)
        law = gear.law if gear.law is not None else ContourValveLift(gear)
        return TrainLift(gear, law, side_stiffness=self.side_stiffness(spec))

    def side_stiffness(self, spec) -> float | None:
        """The [gear.*] stiffness of its cam side (N/m), or None."""
        return None

    def _lift(self, ctx) -> TrainLift:
        return ctx.lift if isinstance(ctx.lift, TrainLift) else self.build_lift(ctx.scene)

    def _train(self, ctx):
        return self._lift(ctx).gear

    def _kin(self, ctx):
        return self._lift(ctx).kinematics(ctx.theta)

    # -- 6: figures ---------------------------------------------------------------------------------
    def kinematics(self, ctx, d) -> tuple[dict, dict]:
        """Pressure angle, the cam's radius of curvature at the contact, the ratio and its first two
        derivatives in the cam angle (per rad, exact jets), the arm's angle."""
        k = self._kin(ctx)
        alpha = pressure_angle(k)
        columns = {
            "pressure_angle_deg": np.degrees(alpha),
            "contour_radius_m": k.surface.radius,
            "valve_ratio": k.ratio,
            "valve_ratio_d1": np.sign(k.ratio_jet[0]) * k.ratio_jet[1],
            "valve_ratio_d2": np.sign(k.ratio_jet[0]) * k.ratio_jet[2],
            "arm_angle_deg": np.degrees(self.arm_angle(k)),
        }
        columns.update(self.extra_kinematics(k))
        theta_deg = np.degrees(ctx.theta)
        i = int(np.argmax(np.abs(alpha)))
        summary = {
            "min_valve_ratio": float(k.ratio.min()),
            "max_valve_ratio": float(k.ratio.max()),
            "max_pressure_angle_deg": float(np.degrees(abs(alpha[i]))),
            "max_pressure_angle_cam_angle_deg": float(theta_deg[i]),
            "min_contour_radius_m": float(np.min(k.surface.radius)),
        }
        return columns, summary

    def arm_angle(self, k) -> np.ndarray:
        return k.arm_angle[0]

    def extra_kinematics(self, k) -> dict:
        return {}

    def frictions(self, scene) -> tuple[float, float]:
        spec = scene.contact if scene.contact is not None else ContactSpec()
        return spec.sliding_friction, spec.tip_friction

    def roller_radius(self, train) -> float:
        """The cam-side roller's radius (0: a pad or a flat lifter)."""
        return 0.0

    def counter_radius(self, train) -> float:
        """Signed radius of the follower's surface on the cam (roller, pad; inf: flat)."""
        raise NotImplementedError

    def statics_geometry(self, scene, train, k, from_columns: bool = False) -> ContactGeometry:
        mu_c, mu_t = self.frictions(scene)
        forces = train.contact_forces(k, np.ones(len(k.theta)), mu_c, mu_t)
        alpha = pressure_angle(k)
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(np.isfinite(forces.normal), forces.normal * np.cos(alpha), np.inf)
            arm = np.where(np.isfinite(forces.normal), forces.torque / forces.normal, 0.0)
        r = self.roller_radius(train)
        return ContactGeometry(pressure_angle=alpha, ratio=ratio, torque_arm=arm, body_arm=arm,
                               body_radius=np.hypot(k.surface.contact[:, 0], k.surface.contact[:, 1]),
                               contour_radius=k.surface.radius, counter_radius=self.counter_radius(train),
                               roller_diameter=2.0 * r if r > 0.0 else None, from_columns=from_columns)

    def contact_geometry(self, ctx) -> ContactGeometry:
        c = ctx.columns
        return self.statics_geometry(ctx.scene, self._train(ctx), self._kin(ctx),
                                     "pressure_angle_deg" in c and "contour_radius_m" in c)

    def cam_width(self, train) -> float | None:
        raise NotImplementedError

    def cam_hertz(self, train, k, normal, e_star: float, width: float) -> np.ndarray:
        return hertz_line_stress(normal, width, self.counter_radius(train), k.surface.radius, e_star)

    def contact_figures(self, ctx, geometry, columns) -> tuple[dict, dict]:
        """The contact point, the friction at the cam and at the tip (exact statics), the sliding
        and entrainment velocities of both contacts (m/s), the tip's scrub, the Hertz stress of the
        valve pad on the tip and, when the gear's part gives the contact's width, the cam's own Hertz
        stress for its contact type in place of the generic one."""
        scene, train, k, w = ctx.scene, self._train(ctx), self._kin(ctx), ctx.omega
        spec = scene.contact if scene.contact is not None else ContactSpec()
        mu_c, mu_t = self.frictions(scene)
        force = np.asarray(ctx.columns["contact_force_N"], dtype=float)
        forces = train.contact_forces(k, force, mu_c, mu_t)
        e_star = effective_modulus(spec.youngs_modulus, spec.poisson_ratio, spec.roller_youngs_modulus,
                                   spec.roller_poisson_ratio)
        tip, cam = k.tip, k.cam_velocities
        tip_sigma = tip_stress(train.valve, tip, forces.tip_normal, e_star, None) if train.valve.tip_radius else np.zeros_like(force)
        out = {
            "cam_contact_x_m": k.surface.contact[:, 0],
            "cam_contact_y_m": k.surface.contact[:, 1],
            "cam_friction_force_N": forces.friction,
            "cam_sliding_velocity_m_s": w * cam.sliding,
            "cam_entrainment_velocity_m_s": w * cam.entrainment,
            "tip_contact_x_m": tip.point[:, 0],
            "tip_contact_y_m": tip.point[:, 1],
            "tip_scrub_m": tip.scrub,
            "tip_scrub_velocity_m_s": w * tip.scrub_rate,
            "tip_normal_force_N": forces.tip_normal,
            "tip_friction_force_N": forces.tip_friction,
            "tip_sliding_velocity_m_s": w * tip.velocities.sliding,
            "tip_entrainment_velocity_m_s": w * tip.velocities.entrainment,
            "tip_hertz_stress_Pa": tip_sigma,
        }
        out.update(self.extra_contact(train, k, forces))
        theta_deg = np.degrees(ctx.theta)
        summary = {
            "cam_sliding_friction": mu_c,
            "tip_friction": mu_t,
            "max_tip_scrub_m": float(np.max(np.abs(tip.scrub))),
            "tip_scrub_travel_m": float(np.ptp(tip.scrub)),
            "max_tip_sliding_velocity_m_s": float(np.max(np.abs(out["tip_sliding_velocity_m_s"]))),
            "max_cam_sliding_velocity_m_s": float(np.max(np.abs(out["cam_sliding_velocity_m_s"]))),
            "max_tip_hertz_stress_Pa": float(np.max(tip_sigma)),
        }
        width = self.cam_width(train)
        if width is not None:  # the gear's own contact: its width and its contact type
            sigma = self.cam_hertz(train, k, np.asarray(columns["cam_normal_force_N"]), e_star, width)
            i = int(np.argmax(np.where(np.isfinite(sigma), sigma, -1.0)))
            convex = k.surface.radius > 0.0
            out["hertz_stress_Pa"] = sigma
            summary.update({
                "max_hertz_stress_Pa": float(sigma[i]),
                "max_hertz_stress_cam_angle_deg": float(theta_deg[i]),
                "max_hertz_stress_convex_Pa": float(np.max(np.where(convex, sigma, 0.0))),
                "max_hertz_stress_concave_Pa": float(np.max(np.where(~convex, sigma, 0.0))),
                "hertz_width_m": width,
                "hertz_width_from_rule": False,
                "hertz_utilisation": float(sigma[i] / spec.allowable_stress),
            })
        return out, summary

    def extra_contact(self, train, k, forces) -> dict:
        return {}

    def cam_contact(self, scene, lift, theta) -> GearContact:
        """The statics' geometry and both surfaces' velocities relative to the contact (a roller's
        equal: it rolls); the driven point swings on an arc (finger, OHC rocker) or slides (lifter)."""
        train = lift.gear
        k = train.kinematics(np.asarray(theta, dtype=float))
        geometry = self.statics_geometry(scene, train, k)
        motion = SurfaceMotion(k.cam_velocities.first, k.cam_velocities.second)
        r = self.roller_radius(train)
        pitch = k.surface.radius + r if r > 0.0 else None
        return GearContact(geometry, motion, oscillating=self.oscillating(train), pitch_radius=pitch,
                           stress=self.point_stress(train, k))

    def point_stress(self, train, k):
        """The cam contact's own pressure for the design rule where it is no line contact (a crowned
        face: an ellipse), as GearContact.stress; None: the rule's line contact."""
        return None

    def oscillating(self, train) -> bool:
        return True

    def lifter_ratio(self, scene, lift, theta):
        """The train's kinematic ratio (explorer.gears.arm: |ds/dpsi| / arm, the valve's travel per
        travel of the arm's reference point; explorer.gears.pushrod: ds/dL, per travel of the
        lifter), the [lift] being the valve's."""
        train = lift.gear
        k = train.kinematics(np.asarray(theta, dtype=float))
        if hasattr(train, "lifter"):
            return "lifter", np.asarray(k.ratio, dtype=float)
        return ("roller centre" if train.arm.cam_side.kind == "roller" else "pad crown"), np.asarray(k.ratio, dtype=float)

    # -- 8: report ---------------------------------------------------------------------------------
    def report(self, ctx) -> EffectOutput:
        train, k = self._train(ctx), self._kin(ctx)
        contour = k.surface.contour
        convex = k.surface.radius[k.surface.radius > 0.0]
        angle = self.arm_angle(k)
        summary = {
            "rest_arm_angle_deg": math.degrees(float(angle[np.argmin(k.lift[0])])),
            "arm_swing_deg": float(np.degrees(np.ptp(angle))),
            "min_valve_ratio": float(k.ratio.min()),
            "max_valve_ratio": float(k.ratio.max()),
            "cam_max_radius_m": float(np.max(np.hypot(contour[:, 0], contour[:, 1]))),
            "min_convex_contour_radius_m": float(convex.min()) if convex.size else None,
            "max_tip_scrub_m": float(np.max(np.abs(k.tip.scrub))),
            **self.extra_report(train, k),
        }
        own = self._lift(ctx).linkage_stiffness
        if own is not None:  # the cam side's stiffness referred to the valve, before [linkage] in series
            referred = own(ctx.theta)[0]
            summary["valve_referred_side_stiffness_N_m"] = [float(referred.min()), float(referred.max())]
        return EffectOutput(summary=summary)

    def extra_report(self, train, k) -> dict:
        return {}

    # -- 9: the cam ---------------------------------------------------------------------------------
    def cam_profile(self, scene, lift=None):
        lift = lift if lift is not None else self.build_lift(scene)
        roller = self.roller_radius(lift.gear)
        cut_for = (CutFor(scene.follower.type, "roller", roller) if roller > 0.0
                   else CutFor(scene.follower.type, "face", self.counter_radius(lift.gear)))
        return TrainCam(lift.gear, roller, scene.name, scene.source, lift.law, cut_for)
