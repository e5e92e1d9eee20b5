"""Units at the boundary, including the seeds' technical system."""

import math

import pytest

from explorer.core.errors import InputError
from explorer.core.units import G0, to_si


def si(value, dim):
    return to_si(value, dim, file="f.toml", key="k")


def test_kgf_is_exact():
    assert si("385 kgf", "force") == pytest.approx(385 * 9.80665, rel=1e-15)
    assert si("1 kp", "force") == pytest.approx(G0, rel=1e-15)


def test_technical_mass_unit():
    # Schenker: M = 2.9 kgf*s^2/m = 28.439 kg
    assert si("2.9 kgf*s**2/m", "mass") == pytest.approx(2.9 * 9.80665, rel=1e-14)
    assert si("2.9 TME", "mass") == pytest.approx(2.9 * 9.80665, rel=1e-14)


def test_technical_atmosphere_and_stiffness():
    assert si("4 at", "pressure") == pytest.approx(4 * 98066.5, rel=1e-12)
    # k = 1 800 000 kg/m (kgf per metre) in Schenker's Fig. 4
    assert si("1800000 kgf/m", "stiffness") == pytest.approx(1.8e6 * G0, rel=1e-14)


def test_bare_numbers_are_documented_defaults():
    assert si(0.02, "length") == 0.02
    assert si(90, "angle") == pytest.approx(math.pi / 2)
    assert si(60, "speed") == pytest.approx(2 * math.pi)
    assert si("3000 rpm", "speed") == pytest.approx(100 * math.pi)


@pytest.mark.parametrize("value,dim", [("5 mm", "mass"), ("3 kg", "force"), ("abc", "length"), ("nan mm", "length"),
                                       (True, "length"), ([1], "length"), ("", "force"), ("1 m", "speed")])
def test_bad_quantities(value, dim):
    with pytest.raises(InputError) as info:
        si(value, dim)
    assert str(info.value).startswith("f.toml: k: ")


@pytest.mark.parametrize("value, dim", [("10 m m", "length"), ("1 k N", "force"), ("3 N / m m", "stiffness")])
def test_spaces_inside_a_unit_are_not_dropped(value, dim):
    """pint reads "10 m m" as 10 m**2 and "1 k N" as nonsense: the fast path must not turn them
    into "mm" and "kN" (it used to drop every space)."""
    with pytest.raises(InputError):
        si(value, dim)


def test_spaces_around_operators_are_fine():
    assert si("2.9 kgf * s**2 / m", "mass") == pytest.approx(2.9 * G0, rel=1e-15)
    assert si("25 N / mm", "stiffness") == pytest.approx(25e3, rel=1e-15)
