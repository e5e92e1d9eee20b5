"""Issue #22 items 2 and 3: every cam, entered or computed, passes the same validity checks
(explorer.lift.validity), and a refusal of a computed cam names what made it impossible; data
files are checked for their physical range row by row, naming the line, never the content.

The command line runs in-process under a time limit (a quarter of EXPLORER_TEST_TIMEOUT, as
tests/test_hostile_input.py): a refusal is exit status 2, one line `error: FILE: KEY: reason`, no
traceback, and nothing written. Hypothesis generates hostile table and contour-point files.
"""

from __future__ import annotations

import contextlib
import io
import math
import re
import signal
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from explorer.cli import main
from explorer.core.errors import InputError
from explorer.scene.scene import load_scene, loads_scene

from conftest import ROOT, SCENES, process_timeout

CASE_SECONDS = process_timeout(0.25)
POLYDYNE = SCENES / "polydyne_demo.toml"
MEASURED = ROOT / "assets" / "data" / "measured_lift.csv"
SECRET = "s3cr3t"


class Hang(Exception):
    pass


def run(argv: list[str], directory: Path) -> tuple[int | None, str, set[str]]:
    """(exit status, stderr, files written into `directory`) of the command line, in-process."""
    before = {p.name for p in directory.iterdir()}

    def alarm(signum, frame):
        raise Hang()

    err, out = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, CASE_SECONDS)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            status = main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    return status, err.getvalue(), {p.name for p in directory.iterdir()} - before


def refused(argv, directory: Path, key: str) -> str:
    """The one error line of a refused command (asserting exit 2, one line, the key, nothing written)."""
    status, err, written = run(argv, directory)
    lines = err.splitlines()
    assert status == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    assert "Traceback" not in err
    assert f": {key}: " in lines[0], lines[0]
    assert written == set(), written
    return lines[0]


# --- item 2: a computed cam is checked like an entered one -------------------------------------


def test_soft_polydyne_is_refused_naming_the_stiffness(tmp_path):
    """The reported case: stiffness = "1 N/m" made a cam of 543 m lift and exit 0. Now: exit 2, one
    line naming linkage.stiffness at the design speed, the fault, and what to change."""
    line = refused(["simulate", POLYDYNE, "--set", 'linkage.stiffness="1 N/m"', "-o", tmp_path / "o.csv",
                    "--summary", tmp_path / "s.json"], tmp_path, "linkage.stiffness")
    assert "1 N/m at the design speed 2000 rpm is not a valid cam" in line
    assert "the lift reaches 611.6 m" in line and "more than 1 m" in line
    assert re.search(r"stiffen the linkage \(at [0-9.e+]+ N/m the cam passes\)", line)
    assert "no lower design speed helps" in line  # the preload alone deflects a 1 N/m linkage 250 m


def _advised(line: str, pattern: str) -> float:
    match = re.search(pattern, line)
    assert match, line
    return float(match.group(1))


def test_polydyne_advice_is_right():
    """The stiffness and the design speed the refusal advises pass the check; 3 % less stiffness or
    3 % more speed fail (bisection to 1 %, the stiffness rounded up, the speed down)."""
    base = ['lift.design_rpm=4500', 'spring.preload="1500 N"', 'lift.ramp="30 deg"']
    with pytest.raises(InputError) as info:
        load_scene(POLYDYNE, base + ['linkage.stiffness="2.5e5 N/m"'])
    line = info.value.reason
    assert info.value.key == "linkage.stiffness" and "undercut" in line
    k = _advised(line, r"at ([0-9.e+]+) N/m the cam passes")
    rpm = _advised(line, r"at ([0-9.]+) rpm it passes")
    load_scene(POLYDYNE, base + [f'linkage.stiffness="{k!r} N/m"'])
    load_scene(POLYDYNE, base + ['linkage.stiffness="2.5e5 N/m"', f"lift.design_rpm={rpm!r}"])
    with pytest.raises(InputError, match="not a valid cam"):
        load_scene(POLYDYNE, base + [f'linkage.stiffness="{k / 1.03!r} N/m"'])
    with pytest.raises(InputError, match="not a valid cam"):
        load_scene(POLYDYNE, base + ['linkage.stiffness="2.5e5 N/m"', f"lift.design_rpm={rpm * 1.03!r}"])


def test_polydyne_whose_wanted_lift_is_no_cam_names_the_lift():
    """When even a rigid linkage fails, the stiffness is not the cause: the refusal names `lift`."""
    with pytest.raises(InputError) as info:
        load_scene(POLYDYNE, ['follower.roller_radius="60 mm"', 'follower.base_radius="5 mm"'])
    assert info.value.key == "lift" and "even with a rigid linkage" in info.value.reason
    assert "undercut" in info.value.reason


def test_polydyne_rebuilt_in_a_sweep_is_checked():
    """The polydyne cam is redesigned whenever its train changes (a sweep of linkage.stiffness builds
    the lift from the changed scene): the build checks it too."""
    from dataclasses import replace

    from explorer.effects.lift import build_lift

    scene = load_scene(POLYDYNE)
    soft = scene.with_changes(linkage=replace(scene.linkage, stiffness=1.0))
    with pytest.raises(InputError) as info:
        build_lift(soft)
    assert info.value.key == "linkage.stiffness" and "611.6 m" in info.value.reason


SPLINE_345 = """name = "345 as stations"
effects = ["kinematics"]
[drive]
rpm = 1000
[lift]
law = "spline"
start = "40 deg"
continuity = 2
[[lift.stations]]
angle = "0 deg"
s = "0 mm"
v = "0 m/s"
a = "0 m/s**2"
[[lift.stations]]
angle = "60 deg"
s = "12 mm"
v = "0 m/s"
a = "{a}"
[[lift.stations]]
angle = "140 deg"
s = "0 mm"
v = "0 m/s"
a = "0 m/s**2"
[follower]
base_radius = "20 mm"
roller_radius = "{r} mm"
[solver]
steps_per_revolution = 7200
"""
LAW_345 = SPLINE_345.split("[lift]")[0] + """[lift]
law = "polynomial-345"
height = "12 mm"
start = "40 deg"
rise = "60 deg"
return = "80 deg"
[follower]
base_radius = "20 mm"
roller_radius = "{r} mm"
[solver]
steps_per_revolution = 7200
"""


def test_entered_and_computed_cams_pass_one_check():
    """The 3-4-5 rise (60 deg) and return (80 deg: the worst point is unique) entered as a law and
    computed as a spline through stations (the same polynomials: s, v, a at rest, top, rest) fail
    with the same fault text, at the same angle: one function checks both, the entered one in the kinematics effect, the computed one at
    load (which then also names what made it)."""
    from explorer.effects.pipeline import simulate

    # the 3-4-5's acceleration at the top is 0 (f'' = 60u - 180u^2 + 120u^3 at u = 1)
    roller = 40
    with pytest.raises(InputError) as entered:
        simulate(loads_scene(LAW_345.format(r=roller), "law.toml"))
    with pytest.raises(InputError) as computed:
        loads_scene(SPLINE_345.format(r=roller, a="0 m/s**2"), "spline.toml")
    assert entered.value.key == "follower.roller_radius" and computed.value.key == "lift.stations"
    fault = entered.value.reason.split(" (reduce")[0]
    assert fault.startswith("undercut: roller radius 40 mm exceeds the convex pitch-curve radius")
    assert f"is not a valid cam: {fault};" in computed.value.reason
    assert "the lift through these stations" in computed.value.reason
    # below the undercut both pass
    simulate(loads_scene(LAW_345.format(r=30), "law.toml"))
    loads_scene(SPLINE_345.format(r=30, a="0 m/s**2"), "spline.toml")


def test_cam_fault_checks_in_order_and_can_fail_each_way():
    from explorer.lift.validity import MAX_LIFT, cam_fault

    theta = np.linspace(0.0, 2 * math.pi, 9, endpoint=False)
    ok = np.zeros((4, theta.size))
    assert cam_fault(theta, ok) is None
    bad = ok.copy()
    bad[2, 3] = np.inf
    assert cam_fault(theta, bad).check == "finite"
    low = ok.copy()
    low[0, 5] = -2e-9
    fault = cam_fault(theta, low)
    assert fault.check == "lift range" and "dips below the base circle by 2e-06 mm at cam angle 200.000 deg" in fault.text
    assert cam_fault(theta, low, dip=1e-9) is None  # within the allowance (1 nm rounding + 1 nm)
    high = ok.copy()
    high[0, 1] = MAX_LIFT * 1.5
    assert cam_fault(theta, high).check == "lift range"
    phi = np.zeros(theta.size)
    phi[4] = 0.5 * math.pi
    assert cam_fault(theta, ok, pressure_angle=phi).check == "pressure angle"
    rho = np.full(theta.size, 0.05)
    rho[6] = 0.004
    fault = cam_fault(theta, ok, pitch_radius=rho, roller_radius=0.005)
    assert fault.check == "undercut" and "at cam angle 240.000 deg" in fault.text
    assert cam_fault(theta, ok, pitch_radius=-rho, roller_radius=0.005) is None  # concave: no undercut


def test_built_in_scenes_pass_the_check():
    """Every built-in translating-roller cam passes (the check refuses no scene that ran before)."""
    from explorer.effects.lift import build_lift
    from explorer.lift.validity import lift_fault

    for path in sorted(SCENES.glob("*.toml")):
        scene = load_scene(path)
        assert lift_fault(build_lift(scene), scene.follower) is None, path.name


def test_acceleration_law_integrated_lift_is_checked(tmp_path):
    line = refused(["simulate", SCENES / "acceleration_demo.toml", "--set", 'follower.roller_radius="40 mm"',
                    "--set", 'follower.base_radius="5 mm"', "-o", tmp_path / "o.csv"], tmp_path, "lift.points")
    assert "the lift integrated from these accelerations is not a valid cam: undercut" in line


def test_smoothed_table_is_checked(tmp_path):
    line = refused(["simulate", SCENES / "table_demo.toml", "--set", 'follower.roller_radius="20 mm"',
                    "--set", 'follower.base_radius="5 mm"', "-o", tmp_path / "o.csv"], tmp_path, "lift.file")
    assert "the smoothed lift of measured_lift.csv is not a valid cam: undercut" in line


def test_design_optimum_is_checked():
    """explorer design's optimum is a computed cam: an open area that only a lift of more than 1 m
    holds (an average lift of 0.7 m over the 160 deg event: below the bound at which design refuses
    the area before any work, 1 m over the event, so the optimiser runs) gives a lift above 1 m,
    refused naming the option to change. (In-process without the CLI's time limit: the
    optimisation takes ~7 s of CPU.)"""
    from explorer.studies.design import DesignLimits, design

    scene = load_scene(SCENES / "spline_demo.toml")
    with pytest.raises(InputError) as info:
        design(scene, "peak-acceleration", DesignLimits(open_area=0.7 * math.radians(160.0) * 1.0))
    line = info.value.reason
    assert info.value.key == "lift.stations"
    assert "the optimised lift (--objective peak-acceleration) is not a valid cam: the lift reaches" in line
    assert "more than 1 m" in line and "--open-area" in line


def test_fitted_rocking_cam_is_checked_like_the_written_one(tmp_path):
    """explorer fit's contour goes through the one path of written contours (make_rocking_gear, the
    one check); a target it cannot meet names gear.target and what to change."""
    line = refused(["fit", SCENES / "rocking_cam.toml", "--lift", "60 mm"], tmp_path, "gear.target")
    assert "the fitted contour" in line and "undercut" in line and "lower gear.target.lift" in line


# --- item 3: data files in their physical range -----------------------------------------------


TABLE_SCENE = (SCENES / "table_demo.toml").read_text().replace("../data/measured_lift.csv", "lift.csv")
POINTS_SCENE = """name = "points"
effects = ["kinematics"]
[drive]
rpm = 1000
[lift]
law = "contour"
[cam]
file = "points.csv"
unit = "mm"
[follower]
base_radius = "25 mm"
roller_radius = "5 mm"
"""


def table_rows() -> list[str]:
    """The shipped measurement (header and comments included), as lines."""
    return MEASURED.read_text().splitlines()


def point_rows() -> list[str]:
    """An eccentric circle (radius 30 mm about (5, 0) mm: base radius 25 mm), 36 points, with a header."""
    rows = ["x_mm,y_mm"]
    for i in range(36):
        a = 2 * math.pi * i / 36
        rows.append(f"{5 + 30 * math.cos(a):.9f},{30 * math.sin(a):.9f}")
    return rows


def test_data_files_as_shipped_are_accepted(tmp_path):
    (tmp_path / "lift.csv").write_text("\n".join(table_rows()) + "\n")
    (tmp_path / "scene.toml").write_text(TABLE_SCENE)
    (tmp_path / "points.csv").write_text("\n".join(point_rows()) + "\n")
    (tmp_path / "points.toml").write_text(POINTS_SCENE)
    for scene in ("scene.toml", "points.toml"):
        status, err, written = run(["simulate", tmp_path / scene, "-o", tmp_path / f"{scene}.csv"], tmp_path)
        assert status == 0 and err == "" and written == {f"{scene}.csv"}, err


def test_negative_table_lift_is_refused_with_its_line(tmp_path):
    """The reported case: a table of -5 sin^2 theta mm ran with negative lift and exit 0."""
    rows = ["angle_deg,lift_mm"] + [f"{a},{-5 * math.sin(math.radians(a)) ** 2:.4f}" for a in range(360)]
    (tmp_path / "lift.csv").write_text("\n".join(rows) + "\n")
    (tmp_path / "scene.toml").write_text(TABLE_SCENE)
    line = refused(["simulate", tmp_path / "scene.toml", "-o", tmp_path / "o.csv"], tmp_path, "lift.file")
    assert "lift.csv: line 3: the lift is below the base circle" in line  # line 2 reads -0.0000
    assert "-0.0003" not in line


# (what the hostile row is, the row, what the error says)
BAD_TABLE_ROWS = [
    ("nan lift", "45,nan", "values must be finite"),
    ("infinite angle", "-inf,1.0", "values must be finite"),
    ("overflowing lift", "45,1e999", "values must be finite"),
    ("angle past ten turns", "3601,1.0", "the angle is outside +-3600 deg"),
    ("lift over 1 m", "45,1000.5", "a lift above 1 m"),
    ("lift below the base circle", "45,-0.5", "the lift is below the base circle by more than 0.103 mm"),
    ("three columns", "45,1.0,2.0", "expected 2 columns"),
    ("text", f"{SECRET},{SECRET}", "cannot read it as two numbers"),
]


@pytest.mark.parametrize("row, reason", [case[1:] for case in BAD_TABLE_ROWS], ids=[c[0] for c in BAD_TABLE_ROWS])
def test_bad_table_row_names_its_line_not_its_content(tmp_path, row, reason):
    lines = table_rows()
    at = 50
    lines[at] = row  # the file's line 51
    (tmp_path / "lift.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "scene.toml").write_text(TABLE_SCENE)
    line = refused(["simulate", tmp_path / "scene.toml", "-o", tmp_path / "o.csv"], tmp_path, "lift.file")
    assert f"lift.csv: line {at + 1}: {reason}" in line
    assert row not in line and SECRET not in line


def test_noise_allowance_follows_the_stated_noise(tmp_path):
    """A base-circle reading 0.2 mm below zero is beyond 1 % of the 10.3 mm peak (0.103 mm) but
    within 5 sigma of a stated 0.05 mm gauge noise (0.25 mm)."""
    lines = table_rows()
    lines[10] = "5,-0.2"
    (tmp_path / "lift.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "scene.toml").write_text(TABLE_SCENE)
    with pytest.raises(InputError, match="line 11: the lift is below the base circle by more than 0.103 mm"):
        load_scene(tmp_path / "scene.toml")
    load_scene(tmp_path / "scene.toml", ['lift.smoothing="0.05 mm"'])


def test_out_of_order_table_names_the_line(tmp_path):
    lines = table_rows()
    lines[20], lines[21] = lines[21], lines[20]
    (tmp_path / "lift.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "scene.toml").write_text(TABLE_SCENE)
    with pytest.raises(InputError) as info:
        load_scene(tmp_path / "scene.toml")
    assert "line 22: angles must increase strictly" in info.value.reason
    assert lines[21].split(",")[0] not in info.value.reason.replace("line 22", "")


BAD_POINT_ROWS = [
    ("nan", "nan,3", "coordinates must be finite"),
    ("overflow", "1e999,3", "coordinates must be finite"),
    ("20 m away", "20000,3", "the point lies more than 10 m from the cam centre"),
    ("at the centre", "0,0", "the point lies within 1 nm of the cam centre"),
    ("one column", "12.5", "expected two numbers x, y, got 1"),
    ("text", f"{SECRET},1", "expected two numbers x, y"),
]


@pytest.mark.parametrize("row, reason", [case[1:] for case in BAD_POINT_ROWS], ids=[c[0] for c in BAD_POINT_ROWS])
def test_bad_point_row_names_its_line_not_its_content(tmp_path, row, reason):
    lines = point_rows()
    lines[7] = row
    (tmp_path / "points.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "points.toml").write_text(POINTS_SCENE)
    line = refused(["simulate", tmp_path / "points.toml", "-o", tmp_path / "o.csv"], tmp_path, "cam.file")
    assert f"points.csv line 8: {reason}" in line
    assert row not in line and SECRET not in line


def test_inline_points_name_the_point():
    points = [[5 + 30 * math.cos(2 * math.pi * i / 36), 30 * math.sin(2 * math.pi * i / 36)] for i in range(36)]
    points[4] = [2e4, 0.0]
    text = POINTS_SCENE.replace('file = "points.csv"', f"points = {points!r}")
    with pytest.raises(InputError) as info:
        loads_scene(text, "x.toml")
    assert info.value.key == "cam.points[4]" and "more than 10 m" in info.value.reason


# --- hypothesis: hostile data files ------------------------------------------------------------

NUMBER = st.floats(allow_nan=False, allow_infinity=False, width=64).map(repr)
# cells that make a row bad whatever the rest of the file: unreadable or not finite ('#' starts a
# comment and line breaks start a new line: left out, they would hide the row rather than spoil it)
LINE_BREAKS = "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029#"
BAD_TEXT = st.one_of(
    st.sampled_from(["nan", "NaN", "inf", "-inf", "1e999", "-1e999", SECRET, "", "0x10", "1,5", "--1", "\x00"]),
    st.text(alphabet=st.characters(blacklist_categories=("Nd", "Cs"), blacklist_characters=LINE_BREAKS),
            min_size=1, max_size=12),
)


def bad_cell(beyond: float):
    """An unreadable or non-finite cell, or a finite number beyond `beyond` (in the file's unit)."""
    return st.one_of(BAD_TEXT, st.floats(min_value=beyond, max_value=1e300).map(repr))


@st.composite
def hostile_table(draw):
    """The shipped table with one row made bad (its line number returned), or wholly random bytes."""
    if draw(st.integers(0, 9)) == 0:
        return draw(st.binary(max_size=400)), None
    lines = table_rows()
    at = draw(st.integers(5, len(lines) - 1))  # after the header (line 5): a text row is no header
    kind = draw(st.sampled_from(["angle", "lift", "lift-low", "lift-high", "columns"]))
    angle, lift = lines[at].split(",")
    if kind == "angle":
        row = f"{draw(bad_cell(3600.5))},{lift}"  # deg: past ten turns
    elif kind == "lift":
        row = f"{angle},{draw(bad_cell(1000.5))}"  # mm: over 1 m
    elif kind == "lift-low":  # below the base circle by far more than the noise allowance (0.103 mm)
        row = f"{angle},{draw(st.floats(min_value=-1e300, max_value=-1.0))!r}"
    elif kind == "lift-high":  # over 1 m in mm
        row = f"{angle},{draw(st.floats(min_value=1000.5, max_value=1e300))!r}"
    else:
        row = ",".join(draw(st.lists(NUMBER, min_size=3, max_size=6)))
    lines[at] = row
    return ("\n".join(lines) + "\n").encode("utf-8", "surrogatepass"), at + 1


@st.composite
def hostile_points(draw):
    if draw(st.integers(0, 9)) == 0:
        return draw(st.binary(max_size=400)), None
    lines = point_rows()
    at = draw(st.integers(2, len(lines) - 1))  # after the first data row: a text row is no header
    x, y = lines[at].split(",")
    kind = draw(st.sampled_from(["x", "y", "far", "centre", "columns"]))
    if kind == "x":
        row = f"{draw(bad_cell(10000.5))},{y}"  # mm: beyond 10 m
    elif kind == "y":
        row = f"{x},{draw(bad_cell(10000.5))}"
    elif kind == "far":
        row = f"{draw(st.floats(min_value=10001.0, max_value=1e300))!r},{y}"
    elif kind == "centre":
        row = f"{draw(st.floats(min_value=-1e-7, max_value=1e-7))!r},0"
    else:
        row = ",".join(draw(st.lists(NUMBER, min_size=3, max_size=6)))
    lines[at] = row
    return ("\n".join(lines) + "\n").encode("utf-8", "surrogatepass"), at + 1


def _check_hostile(scene_text: str, data_name: str, data: bytes, line: int | None, key: str) -> None:
    with tempfile.TemporaryDirectory() as name:
        directory = Path(name)
        (directory / data_name).write_bytes(data)
        (directory / "scene.toml").write_text(scene_text)
        out = refused(["simulate", directory / "scene.toml", "-o", directory / "o.csv", "--summary",
                       directory / "s.json"], directory, key)
        assert SECRET not in out and "\x00" not in out
        if line is not None:
            assert f"line {line}:" in out, out
        assert len(out) < 400


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(hostile_table())
def test_hostile_table_file_is_one_line_exit_2(case):
    data, line = case
    _check_hostile(TABLE_SCENE, "lift.csv", data, line, "lift.file")


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(hostile_points())
def test_hostile_point_file_is_one_line_exit_2(case):
    data, line = case
    _check_hostile(POINTS_SCENE, "points.csv", data, line, "cam.file")
