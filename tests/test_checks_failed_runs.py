"""An operating speed whose runs fail is refused in one line naming --rpm (exit 2, nothing
written), never judged as "no seat impact" or dropped silently."""

from __future__ import annotations

import pytest

from explorer import cli

from conftest import SCENES

FLOAT = SCENES / "valve_float_demo.toml"


@pytest.mark.parametrize("rpm,named", [("0.5,1", "0.5, 1 rpm"), ("0.5,3000", "0.5 rpm")])
def test_failed_speeds_are_refused_naming_them(tmp_path, capsys, rpm, named):
    out = tmp_path / "report.json"
    assert cli.main(["check", str(FLOAT), "--rpm", rpm, "-o", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("error: --rpm: drive.rpm: the engine cannot run the scene at " + named)
    assert not out.exists()
