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
    # the demo's kinematics (it opens with forces and the elastic linkage too, #28.10)
    proc = run_cli("simulate", DEMO, "--set", 'effects=["kinematics", "lash"]', "-o", out, "--summary", summary)
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
    assert json.loads(result.json_text()).keys() == result.report().keys() == {*result.summary, "effects", "events", "warnings"}


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
result = simulate(load_scene({str(DEMO)!r}, ['effects=["kinematics", "lash"]']))
assert result.columns["valve_lift_m"].size == 3600
registry = ("explorer.dynamics", "explorer.dynamics.solvers", "explorer.dynamics.solver_base")  # the solver table, read by the scene loader
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


def test_a_builtin_scene_by_name_reads_its_data_file_beside_itself(tmp_path, monkeypatch):
    """`explorer simulate table_demo.toml` and `explorer serve table_demo.toml` in another
    directory: the scene's relative `file = "../data/measured_lift.csv"` is taken from the
    folder of the scene file found, not from the working directory (it failed with
    "measured_lift.csv: file not found"). Oracle: the same scene given by its path. Errors still
    name the file as it was given."""
    from explorer import load_scene
    from explorer.core.errors import InputError
    from explorer.effects.pipeline import simulate
    from explorer.view.browser import model

    table_demo = ROOT / "assets" / "scenes" / "table_demo.toml"
    monkeypatch.chdir(tmp_path)
    by_name, by_path = tmp_path / "a.json", tmp_path / "b.json"
    assert cli.main(["simulate", "table_demo.toml", "--summary", str(by_name)]) == 0
    assert cli.main(["simulate", str(table_demo), "--summary", str(by_path)]) == 0
    drop = ("effects",)  # compute times differ
    a, b = (json.loads(p.read_text()) for p in (by_name, by_path))
    assert {k: v for k, v in a.items() if k not in drop} == {k: v for k, v in b.items() if k not in drop}
    named, found = load_scene("table_demo"), load_scene(table_demo)
    assert named.source == "table_demo" and named.lift.options.path == found.lift.options.path
    assert named.directory == table_demo.parent
    # what `explorer serve table_demo.toml` computes: the page's request carries the name as given
    prepared = model.prepare(model.Request(path="table_demo.toml"))
    assert prepared.result.columns["valve_lift_m"].max() == simulate(found).columns["valve_lift_m"].max()
    # a bad value still names the file as typed
    with pytest.raises(InputError) as err:
        load_scene("table_demo.toml", ["lift.file='nosuch.csv'"])
    assert str(err.value).startswith("table_demo.toml: lift.file: nosuch.csv: file not found")


def test_builtin_scenes_by_their_dropdown_name(tmp_path, monkeypatch, capsys):
    """Issue #13.9: `explorer simulate cycloidal_demo.toml` in any directory finds the built-in
    scene the explorer's Scene dropdown lists under that name (with or without .toml); a file of
    that name in the working directory wins; a name with a directory part is always a path; an
    unknown name is still one error line naming the file as it was given."""
    monkeypatch.chdir(tmp_path)
    by_name, by_path = tmp_path / "a.json", tmp_path / "b.json"
    assert cli.main(["simulate", "cycloidal_demo.toml", "--summary", str(by_name)]) == 0
    assert cli.main(["simulate", str(DEMO), "--summary", str(by_path)]) == 0
    a, b = json.loads(by_name.read_text()), json.loads(by_path.read_text())
    assert a["scene"] == b["scene"] == "Cycloidal demo"
    assert cli.main(["simulate", "cycloidal_demo", "--summary", str(by_name)]) == 0
    assert json.loads(by_name.read_text())["scene"] == "Cycloidal demo"
    # a local file of that name is what the user means
    (tmp_path / "cycloidal_demo.toml").write_text(DEMO.read_text().replace('"Cycloidal demo"', '"Local copy"'))
    assert cli.main(["simulate", "cycloidal_demo.toml", "--summary", str(by_name)]) == 0
    assert json.loads(by_name.read_text())["scene"] == "Local copy"
    capsys.readouterr()
    for given in ("./nosuch_demo.toml", "nosuch_demo.toml", "sub/cycloidal_demo.toml"):
        assert cli.main(["simulate", given]) == 2
        assert capsys.readouterr().err == f"error: {given}: -: file not found\n"


def test_outputs_have_normal_permissions_and_no_roundoff_noise(tmp_path):
    """Issue #13.9: CSV and JSON are created 0666 less the umask (0644 under umask 022), not 0600;
    the printed summary holds no round-off (4.97e-14 for a difference of equal decelerations,
    53.400000000000006, -0): explorer.core.units.printable."""
    import os

    out, summary = tmp_path / "out.csv", tmp_path / "out.json"
    old = os.umask(0o022)
    try:
        proc = run_cli("simulate", SCENES / "pivoted_roller_lever.toml", "-o", out, "--summary", summary)
    finally:
        os.umask(old)
    assert proc.returncode == 0, proc.stderr
    assert (out.stat().st_mode & 0o777) == 0o644 and (summary.stat().st_mode & 0o777) == 0o644
    text = summary.read_text()
    data = json.loads(text)
    # the deceleration difference of this scene is a difference of equal figures: exactly 0 printed
    assert data["deceleration_difference_m_s2"] == 0.0
    assert not re.search(r"e-1\d|e-[2-9]\d|-0[,\n]|-0\.0[,\n]", text), text
    numbers = [float(m) for m in re.findall(r"-?\d+\.\d+(?:e-?\d+)?", text)]
    assert numbers and all(x == float(f"{x:.12g}") for x in numbers)


def test_printable_rule():
    from explorer.core.units import printable

    assert printable(4.973799150320701e-14) == 0.0
    assert str(printable(-1e-12)) == "0.0"  # never -0
    assert printable(53.400000000000006) == 53.4
    assert printable(-1.2699e-3) == -1.2699e-3
    assert printable(1.003992514422124e-09, "closure_relative_error") == 1.00399251442e-09
    assert printable(2.5e-9) == 2.5e-9
    # a hydraulic conductance's working values lie far below the floor: its key's unit keeps them
    # (an adjuster's leak-down 8.48e-15 m^3/(s Pa)); a length, force or pressure that small is noise
    assert printable(8.482300164692441e-15, "leak_conductance_m3_s_Pa") == 8.48230016469e-15
    assert printable(-1.2e-20, "x_m3_s_Pa") == -1.2e-20
    for key in ("lift_m", "force_N", "pressure_Pa", "m3_s_Pa_count"):
        assert printable(8.48e-15, key) == 0.0
