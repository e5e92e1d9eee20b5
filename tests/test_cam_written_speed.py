"""A cam is steel: the lift laws whose values are in time units (an acceleration law's m/s^2, a
spline's station v/a/j/snap, a polydyne designed for its train) define their cam at the speed the
scene file was written for (Drive.cam_omega: [lift] reference_rpm / design_rpm when given, else
the file's drive.rpm). Before, `--set drive.rpm=X` (and the browser's speed field, which loads the
file with that override) rebuilt the cam at X, while the speed sweep kept the file's: the two
disagreed about the same speed. The oracle: the lift curve of the file's own speed, float for
float, and the sweep's own row at X."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from explorer import loads_scene, simulate, sweep
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

from conftest import SCENES

THETA = np.linspace(0.0, 2.0 * math.pi, 2001)


def text_without(path, key: str) -> str:
    """The scene file's text with [lift] `key` removed (so the law falls back to the file's speed)."""
    text = path.read_text()
    out = re.sub(rf"^{key}\s*=.*$", "", text, flags=re.M)
    assert out != text, key
    return out


def rows(scene):
    return build_lift(scene).derivatives(THETA)


CASES = [
    # an acceleration law in m/s^2 without reference_rpm (240 rpm in the file)
    ("acceleration_demo.toml", "reference_rpm", 480.0),
    # a polydyne without design_rpm (2000 rpm in the file): redesigning it at 2600 would make another cam
    ("polydyne_demo.toml", "design_rpm", 2600.0),
    ("polydyne_spline.toml", "design_rpm", 2600.0),
]


@pytest.mark.parametrize("name, key, rpm", CASES)
def test_an_override_of_the_speed_keeps_the_cam(name, key, rpm):
    text = text_without(SCENES / name, key)
    own = loads_scene(text, source=name)
    fast = loads_scene(text, source=name, overrides=[f"drive.rpm={rpm:g}"])
    assert fast.drive.rpm == rpm and fast.drive.written_rpm == own.drive.rpm
    assert fast.drive.cam_omega == own.drive.omega
    np.testing.assert_array_equal(rows(fast), rows(own))


def test_a_spline_with_time_based_stations_keeps_its_cam():
    """spline_demo with its nose acceleration given in m/s^2 (time units, no reference_rpm)."""
    text = (SCENES / "spline_demo.toml").read_text()
    nose = 's = "10 mm"\nv = "0 m/s"\na = "free"'
    assert nose in text and "reference_rpm" not in text
    text = text.replace(nose, 's = "10 mm"\nv = "0 m/s"\na = "-1500 m/s**2"')
    own = loads_scene(text, source="spline_demo.toml")
    fast = loads_scene(text, source="spline_demo.toml", overrides=["drive.rpm=3000"])
    np.testing.assert_array_equal(rows(fast), rows(own))
    # the nose acceleration is the station's at the file's 2000 rpm, (3000/2000)^2 of it at 3000
    nose_angle = np.radians([60.0 + 80.0])
    assert own.drive.omega**2 * build_lift(own).derivatives(nose_angle)[2][0] == pytest.approx(-1500.0, rel=1e-9)


def test_the_override_and_the_sweep_agree(tmp_path):
    """simulate at --set drive.rpm=480 and the sweep's row at 480 rpm: the same figures (the
    sweep replaces the speed in the loaded scene, keeping its cam); the float speed, a property
    of the cam and the spring alone, is the file's cam's in both."""
    path = tmp_path / "accel.toml"
    path.write_text(text_without(SCENES / "acceleration_demo.toml", "reference_rpm"))
    forces = ['effects=["kinematics", "lash", "forces"]', 'spring.preload="3000 N"', 'spring.rate="20 N/mm"']
    one = simulate(load_scene(path, [*forces, "drive.rpm=480"]))
    base = simulate(load_scene(path, forces))
    cols = sweep(load_scene(path, forces), {"drive.rpm": [240.0, 480.0]}, workers=1).columns
    assert list(cols["drive_rpm"]) == [240.0, 480.0]
    assert cols["min_contact_force_N"][1] == pytest.approx(one.summary["min_contact_force_N"], rel=1e-12)
    assert cols["float_speed_rpm"][1] == pytest.approx(one.summary["jump_speed_rpm"], rel=1e-12)
    assert one.summary["jump_speed_rpm"] == pytest.approx(base.summary["jump_speed_rpm"], rel=1e-12)
    # 4 x the file's 240 rpm accelerations: the cam is the file's, run twice as fast
    assert one.summary["max_valve_accel_m_s2"] == pytest.approx(4.0 * base.summary["max_valve_accel_m_s2"], rel=1e-12)


def test_the_file_speed_itself_has_no_written_speed():
    """At the file's own speed (no override, or an override to the same value) the drive is the
    one it always was: golden results and caches keyed by the scene do not change."""
    scene = load_scene(SCENES / "valve_float_demo.toml")
    assert scene.drive.written_rpm is None
    same = load_scene(SCENES / "valve_float_demo.toml", [f"drive.rpm={scene.drive.rpm:g}"])
    assert same.drive == scene.drive


@pytest.mark.parametrize("name, key, rpm", CASES)
def test_every_way_of_changing_the_speed_keeps_the_cam(name, key, rpm):
    """The browser's speed field (its override string), a speed with a unit and the Python API /
    sweep / check route (scene_for replaces the speed in a loaded scene): the file's cam in each."""
    from explorer.studies.sweep_spec import scene_for
    from explorer.view.browser.parameters import override

    text = text_without(SCENES / name, key)
    own = loads_scene(text, source=name)
    moved = {
        "browser": loads_scene(text, source=name, overrides=[override("drive.rpm", float(rpm))]),
        "with a unit": loads_scene(text, source=name, overrides=[f'drive.rpm="{rpm:g} rpm"']),
        "API / sweep / check": scene_for(own, ("drive.rpm",), (rpm,)),
    }
    for how, scene in moved.items():
        assert scene.drive.rpm == pytest.approx(rpm, rel=1e-15), how
        np.testing.assert_array_equal(rows(scene), rows(own), err_msg=how)


def test_an_explicit_reference_speed_wins_over_the_files():
    """design_rpm written in [lift] fixes the cam whatever drive.rpm the file writes."""
    text = (SCENES / "polydyne_demo.toml").read_text()
    assert "design_rpm" in text and "[drive]\nrpm = 2000" in text
    other = loads_scene(text.replace("[drive]\nrpm = 2000", "[drive]\nrpm = 1500"), source="x.toml")
    np.testing.assert_array_equal(rows(other), rows(loads_scene(text, source="x.toml")))


def test_a_bad_written_speed_is_refused_even_when_overridden():
    """The file's own drive.rpm defines the cam of a law in time units, so a bad one is an error
    though --set replaces it (before, it was skipped silently and the cam built at the override)."""
    from explorer.core.errors import InputError

    text = text_without(SCENES / "acceleration_demo.toml", "reference_rpm").replace("rpm = 240", 'rpm = "240 m"')
    assert '"240 m"' in text
    with pytest.raises(InputError) as err:
        loads_scene(text, source="bad.toml", overrides=["drive.rpm=480"])
    assert err.value.key == "drive.rpm" and "the file's value" in err.value.reason and "240 m" in err.value.reason
    # a file without a speed of its own takes the override as its only one
    no_speed = re.sub(r"^rpm\s*=.*$", "", text, count=1, flags=re.M)
    scene = loads_scene(no_speed, source="x.toml", overrides=["drive.rpm=480"])
    assert scene.drive.rpm == 480.0 and scene.drive.written_rpm is None
