"""`explorer record`: .rrd files read back with rerun.chunk.RrdReader and compared with
`explorer simulate` on the same scene (values, entity paths, timelines, events, blueprint, 3D).

Tolerances: the series are float64 in both the CSV (repr round-trips exactly) and the .rrd, so
they must be equal bit for bit (lengths: the CSV's metres times 1000, the same multiplication). The `time` timeline is stored as integer nanoseconds: within
0.5 ns of time_s. Transforms are stored as float32 by rerun: relative 1e-6 of the gear's size.
"""

from __future__ import annotations

import math
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from explorer import load_scene
from explorer.cli import main
from explorer.effects.pipeline import simulate
from explorer.view.rerun.recording import TIMELINE_ANGLE, entity_path, series_layout
from explorer.view.rerun.read import read_blueprint_views, read_rrd
from conftest import process_timeout

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "assets" / "scenes"
FLOAT = SCENES / "valve_float_demo.toml"  # kinematics, lash, forces, contact: the most columns
CYCLOIDAL = SCENES / "cycloidal_demo.toml"


def simulate_csv(tmp_path: Path, scene: Path, *overrides: str) -> dict[str, np.ndarray]:
    """`explorer simulate` output as arrays by column name."""
    out = tmp_path / f"sim_{len(list(tmp_path.iterdir()))}.csv"
    args = ["simulate", str(scene), "-o", str(out)]
    for o in overrides:
        args += ["--set", o]
    assert main(args) == 0
    names = out.read_text().splitlines()[0].split(",")
    table = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    return {name: table[:, i] for i, name in enumerate(names)}


def record(tmp_path: Path, *args: str, name: str = "run.rrd") -> Path:
    out = tmp_path / name
    assert main(["record", *args, "-o", str(out)]) == 0
    return out


# ---------------------------------------------------------------------------------------------
# the documented mapping


DOCUMENTED = {  # the examples of the module docstring
    "valve_lift_m": "/valve/lift", "valve_velocity_m_s": "/valve/velocity",
    "valve_accel_m_s2": "/valve/acceleration", "valve_jerk_m_s3": "/valve/jerk",
    "follower_lift_m": "/follower/lift", "rigid_valve_lift_m": "/valve_rigid/lift",
    "linkage_force_N": "/forces/linkage", "spring_force_N": "/forces/spring",
    "contact_force_N": "/forces/contact", "camshaft_torque_Nm": "/torque/camshaft",
    "hertz_stress_Pa": "/stress/hertz", "pressure_angle_deg": "/angles/pressure",
    "contour_radius_m": "/lengths/contour_radius", "mystery": "/other/mystery",
}


def test_documented_entity_paths():
    import explorer.view.rerun.recording as recording

    for column, path in DOCUMENTED.items():
        assert entity_path(column) == path, column
        assert path in recording.__doc__ or column == "mystery", f"{path} not documented"


def test_layout_has_unique_paths_and_skips_the_timelines():
    columns = list(simulate(load_scene(FLOAT)).columns)
    layout = series_layout(columns)
    assert len({s.path for s in layout}) == len(layout) == len(columns) - 2
    assert {s.column for s in layout} == set(columns) - {"cam_angle_deg", "time_s"}
    # a clash goes to /other instead of overwriting
    clash = series_layout(["spring_force_N", "spring_N"])
    assert [s.path for s in clash] == ["/forces/spring", "/other/spring_N"]


# ---------------------------------------------------------------------------------------------
# one scene: values, timelines, events, summary, blueprint, 3D


@pytest.fixture(scope="module")
def float_recording(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("float")
    csv = simulate_csv(tmp, FLOAT)
    out = record(tmp, str(FLOAT))
    return out, csv


def test_series_equal_simulate_output(float_recording):
    out, csv = float_recording
    runs = read_rrd(out)
    assert len(runs) == 1
    run = runs[0]
    assert run.name == "Valve float demo"
    assert run.application_id == "valve-gear-explorer"
    series = run.series
    n = csv["time_s"].size
    assert n == 3600
    for s in series_layout(csv):
        got = series[s.path]
        assert np.array_equal(got["value"], s.values(csv)), s.column  # bit for bit
        assert s.scale == (1e3 if s.column.endswith("_m") else 1.0), s.column  # lengths in mm (#13.8)
        assert np.array_equal(got["step"], np.arange(n))
        assert np.max(np.abs(got["time"] - csv["time_s"] * 1e9)) <= 0.5
        # the cam-angle timeline counts hundredths of a degree (#28.11: whole degrees made
        # staircases, #13.8: millidegrees squeezed the plots into a 1-degree window)
        assert np.array_equal(got[TIMELINE_ANGLE], np.rint(100.0 * csv["cam_angle_deg"]).astype(np.int64))
    # the headline quantities are where the docstring says
    for path in ("/valve/lift", "/valve/velocity", "/valve/acceleration", "/valve/jerk", "/forces/linkage",
                 "/forces/spring", "/forces/contact", "/torque/camshaft", "/angles/pressure", "/stress/hertz"):
        assert path in series, path
    # every series has its name (with unit) for the legend
    assert run.static["/valve/lift"]["SeriesLines:names"] == ["valve lift [mm]"]
    assert run.static["/forces/linkage"]["SeriesLines:names"] == ["linkage force [N]"]


def test_every_sample_has_its_own_place_on_the_cam_angle_timeline(float_recording, tmp_path):
    """Issue #28.11: in whole degrees, ten of the 3600 samples of a revolution shared each value
    of the cam-angle timeline and a series plotted against it was a staircase of vertical runs.
    Read back, every sample has its own position (strictly increasing), within half a hundredth
    of a degree of its cam angle, at the default 3600 steps and at 36 000, the finest the
    timeline separates; the timeline's name says its unit."""
    assert TIMELINE_ANGLE == "cam_angle_0.01deg"
    out, csv = float_recording
    got = read_rrd(out)[0].series["/valve/lift"]
    position = got[TIMELINE_ANGLE]
    assert position.size == csv["cam_angle_deg"].size == 3600
    assert np.all(np.diff(position) > 0)  # no two samples share a position
    assert np.max(np.abs(position / 100.0 - csv["cam_angle_deg"])) <= 0.005 + 1e-9
    fine = record(tmp_path, str(CYCLOIDAL), "--no-parts", "--set", "solver.steps_per_revolution=36000", name="fine.rrd")
    position = read_rrd(fine)[0].series["/valve/lift"][TIMELINE_ANGLE]
    assert position.size == 36000 and np.array_equal(position, np.arange(36000))


def test_events_and_warnings_are_logged_at_their_instants(float_recording):
    out, _ = float_recording
    result = simulate(load_scene(FLOAT))
    events = result.events
    warnings = result.warnings
    assert events and warnings  # this scene has lash impacts and a float warning
    log = read_rrd(out)[0].temporal["/events"]
    texts, levels = list(log["TextLog:text"]), list(log["TextLog:level"])
    assert len(texts) == len(events) + len(warnings)
    warn_rows = [i for i, lv in enumerate(levels) if lv == "WARN"]
    assert [texts[i] for i in warn_rows] == [f"warning: {w}" for w in warnings]
    assert all(log["time"][i] == 0 for i in warn_rows)
    info = [i for i, lv in enumerate(levels) if lv == "INFO"]
    for event in events:
        rows = [i for i in info if texts[i].startswith(event["kind"] + " at ")]
        times = [log["time"][i] for i in rows]
        assert any(abs(t - event["time_s"] * 1e9) <= 0.5 for t in times), event
        i = rows[int(np.argmin([abs(t - event["time_s"] * 1e9) for t in times]))]
        assert log[TIMELINE_ANGLE][i] == np.rint(100.0 * event["cam_angle_deg"])
        n = result.columns["time_s"].size  # the step at or before the instant
        assert log["step"][i] == math.floor(event["cam_angle_deg"] / 360 * n + 1e-9)


def test_summary_document(float_recording):
    out, _ = float_recording
    doc = read_rrd(out)[0].static["/summary"]
    text = doc["TextDocument:text"][0]
    assert text.startswith("# Valve float demo")
    assert "jump_speed_rpm" in text and "valve float" in text


def test_the_layout_read_from_a_file_is_the_one_sent_last(tmp_path):
    """A live session's file holds a blueprint per layout sent; rerun's reader lists them in no
    fixed order (reading its first gave the first, second or third of three from run to run, and
    a test once read a layout older than the checks). The reader takes the one sent last."""
    import rerun as rr
    import rerun.blueprint as rrb

    out = tmp_path / "layouts.rrd"
    rec = rr.RecordingStream("blueprint-order-test")
    rec.save(out)
    for i in range(6):
        rec.send_blueprint(rrb.Blueprint(rrb.TimeSeriesView(name=f"layout {i}", origin="/")), make_active=True)
    rec.flush()
    rec.disconnect()
    assert [v["name"] for v in read_blueprint_views(out)] == ["layout 5"]


def test_blueprint_has_3d_beside_s_v_p_and_forces(float_recording):
    out, _ = float_recording
    views = read_blueprint_views(out)
    classes = [v["class"] for v in views]
    assert "3D" in classes and "TextLog" in classes
    spatial = next(v for v in views if v["class"] == "3D")
    assert spatial["origin"] == "/parts"
    series = {v["name"]: v["contents"] for v in views if v["class"] == "TimeSeries"}
    assert "/valve/lift/**" in series["valve lift s"]  # with children: a sweep's overlay draws there too
    assert "/valve/velocity/**" in series["velocity v"]
    assert "/valve/acceleration/**" in series["acceleration p"]
    assert series["forces"] == ["/forces/**"]
    assert "/torque/camshaft" in series["torque"] and "/stress/hertz" in series["stress"]
    # #13.8: every plot spans the revolution on the cam-angle timeline (not a 1-degree window),
    # which the time panel shows, playing a revolution in ANGLE_PLAYBACK_S seconds at 1x
    from explorer.view.rerun.recording import ANGLE_PLAYBACK_S

    for v in views:
        if v["class"] == "TimeSeries":
            assert v["time_ranges"][TIMELINE_ANGLE] == (0, 36000), v["name"]  # one revolution
    panel = next(v for v in views if v["class"] == "TimePanel")
    assert panel["timeline"] == TIMELINE_ANGLE and panel["playback_speed"] == 1.0
    assert 36000.0 / panel["fps"] == pytest.approx(ANGLE_PLAYBACK_S) and 2.0 <= ANGLE_PLAYBACK_S <= 20.0


def test_legends_sit_where_the_curves_are_not(float_recording):
    """#13.8: each main plot's legend is in the corner whose legend box (LEGEND_BOX of the plot)
    holds no sample of its curves, as the viewer draws them (the curves' own y range)."""
    from explorer.view.rerun.recording import LEGEND_BOX, MAIN_VIEWS, view_paths

    out, _ = float_recording
    run = read_rrd(out)[0]
    views = {v["name"]: v for v in read_blueprint_views(out) if v["class"] == "TimeSeries"}
    w, h = LEGEND_BOX
    for name in [n for n, _ in MAIN_VIEWS] + ["forces"]:
        paths = view_paths(name, run.series)
        assert paths, name
        corner = views[name]["legend_corner"]
        x = np.concatenate([run.series[p][TIMELINE_ANGLE] for p in paths]).astype(float) / 100.0
        y = np.concatenate([run.series[p]["value"] for p in paths])
        u, v = x / 360.0, (y - y.min()) / (y.max() - y.min())
        across = u >= 1 - w if corner.startswith("Right") else u <= w
        up = v >= 1 - h if corner.endswith("Top") else v <= h
        assert not np.any(across & up), (name, corner)


def test_parts_replay_the_motion(float_recording):
    """Meshes as built by explorer.view.parts, poses per step; and an independent physical check:
    the valve (z up, opening downwards) sits lower by exactly the valve lift."""
    from explorer.view import parts as meshes

    out, csv = float_recording
    run = read_rrd(out)[0]
    result = simulate(load_scene(FLOAT))
    parts = meshes.build_parts(result.scene, result)
    poses = meshes.part_poses(result.scene, result)
    size = float(np.max(np.abs(np.vstack([m.vertices for m in parts.values()]))))
    tol = 1e-6 * size  # float32 storage
    assert run.static["/parts"]["ViewCoordinates:xyz"] is not None
    for name, mesh in parts.items():
        static = run.static[f"/parts/{name}"]
        vertices = np.asarray(static["Mesh3D:vertex_positions"], dtype=float)
        assert vertices.shape == mesh.vertices.shape
        assert np.max(np.abs(vertices - mesh.vertices)) <= tol
        assert np.asarray(static["Mesh3D:triangle_indices"]).shape == mesh.faces.shape
        positions, wxyz = poses[name]
        if f"/parts/{name}" in run.temporal:
            rows = run.temporal[f"/parts/{name}"]
            assert np.array_equal(rows["step"], np.arange(positions.shape[0]))
            assert np.max(np.abs(rows["Transform3D:translation"] - positions)) <= tol
            assert np.max(np.abs(rows["Transform3D:quaternion"] - wxyz[:, [1, 2, 3, 0]])) <= 1e-6
        else:  # a part that never moves has one static pose
            assert np.all(positions == positions[0]) and np.all(wxyz == wxyz[0])
            assert np.max(np.abs(np.asarray(static["Transform3D:translation"][0]) - positions[0])) <= tol
    valve_z = run.temporal["/parts/valve"]["Transform3D:translation"][:, 2]
    closed = valve_z[np.argmin(csv["valve_lift_m"])]
    assert np.max(np.abs((closed - valve_z) - csv["valve_lift_m"])) <= tol
    cam_q = run.temporal["/parts/cam"]["Transform3D:quaternion"]  # x y z w: turning about y
    angle = -2.0 * np.arctan2(cam_q[:, 1], cam_q[:, 3])  # counter-clockwise in the cam plane
    assert np.max(np.abs(np.angle(np.exp(1j * (angle - np.radians(csv["cam_angle_deg"])))))) <= 1e-6
    scale = run.temporal["/parts/spring"]["Transform3D:scale"]
    assert np.max(np.abs(scale[:, 2] - meshes.spring_axial_scale(result.scene, result))) <= 1e-6
    assert np.all(scale[:, :2] == 1.0)


# ---------------------------------------------------------------------------------------------
# several recordings in one file


def test_sweep_and_several_scenes_make_separate_recordings(tmp_path):
    steps = "solver.steps_per_revolution=360"
    out = record(tmp_path, str(CYCLOIDAL), str(FLOAT), "--set", steps, "--sweep", "drive.rpm=600,1200",
                 "--no-parts")
    runs = {r.name: r for r in read_rrd(out)}
    # the varied value first (#13.8): the viewer's list cuts long names at the end
    expected = {f"drive.rpm={rpm} · {scene}" for scene in ("Cycloidal demo", "Valve float demo")
                for rpm in (600, 1200)}
    assert set(runs) == expected | {"overlay: all 4 runs"}
    assert len({r.recording_id for r in runs.values()}) == 5
    for scene_file, scene_name in ((CYCLOIDAL, "Cycloidal demo"), (FLOAT, "Valve float demo")):
        for rpm in (600, 1200):
            csv = simulate_csv(tmp_path, scene_file, steps, f"drive.rpm={rpm}")
            series = runs[f"drive.rpm={rpm} · {scene_name}"].series
            for s in series_layout(csv):
                assert np.array_equal(series[s.path]["value"], s.values(csv)), (scene_name, rpm, s.column)
            # the time axis follows the speed: one revolution lasts 60/rpm s
            last = series["/valve/lift"]["time"][-1]
            assert abs(last - 60.0 / rpm * 359 / 360 * 1e9) <= 0.5
    assert read_blueprint_views(out)  # the layout travels with the merged file
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []  # no leftovers


def test_two_sweeps_make_every_combination(tmp_path):
    out = record(tmp_path, str(CYCLOIDAL), "--set", "solver.steps_per_revolution=72", "--no-parts",
                 "--set", 'effects=["kinematics", "lash"]',  # rigid: the lift falls by the lash exactly
                 "--sweep", "drive.rpm=600,1200", "--sweep", 'valve.lash=0.1mm,0.2mm')
    names = sorted(r.name for r in read_rrd(out))
    assert names == sorted([f"drive.rpm={r}, valve.lash={l} · Cycloidal demo"
                            for r in (600, 1200) for l in ("0.1mm", "0.2mm")] + ["overlay: all 4 runs"])
    lifts = {r.name: r.series["/valve/lift"]["value"].max() for r in read_rrd(out) if "/valve/lift" in r.series}
    # more lash, less valve lift, by exactly the lash difference (ratio 1), in mm
    a = lifts["drive.rpm=600, valve.lash=0.1mm · Cycloidal demo"]
    b = lifts["drive.rpm=600, valve.lash=0.2mm · Cycloidal demo"]
    assert abs((a - b) - 0.1) <= 1e-9


def test_a_sweep_has_an_overlay_of_its_runs(tmp_path):
    """#13.8: a sweep's file holds one recording more whose lift, velocity, acceleration and
    forces are every run's (thinned as overlay_entry keeps them), each a child of the path the
    layout's views draw, named by the run's label: the views show the runs over each other."""
    from explorer.view.rerun.recording import overlay_entry

    rpms = (2000, 3000, 4000)
    out = record(tmp_path, str(FLOAT), "--no-parts", "--set", "solver.steps_per_revolution=720",
                 "--sweep", "drive.rpm=" + ",".join(map(str, rpms)))
    runs = {r.name: r for r in read_rrd(out)}
    overlay = runs.pop("overlay: all 3 runs")
    views = {v["name"]: v["contents"] for v in read_blueprint_views(out) if v["class"] == "TimeSeries"}
    for k, rpm in enumerate(rpms, start=1):
        label = f"drive.rpm={rpm} · Valve float demo"
        result = simulate(load_scene(FLOAT, ["solver.steps_per_revolution=720", f"drive.rpm={rpm}"]))
        _, angle, _, curves = overlay_entry(label, result)
        assert {"/valve/lift", "/valve/velocity", "/valve/acceleration", "/forces/contact"} <= set(curves)
        for path, values in curves.items():
            child = f"{path}/run{k:02d}"
            assert np.array_equal(overlay.series[child]["value"], values), child
            assert np.array_equal(overlay.series[child][TIMELINE_ANGLE], np.rint(100.0 * angle).astype(np.int64))
            assert overlay.static[child]["SeriesLines:names"] == [label]
            # the view that draws `path` in a run draws the overlay's child too
            assert any(c == f"{path}/**" or (c.endswith("/**") and child.startswith(c[:-2])) for cs in views.values()
                       for c in cs), child
        # the overlay's lift is the run's own lift, thinned
        stride = 720 // len(angle)
        assert np.array_equal(curves["/valve/lift"], runs[label].series["/valve/lift"]["value"][::stride])


# ---------------------------------------------------------------------------------------------
# bad input and interrupted writes


@pytest.mark.parametrize("args, needle", [
    (["--sweep", "drive.rpm=100,,200"], "--sweep"),
    (["--sweep", "rpm=100"], "dotted"),
    (["--sweep", "drive.rpm=fast"], "drive.rpm"),
    (["--set", "drive.rpm=-5"], "drive.rpm"),
    (["--set", "nosuch.key=1"], "nosuch"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, needle):
    out = tmp_path / "run.rrd"
    code = main(["record", str(CYCLOIDAL), *args, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("error: ") and err.count("\n") == 1 and needle in err
    assert list(tmp_path.iterdir()) == []


def test_bad_output_and_scene(tmp_path, capsys):
    for args, needle in ((["-o", str(tmp_path / "run.csv")], ".rrd"),
                         (["-o", str(tmp_path / "missing" / "run.rrd")], "does not exist"),
                         (["-o", str(tmp_path)], ".rrd")):
        assert main(["record", str(CYCLOIDAL), *args]) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: ") and err.count("\n") == 1 and needle in err
    assert main(["record", str(tmp_path / "nope.toml"), "-o", str(tmp_path / "run.rrd")]) == 2
    assert "file not found" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_failure_while_writing_leaves_previous_file_and_no_temporaries(tmp_path, monkeypatch, capsys):
    import explorer.view.rerun.recording as recording

    out = tmp_path / "run.rrd"
    out.write_bytes(b"previous content")

    def broken_merge(pieces, target):
        Path(target).write_bytes(b"half")
        raise RuntimeError("disk full")

    monkeypatch.setattr(recording, "merge_rrd", broken_merge)
    code = main(["record", str(CYCLOIDAL), "--sweep", "drive.rpm=600,1200", "--no-parts",
                 "--set", "solver.steps_per_revolution=72", "-o", str(out)])
    assert code == 1
    assert capsys.readouterr().err == f"error: {out}: --output: writing failed: disk full\n"
    assert out.read_bytes() == b"previous content"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.rrd"]


def _record_and_kill(tmp_path: Path, out: Path, delay: float) -> int:
    """Start a long `explorer record`, SIGKILL it `delay` s after its first temporary appears."""
    cmd = [sys.executable, "-m", "explorer", "record", str(CYCLOIDAL), "--no-parts",
           "--set", "solver.steps_per_revolution=100000", "--sweep", "drive.rpm=1000,2000,3000", "-o", str(out)]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + process_timeout()
        while time.monotonic() < deadline and proc.poll() is None:
            if any(p.name.startswith(f".{out.name}.") for p in tmp_path.iterdir()):
                break
            time.sleep(0.002)
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        return proc.wait(timeout=process_timeout(0.25))
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


@pytest.mark.parametrize("previous", [None, b"the previous recording"])
def test_killed_midway_never_leaves_a_truncated_target(tmp_path, previous):
    out = tmp_path / "run.rrd"
    if previous is not None:
        out.write_bytes(previous)
    code = _record_and_kill(tmp_path, out, delay=0.3)
    assert code == -signal.SIGKILL, "the recording finished before it could be interrupted"
    # killed while writing: its temporaries are there, under hidden names
    assert any(p.name.startswith(".run.rrd.") for p in tmp_path.iterdir())
    if previous is None:
        assert not out.exists()
    else:
        assert out.read_bytes() == previous
    time.sleep(0.5)  # a merge child may still be finishing its temporary; it never renames
    if previous is None:
        assert not out.exists()
    else:
        assert out.read_bytes() == previous


def test_parts_that_cannot_be_built_leave_a_warning_and_the_series(tmp_path, capsys, monkeypatch):
    import explorer.view.rerun.recording as recording

    def no_meshes(label, result, magnification=None):  # with_parts's signature
        raise NotImplementedError("no meshes for this gear")

    monkeypatch.setattr(recording, "with_parts", no_meshes)
    out = record(tmp_path, str(CYCLOIDAL), "--set", "solver.steps_per_revolution=72")
    assert "3D parts left out (NotImplementedError: no meshes for this gear)" in capsys.readouterr().err
    run = read_rrd(out)[0]
    assert "/valve/lift" in run.series and not any(p.startswith("/parts") for p in run.temporal)


def test_an_incomplete_file_is_never_renamed_into_place(tmp_path, monkeypatch, capsys):
    """rerun's file sink only logs write errors: the footer check stops a broken file."""
    import explorer.view.rerun.worker as worker

    out = tmp_path / "run.rrd"
    out.write_bytes(b"previous content")
    real_write = worker.write_file

    def truncating_write(worker_, path, run, layout):
        real_write(worker_, path, run, layout)
        data = Path(path).read_bytes()
        Path(path).write_bytes(data[: len(data) // 2])  # as if the disk filled up

    monkeypatch.setattr(worker, "write_file", truncating_write)
    code = main(["record", str(CYCLOIDAL), "--no-parts", "--set", "solver.steps_per_revolution=72", "-o", str(out)])
    assert code == 1 and "incomplete (no rrd footer)" in capsys.readouterr().err
    assert out.read_bytes() == b"previous content"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.rrd"]
