"""The table of effects: every name a scene may list in `effects`, with what the scene loader, the
pipeline and the sweep engine need to know of it (an EffectSpec, whose docstring lists, numbered,
what an effect must provide). Adding an effect: its module and one line of EFFECTS (or
`register_effect(spec)`).

The functions are "module:function" references, imported when an effect first runs: a
kinematics-only scene never imports a dynamics solver (tests/test_elastic_effect.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from fnmatch import fnmatchcase
from typing import Callable

from ..core.plugins import Registration, Registry, resolve


@dataclass(frozen=True)
class SectionFigures:
    """Sweep figures an effect gives when the scene has an owned section (EffectSpec item 6)."""

    section: str  # a Scene field (an OWNED_SECTIONS name): the figures when it is not None
    figures: tuple[str, ...]
    row: Callable | str  # "module:function" (a Result) -> {figure: float}, NaN where there is none


@dataclass(frozen=True)
class EffectSpec:
    """One line of the effect table: an effect a scene may list.

    To add an effect you write its function and add one EffectSpec. The effect must:

    1. Provide `function`, "module:function" (or a function) (ctx: effects.context.Context) ->
       result.EffectOutput: columns over ctx.theta (SI, the unit in the name), summary figures, events
       (result.Event: kind, time_s within the revolution, cam_angle_deg, values) and warnings (one
       line each). It reads the scene, the lift curve and the columns and summary of the effects
       before it; it asks the scene's gear (ctx.gear) for what is particular to the gear, never
       follower.type. Columns of a later effect replace earlier ones of the same name (valve_* holds
       the most detailed motion; rigid_valve_* keeps the rigid one).
    2. List `depends` (effects that must run before it: the pipeline runs them first, in order),
       `after` (effects it reads when the scene has them, which then run before it but are not
       added: the contact statics take the elastic effect's cam force when there is one) and
       `requires` (scene sections it needs, such as "valve": the scene loader refuses a scene that
       lists it without them).
    3. Declare its `columns` (names or fnmatch patterns, "coil_*_displacement_m"); a gear declares
       what it adds to an effect (Gear.columns). simulate refuses an undeclared column.
    4. Give finite results: NaN only in columns of NAN_WHERE_UNDEFINED (explorer.effects.pipeline),
       never an infinite motion (the pipeline refuses them as an InputError: the scene's values are
       beyond the model).
    5. Optionally add the blocks of the scene sections it owns a report of (`sections`: section ->
       "module:function" (scene, lift) -> (block, warnings), stored under the section's name).
    6. For sweeps: `sweep_figures`, the figures of a sweep row it gives, and `row`, "module:function"
       (a Result: summary, events, columns) -> {figure: float} (NaN where there is none); `figures`,
       its figures-only form "module:function" (ctx, cache) -> EffectOutput, which computes just what
       rows and later effects read and keeps across the runs of a sweep what does not change between
       them in `cache` (explorer.effects.pipeline.figures); None: the sweep runs the effect itself.
       `section_figures` (SectionFigures): figures a row holds only when the scene has an owned
       section, with the row function that gives them (the elastic effect's adjuster figures with
       [hla]); a scene without the section has neither.
    7. Import nothing heavy at module level: the table names the module.
    """

    name: str
    function: Callable | str  # item 1
    depends: tuple[str, ...] = ()  # item 2
    after: tuple[str, ...] = ()
    requires: tuple[str, ...] = ()
    columns: tuple[str, ...] = ()  # item 3
    sections: tuple[tuple[str, str], ...] = ()  # item 5
    sweep_figures: tuple[str, ...] = ()  # item 6
    row: Callable | str | None = None
    figures: Callable | str | None = None
    section_figures: tuple[SectionFigures, ...] = ()
    description: str = ""

    def run(self) -> Callable:
        return resolve(self.function)

    def declares(self, column: str) -> bool:
        return declared(column, self.columns)

    def section_figures_of(self, scene) -> tuple[SectionFigures, ...]:
        """Its section_figures whose section the scene has."""
        return tuple(extra for extra in self.section_figures if getattr(scene, extra.section, None) is not None)


_KIN = "explorer.effects.kinematics"
_ELASTIC_FIGURES = ("first_separation_deg", "separations", "flight_time_s", "max_deviation_m", "peak_linkage_force_N",
                    "peak_camshaft_back_pressure_N", "lift_off_delay_s", "seating_velocity_m_s", "seat_impacts",
                    "largest_bounce_m", "residual_deviation_m", "residual_amplitude_m")
# with a hydraulic lash adjuster ([hla], effects/train_elastic.py): how far the valve stays off its seat over
# the last revolution's base circle (0: it seats; where a speed sweep shows pump-up beginning), the lash the
# adjuster took up, its plunger's travel over that revolution and its chamber's peak pressure
_HLA_FIGURES = ("pump_up_valve_lift_m", "hla_lash_taken_up_m", "hla_plunger_travel_per_revolution_m",
                "hla_chamber_pressure_max_Pa")

EFFECTS: Registry[EffectSpec] = Registry("effect", {spec.name: spec for spec in (
    EffectSpec("kinematics", f"{_KIN}:kinematics_effect", figures=f"{_KIN}:kinematics_figures",
               columns=("follower_lift_m", "follower_velocity_m_s", "follower_accel_m_s2", "follower_jerk_m_s3",
                        "valve_lift_m", "valve_velocity_m_s", "valve_accel_m_s2", "valve_jerk_m_s3", "rigid_valve_*"),
               description="rigid motion of follower and valve (lift, velocity, acceleration, jerk)"),
    EffectSpec("lash", f"{_KIN}:lash_effect", depends=("kinematics",), figures=f"{_KIN}:lash_figures",
               description="where the lash is taken up and the valve seats, the impact speeds"),
    EffectSpec("forces", "explorer.effects.forces:forces_effect", depends=("kinematics", "lash"),
               requires=("valve", "spring"),
               columns=("spring_force_N", "inertia_force_N", "friction_force_N", "closing_load_N", "contact_force_N",
                        "linkage_force_N", "follower_force_N", "required_spring_force_N", "spring_margin_N"),
               sections=(("spring_design", "explorer.effects.spring_design:spring_design_summary"),),
               sweep_figures=("min_contact_force_N", "float_speed_rpm"), row="explorer.effects.forces:forces_row",
               figures="explorer.effects.forces:forces_figures",
               description="rigid valve-train loads, the float (jump) speed, Schenker's side figures"),
    EffectSpec("contact", "explorer.effects.contact:contact_effect", depends=("kinematics", "lash", "forces"),
               after=("elastic",),  # its cam force, when the scene has it: the dynamic_* figures
               columns=("cam_normal_force_N", "cam_tangential_force_N", "camshaft_torque_Nm", "self_locking_margin_deg",
                        "hertz_stress_Pa", "pressure_angle_deg", "contour_radius_m",
                        "dynamic_cam_normal_force_N", "dynamic_camshaft_torque_Nm", "dynamic_*hertz_stress_Pa"),
               sweep_figures=("max_camshaft_torque_Nm",), row="explorer.effects.contact:contact_row",
               figures="explorer.effects.contact:contact_figures",
               description="contact statics: normal force with friction, camshaft torque, Hertz stress, cam width; "
                           "with the elastic effect, the same on its cam force (dynamic_*)"),
    EffectSpec("elastic", "explorer.effects.elastic:elastic_effect", depends=("kinematics", "lash"),
               requires=("valve", "spring", "linkage"),
               columns=("valve_lift_m", "valve_velocity_m_s", "valve_accel_m_s2", "valve_jerk_m_s3", "linkage_force_N",
                        "camshaft_back_pressure_N", "deviation_from_drive_m", "valve_in_contact", "valve_phase",
                        "spring_force_retainer_N", "spring_force_static_N", "surge_force_N", "seat_force_N",
                        "coil_*_displacement_m",
                        # a train of parts and its joints, an adjuster (effects/train_elastic.py, issue #25)
                        "part_*_displacement_m", "part_*_velocity_m_s", "part_*_accel_m_s2", "contact_*_force_N",
                        "contact_*_closed", "hla_plunger_travel_m", "hla_chamber_pressure_Pa", "hla_check_valve_open"),
               sweep_figures=_ELASTIC_FIGURES, row="explorer.effects.elastic_events:elastic_row",
               section_figures=(SectionFigures("hla", _HLA_FIGURES, "explorer.effects.train_elastic:hla_row"),),
               description="the valve driven through the elastic linkage (lift-off, float, bounce, seat impact, surge)"),
    EffectSpec("gear", "explorer.effects.gear:gear_effect", depends=("kinematics",),
               description="what is particular to the scene's gear (its report)"),
)})


def declared(column: str, patterns: tuple[str, ...]) -> bool:
    """Whether a column is one of `patterns` (names, or fnmatch patterns with "*")."""
    return column in patterns or any("*" in p and fnmatchcase(column, p) for p in patterns)


def register_effect(spec: EffectSpec, *, replace: bool = False) -> Registration:
    """Add an effect to the table (one call; `.undo()` removes it again)."""
    return EFFECTS.register(spec.name, spec, replace=replace)


def effect_spec(name: str) -> EffectSpec:
    return EFFECTS[name]


def names() -> tuple[str, ...]:
    return EFFECTS.names()


def order(effects) -> list[str]:
    """The effects and what they depend on, dependencies first (RuntimeError on a cycle); an effect
    another lists in `after` runs before that one when it is among them."""
    wanted: set[str] = set()

    def close(name: str) -> None:
        if name not in wanted:
            wanted.add(name)
            for dep in EFFECTS[name].depends:
                close(dep)

    for effect in effects:
        close(effect)
    out: list[str] = []

    def visit(name: str, path: tuple[str, ...]) -> None:
        if name in out:
            return
        if name in path:
            raise RuntimeError(f"effect dependency cycle: {' -> '.join(path + (name,))}")
        spec = EFFECTS[name]
        for dep in spec.depends + tuple(a for a in spec.after if a in wanted):
            visit(dep, path + (name,))
        out.append(name)

    for effect in effects:
        visit(effect, ())
    return out


def sweep_figures(effects, scene=None) -> tuple[str, ...]:
    """The sweep-row figures of the effects (with their dependencies), in table order; with the
    scene, those of the sections it has too (EffectSpec.section_figures) after each effect's own."""
    wanted = set(order(effects))
    out: list[str] = []
    for name, spec in EFFECTS.items():
        if name in wanted:
            out.extend(spec.sweep_figures)
            if scene is not None:
                out.extend(f for extra in spec.section_figures_of(scene) for f in extra.figures)
    return tuple(out)
