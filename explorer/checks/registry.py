"""The table of design rules: one line each (explorer.checks.rule.RuleSpec; explorer.checks.rule.Rule
lists, numbered, what a rule must provide), with every default limit, its source and how firm it
is. Adding a rule: its module under explorer/checks/rules/ and one line of RULES (or
`register_rule(spec)`, whose Registration undoes it). docs/guide/checks.md's rule table is
generated from the built-in lines (`python -m explorer.checks`; tests/test_checks.py holds the page
to it).

Import-light: names and numbers only; a rule's measure is a "module:function" reference, imported
when a design is checked.
"""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Mapping

from ..core.plugins import Registration, Registry, resolve
from .rule import Plotted, Rule, RuleSpec, Setting  # noqa: F401 (Rule: the type measure_function returns)

_R = "explorer.checks.rules"
DEG = math.pi / 180.0
RPM = 2.0 * math.pi / 60.0  # rad/s per rev/min
IN_PER_DEG = 0.0254 / DEG  # m/rad per in/deg

# display units: name -> (factor from SI, offset)
UNITS: Mapping[str, tuple[float, float]] = MappingProxyType({
    "": (1.0, 0.0), "deg": (1.0 / DEG, 0.0), "rpm": (1.0 / RPM, 0.0), "m/s": (1.0, 0.0), "MPa": (1e-6, 0.0),
    "mm": (1e3, 0.0), "mm/deg": (1e3 * DEG, 0.0), "degC": (1.0, -273.15), "um": (1e6, 0.0),
})
# the SI unit of a value whose display unit is the key (the JSON report names both)
SI_UNITS: Mapping[str, str] = MappingProxyType({
    "": "", "deg": "rad", "rpm": "rad/s", "m/s": "m/s", "MPa": "Pa", "mm": "m", "mm/deg": "m/rad", "degC": "K",
    "um": "m",
})

NORTON_DOM = "R. L. Norton, Design of Machinery, ch. 8 (cam design: pressure angle), and his DYNACAM help"
TRADE_CAM = "cam designer's notes, camprofiledesigns.com ('cam talk', Jan 2024)"
SHIGLEY_SPRINGS = "J. E. Shigley et al., Mechanical Engineering Design, ch. 10 (mechanical springs)"
SHIGLEY_CRITICAL = (SHIGLEY_SPRINGS.replace("(mechanical springs)", "'Critical frequency of helical springs'") +
                    ", after Wolford and Smith; f1 of both ends fixed: A. M. Wahl, Mechanical Springs (1944)")
HAMROCK = ("B. J. Hamrock, S. R. Schmid, B. O. Jacobson, Fundamentals of Machine Elements, lubrication chapter: "
           "film parameter ranges (boundary < 1, partial 1-5, elastohydrodynamic 3-10)")
SEED_004 = "seed 004 ('Oel- und Gasmaschinen', p. 404)"

SPRING_OPTIONS = (
    Setting("wire", "chrome-silicon", "choice", "", "the valve-spring wire (ASTM A401) unless the design names "
            "another; S_ut = A/d^m: explorer/mechanics/materials.py", "the wire's certificate governs",
            choices=("music-wire", "oil-tempered", "hard-drawn", "chrome-vanadium", "chrome-silicon")),
    Setting("correction", "wahl", "choice", "", "A. M. Wahl, Mechanical Springs (1944): K = (4C-1)/(4C-4) + 0.615/C",
            "textbook", choices=("wahl", "bergstrasser", "direct-shear")),
)

_BUILTIN: tuple[RuleSpec, ...] = (
    RuleSpec("pressure_angle", f"{_R}.pressure_angle:measure", "Pressure angle", "largest |pressure angle|", "deg",
             "max", (
                 Setting("fail_translating", 30.0 * DEG, "angle", "deg", NORTON_DOM + ": translating roller follower "
                         "below about 30 deg", "textbook rule of thumb"),
                 Setting("fail_oscillating", 35.0 * DEG, "angle", "deg", NORTON_DOM + ": oscillating (pivoted) "
                         "follower below about 35 deg", "textbook rule of thumb"),
                 Setting("warn", None, "angle", "deg", "none by default", "-"),
             ), "kinematics", (Plotted("pressure_angle_deg", 180.0 / math.pi, mirrored=True),)),
    RuleSpec("self_locking", f"{_R}.self_locking:measure", "Self-locking margin",
             "smallest 90 - rho - |alpha| while the cam lifts",
             "deg", "min", (
                 Setting("fail", 0.0, "angle", "deg", SEED_004 + ": self-locking at alpha + rho = 90 deg",
                         "geometric necessity"),
                 Setting("warn", 20.0 * DEG, "angle", "deg", SEED_004 + ": alpha must stay 'well below' 90 deg - rho; "
                         "the seed gives no figure", "judgement"),
             ), "kinematics"),
    RuleSpec("roller_curvature", f"{_R}.roller_curvature:measure", "Cam curvature (roller)",
             "smallest convex pitch radius / roller radius", "", "min", (
                 Setting("fail", 1.0, "number", "", "undercut: a convex pitch radius at or below the roller's folds "
                         "the envelope into a cusp (" + NORTON_DOM.split(",")[0] + ", cam curvature)",
                         "geometric necessity", minimum=0.0),
                 Setting("warn", 2.0, "number", "", "smallest convex pitch radius 2-3 x the roller radius "
                         "(machine-design lecture notes; Norton)", "rule of thumb", minimum=0.0),
             ), "kinematics"),
    RuleSpec("face_curvature", f"{_R}.face_curvature:measure", "Cam curvature (flat face)",
             "smallest radius of curvature rho = Rb + s + s''", "mm", "min", (
                 Setting("fail", 0.0, "length", "mm", "R. L. Norton, Cam Design and Manufacturing Handbook: "
                         "rho > 0 everywhere for a flat-faced follower, else a cusp", "geometric necessity",
                         minimum=0.0),
                 Setting("warn", None, "length", "mm", "none by default (a minimum radius for grinding or "
                         "stress is the design's)", "-", minimum=0.0),
             ), "kinematics"),
    RuleSpec("face_width", f"{_R}.face_width:measure", "Face width left",
             "face half-width - the contact's farthest reach - half the gear's face margin", "mm", "min", (
                 Setting("fail", 0.0, "length", "mm", "R. L. Norton, Cam Design and Manufacturing Handbook: the face "
                         "must cover the contact offset ds/dtheta on both sides (the contact line's far end across "
                         "the lobe's width and offset; the gear's face_margin included)", "geometric necessity",
                         minimum=0.0),
                 Setting("warn", None, "length", "mm", "none by default", "-", minimum=0.0),
             ), "kinematics"),
    RuleSpec("ramp_velocity", f"{_R}.ramp_velocity:measure", "Opening velocity at the end of the lash ramp",
             "lifter lift per cam angle at the lash take-up (the valve's over the gear's ratio where [lift] is "
             "the valve's; the valve's where the gear has no lifter)", "mm/deg", "max", (
                 Setting("fail", 0.002 * IN_PER_DEG, "lift_rate", "mm/deg", TRADE_CAM + ": below about 0.002 in/deg "
                         "for a solid tappet, a lobe (tappet-side) figure", "trade practice", minimum=0.0),
                 Setting("warn", None, "lift_rate", "mm/deg", "none by default", "-", minimum=0.0),
             ), "dynamics", qualifier="lifter side"),
    RuleSpec("seating_velocity", f"{_R}.seating_velocity:measure", "Seating velocity",
             "hardest seat impact: the valve's downward (closing) speed at the seat, a magnitude (elastic; rigid "
             "without a linkage); a sweep's seating_velocity_m_s is the same impact signed, < 0", "m/s", "max", (
                 Setting("fail", 1.0, "velocity", "m/s", TRADE_CAM + ": below about 1.0 m/s (40 in/s) for high-end "
                         "valve trains", "trade practice", minimum=0.0),
                 Setting("warn", 0.76, "velocity", "m/s", TRADE_CAM + ": about 0.76 m/s (30 in/s) for others",
                         "trade practice", minimum=0.0),
             ), "dynamics", (Plotted("valve_velocity_m_s", sign=-1.0),),  # the closing (negative) velocity
             qualifier="downward, magnitude"),
    RuleSpec("float_margin", f"{_R}.float_margin:measure", "Float margin",
             "speed of first separation while the valve is open - highest operating speed", "rpm", "min", (
                 Setting("fail", 100.0 * RPM, "speed", "rpm", "Race Engine Technology, 'Peace and harmony': float "
                         "a couple of hundred rpm above the highest engine speed (200 engine rpm = 100 camshaft rpm "
                         "on a four-stroke)", "trade practice", minimum=0.0),
                 Setting("warn", None, "speed", "rpm", "none by default", "-", minimum=0.0),
             ), "dynamics"),
    RuleSpec("seat_bounce", f"{_R}.seat_bounce:measure", "Seat bounce", "bounces per revolution", "", "max", (
                 Setting("fail", 0.0, "number", "", "Schenker 1902, sec. 4: a valve that leaves its prescribed "
                         "motion 'may land and jump off again'; it should land once", "judgement", minimum=0.0),
                 Setting("warn", None, "number", "", "none by default", "-", minimum=0.0),
                 Setting("min_height", 5e-6, "length", "um", "bounces lower than this are not counted (judgement: "
                         "the order of a seat face's flatness)", "judgement", minimum=0.0),
             ), "dynamics"),
    RuleSpec("hertz_stress", f"{_R}.hertz_stress:measure", "Contact (Hertz) stress", "largest Hertz pressure", "MPa",
             "max", (
                 Setting("material", "scene", "choice", "", "'scene': the [contact] allowable (seed 004's by "
                         "engine, or allowable_stress); others: explorer/mechanics/materials.py",
                         "material-specific", choices=("scene", "large-gas", "diesel", "through-hardened-300HB",
                                                       "carburized-grade-1", "carburized-grade-2")),
                 Setting("fail", None, "pressure", "MPa", "the material's allowable (setting `material`)",
                         "material-specific", minimum=0.0),
                 Setting("warn", None, "pressure", "MPa", "none by default", "-", minimum=0.0),
             ), "contact",
             # the line contact's, a bucket tappet's crown, a pushrod train's lifter tip
             (Plotted("hertz_stress_Pa"), Plotted("face_hertz_stress_Pa"), Plotted("tip_hertz_stress_Pa"))),
    RuleSpec("dynamic_hertz_stress", f"{_R}.dynamic_hertz_stress:measure", "Contact (Hertz) stress, elastic train",
             "largest Hertz pressure under the elastic train's cam force", "MPa", "max", (
                 Setting("material", "scene", "choice", "", "as hertz_stress", "material-specific",
                         choices=("scene", "large-gas", "diesel", "through-hardened-300HB", "carburized-grade-1",
                                  "carburized-grade-2")),
                 Setting("fail", None, "pressure", "MPa", "the material's allowable (setting `material`)",
                         "material-specific", minimum=0.0),
                 Setting("warn", None, "pressure", "MPa", "none by default", "-", minimum=0.0),
             ), "dynamics",
             (Plotted("dynamic_hertz_stress_Pa"), Plotted("dynamic_face_hertz_stress_Pa"))),
    RuleSpec("film_parameter", f"{_R}.film_parameter:measure", "Film parameter (lambda)",
             "smallest h_min / composite roughness over the loaded contact", "", "min", (
                 Setting("fail", 1.0, "number", "", HAMROCK + ": below 1 the asperities carry the load",
                         "regime boundary, not a limit: flat-tappet noses run at 0.2-0.4 on additives", minimum=0.0),
                 Setting("warn", 3.0, "number", "", HAMROCK + ": full EHL from about 3", "regime boundary",
                         minimum=0.0),
             ), "tribology"),
    RuleSpec("entrainment_reversal", f"{_R}.entrainment_reversal:measure", "Entrainment reversal",
             "cam angles where the entrainment velocity passes through zero (loaded contact)", "", "max", (
                 Setting("fail", None, "number", "", "none by default", "-", minimum=0.0),
                 Setting("warn", 0.0, "number", "", "the steady EHL film vanishes at zero entrainment (squeeze "
                         "alone carries it): docs/theory/tribology.md", "a flag, not a limit", minimum=0.0),
             ), "tribology"),
    RuleSpec("flash_temperature", f"{_R}.flash_temperature:measure", "Flash temperature (Blok)",
             "largest contact temperature: bulk + Blok's flash", "degC", "max", (
                 Setting("fail", None, "temperature", "degC", "none by default: the oil's scuffing temperature "
                         "(FZG test, ISO/TR 13989-1) belongs here", "-"),
                 Setting("warn", 423.15, "temperature", "degC", "Blok's postulate of a critical contact temperature; "
                         "150 degC is an order of magnitude for mineral oils without EP additives",
                         "weak: enter the oil's own"),
             ), "tribology"),
    RuleSpec("spring_stress", f"{_R}.spring_stress:measure", "Spring shear stress", "shear stress at full lift",
             "MPa", "max", (
                 *SPRING_OPTIONS,
                 Setting("fail", None, "pressure", "MPa", "45 % of the wire's S_ut (setting `wire`; Katy Spring & "
                         "Mfg., common spring materials)", "maker's data", minimum=0.0),
                 Setting("warn", None, "pressure", "MPa", "none by default", "-", minimum=0.0),
             ), "spring"),
    RuleSpec("spring_fatigue", f"{_R}.spring_fatigue:measure", "Spring fatigue (Goodman)",
             "Goodman safety factor with Zimmerli's data", "", "min", (
                 *SPRING_OPTIONS,
                 Setting("peened", True, "bool", "", "valve springs are shot-peened (Zimmerli: 398/534 MPa "
                         "peened, 241/379 MPa unpeened)", "design fact to state"),
                 Setting("fail", 1.0, "number", "", SHIGLEY_SPRINGS + ": the Goodman line", "criterion", minimum=0.0),
                 Setting("warn", 1.5, "number", "", SHIGLEY_SPRINGS + ": design factor n_f = 1.5 of its fatigue "
                         "design examples", "textbook design factor", minimum=0.0),
             ), "spring"),
    RuleSpec("coil_bind", f"{_R}.coil_bind:measure", "Coil bind",
             "fractional overrun to closure at full lift, xi = F_solid / F_max - 1",
             "", "min", (
                 Setting("fail", 0.0, "number", "", "coils solid at full lift", "geometric necessity", minimum=0.0),
                 Setting("warn", 0.15, "number", "", SHIGLEY_SPRINGS + ", static service: fractional overrun to "
                         "closure xi >= 0.15, F_solid = (1 + xi) F_max", "textbook design value", minimum=0.0),
             ), "spring"),
    RuleSpec("spring_surge", f"{_R}.spring_surge:measure", "Spring surge",
             "distance of a surge frequency from a strong cam harmonic (share of the surge frequency)", "", "min", (
                 Setting("fail", 0.05, "number", "", "judgement: a surge mode within 5 % of a strong harmonic "
                         "resonates", "judgement", minimum=0.0),
                 Setting("warn", 0.10, "number", "", "judgement: twice the fail band (the 15-20 x rule of the "
                         "spring books is spring_frequency's)", "judgement", minimum=0.0),
                 Setting("strength", 0.10, "number", "", "a harmonic counts as strong from 10 % of the largest",
                         "judgement", minimum=0.0),
                 Setting("modes", 3.0, "number", "", "surge modes checked", "judgement", minimum=1.0),
             ), "spring"),
    RuleSpec("spring_frequency", f"{_R}.spring_frequency:measure", "Spring frequency ratio",
             "first natural frequency f1 = (1/2) sqrt(k/m_active) / the camshaft's frequency at the top speed", "",
             "min", (
                 Setting("fail", 15.0, "number", "", SHIGLEY_CRITICAL + ": f1 at least 15 x the forcing frequency "
                         "(the lower figure)", "textbook rule of thumb", minimum=0.0),
                 Setting("warn", 20.0, "number", "", SHIGLEY_CRITICAL + ": 15-20 x (the upper figure)",
                         "textbook rule of thumb", minimum=0.0),
             ), "spring"),
    RuleSpec("trip_latch", f"{_R}.trip_latch:measure", "Trip-gear latch hold",
             "throw-off speed of the latch - highest operating speed", "rpm", "min", (
                 Setting("fail", 0.0, "speed", "rpm", "the valve leaves the latch before the trip above its throw-off "
                         "speed (seeds 000, 003)", "geometric necessity", minimum=0.0),
                 Setting("warn", None, "speed", "rpm", "none by default", "-", minimum=0.0),
             ), "gear"),
    RuleSpec("rocking_cam_swing", f"{_R}.rocking_cam_swing:measure", "Rocking-cam swing",
             "swing beyond the top arc's reach", "deg", "min", (
                 Setting("fail", None, "angle", "deg", "none by default", "-"),
                 Setting("warn", 0.0, "angle", "deg", SEED_004 + ": one contour serves opening and closing; a swing "
                         "that ends on the flank never reaches its full rise", "geometric fact"),
             ), "gear"),
)

RULES: Registry[RuleSpec] = Registry("design rule", {spec.name: spec for spec in _BUILTIN})


def register_rule(spec: RuleSpec, *, replace: bool = False) -> Registration:
    """Add a design rule to the table (one call; `.undo()` or a `with` block removes it again)."""
    return RULES.register(spec.name, spec, replace=replace)


def rules() -> tuple[RuleSpec, ...]:
    """Every rule of the table, in table order (the order of the report)."""
    return tuple(RULES.entries())


def rule_names() -> tuple[str, ...]:
    return RULES.names()


def rule(name: str) -> RuleSpec:
    """The rule `name` (KeyError naming the known ones)."""
    return RULES[name]


def measure_function(spec: RuleSpec) -> "Rule":
    return resolve(spec.measure)  # the one resolver of plug-in references (explorer.core.plugins)


def show(value, unit: str) -> float:
    """An SI value in a display unit of UNITS."""
    factor, offset = UNITS[unit]
    return value * factor + offset


def rules_markdown() -> str:
    """The built-in rules' table as markdown (docs/guide/checks.md)."""
    lines = ["| rule | judges | setting | default | source | firmness |", "|---|---|---|---|---|---|"]
    for spec in _BUILTIN:
        first = True
        for s in spec.settings:
            if s.default is None:
                default = "-"
            elif s.dimension in ("choice", "bool"):
                default = str(s.default).lower() if isinstance(s.default, bool) else str(s.default)
            else:
                default = f"{show(s.default, s.unit):.6g} {s.unit}".strip()
            judged = f"`{spec.name}`" if first else ""
            what = f"{spec.title}: {spec.quantity} ({'at most' if spec.sense == 'max' else 'at least'})" if first else ""
            cells = [judged, what, s.name, default, s.source, s.firmness]
            lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
            first = False
    return "\n".join(lines) + "\n"

