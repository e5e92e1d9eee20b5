"""Scene files (TOML) -> a validated, frozen Scene with every quantity in SI.

A scene describes one valve gear at one speed and lists the effects to compute. Each section is
read through `reader.Table`, so any bad value ends in one InputError naming file, key and
reason. Sections owned by other modules (lift-law options, [cam], [contact], ...) are parsed by
those modules' `parse_*` functions, called from here so that all validation happens at load time.
"""

from __future__ import annotations

import copy
import math
import os
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Mapping

from ..core.errors import InputError, echo
from ..core.files import MAX_SCENE_FILE_BYTES, data_folder, read_regular
from ..core.plugins import resolve
from ..core.reader import Table, toml_loads
from ..dynamics import solvers
from ..effects import registry as effect_table
from ..gears import registry as gear_table
from ..gears.base import Gear, GearSpec
from ..lift import registry as laws
from .builtin import find_scene
from .train_section import CONTACTS, LinkageElement, check_train, parse_elements

if TYPE_CHECKING:
    from ..lift.contours.spec import CamSpec
    from ..mechanics.contact import ContactSpec
    from ..mechanics.springs import SpringDesign
    from ..mechanics.tribology import LubricantSpec
    from .checks_section import ChecksSpec
    from .train_section import HLASection

MIN_STEPS = 36
# Plausibility limits: far outside any valve gear, they keep the arithmetic finite (the jerk
# w^3 L''' must not overflow) and catch unit slips such as "10 m" for "10 mm".
MAX_RPM = 100_000.0
MAX_LIFT = 1.0  # m
MIN_EVENT_ANGLE = math.radians(0.1)  # rise and return of the analytic laws
MAX_RATIO = 100.0
MAX_STEPS = 1_000_000  # at this count simulate (elastic) needs ~20 s and 0.7 GB, record ~50 s and 2 GB; 10x that took 4 min and 5.6 GB

# Optional sections parsed by the module that owns them: section -> "module:function".
# The function takes (Table, partial scene fields dict) and returns a frozen object.
OWNED_SECTIONS: dict[str, str] = {
    "cam": "explorer.lift.contours.spec:parse_cam_section",
    "contact": "explorer.scene.contact_section:parse_contact_section",
    "spring_design": "explorer.mechanics.springs:parse_spring_design_section",
    "lubricant": "explorer.mechanics.tribology:parse_lubricant_section",
    "checks": "explorer.scene.checks_section:parse_checks_section",
    "hla": "explorer.scene.train_section:parse_hla_section",
}
# what a section needs, for the message when an effect requires a scene without it
SECTION_KEYS = {"valve": "mass", "spring": "preload and rate", "linkage": "stiffness"}


@dataclass(frozen=True)
class Drive:
    rpm: float  # rev/min, > 0
    operating_range: tuple[float, float] | None = None  # rev/min, lowest and highest (explorer check)
    # rev/min as the scene file wrote drive.rpm, where an override (--set, the browser's speed) ran
    # it at another: None when the run's speed is the file's (cam_omega)
    written_rpm: float | None = None

    @property
    def omega(self) -> float:
        """Camshaft angular speed in rad/s."""
        return self.rpm * 2.0 * math.pi / 60.0

    @property
    def cam_omega(self) -> float:
        """The speed (rad/s) at which a lift law given in time units (an acceleration, a spline's
        stations, a polydyne's design) defines its cam when it names no speed of its own: the
        file's drive.rpm. A cam is steel: running it at another speed (--set drive.rpm, a sweep,
        the browser's speed) must not reshape it, so all of them take the same cam."""
        return (self.rpm if self.written_rpm is None else self.written_rpm) * 2.0 * math.pi / 60.0


@dataclass(frozen=True)
class LiftSpec:
    law: str
    height: float = 0.0  # m, follower (roller-centre) lift, lash included
    start: float = 0.0  # rad
    rise: float = 0.0  # rad
    dwell: float = 0.0  # rad
    ret: float = 0.0  # rad
    return_law: str | None = None
    options: Any = None  # law-specific, parsed by the law's module


@dataclass(frozen=True)
class Follower:
    type: str = gear_table.DEFAULT  # the gear (explorer/gears/registry.py)
    base_radius: float = 0.03  # m, base circle of the cam contour
    roller_radius: float = 0.0  # m
    offset: float = 0.0  # m, follower axis offset from the cam centre
    ratio: float = 1.0  # valve travel per follower travel

    @property
    def roller_envelope(self) -> bool:
        """True when the cam is the envelope of this roller (radius roller_radius, base circle
        base_radius) on a straight path at `offset` -- the gear says (Gear.roller_envelope): a cam
        made for it is checked in the closed forms of explorer.lift.validity.translating_fault."""
        return gear_table.gear(self.type).roller_envelope


@dataclass(frozen=True)
class Valve:
    mass: float  # kg, effective moving mass referred to the valve
    lash: float = 0.0  # m, clearance at the valve
    oscillating_mass: float | None = None  # kg, Schenker's M1 (mass while the linkage is compressed)


@dataclass(frozen=True)
class Spring:
    preload: float  # N at closed valve
    rate: float  # N/m
    # the spring as a body (issue #15): its mass, the masses it is cut into (0: massless, the
    # linkage model of Schenker), the damping ratio of its own modes, its lengths (coil clash)
    mass: float = 0.0  # kg, the active coils
    elements: int = 0
    damping_ratio: float = 0.0
    free_length: float | None = None  # m
    solid_height: float | None = None  # m
    # the wire geometry when the scene gives it (the design rules' stresses: explorer.checks)
    wire_diameter: float | None = None  # m
    coil_diameter: float | None = None  # m, mean
    active_coils: float | None = None


@dataclass(frozen=True)
class Loads:
    friction: float = 0.0  # N, Coulomb, opposes valve motion
    closing: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))  # N, + closes

    @property
    def closing_total(self) -> float:
        return float(sum(self.closing.values()))


@dataclass(frozen=True)
class Linkage:
    stiffness: float  # N/m referred to the valve
    damping: float = 0.0  # N*s/m, viscous, in parallel with the stiffness
    # the valve train as parts (issue #25, explorer/scene/train_section.py): the parts from the cam,
    # each with its cam-side joint; stiffness and damping above are then the joint at the valve,
    # one-sided (it can open: valve.lash is its gap) or bonded
    elements: tuple[LinkageElement, ...] = ()
    one_sided: bool = True


@dataclass(frozen=True)
class Seat:
    restitution: float = 0.0
    stiffness: float | None = None  # N/m: an elastic seat (bounce resolved in time) instead of restitution
    damping: float = 0.0  # N*s/m, with stiffness


@dataclass(frozen=True)
class Solver:
    method: str = solvers.DEFAULT
    steps_per_revolution: int = 3600
    # the method's own [solver] options (explorer/dynamics/solvers.py: scene_options), each given
    # or at its default
    options: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))


@dataclass(frozen=True)
class Scene:
    name: str
    effects: tuple[str, ...]
    drive: Drive
    lift: LiftSpec
    follower: Follower
    valve: Valve | None
    spring: Spring | None
    loads: Loads
    linkage: Linkage | None
    seat: Seat
    solver: Solver
    source: str = "<memory>"  # the file the scene came from as the user named it, for messages
    # where its relative paths start: the found file's folder ("": source's folder). Not compared:
    # the data files it names are read into the sections when the scene loads
    folder: str = field(default="", compare=False)
    description: str = ""
    cam: CamSpec | None = None  # owned by explorer.lift.contours.spec
    contact: ContactSpec | None = None  # owned by explorer.scene.contact_section
    spring_design: SpringDesign | None = None  # owned by explorer.mechanics.springs (advice and historic rules)
    lubricant: LubricantSpec | None = None  # owned by explorer.mechanics.tribology (the design rules' film and flash temperature)
    checks: ChecksSpec | None = None  # owned by explorer.scene.checks_section (design-rule settings, read by explorer.checks)
    gear: GearSpec | None = None  # the [gear] section, owned by the follower's gear
    hla: HLASection | None = None  # owned by explorer.scene.train_section (a hydraulic lash adjuster under the lever)

    @property
    def gear_plugin(self) -> Gear:
        """The follower type's gear (explorer/gears/registry.py): what the effects, the sweep engine,
        the exports and the views ask instead of testing follower.type."""
        return gear_table.gear(self.follower.type)

    @property
    def directory(self) -> Path:
        return data_folder({"source": self.source, "folder": self.folder})

    @property
    def omega(self) -> float:
        return self.drive.omega

    def with_changes(self, **sections: Any) -> "Scene":
        """A copy with whole sections replaced (for sweeps and the GUI)."""
        return replace(self, **sections)


TOP_KEYS = (
    "name", "description", "effects", "drive", "lift", "follower", "valve", "spring", "loads",
    "linkage", "seat", "solver", *OWNED_SECTIONS, "gear",
)


def load_scene(path: str | os.PathLike, overrides: list[str] | tuple[str, ...] = ()) -> Scene:
    """Read and validate a scene file; `overrides` are "section.key=value" strings (TOML values)."""
    # errors name the file as given; its relative data files are found beside the file itself
    # (`explorer simulate table_demo.toml` from any directory reads the package's data)
    written = read_scene_data(path)
    data = apply_overrides(written, overrides, str(path))
    folder = os.path.dirname(os.path.abspath(find_scene(path)))
    return scene_from_dict(data, str(path), folder=folder, written=written)


def read_scene_data(path: str | os.PathLike, overrides=()) -> dict:
    """A scene file's TOML tables, overrides applied, not yet validated (InputError: the file
    cannot be read or is no TOML)."""
    file = str(path)  # errors name the file as the user gave it
    data = read_regular(find_scene(path), file=file, key="-", limit=MAX_SCENE_FILE_BYTES)
    try:
        # "utf-8-sig": the byte-order mark Windows editors put first is not TOML; drop it
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(file, "-", "not a UTF-8 text file") from None
    return _toml_data(text, file, overrides)


# tomllib and copy.deepcopy recurse once per level of nesting: a few thousand nested arrays or
# tables end in RecursionError. No scene nests deeper than a few levels.
MAX_NESTING = 32


def loads_scene(text: str, source: str = "<memory>", overrides=()) -> Scene:
    written = _toml_data(text, source, ())
    return scene_from_dict(apply_overrides(written, overrides, source), source, written=written)


def _toml_data(text: str, source: str, overrides) -> dict:
    try:
        data = toml_loads(text, source)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(source, "-", f"malformed TOML: {_first_line(str(exc))}") from None
    except RecursionError:
        raise InputError(source, "-", f"malformed TOML: nested too deeply (at most {MAX_NESTING} levels)") from None
    _check_nesting(data, source, "-")
    # freshly parsed: no copy to protect (apply_overrides copies before it changes anything)
    return apply_overrides(data, overrides, source) if overrides else data


def _first_line(text: str) -> str:
    return text.splitlines()[0] if text else text


def _check_nesting(value, file: str, key: str) -> None:
    """InputError if arrays/tables nest deeper than MAX_NESTING (iterative: no recursion)."""
    stack = [(value, 0)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_NESTING:
            raise InputError(file, key, f"nested too deeply (at most {MAX_NESTING} levels of arrays and tables)")
        if isinstance(node, dict):
            stack.extend((v, depth + 1) for v in node.values())
        elif isinstance(node, list):
            stack.extend((v, depth + 1) for v in node)


def apply_overrides(data: dict, overrides, file: str) -> dict:
    """Apply "a.b.c=value" overrides to a copy of the raw TOML dict. Values are TOML when they
    parse as TOML (numbers, booleans, quoted strings, arrays), otherwise taken as plain strings,
    so `--set lift.height="12 mm"` and `--set lift.height=12mm` both work."""
    data = copy.deepcopy(data)
    for item in overrides:
        if "=" not in item:
            raise InputError(file, item, "override must look like section.key=value")
        dotted, text = item.split("=", 1)
        dotted = dotted.strip()
        parts = dotted.split(".")
        if not dotted or any(not p for p in parts):
            raise InputError(file, dotted or item, "override key must be dotted, such as lift.height")
        if len(parts) > MAX_NESTING:
            raise InputError(file, dotted[:60], f"override key nested too deeply (at most {MAX_NESTING} levels)")
        try:
            value = toml_loads(f"v = {text}", file, dotted)["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        except RecursionError:
            raise InputError(file, dotted, f"value nested too deeply (at most {MAX_NESTING} levels)") from None
        _check_nesting(value, file, dotted)
        if isinstance(value, str) and value == text.strip() and "=" in value:
            # "drive.rpm=5=6": a second "=" is a typo, not part of a quantity or a name
            raise InputError(file, dotted, "more than one '=' in the override; write section.key=value")
        node = data
        for part in parts[:-1]:
            child = node.setdefault(part, {})
            if not isinstance(child, dict):
                raise InputError(file, dotted, f"'{part}' is not a table")
            node = child
        node[parts[-1]] = value
    return data


def _rpm(drive_t) -> float:
    """drive.rpm in rev/min (InputError naming it when it is no speed or beyond MAX_RPM)."""
    rpm_si = drive_t.quantity("rpm", "speed", positive=True)
    raw_rpm = drive_t.raw("rpm")
    # a bare number is rev/min already: keep it exact rather than round-tripping through rad/s
    rpm = float(raw_rpm) if isinstance(raw_rpm, (int, float)) else rpm_si * 60.0 / (2.0 * math.pi)
    if rpm > MAX_RPM:
        raise drive_t.error("rpm", f"more than {MAX_RPM:g} rpm is outside any valve gear, got {echo(raw_rpm)}")
    return rpm


def _written_rpm(written: Mapping[str, Any] | None, file: str, rpm: float) -> float | None:
    """The file's own drive.rpm (rev/min) where an override changed it, else None. A file without
    one (the override supplies it) has no other speed: None. A file whose own value is no speed is
    refused though overridden: a lift law in time units defines its cam at that value."""
    drive = written.get("drive") if isinstance(written, Mapping) else None
    if not isinstance(drive, Mapping) or "rpm" not in drive:
        return None
    try:
        own = _rpm(Table({"rpm": drive["rpm"]}, file, "drive"))
    except InputError as exc:
        raise InputError(file, exc.key, f"{exc.reason} (the file's value, whatever --set says: a lift law in time "
                         "units defines its cam at it)") from None
    return None if own == rpm else own


def scene_from_dict(data: Mapping[str, Any], file: str = "<memory>", folder: str = "",
                    written: Mapping[str, Any] | None = None) -> Scene:
    """The validated scene of TOML tables `data`; `written`: the file's tables before overrides,
    whose drive.rpm defines the cam of laws given in time units (Drive.cam_omega)."""
    top = Table(data, file, "")
    top.reject_unknown(TOP_KEYS)
    name = top.string("name", default=Path(file).stem if file != "<memory>" else "scene")
    description = top.string("description", default="")

    effects_raw = top.raw("effects", default=["kinematics"])
    if not isinstance(effects_raw, list) or not all(isinstance(e, str) for e in effects_raw):
        raise top.error("effects", "expected a list of effect names, such as [\"kinematics\", \"lash\"]")
    for effect in effects_raw:
        if effect not in effect_table.EFFECTS:
            raise top.error("effects", f"unknown effect {echo(effect)}; known: {', '.join(effect_table.names())}")
    effects = tuple(dict.fromkeys(effects_raw))
    if not effects:
        raise top.error("effects", "list at least one effect")

    drive_t = top.table("drive")
    drive_t.reject_unknown(("rpm", "operating_range"))
    rpm = _rpm(drive_t)
    drive = Drive(rpm=rpm, operating_range=_operating_range(drive_t), written_rpm=_written_rpm(written, file, rpm))

    follower = _parse_follower(top.table("follower", required=False), file)
    lift = _parse_lift(top.table("lift"), file)
    valve = _parse_valve(top.table("valve", required=False))
    spring = _parse_spring(top.table("spring", required=False))
    loads = _parse_loads(top.table("loads", required=False), file)
    linkage = _parse_linkage(top.table("linkage", required=False), follower.ratio)
    seat = _parse_seat(top.table("seat", required=False) or Table({}, file, "seat"))
    solver = _parse_solver(top.table("solver", required=False) or Table({}, file, "solver"))

    needs = set(effect_table.order(effects))
    for section, given in (("valve", valve), ("spring", spring), ("linkage", linkage)):
        if given is None and any(section in effect_table.effect_spec(e).requires for e in needs):
            users = [f"'{name}'" for name, spec in effect_table.EFFECTS.items() if section in spec.requires]
            who = f"effect {users[0]} needs" if len(users) == 1 else f"effects {', '.join(users[:-1])} and {users[-1]} need"
            raise InputError(file, section, f"missing section: {who} [{section}] {SECTION_KEYS[section]}")
    if spring is not None and spring.elements > 0:
        _check_spring_chain(spring, valve, seat, loads, file)

    fields: dict[str, Any] = dict(
        name=name, description=description, effects=effects, drive=drive, lift=lift, follower=follower,
        valve=valve, spring=spring, loads=loads, linkage=linkage, seat=seat, solver=solver, source=file,
        folder=folder,
    )
    for section, target in OWNED_SECTIONS.items():
        table = top.table(section, required=False)
        fields[section] = resolve(target)(table, fields) if table is not None or section in needs else None
    check_train(fields, file)  # [[linkage.elements]] and [hla] against the valve and the seat (issue #25)
    fields["gear"] = _parse_gear(top.table("gear", required=False), fields)
    law = laws.law_spec(lift.law)
    if law.parser is not None:
        fields["lift"] = replace(lift, options=law.parse(top.table("lift"), fields))
    for section in law.sections:
        if fields.get(section) is None:
            raise InputError(file, section, f"missing section: lift.law = '{law.name}' takes the lift from [{section}]")
    if law.gear_made and not gear_table.gear(follower.type).makes_lift:
        makers = [name for name, gear in gear_table.GEARS.items() if gear.makes_lift]
        raise InputError(file, "lift.law", f"lift.law = 'gear' is for the {' and '.join(makers)} gears")
    return Scene(**fields)


def _parse_gear(table: Table | None, fields: dict) -> GearSpec | None:
    """[gear] through the follower's gear (its keys, checks and geometry, at load time)."""
    gear = gear_table.gear(fields["follower"].type)
    if table is not None and not gear.parts:
        owners = [name for name, other in gear_table.GEARS.items() if other.parts]
        raise InputError(fields["source"], "gear", f"[gear] describes the gears {', '.join(owners)}; follower.type is "
                         f"{gear.type!r}")
    return gear.parse(table, fields)


def _operating_range(t: Table) -> tuple[float, float] | None:
    """[drive] operating_range = [LOWEST, HIGHEST] speeds (bare numbers rev/min), or None."""
    if not t.has("operating_range"):
        return None
    raw = t.raw("operating_range")
    if not isinstance(raw, list) or len(raw) != 2:
        raise t.error("operating_range", "expected [LOWEST, HIGHEST], such as [\"800 rpm\", \"6500 rpm\"]")
    ends = []
    for i, value in enumerate(raw):
        item = Table({"v": value}, t.file, t.key(f"operating_range[{i}]"))
        si = item.quantity("v", "speed", positive=True)
        ends.append(float(value) if isinstance(value, (int, float)) and not isinstance(value, bool)
                    else float(f"{si * 60.0 / (2.0 * math.pi):.12g}"))  # "800 rpm" is 800, not 799.99...
    if not ends[0] < ends[1] <= MAX_RPM:
        raise t.error("operating_range", f"needs LOWEST < HIGHEST <= {MAX_RPM:g} rpm, got {raw!r}")
    return ends[0], ends[1]


def _parse_follower(t: Table | None, file: str) -> Follower:
    if t is None:
        return Follower()
    t.reject_unknown(("type", "base_radius", "roller_radius", "offset", "ratio"))
    follower = Follower(
        type=t.string("type", gear_table.DEFAULT, choices=gear_table.gear_types()),
        base_radius=t.quantity("base_radius", "length", 0.03, positive=True),
        roller_radius=t.quantity("roller_radius", "length", 0.0, nonnegative=True),
        offset=t.quantity("offset", "length", 0.0),
        ratio=t.number("ratio", 1.0, minimum=0.0, open_minimum=True, maximum=MAX_RATIO),
    )
    if abs(follower.offset) >= follower.base_radius + follower.roller_radius:
        raise t.error("offset", "offset must be smaller than base radius + roller radius")
    return follower


def _parse_lift(t: Table, file: str) -> LiftSpec:
    spec = laws.law_spec(t.string("law", choices=laws.names()))
    law = spec.name
    t.reject_unknown(laws.COMMON_KEYS + spec.keys)
    if not spec.event_keys:
        return LiftSpec(law=law)
    unless = spec.shaped_unless
    shaped = spec.shaped and not (unless is not None and t.has(unless[0]) and t.raw(unless[0]) == unless[1])
    height = t.quantity("height", "length", positive=True) if shaped else t.quantity("height", "length", 0.0, nonnegative=True)
    start = t.quantity("start", "angle", 0.0)
    if not 0.0 <= start < 2.0 * math.pi:
        raise t.error("start", "must lie in [0 deg, 360 deg)")
    if height > MAX_LIFT:
        raise t.error("height", f"more than {MAX_LIFT:g} m of lift is outside any valve gear, got {echo(t.raw('height'))}")
    rise = t.quantity("rise", "angle", positive=True) if shaped else t.quantity("rise", "angle", 0.0, nonnegative=True)
    dwell = t.quantity("dwell", "angle", 0.0, nonnegative=True)
    ret = t.quantity("return", "angle", rise, positive=True) if shaped else t.quantity("return", "angle", 0.0, nonnegative=True)
    return_law = t.string("return_law", None, choices=laws.closed_form_names()) if t.has("return_law") else None
    for key, angle in (("rise", rise), ("return", ret)):
        if shaped and angle < MIN_EVENT_ANGLE:
            raise t.error(key, f"must be at least {math.degrees(MIN_EVENT_ANGLE):g} deg, got {angle:.3g} rad")
    if rise + dwell + ret > 2.0 * math.pi * (1.0 + 1e-12):
        total = math.degrees(rise + dwell + ret)
        raise t.error("return", f"rise + dwell + return = {total:.6g} deg exceeds 360 deg")
    return LiftSpec(law=law, height=height, start=start, rise=rise, dwell=dwell, ret=ret, return_law=return_law)


def _parse_valve(t: Table | None) -> Valve | None:
    if t is None:
        return None
    t.reject_unknown(("mass", "lash", "oscillating_mass"))
    mass = t.quantity("mass", "mass", positive=True)
    m1 = t.quantity("oscillating_mass", "mass", positive=True) if t.has("oscillating_mass") else None
    if m1 is not None and m1 > mass:
        raise t.error("oscillating_mass", "cannot exceed the total moving mass valve.mass")
    return Valve(mass=mass, lash=t.quantity("lash", "length", 0.0, nonnegative=True), oscillating_mass=m1)


SPRING_GEOMETRY = ("wire_diameter", "coil_diameter", "active_coils", "shear_modulus")
# a rate or mass given besides the wire geometry must agree with it within this fraction
SPRING_CONSISTENCY = 0.01


def _parse_spring(t: Table | None) -> Spring | None:
    if t is None:
        return None
    t.reject_unknown(("preload", "rate", "mass", *SPRING_GEOMETRY, "density", "solid_height", "free_length",
                      "elements", "damping_ratio"))
    preload = t.quantity("preload", "force", nonnegative=True)
    geometry = [name for name in SPRING_GEOMETRY if t.has(name)]
    rate = mass = None
    d = D = n = None
    if geometry:
        missing = [name for name in SPRING_GEOMETRY if not t.has(name)]
        if missing:
            raise t.error(missing[0], f"missing key: the rate G*d^4/(8*D^3*n) needs {', '.join(SPRING_GEOMETRY)}")
        d = t.quantity("wire_diameter", "length", positive=True)
        D = t.quantity("coil_diameter", "length", positive=True)
        n = t.number("active_coils", minimum=0.0, open_minimum=True)
        G = t.quantity("shear_modulus", "pressure", positive=True)
        if not D > d:
            raise t.error("coil_diameter", "must exceed spring.wire_diameter (mean coil diameter)")
        rate = G * d**4 / (8.0 * D**3 * n)
        if t.has("density"):
            # the active coils' wire: length pi D n, section pi d^2 / 4
            mass = t.quantity("density", "density", positive=True) * math.pi**2 * d * d * D * n / 4.0
    elif t.has("density"):
        raise t.error("density", "gives the spring's mass only with its wire geometry "
                      f"({', '.join(SPRING_GEOMETRY)}); or give spring.mass")
    rate = _agreeing(t, "rate", "stiffness", rate, "N/m")
    mass = _agreeing(t, "mass", "mass", mass, "kg")
    elements = int(t.number("elements", 0, integer=True, minimum=0, maximum=MAX_SPRING_ELEMENTS))
    free = t.quantity("free_length", "length", positive=True) if t.has("free_length") else None
    solid = t.quantity("solid_height", "length", positive=True) if t.has("solid_height") else None
    if free is not None and solid is not None and not solid < free:
        raise t.error("solid_height", "must be below spring.free_length")
    return Spring(
        preload=preload, rate=rate, mass=mass, elements=elements,
        damping_ratio=t.number("damping_ratio", 0.0, minimum=0.0, maximum=1.0, open_maximum=True),
        free_length=free, solid_height=solid, wire_diameter=d, coil_diameter=D, active_coils=n,
    )


MAX_SPRING_ELEMENTS = 256


def _agreeing(t: Table, key: str, dimension: str, from_geometry: float | None, unit: str) -> float:
    """The spring's `key`: as given, from the wire geometry, or both when they agree within 1 %
    (else an error naming both)."""
    if not t.has(key):
        return 0.0 if from_geometry is None else from_geometry
    given = t.quantity(key, dimension, nonnegative=True)
    if from_geometry is not None and abs(given - from_geometry) > SPRING_CONSISTENCY * from_geometry:
        source = ("spring.shear_modulus, wire_diameter, coil_diameter, active_coils" if key == "rate"
                  else "spring.density and the wire geometry")
        raise t.error(key, f"{given:.6g} {unit} disagrees with {from_geometry:.6g} {unit} from {source} by "
                      f"{100.0 * abs(given / from_geometry - 1.0):.3g} % (at most {100 * SPRING_CONSISTENCY:g} %)")
    return given


def _parse_seat(t: Table) -> Seat:
    t.reject_unknown(("restitution", "stiffness", "damping"))
    if t.has("stiffness") and t.has("restitution"):
        raise t.error("stiffness", "an elastic seat resolves the bounce in time: give seat.stiffness (and "
                      "seat.damping) or seat.restitution, not both")
    if t.has("damping") and not t.has("stiffness"):
        raise t.error("damping", "is the damping of an elastic seat: give seat.stiffness too")
    return Seat(
        restitution=t.number("restitution", 0.0, minimum=0.0, maximum=1.0, open_maximum=True),
        stiffness=t.quantity("stiffness", "stiffness", positive=True) if t.has("stiffness") else None,
        damping=t.quantity("damping", "damping", 0.0, nonnegative=True),
    )


def _check_spring_chain(spring: Spring, valve, seat: Seat, loads, file: str) -> None:
    """What the spring as a chain of masses (spring.elements > 0) needs from the other sections."""
    if not spring.mass > 0.0:
        raise InputError(file, "spring.elements", "the spring as masses needs its mass: give spring.mass, or "
                         "spring.density with its wire geometry")
    if not spring.rate > 0.0:
        raise InputError(file, "spring.elements", "the spring as masses needs spring.rate > 0 (or its wire geometry)")
    if seat.stiffness is None:
        raise InputError(file, "seat.stiffness", "with spring.elements > 0 the valve's bounce on its seat is "
                         "resolved in time: give seat.stiffness (and seat.damping) instead of a restitution")
    if valve is not None and valve.oscillating_mass is not None:
        raise InputError(file, "valve.oscillating_mass", "with spring.elements > 0 the spring's mass is modelled "
                         "itself: give valve.mass without the spring's share, and no oscillating_mass")


def _parse_loads(t: Table | None, file: str) -> Loads:
    if t is None:
        return Loads()
    t.reject_unknown(("friction", "closing"))
    friction = t.quantity("friction", "force", 0.0, nonnegative=True)
    closing: dict[str, float] = {}
    ct = t.table("closing", required=False)
    if ct is not None:
        for key in ct.data:
            closing[key] = ct.quantity(key, "force")
    return Loads(friction=friction, closing=MappingProxyType(closing))


def _parse_linkage(t: Table | None, follower_ratio: float = 1.0) -> Linkage | None:
    if t is None:
        return None
    t.reject_unknown(("stiffness", "damping", "elements", "contact"))
    return Linkage(
        stiffness=t.quantity("stiffness", "stiffness", positive=True),
        damping=t.quantity("damping", "damping", 0.0, nonnegative=True),
        elements=parse_elements(t, follower_ratio),
        one_sided=t.string("contact", "one-sided", choices=CONTACTS) == "one-sided",
    )


def _parse_solver(t: Table) -> Solver:
    known = solvers.scene_options()
    t.reject_unknown(("method", "steps_per_revolution", *known))
    steps = t.number("steps_per_revolution", 3600, integer=True)
    if steps < MIN_STEPS:
        raise t.error("steps_per_revolution", f"too few steps: {steps:.6g} (at least {MIN_STEPS})")
    if steps > MAX_STEPS:
        raise t.error("steps_per_revolution", f"too many steps: {steps:.6g} (at most {MAX_STEPS})")
    method = t.string("method", solvers.DEFAULT, choices=solvers.names())
    # every option given is checked (by the first solver that has it), the method's own are kept
    values = {name: _solver_option(t, option) for name, option in known.items() if t.has(name)}
    own = {option.name: values.get(option.name, option.default) for option in solvers.solver(method).scene_options}
    return Solver(method=method, steps_per_revolution=int(steps), options=MappingProxyType(own))


def _solver_option(t: Table, option) -> Any:
    if option.choices:
        return t.string(option.name, option.default, choices=option.choices)
    return t.number(option.name, option.default, minimum=option.minimum, maximum=option.maximum)
