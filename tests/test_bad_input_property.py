"""Hostile values for every scene key, every command-line option and every data file (issue #22,
"done when"): hypothesis draws values that no key or option can accept and asserts that each
ends in exit status 2 with one line `error: ...`, no traceback, nothing written, within a time
bound. In-process (explorer.cli.main) under an alarm; the examples are derandomized by the
suite's profile (conftest), so the gate draws the same ones every run.

The values are built to be invalid everywhere they go: non-finite numbers, integers beyond any
range or Python's 4300-digit limit, arrays nested past the reader's depth, tables where a value
belongs, strings of a megabyte or with NUL bytes and control characters, and for options the
same plus malformed ranges, negative counts and unusable paths. Free text (a scene's name and
description) accepts any string and is left out.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import signal
import tempfile
import time
import tomllib
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import SCENES, process_timeout
from explorer.cli import main

CASE_SECONDS = process_timeout(0.25)  # a case slower than this hangs (most end in milliseconds)
SECRET = "s3cr3t-content-marker"  # put into data files: an error line must never show it
MEGABYTE = "x" * (1 << 20)
FREE_TEXT = {"name", "description"}


class Hang(Exception):
    pass


def run(argv) -> tuple[object, str, float]:
    """(exit status or the exception raised, stderr, seconds) of `explorer ARGV` in this process."""

    def alarm(signum, frame):
        raise Hang()

    err = io.StringIO()
    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, CASE_SECONDS)
    started = time.perf_counter()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            status = main([str(a) for a in argv])
    except SystemExit as exc:
        status = exc.code
    except BaseException as exc:  # noqa: BLE001 - a hang or a traceback: the failure being looked for
        status = exc
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    return status, err.getvalue(), time.perf_counter() - started


def assert_refused(argv, directory: Path, inputs=frozenset()) -> None:
    status, err, seconds = run(argv)
    shown = " ".join(map(str, argv))[:300]
    assert not isinstance(status, BaseException), f"{shown}: {type(status).__name__}: {str(status)[:300]}"
    lines = err.splitlines()
    assert status == 2, f"{shown}: exit {status}: {err[:500]}"
    assert len(lines) == 1 and lines[0].startswith("error: "), f"{shown}: {err[:500]}"
    assert "Traceback" not in err and SECRET not in err, f"{shown}: {err[:500]}"
    assert len(lines[0]) < 800, lines[0][:300]
    written = {p.name for p in directory.iterdir()} - set(inputs)
    assert written == set(), f"{shown}: wrote {written}"
    assert seconds < CASE_SECONDS


# ------------------------------------------------------------------ values no key accepts
def _nested(depth: int) -> str:
    return "[" * depth + "]" * depth


TOML_VALUES = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "+nan", "1e400", "-1e400", _nested(40), "{ a = 1 }", "{}",
                     '"\\u0000"', '"10 mm\\u0000"', '"\\u202e10 mm"', '"１０ mm"', '"10 mm\\n10 mm"', '""',
                     '"../../../../../../etc/shadow"', '"/dev/zero"', '"' + MEGABYTE + '"', "[nan, inf]",
                     '["\\u0000"]', "1979-05-27T07:32:00Z", '"' + "(" * 500 + ')"']),
    st.integers(4301, 6000).map(lambda n: "1" * n),  # beyond Python's integer conversion
    st.integers(400, 4000).map(lambda n: "-" + "9" * n),  # far beyond any range, below the limit
    st.floats(allow_nan=False, allow_infinity=False, min_value=1e200).map(lambda x: f"{-x!r}"),
)


def _leaf_keys(data, prefix="") -> list[str]:
    keys = []
    for name, value in data.items():
        key = f"{prefix}{name}"
        if isinstance(value, dict):
            keys += _leaf_keys(value, key + ".")
        elif name not in FREE_TEXT:
            keys.append(key)
    return keys


SCENE_KEYS = sorted({(path.name, key) for path in SCENES.glob("*.toml")
                     for key in _leaf_keys(tomllib.loads(path.read_text()))})


def test_every_scene_key_of_the_built_in_scenes_is_drawn():
    keys = {key for _, key in SCENE_KEYS}
    assert len(SCENE_KEYS) > 150 and {"drive.rpm", "follower.type", "gear.trip.buffer", "lift.file"} <= keys


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(SCENE_KEYS), TOML_VALUES)
def test_a_hostile_value_for_any_scene_key_is_one_line(scene_key, value):
    scene, key = scene_key
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        assert_refused(["simulate", SCENES / scene, "--set", f"{key}={value}", "-o", out / "o.csv",
                        "--summary", out / "s.json"], out)


# ------------------------------------------------------------------ every option
QUANTITIES = ["nan", "inf mm", "1e999 mm", "-1e999 mm", "10**10**10 mm", "１０ mm", "10 mm\x00", "", MEGABYTE,
              "1" * 4301, "5 kg", "-5 mm", "10 (mm", "0x10 mm", "\u202e10 mm", "10 mm; rm -rf /"]
COUNTS = ["-1", "1.5", "x", "", "1" * 4301, "1e3", "0x10", "--", "-99999999999999999999", MEGABYTE]
RANGES = ["3000:1000:10", "1:2:0", "1:2:1", "nan:5:3", "1:2:" + "1" * 4301, MEGABYTE, ",,,", "1::2", "a:b:c",
          "1e999:2e999:3", "-5:5:3", "0:100:5", "1000:2000:3:cubic", "1000,,2000", "1000:2000:3:log:log"]
DISTRIBUTIONS = ["normal(0.25 mm, -1 mm)", "weibull(1, 2)", "normal(", MEGABYTE, "uniform(2 mm, 1 mm)",
                 "normal(nan mm, 1 mm)", "normal(1e999 mm, 1 mm)", "uniform(0.2 mm)", "normal(0.2 mm, 0.1 s)"]
KEYS = ["", "x" * 5000, "drive.rpm\x00", "valve", "..", "drive..rpm", "lift.height", "valve.colour"]
ADDRESSES = ["", "x", "tcp://:0", "http://a:b", MEGABYTE, "tcp://127.0.0.1:0", "tcp://127.0.0.1:99999"]
PATHS = ["", "/", "/proc", "/nonexistent-directory/o.{ext}", "x" * 5000 + ".{ext}", "a\x00b.{ext}", "{tmp}",
         "/proc/self/fd/9999/o.{ext}", "/sys/o.{ext}"]
ROCKING, SPLINE, FLOAT, POLYDYNE = (SCENES / n for n in ("rocking_cam.toml", "spline_demo.toml", "valve_float_demo.toml",
                                                         "polydyne_demo.toml"))
TABLE = "{tmp}/o.csv"
# (argv with {v} where the hostile value goes, the values to draw from); {tmp} is the case's directory
OPTIONS = [
    (["simulate", FLOAT, "-o", "{v}"], PATHS),
    (["simulate", FLOAT, "--summary", "{v}"], PATHS),
    (["simulate", FLOAT, "--set", "{v}=1", "-o", TABLE], [k for k in KEYS if k != "lift.height"]),  # 1 m: a lift
    (["sweep", FLOAT, "--vary", "drive.rpm={v}", "-o", TABLE], RANGES),
    (["sweep", FLOAT, "--vary", "{v}=1000:2000:3", "-o", TABLE], KEYS),
    (["sweep", FLOAT, "--sample", "valve.lash={v}", "--runs", "2", "-o", TABLE], DISTRIBUTIONS),
    (["sweep", FLOAT, "--sample", "valve.lash=uniform(0.2 mm, 0.3 mm)", "--runs", "{v}", "-o", TABLE], COUNTS),
    (["sweep", FLOAT, "--sample", "valve.lash=uniform(0.2 mm, 0.3 mm)", "--runs", "2", "--seed", "{v}", "-o", TABLE],
     COUNTS),
    (["sweep", FLOAT, "--vary", "drive.rpm=1000:2000:3", "--workers", "{v}", "-o", TABLE], COUNTS + ["0"]),
    (["sweep", FLOAT, "--vary", "drive.rpm=1000:2000:3", "--scheduler", "{v}", "-o", TABLE], ADDRESSES),
    (["sweep", FLOAT, "--vary", "drive.rpm=1000:2000:3", "-o", "{v}"], [p.replace("{ext}", "csv") for p in PATHS]),
    (["sweep", FLOAT, "--vary", "drive.rpm=1000:2000:3", "-o", TABLE, "--plot", "{v}"],
     [p.replace("{ext}", "png") for p in PATHS]),
    (["sweep", FLOAT, "--vary", "drive.rpm=1000:2000:3", "-o", TABLE, "--record", "{v}"],
     [p.replace("{ext}", "rrd") for p in PATHS]),
    (["residual", POLYDYNE, "--rpm", "{v}", "-o", TABLE], RANGES),
    (["residual", POLYDYNE, "--rpm", "1500,2000", "--workers", "{v}", "-o", TABLE], COUNTS + ["0"]),
    (["residual", POLYDYNE, "--rpm", "1500,2000", "-o", "{v}"], [p.replace("{ext}", "csv") for p in PATHS]),
    (["design", SPLINE, "--objective", "{v}"], KEYS),
    (["design", SPLINE, "--objective", "peak-acceleration", "--max-pressure-angle", "{v}"], QUANTITIES + ["95 deg"]),
    (["design", SPLINE, "--objective", "peak-acceleration", "--radius-margin", "{v}"], QUANTITIES),
    (["design", SPLINE, "--objective", "peak-acceleration", "--contact-margin", "{v}"], QUANTITIES + ["1e6 N"]),
    (["design", SPLINE, "--objective", "peak-acceleration", "--contact-margin", "10 N", "--contact-rpm", "{v}"],
     QUANTITIES + ["-1", "x", "", "1" * 4301, "0", "1e9", "nan"]),
    (["design", SPLINE, "--objective", "residual-vibration", "--band", "{v}"], RANGES + ["2000:1000"]),
    (["design", SPLINE, "--objective", "peak-acceleration", "--open-area", "{v}"], QUANTITIES + ["1e9 mm*deg"]),
    (["export", FLOAT, "--format", "{v}"], KEYS),
    (["export", FLOAT, "--format", "dxf", "--tolerance", "{v}", "-o", "{tmp}/o.dxf"], QUANTITIES),
    (["export", FLOAT, "--format", "csv", "--points", "{v}", "-o", TABLE], COUNTS + ["0", "100000000"]),
    (["export", FLOAT, "--format", "stl", "--width", "{v}", "-o", "{tmp}/o.stl"], QUANTITIES + ["11 m"]),
    (["export", FLOAT, "--format", "grind", "--grinding-wheel-radius", "{v}", "-o", TABLE], QUANTITIES),
    (["export", FLOAT, "--format", "csv", "-o", "{v}"], [p.replace("{ext}", "csv") for p in PATHS]),
    (["fit", ROCKING, "--lift", "{v}"], QUANTITIES + ["100 m"]),
    (["fit", ROCKING, "--open-angle", "{v}"], QUANTITIES + ["400 deg"]),
    (["fit", ROCKING, "--max-pressure-angle", "{v}"], QUANTITIES),
    (["spectrum", FLOAT, "--orders", "{v}", "-o", TABLE], COUNTS + ["0", "100000000"]),
    (["spectrum", FLOAT, "-o", TABLE, "--plot", "{v}"], [p.replace("{ext}", "png") for p in PATHS]),
    (["record", FLOAT, "--sweep", "drive.rpm={v}", "-o", "{tmp}/o.rrd"], RANGES),
    (["record", FLOAT, "--sweep", "{v}=1000", "-o", "{tmp}/o.rrd"], KEYS),
    (["record", FLOAT, "-o", "{v}"], [p.replace("{ext}", "rrd") for p in PATHS]),
    (["record", FLOAT, "--magnification", "{v}", "-o", "{tmp}/o.rrd"], COUNTS[:1] + QUANTITIES + ["0", "1001"]),
    (["bench", FLOAT, "--repeats", "{v}", "--output-dir", "{tmp}"], COUNTS + ["0"]),
    (["bench", FLOAT, "--output-dir", "{v}"], ["/nonexistent-directory/x", "x" * 5000, "a\x00b", "/proc/self/fd/9999"]),
    (["serve", FLOAT, "--port", "{v}"], COUNTS + ["65536", "99999"]),
    (["view", "{v}"], ["/nonexistent.rrd", "", "x" * 5000 + ".rrd", "a\x00b.rrd", "{tmp}", "/dev/zero"]),
    (["simulate", "{v}"], ["/nonexistent.toml", "", "x" * 5000, "a\x00b", "{tmp}", "/dev/zero", "/proc/self/mem"]),
]
OPTION_CASES = [(i, value) for i, (_, values) in enumerate(OPTIONS) for value in values]


def test_every_command_is_drawn():
    commands = {argv[0] for argv, _ in OPTIONS}
    assert commands == {"simulate", "sweep", "residual", "design", "export", "fit", "spectrum", "record", "bench",
                        "serve", "view"}


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(OPTION_CASES))
def test_a_hostile_value_for_any_option_is_one_line(case):
    index, value = case
    argv, _ = OPTIONS[index]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        filled = [str(a).replace("{v}", value).replace("{tmp}", tmp) for a in argv]
        assert_refused(filled, out)


def _not_a_number(text: str) -> bool:
    try:
        float(text)
    except (ValueError, OverflowError):
        return True
    return False


BAD_MAGNIFICATIONS = st.one_of(
    st.floats(max_value=0.0).map(repr),  # zero, negative, -inf, and nan among them
    st.floats(min_value=1000.0, exclude_min=True).map(repr),  # beyond the bound, inf among them
    st.sampled_from(["nan", "-nan", "inf", "+inf", "x20", "20x", "×20", "20 mm", "", "1" * 4301, "1e999", MEGABYTE]),
    st.text(max_size=20).filter(_not_a_number),
)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(BAD_MAGNIFICATIONS)
def test_a_bad_record_magnification_is_one_line_naming_the_option(value):
    """`explorer record --magnification X`: X must be a positive finite number at most
    MAX_MAGNIFICATION; anything else is one line naming the option, exit 2, nothing written
    (checked before the scene is simulated)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        argv = ["record", FLOAT, "--magnification", value, "-o", out / "o.rrd"]
        assert_refused(argv, out)
        assert "--magnification" in run(argv)[1], value[:80]


# ------------------------------------------------------------------ every data file
def _good_table(n=72) -> list[str]:
    return [f"{a:g},{5 * (1 - math.cos(math.radians(a))):.9f}" for a in [i * 360.0 / n for i in range(n)]]


TABLE_SCENE = """effects = ["kinematics", "lash"]
[drive]
rpm = 3000
[lift]
law = "table"
file = "data.csv"
[valve]
mass = "0.1 kg"
lash = "0.3 mm"
"""
CONTOUR_SCENE = """name = "t"
effects = ["kinematics"]
[drive]
rpm = 600
[lift]
law = "contour"
[follower]
base_radius = "10 mm"
roller_radius = "5 mm"
[cam]
unit = "mm"
file = "data.csv"
"""
HOSTILE_LINES = st.one_of(
    st.sampled_from([f"25,{SECRET}", f"{SECRET}", "25,nan", "25,inf", "25,-inf", "25,1e999", "25," + "9" * 5000,
                     "25,1,2", "25", ",", "25;;", "\x00\x00", "25,1\x00", "\u202e25,1", "１,２", "15,1", "25, 0x10",
                     MEGABYTE]),
    st.text(min_size=1, max_size=40).map(lambda t: f"{SECRET},{t}"),
)
DATA_FILES = st.one_of(
    st.builds(lambda lines, at, bad: "\n".join(lines[:at] + [bad] + lines[at:]) + "\n",
              st.just(_good_table()), st.integers(1, 72), HOSTILE_LINES),  # line 1 may be a header
    st.lists(HOSTILE_LINES, min_size=0, max_size=8).map("\n".join),
    st.binary(max_size=200).map(lambda b: b.decode("latin-1") + SECRET),
    st.sampled_from(["", "\n" * 100, "angle,lift\n", "# only a comment\n" * 10]),
)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from([TABLE_SCENE, CONTOUR_SCENE]), DATA_FILES)
def test_a_hostile_data_file_is_one_line_without_its_content(scene, data):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        (out / "scene.toml").write_text(scene)
        (out / "data.csv").write_bytes(data.encode("utf-8", "surrogateescape"))
        assert_refused(["simulate", out / "scene.toml", "-o", out / "o.csv"], out, {"scene.toml", "data.csv"})
