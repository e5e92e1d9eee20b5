"""The gear scenes through `explorer simulate`, bad geometry through the CLI, and the figures."""

import json
import math

import pytest

from conftest import SCENES, run_cli

GEAR_SCENES = ["pivoted_roller_lever.toml", "rocking_cam.toml", "rolling_lever.toml", "trip_gear_dashpot.toml"]


@pytest.mark.parametrize("name", GEAR_SCENES)
def test_scene_runs_through_the_cli(name, tmp_path):
    out, summary = tmp_path / "out.csv", tmp_path / "out.json"
    proc = run_cli("simulate", SCENES / name, "-o", out, "--summary", summary)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(summary.read_text())
    assert "gear" in data["effects"] and data["gear"]["type"]
    header = out.read_text().splitlines()[0].split(",")
    assert "valve_lift_m" in header
    for value in data["gear"].values():
        if isinstance(value, float):
            assert math.isfinite(value)


@pytest.mark.parametrize("name, override, key", [
    ("pivoted_roller_lever.toml", 'gear.lever.pivot=["-150 mm", "-20 mm"]', "gear.lever.pivot"),
    ("rocking_cam.toml", 'gear.eccentric.rod="300 mm"', "gear.eccentric.rod"),
    ("rolling_lever.toml", 'gear.rolling_lever.growth="400 mm"', "gear.rolling_lever.growth"),
    ("trip_gear_dashpot.toml", 'gear.trip.angle="340 deg"', "gear.trip.angle"),
])
def test_bad_geometry_is_one_line_exit_2_no_file(name, override, key, tmp_path):
    out = tmp_path / "out.csv"
    extra = ["--set", 'gear.lever.arm="183 mm"'] if name.startswith("pivoted") else []
    proc = run_cli("simulate", SCENES / name, "--set", override, *extra, "-o", out)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and f": {key}: " in lines[0]
    assert "Traceback" not in proc.stderr
    assert not out.exists()


@pytest.mark.parametrize("law", ["table", "acceleration", "contour"])
def test_a_lever_cam_from_a_lift_that_is_no_closed_form_law_is_one_line(law, tmp_path):
    """The pivoted lever synthesises its cam through a closed-form law's jets: a table or an
    acceleration law is refused at load time by name (it once ended in a KeyError traceback)."""
    out = tmp_path / "out.csv"
    proc = run_cli("simulate", SCENES / "pivoted_roller_lever.toml", "--set", f'lift.law="{law}"', "-o", out)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and ": lift.law: " in lines[0], lines
    assert "Traceback" not in proc.stderr
    assert not out.exists()


def test_summary_figures(tmp_path):
    from explorer.studies.gear_figures import main

    assert main([str(tmp_path)]) == 0
    for name in ("rocking_cam_swings.png", "trip_buffers.png"):
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    table = (tmp_path / "trip_buffers.md").read_text().splitlines()
    assert [row.split("|")[1].strip() for row in table[2:]] == ["none", "air", "oil"]
