"""`explorer design --open-area AREA`: an area of valve lift over cam angle must name its cam-angle
unit. mm*deg has the dimension of a length (deg is a number), so "5 mm" passed as 286 mm*deg
(0.005 m*rad) before; now it is refused in one line, as are mm/deg and mm*deg**2."""

from __future__ import annotations

import pytest

from explorer import cli

from conftest import SCENES

DEMO = SCENES / "spline_demo.toml"


@pytest.mark.parametrize("area", ["5 mm", "5 mm/deg", "5 mm*deg**2", "5 deg"])
def test_an_area_names_one_angle_unit(area, capsys):
    assert cli.main(["design", str(DEMO), "--objective", "peak-acceleration", "--open-area", area]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--open-area" in err and "mm*deg" in err


@pytest.mark.parametrize("area", ["1500 mm*deg", "0.02 m*rad", "1500 deg*mm"])
def test_an_area_with_its_angle_unit_is_read(area):
    from explorer.cli.design import _angle_power

    assert _angle_power(area) == 1
