"""The README's walkthrough quotes figures the program computes; they are read from the README
and computed here, so an edit of the scene, the solver or the text that makes them disagree
fails (issue #27.9: figures come from the program, not typed)."""

import re
from pathlib import Path

import numpy as np
import pytest

import explorer

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
DEMO = ROOT / "assets" / "scenes" / "valve_float_demo.toml"


def _quoted(pattern: str) -> re.Match:
    match = re.search(pattern, " ".join(README.split()))
    assert match, f"README no longer says {pattern!r}"
    return match


def test_the_float_speed_the_readme_quotes_is_the_computed_one():
    stated = float(_quoted(r"above the float speed \((\d+) rpm\)").group(1))
    result = explorer.simulate(explorer.load_scene(DEMO))
    # the README rounds to whole rpm
    assert round(result.summary["jump_speed_rpm"]) == stated


def test_the_readme_walkthrough_speeds_are_either_side_of_the_float_speed():
    slow = float(_quoted(r"Type `(\d+)` into \*\*Camshaft rpm\*\*: the warning goes, but the elastic float "
                         r"warning stays").group(1))
    fast = float(_quoted(r"it warns that (\d+) rpm is above the float speed").group(1))
    float_speed = explorer.simulate(explorer.load_scene(DEMO)).summary["jump_speed_rpm"]
    assert slow < float_speed < fast
    # ... and the elastic valve floats there all the same (the float warning of the elastic effect)
    result = explorer.simulate(explorer.load_scene(DEMO, [f"drive.rpm={slow:g}"]))
    assert not any(w.startswith("valve float") for w in result.warnings)
    assert any(w.startswith("elastic float") for w in result.warnings)


def test_the_tutorials_elastic_float_figures_are_the_computed_ones():
    text = " ".join((ROOT / "docs" / "tutorial.md").read_text(encoding="utf-8").split())
    match = re.search(r"Type `(\d+)` into \*\*Camshaft rpm\*\* and pause: the float warning goes\. An elastic "
                      r"float warning stays: .* loses the valve (\w+) times while it is open, from ([\d.]+)° on, "
                      r"for ([\d.]+) ms in all", text)
    assert match, "the tutorial no longer quotes the elastic float at the slow speed"
    rpm, times, first, flight = match.groups()
    s = explorer.simulate(explorer.load_scene(DEMO, [f"drive.rpm={rpm}"])).summary
    words = {"two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7}
    assert s["float_separations"] == words[times]
    assert round(s["first_separation_deg"], 1) == float(first)
    assert round(1e3 * s["float_flight_time_s"], 1) == float(flight)


def test_the_elastic_lift_off_speed_the_readme_quotes_is_the_swept_one():
    """'the elastic valve leaves the cam from about N rpm': the first speed of the README's own
    sweep command (drive.rpm=1000:6000:51, 100 rpm apart) with a separation is N."""
    stated = float(_quoted(r"the elastic valve leaves the cam from about (\d+) rpm").group(1))
    grid = _quoted(r"--vary drive\.rpm=(\d+):(\d+):(\d+)").groups()
    table = explorer.sweep(str(DEMO), vary={"drive.rpm": ":".join(grid)})
    rpm = np.asarray(table.columns["drive_rpm"])
    separated = np.asarray(table.columns["separations"]) > 0
    assert separated.any() and not separated[0]
    # every speed above the first lift-off also lifts off: "from about" is a threshold
    first = int(np.argmax(separated))
    assert separated[first:].all()
    assert rpm[first] == pytest.approx(stated, abs=0.5)
