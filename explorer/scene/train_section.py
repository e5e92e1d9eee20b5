"""Scene keys of the valve train of lumped masses (issue #25): [[linkage.elements]] and [hla].

    [linkage]                 # the joint at the valve (pad-valve tip, or the cam's when alone),
    stiffness = "150 N/um"    # referred to the valve, as without elements
    damping = "50 N*s/m"
    contact = "one-sided"     # that joint: "one-sided" (can open: valve.lash is its gap) or "bonded"

    [[linkage.elements]]      # the parts between the cam and the valve, the follower first
    name = "lifter"           # letters, digits, _ (column names: part_lifter_...)
    mass = "45 g"             # or inertia = "2.1 kg*cm**2" with arm = "38 mm": J / arm^2 at the valve
    ratio = 1.6               # valve travel per travel of this part (default follower.ratio)
    stiffness = "80 N/um"     # the joint on its cam side (the cam contact for the first), along
    damping = "20 N*s/m"      #   this part's travel, referred to the valve by / ratio^2
    lash = "0 mm"             # that joint's gap, along this part's travel
    contact = "one-sided"     # that joint: "one-sided" or "bonded" (the first: one-sided, the cam)

    [hla]                     # a hydraulic lash adjuster under the first part's pivot (a finger's)
    plunger_mass = "12 g"
    plunger_diameter = "12 mm"
    clearance = "6 um"        # radial, plunger in its bore
    leak_length = "8 mm"
    viscosity = "10 mPa*s"
    chamber_volume = "200 mm**3"
    supply_pressure = "3 bar"
    spring_rate = "5 N/mm"    # the plunger spring (> 0)
    spring_preload = "15 N"
    lever = 0.7               # valve travel per plunger travel (end-pivot finger: ratio - 1)
    travel = "1 mm"           # outward travel to the plunger's stop (optional)
    revolutions = 6           # simulated; the last is reported (the adjuster carries its state)
    # optional: bulk_modulus, aeration, polytropic_index, reference_pressure, eccentricity,
    # cracking_pressure, check_diameter, discharge_coefficient, oil_density,
    # refill_pressure_drop, stop_stiffness, stop_damping (dynamics/hla.py says what each is)

Values are SI after loading (units at the edge); the model refers them to the valve when it is
built (dynamics/train.py: TrainModel.from_scene), so a sweep that varies a scene value varies
the model.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, fields

from typing import TYPE_CHECKING

from ..core.errors import InputError
from ..core.reader import Table

if TYPE_CHECKING:  # imported when an [hla] section is read: a scene without one loads no dynamics
    from ..dynamics.hla import HLA

MAX_ELEMENTS = 32  # parts between the cam and the valve: a train has a handful
MAX_REVOLUTIONS = 200  # the adjuster's revolutions: each costs one revolution's solve
ELEMENT_KEYS = ("name", "mass", "inertia", "arm", "ratio", "stiffness", "damping", "lash", "contact")
CONTACTS = ("one-sided", "bonded")
NAME = re.compile(r"[a-z][a-z0-9_]{0,31}")
RESERVED = ("valve", "cam", "spring", "seat", "hla", "plunger", "coil")


@dataclass(frozen=True)
class LinkageElement:
    """A part between the cam and the valve as the scene gives it (SI, along its own travel)."""

    name: str
    mass: float  # kg, moving with the part's travel (0 when given by inertia)
    ratio: float  # valve travel per travel of the part at its cam-side joint
    stiffness: float  # N/m, the joint on its cam side, along the part's travel
    damping: float = 0.0  # N*s/m
    lash: float = 0.0  # m
    one_sided: bool = True
    inertia: float = 0.0  # kg*m^2 about its pivot (a rocker, a finger)
    arm: float = 0.0  # m, pivot to the valve's contact: the inertia counts inertia / arm^2 at the valve

    @property
    def referred_mass(self) -> float:
        """kg at the valve: inertia / arm^2, or mass / ratio^2."""
        return self.inertia / self.arm**2 if self.inertia > 0.0 else self.mass / self.ratio**2


@dataclass(frozen=True)
class HLASection:
    hla: HLA
    revolutions: int = 6


def parse_elements(t: Table, follower_ratio: float) -> tuple[LinkageElement, ...]:
    """[[linkage.elements]] of the [linkage] table t (absent: ())."""
    raw = t.raw("elements", None)  # optional: a linkage without parts is one joint
    if raw is None:
        return ()
    if not isinstance(raw, list) or not all(isinstance(e, dict) for e in raw):
        raise t.error("elements", "expected an array of tables [[linkage.elements]], one per part from the cam")
    if not raw:
        raise t.error("elements", "list at least one part, or leave [[linkage.elements]] out")
    if len(raw) > MAX_ELEMENTS:
        raise t.error("elements", f"at most {MAX_ELEMENTS} parts, got {len(raw)}")
    out: list[LinkageElement] = []
    for i, data in enumerate(raw):
        e = Table(data, t.file, f"{t.key('elements')}[{i}]")
        e.reject_unknown(ELEMENT_KEYS)
        name = e.string("name")
        if not NAME.fullmatch(name):
            raise e.error("name", f"{name[:40]!r}: a lower-case letter, then letters, digits or _ (at most 32)")
        if name in RESERVED or any(p.name == name for p in out):
            raise e.error("name", f"{name!r} is taken (by another part, or: {', '.join(RESERVED)})")
        ratio = e.number("ratio", follower_ratio, minimum=0.0, open_minimum=True, maximum=100.0)
        if e.has("inertia") or e.has("arm"):
            if e.has("mass"):
                raise e.error("mass", "give the part's mass, or its inertia and arm, not both")
            inertia = e.quantity("inertia", "inertia", positive=True)
            arm = e.quantity("arm", "length", positive=True)
            mass = 0.0
        else:
            mass, inertia, arm = e.quantity("mass", "mass", positive=True), 0.0, 0.0
        contact = e.string("contact", "one-sided", choices=CONTACTS)
        if i == 0 and contact != "one-sided":
            raise e.error("contact", "the first part rides on the cam: its cam-side joint is one-sided")
        out.append(LinkageElement(
            name=name, mass=mass, ratio=ratio, stiffness=e.quantity("stiffness", "stiffness", positive=True),
            damping=e.quantity("damping", "damping", 0.0, nonnegative=True),
            lash=e.quantity("lash", "length", 0.0, nonnegative=True), one_sided=contact == "one-sided",
            inertia=inertia, arm=arm))
    return tuple(out)


HLA_REQUIRED = ("plunger_mass", "plunger_diameter", "clearance", "leak_length", "viscosity", "chamber_volume",
                "supply_pressure", "spring_rate")
# key -> (dimension, default (SI; ... required), positive)
HLA_KEYS: dict[str, tuple[str, object, bool]] = {
    "plunger_mass": ("mass", ..., True),
    "plunger_diameter": ("length", ..., True),
    "clearance": ("length", ..., True),
    "leak_length": ("length", ..., True),
    "viscosity": ("viscosity", ..., True),
    "chamber_volume": ("volume", ..., True),
    "supply_pressure": ("pressure", ..., False),
    "bulk_modulus": ("pressure", 1.5e9, True),
    "reference_pressure": ("pressure", 10e6, True),
    "cracking_pressure": ("pressure", 0.0, False),
    "check_diameter": ("length", 2e-3, True),
    "oil_density": ("density", 850.0, True),
    "refill_pressure_drop": ("pressure", 0.1e6, True),
    "spring_rate": ("stiffness", ..., True),
    "spring_preload": ("force", 0.0, False),
    "travel": ("length", None, True),
    "stop_stiffness": ("stiffness", 1e8, True),
    "stop_damping": ("damping", 0.0, False),
}
HLA_NUMBERS: dict[str, tuple[float, float, float, bool]] = {  # key -> (default, minimum, maximum, open maximum)
    "aeration": (0.0, 0.0, 0.9, False),
    "polytropic_index": (1.0, 1.0, 1.67, False),
    "eccentricity": (0.0, 0.0, 1.0, False),
    "discharge_coefficient": (0.7, 0.01, 1.0, False),
}


def parse_hla_section(t: Table, fields_so_far: dict) -> HLASection:
    """[hla] -> HLASection (the adjuster's parameters in SI and how many revolutions to run)."""
    from ..dynamics.hla import HLA  # local: the adjuster model (numpy) loads only for a scene with [hla]

    t.reject_unknown((*HLA_KEYS, *HLA_NUMBERS, "lever", "revolutions"))
    values: dict = {}
    for key, (dimension, default, positive) in HLA_KEYS.items():
        if default is None and not t.has(key):
            values[key] = None
            continue
        values[key] = t.quantity(key, dimension, default, positive=positive, nonnegative=not positive)
    for key, (default, lo, hi, open_hi) in HLA_NUMBERS.items():
        values[key] = t.number(key, default, minimum=lo, maximum=hi, open_maximum=open_hi)
    follower = fields_so_far.get("follower")
    ratio = follower.ratio if follower is not None else 1.0
    default_lever = ratio - 1.0 if ratio > 1.0 else None
    if not t.has("lever") and default_lever is None:
        raise t.error("lever", "missing key: the valve's travel per unit plunger travel (an end-pivot finger: its "
                      "ratio - 1; follower.ratio is not above 1 here)")
    values["lever"] = t.number("lever", default_lever, minimum=0.0, open_minimum=True, maximum=100.0)
    if values["reference_pressure"] <= values["supply_pressure"]:
        raise t.error("reference_pressure", "must exceed hla.supply_pressure (the aerated oil's secant modulus runs "
                      "from the supply pressure to it)")
    if values["cracking_pressure"] >= values["supply_pressure"] and values["supply_pressure"] > 0.0:
        raise t.error("cracking_pressure", "must be below hla.supply_pressure (the check valve would never open)")
    if 2.0 * values["clearance"] >= values["plunger_diameter"]:
        raise t.error("clearance", "is the radial clearance: it must be far below the plunger's radius")
    revolutions = int(t.number("revolutions", 6, integer=True, minimum=1, maximum=MAX_REVOLUTIONS))
    known = {f.name for f in fields(HLA)}
    return HLASection(HLA(**{k: v for k, v in values.items() if k in known}), revolutions)


def check_train(scene_fields: dict, file: str) -> None:
    """What a train of parts or an adjuster needs of the other sections (InputError else)."""
    linkage, hla = scene_fields.get("linkage"), scene_fields.get("hla")
    elements = linkage.elements if linkage is not None else ()
    if not elements and hla is None:
        if linkage is not None and not linkage.one_sided:
            raise InputError(file, "linkage.contact", "without [[linkage.elements]] the linkage rides on the cam: "
                             "its joint is one-sided")
        return
    if hla is not None and not elements:
        raise InputError(file, "hla", "the adjuster sits under a lever: give the lever (finger or rocker) as "
                         "[[linkage.elements]]")
    if linkage is None:
        raise InputError(file, "linkage", "missing section: [[linkage.elements]] need [linkage] stiffness (the joint "
                         "at the valve)")
    seat, valve = scene_fields["seat"], scene_fields.get("valve")
    if seat.stiffness is None:
        key = "hla" if hla is not None and not elements else "linkage.elements"
        raise InputError(file, "seat.stiffness", f"with {key} the valve's bounce on its seat is resolved in time: give "
                         "seat.stiffness (and seat.damping) instead of a restitution")
    if valve is not None and valve.oscillating_mass is not None:
        raise InputError(file, "valve.oscillating_mass", "with [[linkage.elements]] each part's mass is its own: give "
                         "valve.mass alone")
