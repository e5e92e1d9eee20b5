"""Bad input: every mistake a user can make in a scene ends in one InputError naming file, key
and reason -- never another exception. Hand-picked cases from the issue's list, then hypothesis
mutating a valid scene (wrong types, units of the wrong dimension, NaN/inf, negatives, random
strings, missing keys) and feeding random text as TOML."""

from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from explorer import InputError, simulate
from explorer.scene.scene import loads_scene, scene_from_dict

from conftest import SCENES

BASE_TEXT = (SCENES / "cycloidal_demo.toml").read_text()
BASE = tomllib.loads(BASE_TEXT)


def mutated(path: str, value=..., delete: bool = False) -> dict:
    data = copy.deepcopy(BASE)
    *parents, last = path.split(".")
    node = data
    for part in parents:
        node = node.setdefault(part, {})
    if delete:
        node.pop(last, None)
    else:
        node[last] = value
    return data


def load_error(data) -> InputError:
    with pytest.raises(InputError) as info:
        scene_from_dict(data, "bad.toml")
    return info.value


# (dotted key, value or "DELETE", expected key in the error, words the reason must contain)
CASES = [
    ("lift", "DELETE", "lift", "missing section"),
    ("drive", "DELETE", "drive", "missing section"),
    ("drive.rpm", "DELETE", "drive.rpm", "missing key"),
    ("lift.law", "spline-magic", "lift.law", "unknown value"),
    ("lift.law", 3, "lift.law", "expected a string"),
    ("effects", ["kinematics", "warp-drive"], "effects", "unknown effect"),
    ("effects", "kinematics", "effects", "expected a list"),
    ("effects", [], "effects", "at least one"),
    ("valve.mass", "5 mm", "valve.mass", "not a mass"),
    ("valve.lash", "3 kg", "valve.lash", "not a length"),
    ("spring.rate", "25 N", "spring.rate", "not a stiffness"),
    ("lift.height", "nan mm", "lift.height", "finite"),
    ("lift.height", math.nan, "lift.height", "finite"),
    ("lift.height", math.inf, "lift.height", "finite"),
    ("lift.height", "-2 mm", "lift.height", "greater than zero"),
    ("valve.lash", "-0.1 mm", "valve.lash", "negative"),
    ("valve.mass", "0 kg", "valve.mass", "greater than zero"),
    ("lift.rise", "300 deg", "lift.return", "exceeds 360"),
    ("lift.start", "400 deg", "lift.start", "[0 deg, 360 deg)"),
    ("drive.rpm", 0, "drive.rpm", "greater than zero"),
    ("drive.rpm", -300, "drive.rpm", "greater than zero"),
    ("drive.rpm", "3000 mm", "drive.rpm", "rotational speed"),
    ("solver.steps_per_revolution", 10, "solver.steps_per_revolution", "too few steps"),
    ("solver.steps_per_revolution", 360.5, "solver.steps_per_revolution", "whole number"),
    ("solver.method", "magic", "solver.method", "unknown value"),
    ("follower.ratio", -1.0, "follower.ratio", "greater than 0"),
    ("follower.type", "flat-face-dreams", "follower.type", "unknown value"),
    ("follower.offset", "100 mm", "follower.offset", "smaller than base radius"),
    ("seat.restitution", 1.5, "seat.restitution", "less than 1"),
    ("lift.heigth", "10 mm", "lift.heigth", "unknown key"),
    ("valve", 5, "valve", "expected a table"),
    ("loads.closing.steam", "36 kgf*s", "loads.closing.steam", "not a force"),
    ("lift.height", True, "lift.height", "boolean"),
    ("lift.height", [1, 2], "lift.height", "expected a number or a string"),
    ("lift.height", "ten millimetres", "lift.height", "cannot read"),
    ("name", 42, "name", "expected a string"),
]


@pytest.mark.parametrize("path,value,key,words", CASES, ids=[f"{c[0]}={c[1]!r}" for c in CASES])
def test_bad_value_names_file_key_and_reason(path, value, key, words):
    data = mutated(path, delete=True) if value == "DELETE" else mutated(path, value)
    error = load_error(data)
    assert error.file == "bad.toml"
    assert error.key == key
    assert words in error.reason
    assert "\n" not in str(error)


def test_effect_needs_its_section():
    data = mutated("valve", delete=True)
    data["effects"] = ["forces"]
    error = load_error(data)
    assert error.key == "valve" and "missing section" in error.reason


@pytest.mark.parametrize(
    "text,words",
    [
        ("name = \n", "malformed TOML"),
        ("[drive\nrpm = 3\n", "malformed TOML"),
        ("x = 'unterminated\n", "malformed TOML"),
        ("[drive]\nrpm = 1\n[drive]\nrpm = 2\n", "malformed TOML"),
    ],
)
def test_malformed_toml(text, words):
    with pytest.raises(InputError) as info:
        loads_scene(text, source="bad.toml")
    assert info.value.key == "-" and words in info.value.reason


@pytest.mark.parametrize(
    "override,key,words",
    [
        ("drive.rpm", "drive.rpm", "section.key=value"),
        ("=5", "=5", "dotted"),
        ("drive..rpm=5", "drive..rpm", "dotted"),
        ("drive.rpm.x=5", "drive.rpm.x", "not a table"),
        ("drive.rpm=-1", "drive.rpm", "greater than zero"),
        ("valve.mass=5 mm", "valve.mass", "not a mass"),
        ("lift.law=nonsense", "lift.law", "unknown value"),
    ],
)
def test_bad_overrides(override, key, words):
    with pytest.raises(InputError) as info:
        loads_scene(BASE_TEXT, source="s.toml", overrides=[override])
    assert info.value.key == key and words in info.value.reason


# --- hypothesis: mutate a valid scene ---------------------------------------------------------

KEY_PATHS = sorted(
    f"{section}.{key}" if isinstance(table, dict) else section
    for section, table in BASE.items()
    for key in (table if isinstance(table, dict) else [None])
) + ["lift.return_law", "valve.oscillating_mass", "linkage.damping", "solver.rtol", "effects", "lift.law"]
KEY_PATHS = [p.removesuffix(".None") for p in KEY_PATHS]

UNITS = ["mm", "m", "kg", "N", "N/mm", "kgf", "deg", "rad", "rpm", "s", "at", "kgf*s**2/m", "m/s", "",
         "furlong", "mm**2", "1/s", "%", "degC", "kg/m**3"]

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-10**30, max_value=10**30),
    st.sampled_from([0, -1, 1e-300, 1e300, -0.0, 36, 35, 360, 10**7]),
)
quantities = st.builds(lambda x, u: f"{x} {u}", numbers, st.sampled_from(UNITS))
values = st.one_of(
    numbers,
    quantities,
    st.text(max_size=12),
    st.booleans(),
    st.lists(st.one_of(numbers, st.text(max_size=3)), max_size=3),
    st.dictionaries(st.text(max_size=4), numbers, max_size=2),
    st.sampled_from(["cycloidal", "harmonic", "table", "acceleration", "contour", "kinematics", "lash",
                     "forces", "elastic", "contact", "exact", "translating-roller"]),
)
mutation = st.tuples(st.sampled_from(KEY_PATHS + ["lift", "drive", "valve", "nosuch.key"]), values, st.booleans())


def try_load(data):
    try:
        return scene_from_dict(data, "fuzz.toml")
    except InputError as exc:
        assert exc.file == "fuzz.toml" and exc.key and exc.reason and "\n" not in exc.reason
        return None


def try_simulate(scene):
    """A scene that loads simulates with finite motion, or fails with an InputError that only
    the motion can reveal (undercut of the cam)."""
    try:
        result = simulate(scene)
    except InputError as exc:
        assert "undercut" in exc.reason, exc
        return None
    for name, column in result.columns.items():
        if name.startswith(("follower_", "valve_", "rigid_", "time_", "cam_")):
            assert np.all(np.isfinite(column)), name
    return result


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(mutation, min_size=1, max_size=3))
def test_mutated_scenes_load_or_raise_input_error(mutations):
    data = copy.deepcopy(BASE)
    for path, value, delete in mutations:
        *parents, last = path.split(".")
        node = data
        for part in parents:
            child = node.get(part)
            if not isinstance(child, dict):
                child = node[part] = {}
            node = child
        if delete:
            node.pop(last, None)
        else:
            node[last] = value
    scene = try_load(data)
    if scene is not None and set(scene.effects) <= {"kinematics", "lash"} and scene.solver.steps_per_revolution <= 3600:
        try_simulate(scene)


@settings(max_examples=150, deadline=None)
@given(st.text(max_size=200))
def test_random_text_is_never_a_crash(text):
    try:
        loads_scene(text, source="fuzz.toml")
    except InputError as exc:
        assert exc.file == "fuzz.toml"


@settings(max_examples=100, deadline=None)
@given(st.lists(st.text(max_size=30), max_size=4))
def test_random_overrides_are_never_a_crash(overrides):
    try:
        loads_scene(BASE_TEXT, source="s.toml", overrides=overrides)
    except InputError as exc:
        assert exc.file == "s.toml"


# --- hypothesis: the table and acceleration laws ----------------------------------------------

ACCEL_TEXT = (SCENES / "acceleration_demo.toml").read_text()
ACCEL = tomllib.loads(ACCEL_TEXT)

point_values = st.one_of(
    st.floats(min_value=-1e6, max_value=1e6), st.sampled_from([math.nan, math.inf, -math.inf, 1e308]),
    st.integers(min_value=-400, max_value=400), st.text(max_size=3), st.booleans(),
)
points = st.one_of(
    st.lists(st.lists(point_values, min_size=0, max_size=3), max_size=8),
    st.lists(st.tuples(st.floats(0, 400), st.floats(-1e3, 1e3)).map(list), min_size=2, max_size=8).map(
        lambda p: [[0.0, p[0][1]], *sorted(p[1:])]),
    values,
)


@settings(max_examples=200, deadline=None)
@given(points, st.sampled_from(["m/s**2", "mm/deg**2", "mm/deg", "kg", "g", "", "m/s", "furlong/fortnight**2"]),
       st.sampled_from(["linear", "step", "cubic", 3]))
def test_acceleration_law_inputs(pts, unit, interpolation):
    data = copy.deepcopy(ACCEL)
    data["lift"].update(points=pts, acceleration_unit=unit, interpolation=interpolation)
    if unit != "m/s**2":
        data["lift"].pop("reference_rpm")
    scene = try_load(data)
    if scene is not None:
        try_simulate(scene)


csv_cells = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=32).map(repr), st.integers(-10, 400).map(str),
    st.text(alphabet="0123456789.-e, ;#abc", max_size=6),
)
csv_lines = st.lists(st.lists(csv_cells, min_size=0, max_size=3).map(",".join), max_size=40)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(lines=csv_lines, raw=st.binary(max_size=20))
def test_table_law_files(tmp_path, lines, raw):
    path = tmp_path / "lift.csv"
    path.write_bytes("\n".join(lines).encode() + raw)
    data = mutated("lift", {"law": "table", "file": str(path)})
    scene = try_load(data)
    if scene is not None:
        try_simulate(scene)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(angles=st.lists(st.floats(0, 359.99), min_size=24, max_size=80, unique=True),
       lifts=st.lists(st.floats(-1e3, 1e3), min_size=80, max_size=80))
def test_table_law_random_valid_shapes(tmp_path, angles, lifts):
    """Random but well-formed tables: load and simulate, or a clear InputError (gaps)."""
    angles = sorted(angles)
    path = tmp_path / "lift.csv"
    path.write_text("\n".join(f"{a!r},{l!r}" for a, l in zip(angles, lifts)))
    data = mutated("lift", {"law": "table", "file": str(path), "lift_unit": "mm"})
    scene = try_load(data)
    if scene is not None:
        try_simulate(scene)
