"""The table of lift laws: every value of [lift] law, with what the scene loader, the lift's
builder, the gears and the browser's law dropdown need to know of it.

One line per law (a LawSpec, whose docstring lists, numbered, what a law must provide). The
closed-form laws (explorer/lift/laws.py) need only their normalised function; a law with its own
[lift] keys names its parser and its builder as "module:function" references, imported when a
scene uses the law. Adding a law: its module and one line of LAWS (or `register_law(spec)`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Mapping

from ..core.plugins import Registration, Registry, resolve
from . import laws as closed_forms
from .curves import LiftCurve, law_lift

# [lift] keys every law reads (those with event_keys) or lets through
COMMON_KEYS = ("law", "height", "start", "rise", "dwell", "return", "return_law")


@dataclass(frozen=True)
class LawSpec:
    """One line of the law table: a value of [lift] law.

    To add a law you write its module and add one LawSpec. The law must:

    1. Be a closed form or have a builder. A closed form gives `normalised`, f(u) on [0, 1] with
       f(0) = 0, f(1) = 1 and its analytic derivatives: u -> array (4, ...) of f, f', f'', f''' (the
       rise and return of explorer.lift.curves.LawLift, and of the gears that synthesise a cam through
       the law's jets). Any other law gives `builder`, "module:function" (scene) -> LiftCurve
       (explorer.lift.curves.LiftCurve: derivatives(theta) -> L, L', L'', L''' analytic, and
       breakpoints()); `scene_lift` builds either.
    2. List its own [lift] keys (`keys`), those of them without a default (`required`), and name
       its `parser`, "module:function" (reader.Table of [lift], the partial scene fields) -> a
       frozen options object (scene.lift.options), which validates every key at load time (one
       InputError naming the key) and may build the lift once to check it.
    3. Say how it reads the common keys: `shaped` (height, rise and return make its event and are
       required, as for the closed forms) unless [lift] `shaped_unless` = (key, value); without
       `event_keys` the common keys are not read at all (the lift comes from elsewhere).
    4. Name the scene sections it reads (`sections`), whether the lift is the follower's on the
       [cam] contour (`from_contour`: the gear analyses it, explorer.gears.base.Gear.contour_lift)
       and whether the gear's own geometry makes the lift (`gear_made`: only the gears that make
       their lift take it).
    5. State `smoothness`: the highest derivative of the lift that stays continuous where the
       law meets a dwell (1: the acceleration jumps; 2: the jerk does), None when it depends on
       the law's data (tests check the closed forms').
    6. Import nothing heavy at module level that the table needs: the table names the modules.
    """

    name: str
    normalised: Callable | str | None = None  # closed form (item 1)
    builder: str | None = None  # "module:function" (scene) -> LiftCurve (item 1)
    keys: tuple[str, ...] = ()  # its own [lift] keys (item 2)
    required: tuple[str, ...] = ()  # of those, the ones without a default
    parser: str | None = None  # "module:function" (Table, fields) -> options (item 2)
    shaped: bool = False  # item 3
    shaped_unless: tuple[str, Any] | None = None
    event_keys: bool = True
    sections: tuple[str, ...] = ()  # item 4
    from_contour: bool = False
    gear_made: bool = False
    smoothness: int | None = None  # item 5
    description: str = ""

    @property
    def closed_form(self) -> bool:
        return self.normalised is not None

    def function(self) -> Callable:
        """The normalised closed form f(u) -> (f, f', f'', f''') (item 1)."""
        if self.normalised is None:
            raise TypeError(f"law {self.name!r} is not a closed form")
        return resolve(self.normalised)

    def parse(self, table, fields) -> Any:
        """The law's options from [lift] (None for a law without its own keys)."""
        return None if self.parser is None else resolve(self.parser)(table, fields)

    def fits(self, lift: Mapping[str, Any], sections) -> bool:
        """Whether a scene whose raw [lift] table is `lift` (and whose top-level sections are
        `sections`) can take this law, as far as the table tells (items 2 to 4): no key of another
        law (the loader refuses them), its required keys, height and rise for a shaped event, its
        sections. The law's parser may still refuse a value."""
        keys = set(lift) - {"law"}
        if not keys - set(COMMON_KEYS) <= set(self.keys) or not set(self.required) <= keys:
            return False
        unless = self.shaped_unless
        shaped = self.shaped and not (unless is not None and lift.get(unless[0]) == unless[1])
        return (not shaped or {"height", "rise"} <= keys) and set(self.sections) <= set(sections)


def _closed(name: str, smoothness: int, description: str) -> LawSpec:
    return LawSpec(name, normalised=closed_forms.LAWS[name], shaped=True, smoothness=smoothness, description=description)


LAWS: Registry[LawSpec] = Registry("law", {spec.name: spec for spec in (
    _closed("cycloidal", 2, "cycloidal: acceleration a full sine, jerk jumps at the ends"),
    _closed("harmonic", 1, "simple harmonic: acceleration jumps at the ends"),
    _closed("polynomial-345", 2, "3-4-5 polynomial"),
    _closed("polynomial-4567", 3, "4-5-6-7 polynomial: jerk zero at the ends"),
    _closed("polynomial-56789", 4, "5-6-7-8-9 polynomial: jerk and snap zero at the ends (a polydyne's wanted lift)"),
    _closed("modified-trapezoid", 2, "modified trapezoidal acceleration"),
    _closed("modified-sine", 2, "modified sine acceleration"),
    LawSpec("table", builder="explorer.lift.table:build_table_lift", parser="explorer.lift.table:parse_table_options",
            keys=("file", "angle_unit", "lift_unit", "smoothing"), required=("file",),
            description="measured lift points (CSV), fitted by a smoothing spline"),
    LawSpec("acceleration", builder="explorer.lift.acceleration:build_acceleration_lift",
            parser="explorer.lift.acceleration:parse_acceleration_options",
            keys=("points", "angle_unit", "acceleration_unit", "interpolation", "reference_rpm"), required=("points",),
            description="an acceleration curve integrated twice"),
    LawSpec("contour", event_keys=False, sections=("cam",), from_contour=True,
            description="the lift of the follower on the cam contour in [cam]"),
    LawSpec("gear", gear_made=True, description="the gear's own geometry makes the lift"),
    LawSpec("polydyne", builder="explorer.lift.polydyne:build_polydyne_lift",
            parser="explorer.lift.polydyne:parse_polydyne_options",
            keys=("wanted_law", "design_rpm", "ramp", "stations", "continuity", "reference_rpm"),
            required=("wanted_law", "ramp"), shaped=True, shaped_unless=("wanted_law", "spline"),
            description="the cam that gives the wanted valve lift through the elastic linkage at the design speed"),
    LawSpec("spline", builder="explorer.lift.spline:build_spline_lift", parser="explorer.lift.spline:parse_spline_options",
            keys=("stations", "continuity", "reference_rpm"), required=("stations",),
            description="a piecewise polynomial through stations with the continuity asked"),
)})


def register_law(spec: LawSpec, *, replace: bool = False) -> Registration:
    """Add a law to the table (one call; `.undo()` removes it again). A closed form's function is
    also put where LawLift evaluates the closed forms (explorer.lift.laws.LAWS)."""
    registration = LAWS.register(spec.name, spec, replace=replace)
    if spec.closed_form:
        store = closed_forms.LAWS
        had, previous = spec.name in store, store.get(spec.name)
        store[spec.name] = spec.function()
        registration.also(lambda: store.__setitem__(spec.name, previous) if had else store.pop(spec.name, None))
    return registration


def law_spec(name: str) -> LawSpec:
    return LAWS[name]


def names() -> tuple[str, ...]:
    return LAWS.names()


def closed_form_names() -> tuple[str, ...]:
    """The closed-form laws, in table order (a return_law, the gears' synthesised cams)."""
    return tuple(name for name, spec in LAWS.items() if spec.closed_form)


def normalised(name: str) -> Callable:
    """The normalised closed form of law `name` (KeyError: no such law)."""
    return LAWS[name].function()


def scene_lift(scene) -> LiftCurve:
    """The lift curve of the scene's [lift] law: its builder's, or a LawLift for a closed form. The
    laws that the gear's geometry makes ("gear") or that follow a [cam] contour ("contour") have
    neither: the gear builds those lifts (explorer.gears.base.Gear.build_lift)."""
    spec = law_spec(scene.lift.law)
    if spec.closed_form:
        return law_lift(scene.lift)
    if spec.builder is None:
        raise TypeError(f"law {spec.name!r} has no builder: the follower's gear makes this lift")
    return resolve(spec.builder)(scene)
