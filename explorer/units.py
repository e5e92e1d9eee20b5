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
        if dimension == "angle":
            return math.radians(number)
        if dimension == "speed":
            return number * 2.0 * math.pi / 60.0
        return number
    if not isinstance(value, str):
        raise InputError(file, key, f"expected a number or a string with units, got {type(value).__name__}")
    text = value.strip()
    if not text:
        raise InputError(file, key, "empty value")
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
            number = quantity.to("rad/s").magnitude
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
