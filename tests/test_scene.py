"""Loading valid scenes: SI values, defaults, bare numbers, technical units, overrides, built-in
scenes, and the pint-free fast path for common units (exact: equal to pint's result)."""

from __future__ import annotations

import dataclasses
import math
import re
import subprocess
import sys
import tomllib

import pytest

from explorer import load_scene, loads_scene
from explorer.core import units
from explorer.scene.builtin import builtin_scenes

from conftest import ROOT, SCENES, process_timeout

G0 = 9.80665  # exact by definition of kgf

DEMO = SCENES / "cycloidal_demo.toml"


def test_demo_scene_is_in_si():
    s = load_scene(DEMO)
    assert s.name == "Cycloidal demo" and s.effects == ("kinematics", "lash", "forces", "contact", "elastic")
    assert s.drive.rpm == pytest.approx(3000.0, rel=1e-15)
    assert s.omega == pytest.approx(100 * math.pi, rel=1e-15)
    assert s.lift.law == "cycloidal" and s.lift.return_law is None
    assert s.lift.height == pytest.approx(0.0103, rel=1e-15)
    assert s.lift.start == pytest.approx(math.radians(20), rel=1e-15)
    assert s.lift.rise == s.lift.ret == pytest.approx(math.radians(70), rel=1e-15)
    assert s.lift.dwell == 0.0
    assert (s.follower.base_radius, s.follower.roller_radius, s.follower.offset, s.follower.ratio) == pytest.approx(
        (0.03, 0.012, 0.0, 1.0), rel=1e-15)
    assert s.valve.mass == 0.12 and s.valve.lash == pytest.approx(3e-4, rel=1e-15)
    assert s.spring.preload == 250.0 and s.spring.rate == pytest.approx(25000.0, rel=1e-15)
    assert s.loads.friction == 15.0 and dict(s.loads.closing) == {"gas_on_valve": 20.0}
    assert s.linkage.stiffness == 2e6
    assert s.seat.restitution == 0.0
    assert s.solver.method == "exact" and s.solver.steps_per_revolution == 3600
    assert s.source == str(DEMO) and s.directory == SCENES


def test_defaults_and_bare_numbers():
    """Bare numbers: SI base units, except angles in degrees and speeds in rpm."""
    s = loads_scene('[drive]\nrpm = 240\n[lift]\nlaw = "harmonic"\nheight = 0.0206\nrise = 80\n')
    assert s.name == "scene" and s.effects == ("kinematics",)
    assert s.omega == pytest.approx(8 * math.pi, rel=1e-15)
    assert s.lift.height == 0.0206
    assert s.lift.rise == s.lift.ret == pytest.approx(math.radians(80), rel=1e-15)  # return defaults to rise
    assert s.lift.start == 0.0
    assert s.valve is None and s.spring is None and s.linkage is None
    assert s.follower == type(s.follower)()
    assert s.solver.steps_per_revolution == 3600
    # bare numbers written as strings mean the same
    t = loads_scene('[drive]\nrpm = "240"\n[lift]\nlaw = "harmonic"\nheight = "0.0206"\nrise = "80"\n')
    assert (t.omega, t.lift.height, t.lift.rise) == (s.omega, s.lift.height, s.lift.rise)


def test_technical_units_in_a_scene():
    text = DEMO.read_text().replace('mass = "0.12 kg"', 'mass = "2.9 kgf*s**2/m"').replace(
        'preload = "250 N"', 'preload = "260 kgf"').replace('stiffness = "2e6 N/m"', 'stiffness = "1800000 kgf/m"')
    s = loads_scene(text)
    assert s.valve.mass == pytest.approx(2.9 * G0, rel=1e-15)
    assert s.spring.preload == pytest.approx(260 * G0, rel=1e-15)
    assert s.linkage.stiffness == pytest.approx(1.8e6 * G0, rel=1e-15)


def test_effects_are_deduplicated_in_order():
    text = re.sub(r"^effects = .*$", 'effects = ["lash", "kinematics", "lash"]', DEMO.read_text(), flags=re.M)
    assert loads_scene(text).effects == ("lash", "kinematics")


def test_overrides_create_keys_and_leave_the_file_alone():
    s = load_scene(DEMO, overrides=["loads.closing.steam=36 kgf", "drive.rpm=600", 'lift.law="harmonic"',
                                    "solver.steps_per_revolution=720"])
    assert s.loads.closing["steam"] == pytest.approx(36 * G0, rel=1e-15)
    assert s.drive.rpm == pytest.approx(600.0, rel=1e-15)
    assert s.lift.law == "harmonic" and s.solver.steps_per_revolution == 720
    assert load_scene(DEMO).drive.rpm == pytest.approx(3000.0, rel=1e-15)


def test_load_and_loads_agree_and_scene_is_frozen():
    a = load_scene(DEMO)
    b = loads_scene(DEMO.read_text(), source=str(DEMO))
    assert a == b
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.name = "changed"  # type: ignore[misc]
    c = a.with_changes(drive=type(a.drive)(rpm=100.0))
    assert c.drive.rpm == 100.0 and a.drive.rpm != 100.0


@pytest.mark.parametrize("path", builtin_scenes(), ids=lambda p: p.name)
def test_every_builtin_scene_loads(path):
    scene = load_scene(path)
    assert scene.effects and scene.drive.rpm > 0


def test_fast_unit_path_equals_pint():
    """Every unit of the fast path gives pint's value to within one ulp (same exact factor)."""
    for unit, (dimension, _) in units._FAST_UNITS.items():
        for number in ("1", "30", "2.9", "-0.37", "1e6", "385", "0.12", ".5"):
            text = f"{number} {unit}"
            fast = units._fast_to_si(text, dimension)
            slow = units._pint_to_si(text, text, dimension, file="f", key="k")
            assert fast == pytest.approx(slow, rel=2.3e-16, abs=0), text


def test_fast_path_declines_what_it_does_not_know():
    assert units._fast_to_si("5 mm", "mass") is None  # wrong dimension: pint writes the error
    assert units._fast_to_si("5 furlong", "length") is None
    assert units._fast_to_si("nan mm", "length") is None
    assert units._fast_to_si("1e999 mm", "length") is None
    assert units._fast_to_si("25 N / mm", "stiffness") == pytest.approx(25000.0, rel=1e-15)
    assert units._fast_to_si("5 ft", "length") is None
    assert units.to_si("5 ft", "length", file="f", key="k") == pytest.approx(5 * 0.3048, rel=1e-15)  # via pint


def test_loading_the_demo_needs_no_pint():
    """The fast path covers the shipped demo: a fresh process loads it without building pint."""
    code = f"import sys; from explorer import load_scene; load_scene({str(DEMO)!r}); print('pint' in sys.modules)"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=process_timeout())
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "False"


def test_scene_files_parse_as_toml():
    for path in builtin_scenes():
        tomllib.loads(path.read_text())


@pytest.mark.parametrize("text", ["3000 rpm", "3000 1/min", "3000/min", "50 Hz", "50 1/s", "314.1592653589793 rad/s",
                                  "18000 deg/s", "3000 turn/min"])
def test_rotational_speeds_count_revolutions(text):
    """A rate without an angle ("1/min", the German U/min, or Hz) counts revolutions; pint alone
    would read it as rad/s, 2 pi too slow."""
    assert units.to_si(text, "speed", file="f", key="k") == pytest.approx(100 * math.pi, rel=1e-14)
