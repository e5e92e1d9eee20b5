"""An output that is the same file as an input (the scene, a --rules file) or as another output of
the same command is refused before any work: one line naming the option, exit 2, nothing written
(explorer.core.outputs.distinct_outputs)."""

from __future__ import annotations

import os
import re
import shutil

import pytest

from explorer import cli
from explorer.core.errors import InputError
from explorer.core.outputs import check_output, distinct_outputs

from conftest import SCENES

LINE = re.compile(r"^error: .+: --[a-z-]+: .+$")


@pytest.fixture
def scene(tmp_path):
    path = tmp_path / "X.toml"
    shutil.copy(SCENES / "valve_float_demo.toml", path)
    return path


def _refused(capsys, argv, option, scene, *absent):
    before = scene.read_bytes()
    assert cli.main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and LINE.match(err[0]) and f": {option}: " in err[0], err
    assert "is the input file" in err[0] or "is the same file as" in err[0], err
    assert scene.read_bytes() == before
    for path in absent:
        assert not os.path.lexists(path) or os.path.islink(path), path
    assert not list(scene.parent.glob(".*.part"))


def _link(tmp_path, name, scene):
    link = tmp_path / name
    link.symlink_to(scene)
    return link


def test_simulate_output_over_the_scene_and_summary_over_output(tmp_path, scene, capsys):
    _refused(capsys, ["simulate", scene, "-o", scene], "--output", scene)
    _refused(capsys, ["simulate", scene, "-o", tmp_path / "sub" / ".." / "X.toml"], "--output", scene)
    _refused(capsys, ["simulate", scene, "-o", _link(tmp_path, "L.csv", scene)], "--output", scene)
    o = tmp_path / "o.csv"
    _refused(capsys, ["simulate", scene, "-o", o, "--summary", o], "--summary", scene, o)


def test_export_and_spectrum_over_the_scene(tmp_path, scene, capsys):
    # through links named with the format's extension: `-o X.toml` is refused by its extension first
    _refused(capsys, ["export", scene, "--format", "stl", "-o", _link(tmp_path, "L.stl", scene)], "--output", scene)
    _refused(capsys, ["spectrum", scene, "-o", _link(tmp_path, "L.csv", scene)], "--output", scene)


def test_sweep_residual_check_record_through_a_link_to_the_scene(tmp_path, scene, capsys):
    _refused(capsys, ["sweep", scene, "--vary", "drive.rpm=1000,2000", "-o", _link(tmp_path, "s.csv", scene)],
             "--output", scene)
    png = tmp_path / "p.png"
    _refused(capsys, ["sweep", scene, "--vary", "drive.rpm=1000,2000", "-o", tmp_path / "t.csv", "--plot",
                      _link(tmp_path, "p.png", tmp_path / "t.csv")], "--plot", scene, tmp_path / "t.csv")
    png.unlink()
    _refused(capsys, ["residual", scene, "--rpm", "1000", "-o", _link(tmp_path, "r.csv", scene)], "--output", scene)
    _refused(capsys, ["check", scene, "--rpm", "1000", "-o", _link(tmp_path, "c.json", scene)], "--output", scene)
    rules = tmp_path / "rules.toml"
    rules.write_text("")
    _refused(capsys, ["check", scene, "--rpm", "1000", "--rules", rules, "-o", _link(tmp_path, "d.json", rules)],
             "--output", scene)
    _refused(capsys, ["record", scene, "-o", _link(tmp_path, "x.rrd", scene)], "--output", scene)


def test_bench_output_dir_file_that_is_the_scene(tmp_path, scene, capsys):
    out = tmp_path / "bench"
    out.mkdir()
    (out / "bench_X.csv").symlink_to(scene)
    _refused(capsys, ["bench", scene, "--quick", "--output-dir", out], "--output-dir", scene)


def test_devices_are_not_compared(tmp_path):
    distinct_outputs((check_output("-", "--output"), check_output("-", "--summary")), ())
    with pytest.raises(InputError):
        distinct_outputs((check_output(tmp_path / "a", "--output"), check_output(tmp_path / "a", "--plot")), ())
