"""What a gear is to the rest of the program: the base class every follower type derives from
(Gear, with its numbered contract) and the parsed [gear] section (GearSpec).

A gear plug-in is one class in one module (explorer/gears/<follower_type>.py) and one line of
explorer/gears/registry.py; its 3D parts are one class in explorer/view/ and one line of
explorer/view/gear_views.py. Generic code asks the scene's gear (Scene.gear_plugin, Context.gear)
and never branches on follower.type.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Callable, Mapping

from ..core.errors import InputError, echo
from ..core.reader import Table
from ..lift.registry import law_spec, scene_lift
from ..mechanics.gear_contact import NotApplicable
from ..mechanics.moving_mass import ReferredMass, train_parts

_NONE: Mapping[str, Any] = MappingProxyType({})


@dataclass(frozen=True)
class GearSpec:
    """The [gear] section of a scene, parsed by its gear: sub-table -> {key: SI value}."""

    type: str
    parts: Mapping[str, Mapping[str, Any]]
    file: str = "<memory>"

    def part(self, name: str) -> Mapping[str, Any]:
        return self.parts.get(name, _NONE)


class Gear:
    """Base class of the follower types (gears): what the scene loader, the effects, the sweep
    engine and the exports ask of a gear. Every hook has a default that says "this gear has no
    such thing" (or does what most gears do), so a gear overrides only what it has.

    To add a gear you write one subclass in its own module, `register_gear` it (one line of
    explorer/gears/registry.py, or one call) and give it a GearView in explorer/view/ (one line of
    explorer/view/gear_views.py). The gear must:

    1. Name itself: `type` (the scene's follower.type, unique) and a one-line `description`.
    2. Own its scene keys. `parts` maps each sub-table of [gear] to a parser (a reader.Table of
       [gear.<name>] -> dict of SI values; every key checked with its range, one InputError naming
       the key), `optional_parts` those that may be left out; `parse` turns [gear] into a GearSpec
       (a gear without parts takes no [gear] section). `rejected` maps a scene section the gear
       cannot take to the reason (the scene loader's error). The generic [follower] keys
       (base_radius, roller_radius, offset, ratio) stay the loader's.
    3. Check the scene at load time: `check(spec, fields)` for everything across sections (the
       laws it takes, a roller it needs, sections it needs, ranges that depend on other keys),
       and build its geometry once (`make`), so bad geometry fails at load with the key to change,
       not later as a NaN. `linkage_ratio`: its linkage sets the valve ratio (follower.ratio must
       stay 1: the lift is valve-referred).
    4. Say which lift laws it takes (explorer/lift/registry.py): `makes_lift` for the gears whose
       geometry makes the lift (law "gear"), else `takes_law(law)` (default: the closed forms;
       `law_refusal` the message), and for law "contour" the analysis of a [cam] contour,
       `contour_lift(cam, follower, file)` (`analyses_contours`). `accepts_law` combines them (the
       browser's law list). `roller_envelope`: a cam a law builder computes for it (polydyne,
       spline, table, acceleration) is the envelope of the [follower] roller on a straight path
       at `offset`, checked in closed form (explorer.lift.validity.lift_fault).
    5. Build the lift: `build_lift(scene) -> LiftCurve` (explorer.lift.curves.LiftCurve: analytic
       L, L', L'', L''' and breakpoints; valve-referred with lash included when `linkage_ratio`).
       A lift curve whose linkage has its own elasticity carries `linkage_stiffness` (theta ->
       (k, dk/dtheta), referred to the valve; the elastic effect puts it in series with [linkage]
       and needs a solver that takes k(t)). A lift curve that is a geometry's carries it as
       `.gear` (what `contact_geometry` and the 3D view read).
    6. Add its figures to the generic effects where it has them: `kinematics(ctx, d)` -> (columns,
       summary) after the valve's (pressure angle, radii of curvature, contact offset, ratio...);
       `contact_geometry(ctx)` -> mechanics.contact.ContactGeometry (the contact effect computes
       normal force with friction, torque and Hertz stress from it; `contact_roller`: the width rule
       needs roller_radius > 0); `contact_figures(ctx, geometry, columns)` -> (columns, summary)
       added by the contact effect (sliding and entrainment velocities, a second contact...);
       `cam_contact(scene, lift, theta)` -> mechanics.gear_contact.GearContact, its contact for the
       design rules (explorer.checks: the same ContactGeometry plus each surface's motion), or
       NotApplicable (the default) when it has no cam contact the rules judge.
    7. Replace a generic effect where its physics differ: `effects` maps an effect name to a
       function (ctx) -> result.EffectOutput run instead of the generic one (the trip gear's latch).
       `columns` declares, per effect, the columns it adds to it or its variant returns beyond the
       effect table's (names or fnmatch patterns; the pipeline refuses an undeclared one).
    8. Report what is its own: `report(ctx)` -> EffectOutput, the 'gear' effect (columns, the
       summary block under "gear", events, warnings).
    9. Give the cam to make, if it has one: `cam_profile(scene, lift)` -> a CamProfile
       (explorer.lift.contours.cam_profile: contour, pitch, normal, curvatures at any cam angle)
       for the exports (point table, DXF, STL/GLB, grinding table); None: nothing to export.
    10. Say how sweeps run it: `lift_reads(scene)`, the sweep keys
        (explorer.studies.sweep_spec.SWEEP_KEYS) whose values `build_lift` reads -- () when none
        (the default: the cam's or the geometry's alone), None when it may read any (the speed,
        the train's loads). A gear without variants of effects whose lift reads none shares one
        lift across a sweep's runs (`shares_lift`: the sweep engine's figures-only path, and the
        design checks); `batch_sweeps` when, beyond that, the compiled batch path and the residual
        sweep take its runs (a constant ratio to the valve); else every run is `simulate` whole.
    11. Import only from its own layer and below (core ... effects): names of view, studies or cli
        never appear in it; heavy or optional packages (scipy, numba) only inside functions.
    12. Say what moves with the valve: `moving_parts(scene)` -> the parts of the rigid train beyond
        valve.mass, each a mechanics.moving_mass.ReferredMass (its mass referred to the valve:
        m / r^2 with r the valve's travel per the part's, J / a^2 for a lever of inertia J about
        its pivot and arm a to the valve). The default is the scene's [[linkage.elements]] and
        the spring's third where valve.mass leaves it out (moving_mass.train_parts); a gear with
        moving parts of its own returns those too (super().moving_parts(scene) + its own). The
        rigid forces (the forces effect, the sweep engine's rigid figures, the design rules) take
        valve.mass plus their sum (moving_mass.rigid_mass); the elastic models take their parts
        from [[linkage.elements]], so a part a gear adds here counts in the rigid figures only.
    """

    type: str = ""
    description: str = ""
    parts: Mapping[str, Callable[[Table], dict]] = _NONE  # item 2
    optional_parts: frozenset[str] = frozenset()
    rejected: Mapping[str, str] = _NONE
    linkage_ratio: bool = False  # item 3
    makes_lift: bool = False  # item 4
    contact_roller: bool = False  # item 6
    roller_envelope: bool = False  # item 4: its cam is the [follower] roller's envelope on a straight path
    effects: Mapping[str, Callable] = _NONE  # item 7
    columns: Mapping[str, tuple[str, ...]] = _NONE
    batch_sweeps: bool = False  # item 10
    fits_target: bool = False  # `explorer fit` chooses its contour for a wanted lift (fit)

    # -- 2. scene keys -------------------------------------------------------------------------
    def parse(self, table: Table | None, fields: dict) -> GearSpec | None:
        """[gear] -> GearSpec (None for a gear without parts), checked (3) and built once."""
        file = fields.get("source", "<memory>")
        if not self.parts:
            self.check(None, fields)
            return None
        if table is None:
            raise InputError(file, "gear", f"missing section: follower.type '{self.type}' needs [gear]")
        table.reject_unknown(tuple(self.parts))
        parts: dict[str, Mapping[str, Any]] = {}
        for name, parser in self.parts.items():
            sub = table.table(name, required=False)
            if sub is None:
                if name in self.optional_parts:
                    continue
                raise InputError(file, f"gear.{name}", f"missing section: follower.type '{self.type}' needs [gear.{name}]")
            parts[name] = MappingProxyType(parser(sub))
        spec = GearSpec(type=self.type, parts=MappingProxyType(parts), file=file)
        self.check(spec, fields)
        self.make(spec, fields)
        return spec

    # -- 3. checks at load ---------------------------------------------------------------------
    def check(self, spec: GearSpec | None, fields: dict) -> None:
        """Checks across sections (default: the ratio of a linkage, the laws it takes)."""
        file, follower, lift = fields.get("source", "<memory>"), fields["follower"], fields["lift"]
        if self.linkage_ratio and follower.ratio != 1.0:
            raise InputError(file, "follower.ratio", f"the {self.type} gear's linkage sets the valve ratio; leave "
                             "follower.ratio = 1")
        law = law_spec(lift.law)
        if self.makes_lift and not law.gear_made:
            raise InputError(file, "lift.law", f"the {self.type} gear makes its own lift: set lift.law = \"gear\"")
        if not self.makes_lift and not law.gear_made and not self.takes_law(law):
            raise InputError(file, "lift.law", self.law_refusal(law))

    def make(self, spec: GearSpec | None, source) -> Any:
        """Its geometry from the spec and the scene (or the partial fields while loading); raises
        InputError on bad geometry. Default: nothing to build."""
        return None

    # -- 4. laws -------------------------------------------------------------------------------
    def takes_law(self, law) -> bool:
        """Whether it takes a law (a LawSpec) that its geometry does not make (default: the closed
        forms, whose jets a gear's synthesis can compose)."""
        return law.closed_form

    def accepts_law(self, law) -> bool:
        """Whether a scene of this gear may name `law` at all (what `check` enforces, without the
        messages): its own geometry's law when it makes its lift, else one it takes."""
        if law.gear_made or self.makes_lift:
            return law.gear_made and self.makes_lift
        return self.takes_law(law)

    def law_refusal(self, law) -> str:
        return f"follower type {self.type!r} takes no lift law {law.name!r}"

    analyses_contours: bool = False  # item 4: contour_lift is implemented

    def contour_lift(self, cam, follower, file: str):
        """The lift of this follower on the [cam] contour (law "contour")."""
        raise InputError(file, "follower.type", f"follower type {self.type!r} cannot follow a [cam] contour")

    # -- 5. the lift ---------------------------------------------------------------------------
    def build_lift(self, scene):
        """The scene's lift curve (default: its [lift] law's)."""
        return scene_lift(scene)

    # -- 6. figures in the generic effects -----------------------------------------------------
    def kinematics(self, ctx, d) -> tuple[dict, dict]:
        """(columns, summary) the kinematics effect adds after the valve's; d = L, L', L'', L'''."""
        return {}, {}

    def contact_geometry(self, ctx):
        """The ContactGeometry of the contact statics over ctx.theta."""
        raise InputError(ctx.scene.source, "follower.type", f"effect 'contact' does not model follower type {echo(self.type)}")

    def contact_figures(self, ctx, geometry, columns) -> tuple[dict, dict]:
        """(columns, summary) the contact effect adds after its own (`columns`: those so far)."""
        return {}, {}

    def check_contact(self, follower, file: str) -> None:
        """InputError when the contact statics cannot run on this follower (effect 'contact')."""
        if "contact" in self.effects:  # its own statics
            return
        if type(self).contact_geometry is Gear.contact_geometry:
            raise InputError(file, "follower.type", f"effect 'contact' does not model follower type {echo(self.type)}")
        if self.contact_roller and follower.roller_radius <= 0.0:
            raise InputError(file, "follower.roller_radius",
                             "effect 'contact' needs a roller (roller_radius > 0) for the Hertz stress and the width rule")

    def cam_contact(self, scene, lift, theta):
        """Its cam contact on the angles theta for the design rules (a GearContact), or
        NotApplicable with the reason."""
        raise NotApplicable(f"follower type {self.type!r} has no cam contact the rules judge (its own rules judge it)")

    # -- 7. variants of effects ----------------------------------------------------------------
    def effect(self, name: str) -> Callable | None:
        """Its own function for effect `name`, or None (the generic one runs)."""
        return self.effects.get(name)

    # -- 8. the 'gear' effect ------------------------------------------------------------------
    def report(self, ctx):
        """The 'gear' effect's output: columns, the summary block under "gear", events, warnings."""
        raise InputError(ctx.scene.source, "effects", "effect 'gear' needs a gear follower type and its [gear] section")

    # -- 9. the cam to make --------------------------------------------------------------------
    def cam_profile(self, scene, lift=None):
        """Its cam for the exports (a CamProfile), or None when it has none to make."""
        return None

    # -- 10. sweeps ---------------------------------------------------------------------------
    def lift_reads(self, scene) -> tuple[str, ...] | None:
        """The sweep keys whose values build_lift reads for this scene: () none, None any."""
        return ()

    def shares_lift(self, scene) -> bool:
        """True when a sweep's runs share one lift curve and the generic effects."""
        return not self.effects and self.lift_reads(scene) == ()

    # -- 12. the rigid train's moving parts -----------------------------------------------------
    def moving_parts(self, scene) -> tuple[ReferredMass, ...]:
        """The rigid train's parts beyond valve.mass, referred to the valve (default: the scene's
        [[linkage.elements]] and the spring's share when it is modelled as masses)."""
        return train_parts(scene)

    # -- 13. the follower the cam drives (the design rules' lifter side) -----------------------
    def lifter_ratio(self, scene, lift, theta):
        """(the name of the follower the cam drives, the valve's travel per its travel at the cam
        angles `theta`) for the figures the trade quotes at the lobe (the ramp velocity: a tappet's
        lift per cam degree, the lobe being ground to the tappet's lift), or None when the scene's
        lift is that follower's own and follower.ratio turns it into the valve's (the default: a
        translating roller, a bucket tappet). A gear whose [lift] is the valve's gives its kinematic
        ratio; one with no follower between the cam and the valve ("valve", 1)."""
        return None

    # -- explorer fit --------------------------------------------------------------------------
    def fit(self, scene, theta) -> tuple[dict, list[str]]:
        """(report, warnings) of `explorer fit`: the contour chosen for a wanted lift."""
        raise InputError(scene.source, "follower.type", f"follower type {self.type!r} has no contour to fit")

    def __repr__(self) -> str:
        return f"<gear {self.type}>"
