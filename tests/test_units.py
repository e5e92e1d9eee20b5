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


def test_a_printed_figure_has_no_sign_on_zero_and_no_noise():
    """Issue #28.9: `design` printed a slack of 0 as "+0"; one formatter for signed figures."""
    from explorer.core.units import figure

    assert figure(0.0, signed=True) == "0" and figure(-0.0, signed=True) == "0"
    assert figure(-3e-13, signed=True) == "0"  # below the noise floor
    assert figure(0.25, signed=True) == "+0.25" and figure(-0.25, signed=True) == "-0.25"
    assert figure(1234.5678) == "1235" and figure(53.400000000000006, 6) == "53.4"


def test_resolved_keeps_the_digits_an_error_leaves():
    import numpy as np

    from explorer.core.units import resolved

    assert resolved(2.43e-06, 1.8e-06) == 0.0  # the phase: 0 within its error
    assert resolved(1.2217304763960306, 3e-7) == 1.221730  # decade of the error: 1e-6
    assert resolved(-1e-9, 1e-6) == 0.0 and str(resolved(-1e-9, 1e-6)) == "0.0"  # never -0
    out = resolved(np.array([3.14159265, 2.0, 5.0]), np.array([1e-3, 0.0, np.inf]))
    np.testing.assert_array_equal(out, [3.142, 2.0, 5.0])  # no error or no finite one: unchanged
