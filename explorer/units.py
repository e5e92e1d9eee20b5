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

from .errors import InputError

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
    "torque": ("[force]*[length]", "N*m", "N*m"),
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
    if dimension not in DIMENSIONS:
        raise KeyError(dimension)
    dim, bare_unit, si_unit = DIMENSIONS[dimension]
    if isinstance(value, bool):
        raise InputError(file, key, f"expected a {dimension} such as '10 {bare_unit or '1'}', got a boolean")
    if isinstance(value, (int, float)):
        number = float(value)
        if not math.isfinite(number):
            raise InputError(file, key, f"value must be finite, got {value!r}")
        return _bare_to_si(number, dimension)
    if not isinstance(value, str):
        raise InputError(file, key, f"expected a number or a string with units, got {type(value).__name__}")
    text = value.strip()
    if not text:
        raise InputError(file, key, "empty value")
    fast = _fast_to_si(text, dimension)
    if fast is not None:
        return fast
    return _pint_to_si(value, text, dimension, file=file, key=key)


def _bare_to_si(number: float, dimension: str) -> float:
    """A number without a unit: SI, except angles (degrees) and speeds (rev/min)."""
    if dimension == "angle":
        return math.radians(number)
    if dimension == "speed":
        return number * 2.0 * math.pi / 60.0
    return number


def _pint_to_si(value, text: str, dimension: str, *, file: str, key: str) -> float:
    """The general path: any unit expression pint understands (slow the first time: registry)."""
    dim, bare_unit, si_unit = DIMENSIONS[dimension]
    ureg = registry()
    try:
        quantity = ureg.Quantity(text)
    except Exception as exc:  # pint raises many types for bad text
        raise InputError(file, key, f"cannot read {value!r} as a quantity ({type(exc).__name__})") from None
    if not isinstance(quantity, ureg.Quantity):
        quantity = ureg.Quantity(float(quantity), bare_unit or "")
    if quantity.unitless and dimension not in ("angle", "dimensionless"):
        quantity = ureg.Quantity(quantity.magnitude, bare_unit)
    if dimension == "angle" and quantity.unitless:
        quantity = ureg.Quantity(quantity.magnitude, "deg")
    try:
        if dimension == "speed":
            if quantity.check("[]"):
                raise InputError(file, key, f"{value!r} has no unit of rotational speed (use rpm or rad/s)")
            if not quantity.check("1/[time]"):
                raise InputError(file, key, f"{value!r} is not a rotational speed (dimension {quantity.dimensionality}; use rpm or rad/s)")
            number = quantity.to("rad/s").magnitude
            if "radian" not in str(ureg.get_root_units(quantity.units)[1]):
                # "3000 1/min", "50 Hz": a rate without an angle counts revolutions (pint would
                # take it as rad/s, 2 pi too slow)
                number *= 2.0 * math.pi
        elif dimension in ("angle", "dimensionless"):
            number = quantity.to(si_unit or "dimensionless").magnitude
        else:
            if not quantity.check(dim):
                raise InputError(
                    file, key, f"{value!r} is not a {dimension} (dimension {quantity.dimensionality}, expected {dim})"
                )
            number = quantity.to(si_unit).magnitude
    except InputError:
        raise
    except Exception as exc:
        raise InputError(file, key, f"{value!r} cannot be expressed as a {dimension} ({type(exc).__name__})") from None
    number = float(number)
    if not math.isfinite(number):
        raise InputError(file, key, f"value must be finite, got {value!r}")
    return number


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


def from_si(number: float, unit: str) -> float:
    """SI float -> the given unit (for reports in the seeds' units, e.g. kgf)."""
    ureg = registry()
    return float(ureg.Quantity(number, _si_unit_for(unit, ureg)).to(unit).magnitude)


def _si_unit_for(unit: str, ureg) -> str:
    dims = ureg.Quantity(1.0, unit).dimensionality
    for dim, _bare, si in DIMENSIONS.values():
        if dim and ureg.Quantity(1.0, si).dimensionality == dims:
            return si
    return str(ureg.Quantity(1.0, unit).to_base_units().units)


# Exact conversion factors, used where pint's overhead is not wanted (hot paths, tests of the seeds).
G0 = 9.80665  # m/s^2, standard gravity: 1 kgf = G0 N exactly
KGF = G0  # N per kgf
TECHNICAL_MASS = G0  # kg per kgf*s^2/m
AT = G0 * 1e4  # Pa per technical atmosphere (kgf/cm^2)
