"""The valid range of every physical quantity a scene can hold, in one table.

A value outside its range is no valve gear (10**308 kg, a spring of 1e-320 N/m) and, left in,
ends as an overflow, a division by zero or a grid of petabytes deep inside a solver. So each
quantity is checked at load, and the message states the range. The ranges are per dimension,
wide enough for any engine from a model to a ship's, with a few keys narrower (KEY_RANGES).
The lower bound is for keys that must be positive (a mass, a stiffness, a diameter: divisors,
where a subnormal 1e-320 ended in a division by zero); where zero is allowed (a lash, a damping,
an offset) a tiny value is as good as none, only the upper bound applies, and a subnormal value
(below 2.2e-308 in SI) is taken as 0.
"""

from __future__ import annotations

import fnmatch
import math
import sys

from .errors import InputError, echo

_TURN = 2.0 * math.pi
_RPM = _TURN / 60.0  # rad/s per rev/min

SUBNORMAL = sys.float_info.min  # 2.2e-308: below it a float loses precision, and 1 / x overflows
# dimension -> (smallest non-zero size, largest size) in SI, and the unit the message uses
# with its factor from SI
RANGES: dict[str, tuple[float, float]] = {
    "length": (1e-9, 10.0),  # m: a nanometre of lash to a 10 m lever
    "mass": (1e-6, 1e4),  # kg
    "force": (1e-6, 1e7),  # N: up to a thousand tonnes-force
    "stiffness": (1e-3, 1e12),  # N/m
    "damping": (1e-6, 1e8),  # N*s/m
    "pressure": (1e-3, 1e13),  # Pa: moduli of diamond are ~1.2e12 Pa
    "time": (1e-9, 1e4),  # s
    "angle": (math.radians(1e-9), 10.0 * _TURN),  # rad: a nanodegree to ten turns
    "speed": (1e-3 * _RPM, 1e5 * _RPM),  # rad/s: 0.001 rpm (a revolution in 17 hours) to 100 000 rpm
    "area": (1e-18, 100.0),  # m**2
    "velocity": (1e-9, 1e4),  # m/s
    "acceleration": (1e-9, 1e9),  # m/s**2
    "jerk": (1e-9, 1e14),  # m/s**3
    "torque": (1e-6, 1e10),  # N*m (and N*m/rad: a lever's rotational stiffness)
    "viscosity": (1e-6, 1e4),  # Pa*s: a gas to a bitumen
    "pressure_viscosity": (1e-12, 1e-6),  # 1/Pa: mineral oils ~2e-8
    "temperature": (1.0, 2000.0),  # K
    "lift_rate": (1e-12, 10.0),  # m/rad
    "volume": (1e-15, 1.0),  # m**3: a cubic micrometre to a cubic metre
    "inertia": (1e-12, 1e4),  # kg*m**2
}
SHOWN_UNITS: dict[str, tuple[str, float]] = {
    "angle": ("deg", 180.0 / math.pi),
    "speed": ("rpm", 1.0 / _RPM),
    "length": ("m", 1.0), "mass": ("kg", 1.0), "force": ("N", 1.0), "stiffness": ("N/m", 1.0),
    "damping": ("N*s/m", 1.0), "pressure": ("Pa", 1.0), "time": ("s", 1.0), "area": ("m**2", 1.0),
    "velocity": ("m/s", 1.0), "acceleration": ("m/s**2", 1.0), "jerk": ("m/s**3", 1.0), "torque": ("N*m", 1.0),
    "viscosity": ("Pa*s", 1.0), "pressure_viscosity": ("1/Pa", 1.0), "temperature": ("K", 1.0),
    "lift_rate": ("m/rad", 1.0),
    "volume": ("m**3", 1.0), "inertia": ("kg*m**2", 1.0), "density": ("kg/m**3", 1.0),
}
# dotted key (glob) -> (smallest non-zero size, largest size) in SI, narrower than the dimension's
KEY_RANGES: dict[str, tuple[float, float]] = {
    "gear.air_dashpot.ambient_pressure": (1.0, 1e8),  # Pa: an ambient pressure, not a modulus
    # a rocking cam's contour is one polar curve about its pivot: its flank, and the swing before
    # it, lie within one turn of the body (lift_start + flank < 360 deg is checked with the section)
    "gear.rocking_cam.flank": (RANGES["angle"][0], _TURN),
    "gear.rocking_cam.lift_start": (RANGES["angle"][0], _TURN),
}
# plain numbers (no unit): key -> (minimum, maximum), checked by the key's parser
AMBIENT_TEMPERATURE = (1.0, 2000.0)  # K
OIL_DENSITY = (1.0, 2.0e4)  # kg/m**3
FRICTION_COEFFICIENT = (0.0, 10.0)


def range_for(dimension: str, key: str) -> tuple[float, float] | None:
    for pattern, bounds in KEY_RANGES.items():
        if fnmatch.fnmatchcase(key, pattern):
            return bounds
    return RANGES.get(dimension)


def check_range(number: float, dimension: str, *, file: str, key: str, shown, zero_allowed: bool = True) -> float:
    """`number` (SI) if its size is within the range of its dimension, else InputError with the
    range in the quantity's usual unit. Where zero is allowed (a lash, a damping), the lower
    bound does not apply: a tiny value is as good as none, and a subnormal one is taken as 0."""
    bounds = range_for(dimension, key)
    if bounds is None:
        return number
    lo, hi = bounds
    size = abs(number)
    unit, factor = SHOWN_UNITS[dimension]
    if zero_allowed:
        if size < SUBNORMAL:
            # below the smallest normal float a value is 0 to any measurement, but its arithmetic
            # is not: a spring rate of 1e-320 N/m hung the elastic solver (1e-307 does not)
            return 0.0
        if size <= hi:
            return number
        span = f"between 0 and {hi * factor:.6g} {unit}"
    else:
        if lo <= size <= hi:
            return number
        span = f"between {lo * factor:.6g} {unit} and {hi * factor:.6g} {unit}"
    raise InputError(file, key, f"must be {span}{' in size' if number < 0.0 else ''}, got {_short(shown)}")


def _short(value) -> str:
    return echo(value)
