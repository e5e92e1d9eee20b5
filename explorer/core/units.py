"""Units at the boundary: scene strings such as "30 mm" or "385 kgf" become SI floats.

pint is imported lazily (it costs ~0.2 s) so that `import explorer` stays fast; the registry is
built once per process because building it is the expensive part.

Bare numbers (no unit) mean SI base units for their dimension (m, kg, N, N/m, s, Pa, N*s/m),
except angles, which are degrees, and speeds, which are rev/min. This is documented in the
README's scene reference.
"""

from __future__ import annotations

import functools
import math
import re

from .errors import InputError, echo

# dimension name -> (pint dimensionality string, unit used for bare numbers, SI unit)
DIMENSIONS: dict[str, tuple[str, str, str]] = {
    "length": ("[length]", "m", "m"),
    "mass": ("[mass]", "kg", "kg"),
    "force": ("[force]", "N", "N"),
    "stiffness": ("[force]/[length]", "N/m", "N/m"),
    "damping": ("[force]*[time]/[length]", "N*s/m", "N*s/m"),
    "pressure": ("[pressure]", "Pa", "Pa"),
    "time": ("[time]", "s", "s"),
    "angle": ("", "deg", "rad"),
    "speed": ("1/[time]", "rpm", "rad/s"),
    "area": ("[area]", "m**2", "m**2"),
    "velocity": ("[length]/[time]", "m/s", "m/s"),
    "acceleration": ("[length]/[time]**2", "m/s**2", "m/s**2"),
    "jerk": ("[length]/[time]**3", "m/s**3", "m/s**3"),
    "snap": ("[length]/[time]**4", "m/s**4", "m/s**4"),  # the fourth derivative (a polydyne's wanted spline)
    "torque": ("[force]*[length]", "N*m", "N*m"),
    "density": ("[mass]/[length]**3", "kg/m**3", "kg/m**3"),
    # a lubricant and its surfaces ([lubricant]) and the design rules' thresholds ([checks])
    "viscosity": ("[pressure]*[time]", "Pa*s", "Pa*s"),
    "pressure_viscosity": ("1/[pressure]", "1/Pa", "1/Pa"),
    "temperature": ("[temperature]", "K", "K"),  # absolute: "90 degC" is 363.15 K
    "lift_rate": ("[length]", "m/rad", "m/rad"),  # lift per cam angle ("0.002 in/deg"); pint counts angles as 1
    "volume": ("[length]**3", "m**3", "m**3"),  # a hydraulic lash adjuster's chamber
    "inertia": ("[mass]*[length]**2", "kg*m**2", "kg*m**2"),  # a rocker's about its pivot
    "dimensionless": ("", "", ""),
}


@functools.lru_cache(maxsize=1)
def registry():
    import pint

    ureg = pint.UnitRegistry()
    # The seeds' "technical" system: kgf (= kp) and the technical mass unit kgf*s**2/m.
    # pint knows kgf and at already; "TME" (technische Masseneinheit) is added for convenience.
    ureg.define("technical_mass_unit = kgf * s**2 / m = TME")
    if "kp" not in ureg:
        ureg.define("kilopond = kilogram_force = kp")
    return ureg


def to_si(value, dimension: str, *, file: str, key: str) -> float:
    """Convert a scene value (number or string with units) to an SI float, or raise InputError."""
    number = _to_si(value, dimension, file=file, key=key)
    if not math.isfinite(number):  # a finite number whose conversion overflows (1e308 rpm -> rad/s)
        raise InputError(file, key, f"{echo(value)} is too large to express in SI units")
    return number


def _to_si(value, dimension: str, *, file: str, key: str) -> float:
    if dimension not in DIMENSIONS:
        raise KeyError(dimension)
    dim, bare_unit, si_unit = DIMENSIONS[dimension]
    if isinstance(value, bool):
        raise InputError(file, key, f"expected a {dimension} such as '10 {bare_unit or '1'}', got a boolean")
    if isinstance(value, (int, float)):
        number = plain_number(value, file=file, key=key)
        return _bare_to_si(number, dimension)
    if not isinstance(value, str):
        raise InputError(file, key, f"expected a number or a string with units, got {type(value).__name__}")
    text = value.strip()
    if not text:
        raise InputError(file, key, "empty value")
    parse_quantity(text, file=file, key=key)  # the grammar first: the fast path must not accept more
    fast = _fast_to_si(text, dimension)
    if fast is not None:
        return fast
    return _pint_to_si(value, text, dimension, file=file, key=key)


# Largest and smallest non-zero magnitude of a plain number (a ratio, a coefficient) beyond its
# own limits: 1e-320 is subnormal, 10**400 does not fit a float. Quantities with a unit have
# the narrower ranges of explorer.core.ranges.
MAX_MAGNITUDE = 1e300
MIN_MAGNITUDE = 1e-300
MAX_NUMBER_CHARS = 50  # a hand-written number longer than this is a paste error or an attack


def plain_number(value, *, file: str, key: str) -> float:
    """A TOML int or float as a finite float, or InputError (the key's range is checked by the
    caller, which states it)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**300:
        # float() of a 400-digit int raises OverflowError
        raise InputError(file, key, f"number out of range: at most {MAX_MAGNITUDE:g} in size, got {len(str(abs(value)))} digits")
    number = float(value)
    if not math.isfinite(number):
        raise InputError(file, key, f"value must be finite, got {short_repr(value)}")
    return number


def check_magnitude(number: float, shown, *, file: str, key: str) -> float:
    """`number` unless it is beyond MAX_MAGNITUDE or subnormal-small: for plain numbers without
    a physical range of their own."""
    if abs(number) > MAX_MAGNITUDE or 0.0 < abs(number) < MIN_MAGNITUDE:
        raise InputError(file, key, f"number out of range: 0 or between {MIN_MAGNITUDE:g} and {MAX_MAGNITUDE:g} "
                         f"in size, got {short_repr(shown)}")
    return number


def unit_scale(unit: str, dimension: str, *, file: str, key: str) -> float:
    """The SI size of one `unit` (a unit key's value: angle_unit, lift_unit, ...). A blank unit is
    refused: "1 " would be a bare number, read silently as the dimension's SI unit (degrees for
    an angle)."""
    if not str(unit).strip():
        raise InputError(file, key, "empty unit: write one, such as mm, deg or m/s**2")
    return to_si(f"1 {unit}", dimension, file=file, key=key)


def short_repr(value) -> str:
    """repr of a value for a message, cut so that a hostile value cannot flood the terminal."""
    return echo(value)


# The quantity grammar: a decimal number, then a unit expression of unit names, "*", "/", small
# integer powers ("**n" or "^n") and parentheses. Nothing is evaluated: pint's own parser would
# compute "10**10**10 mm" (for ever), multiply numbers inside the unit ("5=6" is 30) and accept
# "(-8)**(1/3)" (complex), so only the validated unit part ever reaches pint's registry.
_QUANTITY = re.compile(
    r"(?P<number>[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]{1,4})?)\s*(?P<unit>.*)", re.DOTALL
)
_NON_FINITE = re.compile(r"[+-]?(?:nan|inf|infinity)\b.*", re.IGNORECASE | re.DOTALL)
_UNIT_TOKEN = re.compile(r"\s*(?:(?P<name>[A-Za-z_µμΩ]+)|(?P<power>\*\*|\^)\s*(?P<exp>[+-]?[0-9]+)|(?P<op>[*/()])|(?P<one>1(?=\s*/)))")
MAX_UNIT_POWER = 4
MAX_UNIT_DEPTH = 3
MAX_UNIT_CHARS = 60


def parse_quantity(text: str, *, file: str, key: str) -> tuple[float, str]:
    """(magnitude, canonical unit expression, "" for none) of "number [unit]", or InputError."""
    match = _QUANTITY.fullmatch(text)
    if match is not None and match.group("unit").lstrip().startswith(("**", "^")):
        raise InputError(file, key, f"cannot read {short_repr(text)} as a quantity: numbers are not raised to powers "
                         "(write the number out, such as 1e10)")
    if match is None:
        if _NON_FINITE.fullmatch(text):
            raise InputError(file, key, f"value must be finite, got {short_repr(text)}")
        raise InputError(file, key, f"cannot read {short_repr(text)} as a quantity: expected a number and a unit, such as '10 mm'")
    number_text = match.group("number")
    if len(number_text) > MAX_NUMBER_CHARS:
        raise InputError(file, key, f"number too long: at most {MAX_NUMBER_CHARS} characters, got {len(number_text)}")
    number = float(number_text)
    if not math.isfinite(number):
        raise InputError(file, key, f"value must be finite, got {short_repr(text)}")
    if number == 0.0 and re.search(r"[1-9]", number_text.split("e")[0].split("E")[0]):
        raise InputError(file, key, f"number out of range: {short_repr(text)} is too small to be told from 0")
    unit = match.group("unit").strip()
    if unit.startswith("/"):  # "3000/min": per minute
        unit = "1" + unit
    return number, _parse_unit(unit, text, file=file, key=key)


def _parse_unit(unit: str, text: str, *, file: str, key: str) -> str:
    """Validate a unit expression and write it canonically (powers as **n), or InputError."""
    if not unit:
        return ""

    def bad(reason: str) -> InputError:
        return InputError(file, key, f"cannot read {short_repr(text)} as a quantity: {reason}")

    if len(unit) > MAX_UNIT_CHARS:
        raise bad(f"unit longer than {MAX_UNIT_CHARS} characters")
    tokens: list[tuple[str, str]] = []
    pos = 0
    while pos < len(unit):
        m = _UNIT_TOKEN.match(unit, pos)
        if m is None or m.end() == pos:
            raise bad(f"unexpected {unit[pos:].strip()[:10]!r} in the unit (a unit is names with *, / and powers **n)")
        kind = next(k for k in ("name", "power", "op", "one") if m.group(k) is not None)
        if kind == "name" and tokens and tokens[-1][0] == "name":
            # pint reads "m m" as m**2 and "k N" as nonsense: juxtaposition is not a product here
            raise bad("a space inside the unit; write products with '*'")
        if kind == "power":
            exponent = int(m.group("exp"))
            if not (exponent and abs(exponent) <= MAX_UNIT_POWER):
                raise bad(f"unit powers must be whole numbers from -{MAX_UNIT_POWER} to {MAX_UNIT_POWER} (not 0)")
            tokens.append(("power", str(exponent)))
        else:
            tokens.append((kind, m.group(kind)))
        pos = m.end()
    # recursive descent over: expr := factor (("*" | "/") factor)* ; factor := (name | "(" expr ")") power?
    i = 0

    def factor(depth: int) -> str:
        nonlocal i
        if i >= len(tokens):
            raise bad("the unit ends after an operator")
        kind, tok = tokens[i]
        if kind == "name":
            i += 1
            out = tok
        elif tok == "(":
            if depth >= MAX_UNIT_DEPTH:
                raise bad(f"more than {MAX_UNIT_DEPTH} levels of parentheses")
            i += 1
            out = "(" + expr(depth + 1) + ")"
            if i >= len(tokens) or tokens[i][1] != ")":
                raise bad("unbalanced parentheses")
            i += 1
        else:
            raise bad(f"unexpected {echo(tok)} in the unit")
        if i < len(tokens) and tokens[i][0] == "power":
            out += f"**{tokens[i][1]}"
            i += 1
        return out

    def expr(depth: int) -> str:
        nonlocal i
        if depth == 0 and tokens and tokens[0][0] == "one":  # "1/min": a rate
            i = 1
            if i >= len(tokens) or tokens[i][1] != "/":
                raise bad("a number inside the unit")
            i += 1
            out = "1/" + factor(depth)
        else:
            out = factor(depth)
        while i < len(tokens) and tokens[i][1] in "*/" and tokens[i][0] == "op":
            op = tokens[i][1]
            i += 1
            out += op + factor(depth)
        return out

    canonical = expr(0)
    if i != len(tokens):
        raise bad(f"unexpected {echo(tokens[i][1])} in the unit")
    return canonical


def _bare_to_si(number: float, dimension: str) -> float:
    """A number without a unit: SI, except angles (degrees) and speeds (rev/min)."""
    if dimension == "angle":
        return math.radians(number)
    if dimension == "speed":
        return number * 2.0 * math.pi / 60.0
    return number


def _pint_to_si(value, text: str, dimension: str, *, file: str, key: str) -> float:
    """The general path: the unit expression, validated by the grammar, looked up in pint's
    registry (slow the first time: the registry is built); the number never goes to pint."""
    dim, bare_unit, si_unit = DIMENSIONS[dimension]
    number, unit = parse_quantity(text, file=file, key=key)
    if not unit:
        return _bare_to_si(number, dimension)
    ureg = registry()
    try:
        units = ureg.parse_units(unit)
    except Exception as exc:  # pint raises many types for unknown names
        raise InputError(file, key, f"cannot read {short_repr(value)} as a quantity: unknown unit {echo(unit)} "
                         f"({type(exc).__name__})") from None
    quantity = ureg.Quantity(number, units)
    try:
        if dimension == "speed":
            if quantity.check("[]"):
                raise InputError(file, key, f"{short_repr(value)} has no unit of rotational speed (use rpm or rad/s)")
            if not quantity.check("1/[time]"):
                raise InputError(file, key, f"{short_repr(value)} is not a rotational speed (dimension {quantity.dimensionality}; use rpm or rad/s)")
            converted = quantity.to("rad/s").magnitude
            if "radian" not in str(ureg.get_root_units(quantity.units)[1]):
                # "3000 1/min", "50 Hz": a rate without an angle counts revolutions (pint would
                # take it as rad/s, 2 pi too slow)
                converted *= 2.0 * math.pi
        elif dimension == "angle":
            # pint counts radians as dimensionless, so "50 percent" would pass as 50 % of a radian
            if str(ureg.get_root_units(quantity.units)[1]) != "radian":
                raise InputError(file, key, f"{short_repr(value)} is not an angle (use deg or rad, or a bare number of degrees)")
            converted = quantity.to("rad").magnitude
        elif dimension == "dimensionless":
            converted = quantity.to("dimensionless").magnitude
        else:
            if not quantity.check(dim):
                raise InputError(
                    file, key, f"{short_repr(value)} is not a {dimension} (dimension {quantity.dimensionality}, expected {dim})"
                )
            converted = quantity.to(si_unit).magnitude
    except InputError:
        raise
    except Exception as exc:
        raise InputError(file, key, f"{short_repr(value)} cannot be expressed as a {dimension} ({type(exc).__name__})") from None
    converted = float(converted)
    if not math.isfinite(converted):
        raise InputError(file, key, f"value must be finite, got {short_repr(value)}")
    return converted


# Fast path for "number unit" strings with the common units of scene files: a fresh process
# then loads a scene without building pint's registry (~0.2 s). Each factor is exact by the
# unit's definition (kgf = 9.80665 N, deg = pi/180 rad, ...) and is checked against pint in
# tests/test_units.py; any other unit, or a unit of the wrong dimension, takes the pint path,
# which also writes the error messages.
_G = 9.80665
_FAST_UNITS: dict[str, tuple[str, float]] = {
    "m": ("length", 1.0), "cm": ("length", 1e-2), "mm": ("length", 1e-3), "um": ("length", 1e-6),
    "µm": ("length", 1e-6), "in": ("length", 0.0254), "inch": ("length", 0.0254),
    "kg": ("mass", 1.0), "g": ("mass", 1e-3), "t": ("mass", 1e3),
    "kgf*s**2/m": ("mass", _G), "kgf*s^2/m": ("mass", _G), "TME": ("mass", _G),
    "N": ("force", 1.0), "kN": ("force", 1e3), "kgf": ("force", _G), "kp": ("force", _G),
    "N/m": ("stiffness", 1.0), "N/mm": ("stiffness", 1e3), "kN/m": ("stiffness", 1e3),
    "kN/mm": ("stiffness", 1e6), "kgf/m": ("stiffness", _G), "kgf/mm": ("stiffness", _G * 1e3),
    "kgf/cm": ("stiffness", _G * 1e2),
    "N*s/m": ("damping", 1.0),
    "Pa": ("pressure", 1.0), "kPa": ("pressure", 1e3), "MPa": ("pressure", 1e6), "bar": ("pressure", 1e5),
    "at": ("pressure", _G * 1e4), "kgf/cm**2": ("pressure", _G * 1e4), "kgf/cm^2": ("pressure", _G * 1e4),
    "N/mm**2": ("pressure", 1e6), "N/mm^2": ("pressure", 1e6),
    "s": ("time", 1.0), "ms": ("time", 1e-3),
    "deg": ("angle", math.pi / 180.0), "degree": ("angle", math.pi / 180.0),
    "degrees": ("angle", math.pi / 180.0), "rad": ("angle", 1.0), "radian": ("angle", 1.0),
    "rpm": ("speed", 2.0 * math.pi / 60.0), "rad/s": ("speed", 1.0),
    "m**2": ("area", 1.0), "cm**2": ("area", 1e-4), "mm**2": ("area", 1e-6),
    "m/s": ("velocity", 1.0), "mm/s": ("velocity", 1e-3),
    "m/s**2": ("acceleration", 1.0), "m/s^2": ("acceleration", 1.0),
    "N*m": ("torque", 1.0), "kgf*m": ("torque", _G),
    "kg/m**3": ("density", 1.0), "kg/m^3": ("density", 1.0),
    "m**3": ("volume", 1.0), "mm**3": ("volume", 1e-9),
    "Pa*s": ("viscosity", 1.0), "mPa*s": ("viscosity", 1e-3),
    "kg*m**2": ("inertia", 1.0), "kg*cm**2": ("inertia", 1e-4), "kg*mm**2": ("inertia", 1e-6),
    "g*mm**2": ("inertia", 1e-9),
}
_NUMBER = re.compile(r"([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(.*)")
_OPERATOR_SPACES = re.compile(r"\s*([*/^])\s*")


def _fast_to_si(text: str, dimension: str) -> float | None:
    """SI value of "number [unit]" when the unit is in _FAST_UNITS with this dimension, else None."""
    match = _NUMBER.fullmatch(text)
    if match is None:
        return None
    number = float(match.group(1))
    if not math.isfinite(number):
        return None
    # spaces around operators do not matter ("kgf * s**2 / m"); any other space does: pint reads
    # "10 m m" as m**2 and "1 k N" as an unknown unit, so those must not become "mm" and "kN"
    unit = _OPERATOR_SPACES.sub(r"\1", match.group(2).strip())
    if not unit:  # a bare number written as a string: same meaning as the plain number
        return _bare_to_si(number, dimension)
    entry = _FAST_UNITS.get(unit)
    if entry is None or entry[0] != dimension:
        return None
    value = number * entry[1]
    return value if math.isfinite(value) else None


# Exact conversion factors, used where pint's overhead is not wanted (hot paths, tests of the seeds).
G0 = 9.80665  # m/s^2, standard gravity: 1 kgf = G0 N exactly
KGF = G0  # N per kgf
TECHNICAL_MASS = G0  # kg per kgf*s^2/m
AT = G0 * 1e4  # Pa per technical atmosphere (kgf/cm^2)


# Printed figures: a summary holds differences of equal quantities (a deceleration difference,
# a closure integral, a saving of zero) that come out as round-off, 1e-12 instead of 0. No
# length, force, speed, time, pressure ... this program prints means anything below a nano of its
# SI unit, so smaller magnitudes print as 0. Two kinds keep theirs, they are the figure:
# dimensionless relative errors (keys with "relative"), and quantities whose SI unit is so large
# against their working values that those lie far below the floor -- a hydraulic conductance in
# m^3/(s Pa): an adjuster's leak-down gap passes ~1e-14 m^3/s per Pa, its check valve ~1e-10 --
# named by their key's unit suffix (SMALL_SI_UNITS). Those are material and geometry figures (a
# Poiseuille or orifice law), never the difference of two equal figures, so they carry no such
# round-off. The rest keep 12 significant digits: 53.400000000000006 is 53.4, and no computed
# quantity here is known to better than that.
NOISE_FLOOR_SI = 1e-9
SMALL_SI_UNITS = ("_m3_s_Pa",)  # key suffixes: hydraulic conductance
PRINTED_DIGITS = 12


def printable(value: float, key: str = "") -> float:
    """`value` without round-off noise for printing: |value| < NOISE_FLOOR_SI -> 0.0 (unless
    `key` names a relative figure or ends in a unit of SMALL_SI_UNITS), 12 significant digits,
    and never -0.0."""
    if not math.isfinite(value):
        return value
    if abs(value) < NOISE_FLOOR_SI and "relative" not in key and not key.endswith(SMALL_SI_UNITS):
        return 0.0
    value = float(f"{value:.{PRINTED_DIGITS}g}")
    return value + 0.0  # -0.0 + 0.0 is +0.0


def figure(value: float, digits: int = 4, *, signed: bool = False, key: str = "") -> str:
    """The printed text of a computed figure: `printable` (round-off noise is 0, never -0), then
    `digits` significant digits; with `signed` a "+" before a positive figure, none before 0 (a
    constraint exactly at its limit has a slack of 0, not of "+0")."""
    value = printable(float(value), key)
    text = f"{value:.{digits}g}"
    return f"+{text}" if signed and value > 0.0 else text


def resolved(value, error):
    """`value` (scalar or array) rounded to the decade of its uncertainty `error` (>= 0, same
    shape): only the digits that mean something are kept, so a figure whose true value is 0 and
    whose computed value is its error (an FFT phase off by its aliasing, 2.4e-06 rad) prints as
    0. Where `error` is 0 or not finite the value is returned unchanged; never -0."""
    import numpy as np

    value = np.asarray(value, dtype=float)
    error = np.broadcast_to(np.asarray(error, dtype=float), value.shape)
    ok = np.isfinite(error) & (error > 0.0) & np.isfinite(value)
    step = np.where(ok, 10.0 ** np.ceil(np.log10(np.where(ok, error, 1.0))), 1.0)
    out = np.where(ok, np.round(value / step) * step, value) + 0.0
    return out if out.ndim else float(out)
