"""`explorer simulate`: files, columns, summary, overrides, the Python API, and bad input ending
in exactly one line `error: FILE: KEY: reason` with exit status 2 and no file written.

Most cases call `explorer.cli.main` in-process (fast); a handful run the real command in a
subprocess, because only that shows what a user sees (no traceback, `python -m explorer`,
which modules a run imports)."""

from __future__ import annotations

import csv
import json
import re
import subprocess
import sys

import numpy as np
import pytest

from explorer import cli
from conftest import ROOT, SCENES, process_timeout, run_cli

DEMO = SCENES / "cycloidal_demo.toml"
REQUIRED_COLUMNS = ["cam_angle_deg", "time_s", "follower_lift_m", "valve_lift_m", "valve_velocity_m_s",
                    "valve_accel_m_s2", "valve_jerk_m_s3"]
ERROR_LINE = re.compile(r"^error: [^:\n]+: [^:\n]+: .+$")


def read_csv(path):
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    header, body = rows[0], np.array(rows[1:], dtype=float)
    return header, body


def test_simulate_writes_csv_and_summary(tmp_path):
    out, summary = tmp_path / "out.csv", tmp_path / "out.json"
    proc = run_cli("simulate", DEMO, "-o", out, "--summary", summary)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    header, body = read_csv(out)
    assert set(REQUIRED_COLUMNS) <= set(header) and header[:2] == REQUIRED_COLUMNS[:2]
    assert body.shape == (3600, len(header))
    motion = [i for i, name in enumerate(header) if name.startswith(("follower_", "valve_", "time_", "cam_"))]
    assert np.all(np.isfinite(body[:, motion]))  # radii of curvature may be +-inf on straight stretches
    # units in every column name
    assert all(re.search(r"_(deg|s|m|m_s|m_s2|m_s3)$", name) for name in header), header
    data = json.loads(summary.read_text())
    for key in ("scene", "rpm", "steps_per_revolution", "effects", "events", "warnings",
                "impact_velocity_opening_m_s", "impact_velocity_closing_m_s", "max_valve_lift_m"):
        assert key in data, key
    assert set(data["effects"]) == {"kinematics", "lash"}
    for info in data["effects"].values():
        assert info["compute_time_s"] > 0.0 and isinstance(info["requested"], bool)
    for event in data["events"]:
        assert {"kind", "time_s", "cam_angle_deg"} <= set(event)
    # the time column is cam angle / omega at 3000 rpm
    t = body[:, header.index("time_s")]
    theta = np.radians(body[:, header.index("cam_angle_deg")])
    assert t == pytest.approx(theta / (100 * np.pi), rel=1e-14, abs=1e-18)


def test_python_api_matches_csv_columns(tmp_path):
    from explorer import load_scene, simulate

    result = simulate(load_scene(DEMO))
    out = tmp_path / "api.csv"
    assert cli.main(["simulate", str(DEMO), "-o", str(out)]) == 0
    header, body = read_csv(out)
    assert header == list(result.columns)
    for i, name in enumerate(header):
        assert body[:, i] == pytest.approx(result.columns[name], rel=1e-15, abs=0)  # repr round-trips
    assert json.loads(result.json_text()).keys() == dict(result.summary).keys()


def test_summary_to_stdout_without_files(capsys):
    assert cli.main(["simulate", str(DEMO)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["scene"] == "Cycloidal demo"


def test_set_overrides_values(tmp_path):
    summary = tmp_path / "s.json"
    code = cli.main(["simulate", str(DEMO), "--summary", str(summary), "--set", "drive.rpm=600",
                     "--set", "valve.lash=0.5 mm", "--set", 'lift.height="8 mm"'])
    assert code == 0
    data = json.loads(summary.read_text())
    assert data["rpm"] == pytest.approx(600.0, rel=1e-13)
    assert data["lash_m"] == pytest.approx(5e-4, rel=1e-15)
    assert data["max_follower_lift_m"] == pytest.approx(0.008, rel=1e-12)
    assert data["revolution_time_s"] == pytest.approx(0.1, rel=1e-13)


BAD_RUNS = [
    # (scene text or None for the demo, extra arguments, expected "FILE: KEY" part)
    ("name = \n", [], "-"),
    (None, ["--set", "valve.mass=5 mm"], "valve.mass"),
    (None, ["--set", "drive.rpm=0"], "drive.rpm"),
    (None, ["--set", "drive.rpm"], "drive.rpm"),
    (None, ["--set", "lift.law=wobble"], "lift.law"),
    (None, ["--set", "lift.rise=300 deg"], "lift.return"),
    (None, ["--set", "solver.steps_per_revolution=12"], "solver.steps_per_revolution"),
    (None, ["--set", "lift.height=nan"], "lift.height"),
    ("[drive]\nrpm = 100\n", [], "lift"),
    ('effects = ["teleport"]\n[drive]\nrpm = 1\n[lift]\nlaw = "cycloidal"\nheight = "1 mm"\nrise = 10\n', [], "effects"),
    ('[drive]\nrpm = 100\n[lift]\nlaw = "table"\nfile = "nowhere.csv"\n', [], "lift.file"),
    # undercut is found while simulating (the cam geometry), and still writes nothing
    (None, ["--set", "follower.roller_radius=40 mm", "--set", "lift.rise=30 deg", "--set", "lift.return=30 deg"],
     "follower.roller_radius"),
]


@pytest.mark.parametrize("text,extra,key", BAD_RUNS)
def test_bad_input_one_line_exit_2_no_file(tmp_path, capsys, text, extra, key):
    scene = DEMO
    if text is not None:
        scene = tmp_path / "bad.toml"
        scene.write_text(text)
    out, summary = tmp_path / "out.csv", tmp_path / "out.json"
    code = cli.main(["simulate", str(scene), "-o", str(out), "--summary", str(summary), *extra])
    captured = capsys.readouterr()
    assert code == 2
    lines = captured.err.splitlines()
    assert len(lines) == 1 and ERROR_LINE.match(lines[0]), captured.err
    assert lines[0].startswith(f"error: {scene}: {key}: ")
    assert captured.out == ""
    assert not out.exists() and not summary.exists()
    assert not list(tmp_path.glob(".out.*"))  # no temporary files left behind


def test_missing_scene_and_missing_output_directory(tmp_path, capsys):
    assert cli.main(["simulate", str(tmp_path / "none.toml")]) == 2
    assert capsys.readouterr().err.strip().endswith("file not found")
    assert cli.main(["simulate", str(DEMO), "-o", str(tmp_path / "no" / "dir" / "x.csv")]) == 2
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.parametrize(
    "text,args",
    [
        ("[drive\n", []),
        (None, ["--set", "valve.mass=5 mm"]),
        (None, ["--set", "lift.start=400 deg"]),
    ],
)
def test_bad_input_in_a_subprocess(tmp_path, text, args):
    """What the user sees: one line on stderr, exit 2, no traceback, nothing written."""
    scene = DEMO
    if text is not None:
        scene = tmp_path / "bad.toml"
        scene.write_text(text)
    out = tmp_path / "out.csv"
    proc = run_cli("simulate", scene, "-o", out, *args)
    assert proc.returncode == 2
    assert proc.stdout == ""
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and ERROR_LINE.match(lines[0]), proc.stderr
    assert "Traceback" not in proc.stderr
    assert not out.exists()


def test_python_dash_m_help_and_version():
    proc = run_cli("--help")
    assert proc.returncode == 0 and "simulate" in proc.stdout
    proc = run_cli("--version")
    assert proc.returncode == 0 and proc.stdout.startswith("explorer ")


def test_kinematics_only_scene_imports_no_solver_and_no_viewer():
    """Lazy imports: a kinematics scene never loads a dynamics solver, viser or rerun."""
    code = f"""
import sys
from explorer import load_scene, simulate
result = simulate(load_scene({str(DEMO)!r}))
assert result.columns["valve_lift_m"].size == 3600
registry = ("explorer.dynamics", "explorer.dynamics.solvers")  # solver names, read by the scene loader
heavy = [m for m in sys.modules if m.startswith(("explorer.dynamics", "viser", "rerun", "matplotlib", "trimesh"))
         and m not in registry]
print(",".join(heavy))
"""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=process_timeout())
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == ""


@pytest.mark.parametrize("option", ["-o", "--summary"])
def test_output_path_that_is_a_directory(tmp_path, capsys, option):
    """An output that names a directory was a traceback from os.replace after the whole run; it is
    now refused up front in one line, and neither file is written."""
    other = tmp_path / ("x.json" if option == "-o" else "x.csv")
    other_option = "--summary" if option == "-o" else "-o"
    code = cli.main(["simulate", str(DEMO), option, str(tmp_path), other_option, str(other)])
    lines = capsys.readouterr().err.splitlines()
    assert code == 2
    assert len(lines) == 1 and ERROR_LINE.match(lines[0])
    assert lines[0] == f"error: {tmp_path}: {'--output' if option == '-o' else '--summary'}: is a directory, not a file name"
    assert not other.exists()


def test_write_failure_is_one_line(tmp_path):
    """A write that fails after the checks (here: the file-size limit, as a full disk would) still
    ends in one line, exit 2, and leaves neither the file nor its temporary."""
    import resource
    import signal

    def small_files():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # EFBIG instead of a killed process
        resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, 100_000))

    out = tmp_path / "out.csv"
    proc = subprocess.run([sys.executable, "-m", "explorer", "simulate", str(DEMO), "-o", str(out)],
                          preexec_fn=small_files, capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [f"error: {out}: --output: cannot write: File too large"]
    assert list(tmp_path.iterdir()) == []
