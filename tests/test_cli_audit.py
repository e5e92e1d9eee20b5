"""Rough edges of the `explorer` command found by a CLI audit: each bad input is one line naming
the option (or file) and the reason, exit status 2, no traceback, nothing written."""

from __future__ import annotations

import io
import json
import re
import shlex
import time
from pathlib import Path

import pytest

from explorer import cli
from explorer.cli import progress
from conftest import SCENES, run_cli

DEMO = SCENES / "cycloidal_demo.toml"


def _one_error_line(capsys, argv, option, reason, written=()):
    assert cli.main(argv) == 2
    captured = capsys.readouterr()
    err = captured.err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    assert "Traceback" not in err
    assert option in err and reason in err, err
    assert err.count(f"{option}:") == 1, f"option named more than once: {err}"
    for path in written:
        assert not path.exists(), f"{path} written despite the error"
    return err


@pytest.mark.parametrize("range_text", ["1000:inf:3", "1000:-inf:3", "-Infinity:6000:3", "nan:6000:3",
                                        "1000:inf rpm:3"])
def test_vary_non_finite_end_is_named(tmp_path, capsys, range_text):
    out = tmp_path / "s.csv"
    err = _one_error_line(capsys, ["sweep", str(DEMO), "--vary", f"drive.rpm={range_text}", "-o", str(out)],
                          "--vary", "must be finite", [out])
    assert "unit" not in err  # was: "unknown unit 'inf'", the word read as the other end's unit


def test_record_and_residual_non_finite_end(tmp_path, capsys):
    out = tmp_path / "r.rrd"
    _one_error_line(capsys, ["record", str(DEMO), "--sweep", "drive.rpm=1000:inf:3", "-o", str(out)],
                    "--sweep", "must be finite", [out])
    _one_error_line(capsys, ["residual", str(DEMO), "--rpm", "1000:inf:3"], "--rpm", "must be finite")


@pytest.mark.parametrize(("extra", "reason"), [
    (["--runs", "5"], "give --sample too"),  # was reported as a --vary error: "nothing to sweep"
    (["--vary", "drive.rpm=1000:2000:3", "--runs", "5"], "give --sample too"),
    (["--vary", "drive.rpm=1000:2000:3", "--runs", "0"], "whole number >= 1, got 0"),
    (["--sample", "valve.lash=normal(0.25 mm, 0.02 mm)"], "needs --runs N"),
])
def test_runs_errors_name_runs(tmp_path, capsys, extra, reason):
    out = tmp_path / "s.csv"
    err = _one_error_line(capsys, ["sweep", str(DEMO), *extra, "-o", str(out)], "--runs", reason, [out])
    assert "--vary:" not in err


def test_scene_with_utf8_bom_is_read_like_without(tmp_path, capsys):
    """Windows editors (Notepad) start UTF-8 files with a byte-order mark: the same scene."""
    plain = tmp_path / "plain.toml"
    bom = tmp_path / "bom.toml"
    plain.write_bytes(DEMO.read_bytes())
    bom.write_bytes(b"\xef\xbb\xbf" + DEMO.read_bytes())
    summaries = []
    for scene in (plain, bom):
        out = tmp_path / f"{scene.stem}.json"
        assert cli.main(["simulate", str(scene), "--set", "solver.steps_per_revolution=360",
                         "--summary", str(out)]) == 0
        summary = json.loads(out.read_text())
        summary.pop("scene_file", None)
        summaries.append({k: v for k, v in summary.items() if "time" not in k and k != "effects"})
    capsys.readouterr()
    assert summaries[0] == summaries[1]


def test_bom_then_garbage_still_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_bytes(b"\xef\xbb\xbf[drive\n")
    _one_error_line(capsys, ["simulate", str(bad)], str(bad), "malformed TOML")


@pytest.mark.parametrize("port", ["70000", "-1"])
def test_port_out_of_range_one_line(capsys, port):
    err = _one_error_line(capsys, ["serve", str(DEMO), "--port", port], "--port", "from 1 to 65535, or 0")
    assert err.startswith("error: <command line>: --port: ")


def test_port_message_in_a_subprocess():
    proc = run_cli("serve", DEMO, "--port", "70000")
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.startswith("error: <command line>: --port: must be a TCP port from 1 to 65535"), proc.stderr


# ---------------------------------------------------------------- output extensions
@pytest.mark.parametrize(("fmt", "name", "suffix"), [
    ("dxf", "cam.stl", ".dxf"), ("stl", "cam.dxf", ".stl"), ("glb", "cam.gltf", ".glb"), ("csv", "cam.txt", ".csv"),
    ("csv", "cam", ".csv"), ("stl", "cam.csv", ".stl"),
])
def test_export_refuses_a_name_of_another_format(tmp_path, capsys, fmt, name, suffix):
    out = tmp_path / name
    err = _one_error_line(capsys, ["export", str(DEMO), "--format", fmt, "-o", str(out)], "--output",
                          f"must end in {suffix}", [out])
    assert str(out) in err
    assert list(tmp_path.iterdir()) == []


def test_export_grind_and_spectrum_refuse_a_name_not_csv(tmp_path, capsys):
    out = tmp_path / "g.dxf"
    _one_error_line(capsys, ["export", str(DEMO), "--format", "grind", "--grinding-wheel-radius", "150 mm",
                             "-o", str(out)], "--output", "must end in .csv", [out])
    out = tmp_path / "s.png"
    _one_error_line(capsys, ["spectrum", str(DEMO), "--orders", "10", "-o", str(out)], "--output",
                    "must end in .csv", [out])
    assert list(tmp_path.iterdir()) == []


def test_export_and_spectrum_matching_extension_any_case_are_written(tmp_path, capsys):
    out = tmp_path / "CAM.DXF"
    assert cli.main(["export", str(DEMO), "--format", "dxf", "-o", str(out)]) == 0
    assert out.read_text().lstrip().startswith("0")  # a DXF starts with group code 0
    capsys.readouterr()
    table = tmp_path / "s.csv"
    assert cli.main(["spectrum", str(DEMO), "--orders", "5", "-o", str(table)]) == 0
    assert table.exists()


# ---------------------------------------------------------------- progress on stderr
class _Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_draws_on_a_terminal_after_the_first_second_only(monkeypatch):
    monkeypatch.delenv(progress.ENV, raising=False)
    term = _Terminal()
    p = progress.Progress(term, unit="recordings")
    p(1, 10, 0.5)  # within the first second: nothing
    assert term.getvalue() == ""
    p(5, 10, 2.0)
    assert "5/10 recordings" in term.getvalue() and "recordings/s" in term.getvalue()
    assert "2 s left" in term.getvalue()  # 2.5 per second, 5 left
    p.end()
    assert term.getvalue().endswith("\n")
    log = io.StringIO()  # a file or pipe: no carriage-return noise
    quiet = progress.Progress(log)
    quiet(5, 10, 2.0)
    quiet.end()
    assert log.getvalue() == ""
    monkeypatch.setenv(progress.ENV, "1")  # asked for, in a log
    progress.Progress(log)(5, 10, 2.0)
    assert "5/10 runs" in log.getvalue()
    monkeypatch.setenv(progress.ENV, "0")
    silenced = _Terminal()
    progress.Progress(silenced)(5, 10, 2.0)
    assert silenced.getvalue() == ""


def test_ticking_shows_the_seconds_of_a_long_block_and_nothing_of_a_short_one(monkeypatch):
    monkeypatch.delenv(progress.ENV, raising=False)
    short = _Terminal()
    with progress.ticking(short, "export csv"):
        pass
    assert short.getvalue() == ""
    monkeypatch.setattr(progress, "FIRST_SECONDS", 0.05)
    monkeypatch.setattr(progress, "EVERY_SECONDS", 0.01)
    long = _Terminal()
    with progress.ticking(long, "export csv"):
        time.sleep(0.3)
    assert "export csv: working" in long.getvalue() and long.getvalue().endswith("\n")


@pytest.fixture
def eager_progress(monkeypatch):
    """Progress drawn from the start, into the captured (non-terminal) stderr."""
    monkeypatch.setenv(progress.ENV, "1")
    monkeypatch.setattr(progress, "FIRST_SECONDS", 0.0)
    monkeypatch.setattr(progress, "EVERY_SECONDS", 0.001)


def test_record_sweep_export_and_simulate_report_progress(tmp_path, capsys, eager_progress):
    out = tmp_path / "s.rrd"
    assert cli.main(["record", str(DEMO), "--no-parts", "--set", "solver.steps_per_revolution=360",
                     "--sweep", "drive.rpm=1000,2000", "-o", str(out)]) == 0
    assert "2/2 recordings" in capsys.readouterr().err
    assert cli.main(["export", str(DEMO), "--format", "csv", "--points", "400000", "-o", str(tmp_path / "p.csv")]) == 0
    assert "export csv: working" in capsys.readouterr().err
    assert cli.main(["simulate", str(DEMO), "--set", "solver.steps_per_revolution=100000",
                     "-o", str(tmp_path / "s.csv")]) == 0
    assert "simulate: working" in capsys.readouterr().err


def test_no_progress_when_stderr_is_not_a_terminal(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv(progress.ENV, raising=False)
    assert cli.main(["export", str(DEMO), "--format", "csv", "--points", "1000000", "-o", str(tmp_path / "p.csv")]) == 0
    assert capsys.readouterr().err == ""


# ---------------------------------------------------------------- examples in --help
RUN_EXAMPLES = ("simulate", "design", "export", "residual", "spectrum", "bench")  # each a few seconds
PARSE_EXAMPLES = ("view", "serve")  # servers that run until stopped: parsed, scenes checked


def _examples(command: str) -> list[list[str]]:
    parser = cli.build_parser()
    sub = next(a for a in parser._subparsers._group_actions).choices[command]
    text = sub.format_help()
    assert "\nexamples:\n" in text, f"explorer {command} --help has no examples"
    lines = [ln.strip() for ln in text.split("\nexamples:\n", 1)[1].splitlines() if ln.startswith("  explorer ")]
    assert 2 <= len(lines) <= 4, lines
    return [shlex.split(ln)[1:] for ln in lines]


@pytest.mark.parametrize("command", RUN_EXAMPLES + PARSE_EXAMPLES)
def test_help_examples_parse_and_name_built_in_scenes(command):
    from explorer.scene.builtin import find_scene

    for argv in _examples(command):
        assert argv[0] == command
        args = cli.build_parser().parse_args(argv)  # argparse exits on a wrong option
        scene = getattr(args, "scene", None)
        if scene is not None:
            assert Path(find_scene(scene)).is_file(), f"{scene}: not a built-in scene"


@pytest.mark.parametrize("command", RUN_EXAMPLES)
def test_help_examples_run(command, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)  # the examples' outputs are relative names
    for argv in _examples(command):
        assert cli.main(argv) == 0, (argv, capsys.readouterr().err)
    capsys.readouterr()
    assert any(tmp_path.iterdir()) or command in ("design",)


# ---------------------------------------------------------------- documented columns and timelines
DOCS = Path(__file__).resolve().parents[1] / "docs"
LEADING = re.compile(r"starts with these fourteen columns, in this order:\s*`([^`]+)`", re.S)


def _header(tmp_path, scene: str) -> list[str]:
    out = tmp_path / f"{scene}.csv"
    assert cli.main(["simulate", scene, "--set", "solver.steps_per_revolution=360", "-o", str(out)]) == 0
    return out.read_text().splitlines()[0].split(",")


def _leading_in(text: str) -> list[str]:
    return [c.strip() for c in text.split(",") if c.strip()]


@pytest.mark.parametrize("scene", ["cycloidal_demo.toml", "schenker1902_fig2.toml", "pushrod_train.toml",
                                   "trip_gear_dashpot.toml", "rocking_cam.toml"])
def test_documented_leading_columns_are_the_written_header(tmp_path, capsys, scene):
    doc = (DOCS / "reference" / "outputs.md").read_text()
    documented = _leading_in(" ".join(LEADING.search(doc).group(1).split()))
    helptext = cli.build_parser()._subparsers._group_actions[0].choices["simulate"].format_help()
    block = helptext.split("in this order (SI units in the names):\n", 1)[1].split("\nthen ", 1)[0]
    assert _leading_in(block) == documented
    header = _header(tmp_path, scene)
    capsys.readouterr()
    assert header[:len(documented)] == documented, header


def test_documented_table_of_a_built_in_scene_is_its_header(tmp_path, capsys):
    doc = (DOCS / "reference" / "outputs.md").read_text()
    section = doc.split("### Columns of a built-in scene", 1)[1]
    rows = re.findall(r"^\| `([^`]+)` \|", section, re.M)
    header = _header(tmp_path, "cycloidal_demo.toml")
    capsys.readouterr()
    assert rows == header
    assert {"valve_in_contact", "valve_phase"} <= set(rows)


def test_documented_valve_phase_codes_are_the_solvers():
    from explorer.dynamics.phases import PHASE_CODES

    doc = (DOCS / "reference" / "outputs.md").read_text()
    row = next(ln for ln in doc.splitlines() if ln.startswith("| `valve_phase` |"))
    for name, code in PHASE_CODES.items():
        assert f"{code} {name}" in row or f"{code} {dict(contact='moving', flight='in flight', stuck='held', seated='seated')[name]}" in row, (name, row)


def test_record_doc_names_the_timelines_the_recording_uses():
    from explorer.view.rerun.recording import ANGLE_UNITS_PER_DEG, TIMELINE_ANGLE, TIMELINE_STEP, TIMELINE_TIME

    doc = (DOCS / "guide" / "record.md").read_text()
    named = re.search(r"The timelines: (.+?)\.\s", " ".join(doc.split())).group(1)
    assert re.findall(r"`([^`]+)` \(", named) == [TIMELINE_ANGLE, TIMELINE_TIME, TIMELINE_STEP], named
    assert ANGLE_UNITS_PER_DEG == 100 and "hundredths of a degree" in named
    assert "cam_angle_deg" not in named  # the CSV column's name, not a timeline
    record_help = cli.build_parser()._subparsers._group_actions[0].choices["record"].format_help()
    assert f"Timelines: {TIMELINE_ANGLE} (hundredths of a degree" in record_help
