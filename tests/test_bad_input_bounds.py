"""Issue #22, items 5-14: each a class of bad input or unbounded work, each with a test that fails
on the code before the fix. Commands run in-process (explorer.cli.main) under a time limit where
they can; those about signals and child processes run as processes.

  5  one range grammar for every command; a flank past one turn; a default that shapes a result
     is printed, an option without effect refused
  6  every root search on a physical quantity has a proven bracket or one line naming the input
  7  integers beyond Python's 4300-digit conversion limit
  8  seeds out of numpy's range
  9  a plan too large for memory, refused before any allocation with the size it needs
 10  workers capped at the usable cores; workers end with the parent on SIGTERM
 11  a stop signal removes every temporary the program made
 12  every output checked writable before computing; no partial set of outputs
 13  echoed values cut to a readable length
 14  infeasible design limits detected early; every optimisation has an evaluation budget
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import signal
import time

import pytest

from conftest import SCENES, process_timeout
from explorer.cli import main

CASE_SECONDS = process_timeout(0.25)
DIGITS = "1" * 4301  # one more than Python converts (sys.get_int_max_str_digits)
MEGABYTE = "x" * (1 << 20)


class Hang(Exception):
    pass


def run(*argv) -> tuple[int | None, str, str]:
    """(exit status, stderr, stdout) of `explorer ARGV` in this process, under CASE_SECONDS.
    A traceback fails the test by propagating."""

    def alarm(signum, frame):
        raise Hang(f"explorer {' '.join(map(str, argv))[:200]} took more than {CASE_SECONDS:g} s")

    err, out = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, CASE_SECONDS)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            try:
                status = main([str(a) for a in argv])
            except SystemExit as exc:
                status = exc.code
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    return status, err.getvalue(), out.getvalue()


def one_line_error(status, err, *fragments) -> str:
    lines = err.splitlines()
    assert status == 2, (status, err[:600])
    assert len(lines) == 1 and lines[0].startswith("error: "), err[:600]
    assert "Traceback" not in err
    assert len(lines[0]) < 400, lines[0][:600]
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


FLOAT = SCENES / "valve_float_demo.toml"
POLYDYNE = SCENES / "polydyne_demo.toml"
SPLINE = SCENES / "spline_demo.toml"
ROCKING = SCENES / "rocking_cam.toml"


# ------------------------------------------------------------------ 5: one grammar for ranges
RANGE_OPTIONS = {  # command line with {r} where a range of drive.rpm goes
    "sweep": ("sweep", FLOAT, "--vary", "drive.rpm={r}", "-o", "{tmp}/o.csv"),
    "residual": ("residual", POLYDYNE, "--rpm", "{r}", "-o", "{tmp}/o.csv"),
    "record": ("record", FLOAT, "--sweep", "drive.rpm={r}", "-o", "{tmp}/o.rrd"),
}
BAD_RANGES = [
    ("3000:1000:10", "backwards range"),
    ("1000:1000:10", "empty range"),
    ("1000:3000:1", "1 point"),
    ("1000:3000:0", "zero steps"),
    ("1000:3000:x", "plain whole number"),
    ("1000:3000:" + DIGITS, "at most"),
    ("1000::3", "cannot read"),
    ("1000:3000:3:cubic", "cannot read"),
    ("1000,,2000", "empty value"),
]


@pytest.mark.parametrize("command", RANGE_OPTIONS)
@pytest.mark.parametrize("text, reason", BAD_RANGES, ids=[b[1] for b in BAD_RANGES])
def test_every_command_reads_ranges_with_one_grammar(tmp_path, command, text, reason):
    argv = [str(a).replace("{r}", text).replace("{tmp}", str(tmp_path)) for a in RANGE_OPTIONS[command]]
    one_line_error(*run(*argv)[:2], reason)
    assert list(tmp_path.iterdir()) == []


def test_the_interval_of_design_band_is_read_by_the_same_grammar(tmp_path):
    one_line_error(*run("design", SPLINE, "--objective", "residual-vibration", "--band", "3000:1000")[:2],
                   "--band", "backwards range")
    one_line_error(*run("design", SPLINE, "--objective", "residual-vibration", "--band", "1000:3000:5")[:2],
                   "--band", "cannot read")


def test_a_counted_range_gives_the_same_values_in_every_command():
    from explorer.cli.record import parse_sweep
    from explorer.studies.residual import parse_speeds
    from explorer.studies.sweep_spec import parse_axis

    grid = parse_axis("drive.rpm", "1000:3000:5").values.tolist()
    assert parse_speeds("1000:3000:5").tolist() == grid == [1000.0, 1500.0, 2000.0, 2500.0, 3000.0]
    assert [float(v) for v in parse_sweep("drive.rpm=1000:3000:5")[1]] == grid
    assert parse_sweep("valve.lash=0.1:0.3 mm:3")[1] == ["0.1 mm", "0.2 mm", "0.3 mm"]  # the unit as written


def test_fit_refuses_a_flank_that_does_not_fit_in_one_turn():
    one_line_error(*run("fit", ROCKING, "--set", 'gear.rocking_cam.flank="359 deg"')[:2], "gear.rocking_cam.flank",
                   "one turn")
    one_line_error(*run("fit", ROCKING, "--set", 'gear.rocking_cam.flank="400 deg"')[:2], "gear.rocking_cam.flank")


def test_design_refuses_options_without_effect_and_prints_the_default_speed():
    from explorer.scene.scene import load_scene
    from explorer.studies.design import DesignLimits, speed_notes

    one_line_error(*run("design", SPLINE, "--objective", "peak-acceleration", "--contact-rpm", "3000")[:2],
                   "--contact-rpm", "--contact-margin")
    one_line_error(*run("design", SPLINE, "--objective", "peak-acceleration", "--band", "1000:2000")[:2], "--band")
    scene = load_scene(SPLINE)
    default = speed_notes(scene, "peak-acceleration", DesignLimits(contact_margin=50.0))
    assert default == [f"  contact margin 50 N held at every speed up to {scene.drive.rpm:g} rpm (drive.rpm: the "
                       "default without --contact-rpm)"]
    given = speed_notes(scene, "peak-acceleration", DesignLimits(contact_margin=50.0, contact_rpm=4000.0))
    assert given == ["  contact margin 50 N held at every speed up to 4000 rpm (--contact-rpm)"]


# ------------------------------------------------------------------ 7: integers past 4300 digits
def test_integers_beyond_the_conversion_limit_are_one_line(tmp_path):
    scene = tmp_path / "big.toml"
    scene.write_text((SCENES / "cycloidal_demo.toml").read_text().replace("rpm = 3000", f"rpm = {DIGITS}", 1))
    assert DIGITS in scene.read_text()
    out = tmp_path / "o.csv"
    one_line_error(*run("simulate", scene, "-o", out)[:2], "drive.rpm", "4301 digits")
    one_line_error(*run("simulate", FLOAT, "--set", f"drive.rpm={DIGITS}", "-o", out)[:2], "drive.rpm", "4301 digits")
    one_line_error(*run("sweep", FLOAT, "--vary", f"drive.rpm=1000:{DIGITS}:3", "-o", out)[:2], "drive.rpm")
    one_line_error(*run("sweep", FLOAT, "--vary", "drive.rpm=1000:2000:3", "--seed", DIGITS, "-o", out)[:2], "--seed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.toml"]


# ------------------------------------------------------------------ 13: echoed values are cut
@pytest.mark.parametrize("scene, key", [
    (SCENES / "cycloidal_demo.toml", "follower.type"),
    (SCENES / "trip_gear_dashpot.toml", "gear.trip.buffer"),
    (SCENES / "cycloidal_demo.toml", "lift.law"),
    (SCENES / "cycloidal_demo.toml", "lift.height"),
])
def test_a_megabyte_value_is_echoed_cut(tmp_path, scene, key):
    line = one_line_error(*run("simulate", scene, "--set", f'{key}="{MEGABYTE}"', "-o", tmp_path / "o.csv")[:2], key)
    assert "xxxxxxxx" in line or "characters" in line  # shown, cut
    assert list(tmp_path.iterdir()) == []


def test_a_megabyte_option_value_is_echoed_cut(tmp_path):
    one_line_error(*run("sweep", FLOAT, "--vary", f"drive.rpm={MEGABYTE}", "-o", tmp_path / "o.csv")[:2], "drive.rpm")
    one_line_error(*run("design", SPLINE, "--objective", MEGABYTE)[:2], "--objective")
    one_line_error(*run("sweep", FLOAT, "--vary", "drive.rpm=1:2:3", "--workers", MEGABYTE, "-o", "o.csv")[:2],
                   "--workers")
    one_line_error(*run("simulate", FLOAT, "--set", f"{MEGABYTE}=1", "-o", tmp_path / "o.csv")[:2])


def test_echo_is_the_one_formatter_and_safe_for_any_value():
    from explorer.core.errors import InputError, echo

    assert echo("0.3 mm") == "'0.3 mm'"
    assert len(echo(MEGABYTE)) < 80 and "1048578 characters" in echo(MEGABYTE)
    assert "4301 digits" in echo(int(DIGITS[:4300]) * 10 + 1) or "digits" in echo(int(DIGITS[:4300]) * 10 + 1)
    assert "\n" not in echo("a\nb")
    error = InputError(MEGABYTE, MEGABYTE, "unknown value " + MEGABYTE + "; choose one of: a, b")
    assert len(str(error)) < 800 and str(error).endswith("choose one of: a, b")
