"""`explorer sweep` and `explorer.sweep` (issue #14): grids, samples, the table and its files,
interruption, pictures, bad input."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import explorer
from conftest import ROOT, SCENES, kill_tree, process_timeout, run_cli
from explorer.core.errors import InputError
from explorer.studies.sweep_spec import make_plan, parse_axis, parse_sample
from explorer.studies.sweep_table import read_table

FLOAT = SCENES / "valve_float_demo.toml"
CYCLOIDAL = SCENES / "cycloidal_demo.toml"


# ---------------------------------------------------------------- grids and samples
def test_linear_grid_with_units_is_the_linspace_in_si():
    axis = parse_axis("valve.lash", "0.1:0.5 mm:5")  # the unit written once applies to both ends
    assert np.allclose(axis.values, np.linspace(1e-4, 5e-4, 5), rtol=0, atol=1e-18)
    assert axis.values[0] == 1e-4 and axis.values[-1] == 5e-4  # ends exactly as given


def test_log_grid_is_geometric_and_speeds_are_rev_per_min():
    axis = parse_axis("linkage.stiffness", "1 kN/mm:100 kN/mm:3", log=True)
    assert axis.values.tolist() == [1e6, 1e7, 1e8] or np.allclose(axis.values, [1e6, 1e7, 1e8], rtol=1e-15)
    rpm = parse_axis("drive.rpm", "100 rad/s:200 rad/s:2")  # a speed with a unit: rev/min in the table
    assert np.allclose(rpm.values, [100 * 60 / (2 * math.pi), 200 * 60 / (2 * math.pi)], rtol=1e-15)
    assert parse_axis("drive.rpm", "1000,2000, 3000").values.tolist() == [1000.0, 2000.0, 3000.0]


def test_product_of_grids_first_key_slowest():
    plan = make_plan([parse_axis("drive.rpm", "1000:2000:2"), parse_axis("valve.lash", "0.1:0.3 mm:3")])
    assert plan.keys == ("drive.rpm", "valve.lash")
    assert plan.values[:, 0].tolist() == [1000.0] * 3 + [2000.0] * 3
    assert np.allclose(plan.values[:, 1], [1e-4, 2e-4, 3e-4] * 2, rtol=1e-15)


def test_samples_are_seeded_numpy_draws_in_si():
    plan = make_plan(samples=[parse_sample("valve.lash", "normal(0.3 mm, 0.02 mm)"),
                              parse_sample("spring.preload", "uniform(200 N, 0.25 kN)")], runs=1000, seed=7)
    rng = np.random.default_rng(7)  # the oracle: the same generator, same order of draws
    assert np.array_equal(plan.values[:, 0], rng.normal(3e-4, 2e-5, 1000))
    assert np.array_equal(plan.values[:, 1], rng.uniform(200.0, 250.0, 1000))
    again = make_plan(samples=[parse_sample("valve.lash", "normal(0.3 mm, 0.02 mm)"),
                               parse_sample("spring.preload", "uniform(200 N, 0.25 kN)")], runs=1000, seed=7)
    assert np.array_equal(plan.values, again.values)


@pytest.mark.parametrize("key, spec, message", [
    ("drive.rpm", "6000:1000:10", "backwards range"),
    ("drive.rpm", "1000:1000:10", "empty range"),
    ("drive.rpm", "1000:6000:0", "zero steps"),
    ("drive.rpm", "", "empty range"),
    ("valve.lash", "0.1:0.3 N:5", "is not a length"),
    ("foo.bar", "1:2:3", "cannot sweep this key"),
    ("linkage.stiffness", "0:1e6:3:log", "log range needs a start > 0"),
    ("valve.lash", "-1 mm:1 mm:3", "must be >= 0"),
    ("drive.rpm", "1000:2e6:3", "must be"),
])
def test_bad_grids_are_one_input_error(key, spec, message):
    with pytest.raises(InputError, match=message):
        parse_axis(key, spec)


@pytest.mark.parametrize("spec, message", [
    ("weibull(1, 2)", "unknown distribution"),
    ("normal(0.3 mm, -0.1 mm)", "negative standard deviation"),
    ("uniform(0.3 mm, 0.1 mm)", "LOW < HIGH"),
    ("normal(0.3 mm)", "takes two values"),
    ("normal(0.3 kg, 0.1 kg)", "is not a length"),
])
def test_bad_samples_are_one_input_error(spec, message):
    with pytest.raises(InputError, match=message):
        parse_sample("valve.lash", spec)


def test_draws_outside_the_valid_range_and_too_many_runs_are_refused():
    with pytest.raises(InputError, match="of the draws fall outside"):
        make_plan(samples=[parse_sample("valve.lash", "normal(0.1 mm, 0.1 mm)")], runs=500, seed=1)
    with pytest.raises(InputError, match="need --yes"):
        make_plan([parse_axis("drive.rpm", "1000:6000:100000"), parse_axis("valve.lash", "0:1 mm:200")])
    big = make_plan([parse_axis("drive.rpm", "1000:6000:5000"), parse_axis("valve.lash", "0:1 mm:2001")], yes=True)
    assert big.runs == 10_005_000


# ---------------------------------------------------------------- the command
BAD_CLI = [
    (["--vary", "drive.rpm=6000:1000:10"], "backwards range"),
    (["--vary", "drive.rpm=1000:1000:10"], "empty range"),
    (["--vary", "drive.rpm=1000:6000:0"], "zero steps"),
    (["--vary", "valve.lash=0.1:0.3 N:5"], "is not a length"),
    (["--vary", "valve.colour=1:2:3"], "cannot sweep this key"),
    (["--sample", "valve.lash=weibull(1, 2)", "--runs", "3"], "unknown distribution"),
    (["--sample", "valve.lash=normal(0.3 mm, -0.1 mm)", "--runs", "3"], "negative standard deviation"),
    (["--vary", "drive.rpm=1000:6000:100000", "--vary", "valve.lash=0:1 mm:200"], "need --yes"),
    (["--sample", "valve.lash=normal(0.3 mm, 0.01 mm)"], "needs --runs"),
    (["--log", "--vary", "drive.rpm=1000:2000:3"], "--log follows the --vary"),
]


@pytest.mark.parametrize("args, message", BAD_CLI)
def test_cli_bad_input_one_line_status_2_nothing_written(tmp_path, args, message):
    out, png = tmp_path / "t.parquet", tmp_path / "t.png"
    r = run_cli("sweep", FLOAT, *args, "-o", out, "--plot", png)
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], r.stderr
    assert "Traceback" not in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_cli_wrong_output_extension_is_refused_before_work(tmp_path):
    r = run_cli("sweep", FLOAT, "--vary", "drive.rpm=1000:2000:3", "-o", tmp_path / "t.txt")
    assert r.returncode == 2 and "must end in .parquet or .csv" in r.stderr
    assert list(tmp_path.iterdir()) == []


def test_cli_sweep_writes_parquet_csv_png_and_recording(tmp_path):
    out, csv, png, rrd = (tmp_path / n for n in ("s.parquet", "s.csv", "s.png", "s.rrd"))
    r = run_cli("sweep", FLOAT, "--vary", "drive.rpm=2000:5000:6", "-o", out, "--plot", png, "--record", rrd,
                "--workers", "2")
    assert r.returncode == 0, r.stderr
    table = read_table(out)
    assert table.complete and len(table) == 6
    assert list(table.columns)[:2] == ["run", "drive_rpm"]
    assert table.columns["drive_rpm"].tolist() == [2000.0, 2600.0, 3200.0, 3800.0, 4400.0, 5000.0]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    r = run_cli("sweep", FLOAT, "--vary", "drive.rpm=2000:5000:6", "-o", csv, "--workers", "1")
    assert r.returncode == 0, r.stderr
    again = read_table(csv)
    for name in table.columns:  # CSV holds repr() of every float: the same numbers
        assert np.array_equal(np.asarray(again.columns[name], float), np.asarray(table.columns[name], float),
                              equal_nan=True), name
    # no temporary left beside the outputs
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.csv", "s.parquet", "s.png", "s.rrd"]
    from rerun.chunk import RrdReader

    timelines, paths = set(), set()
    for chunk in RrdReader(str(rrd)).stream():
        paths.add(str(chunk.entity_path))
        timelines.update(f.name for f in chunk.to_record_batch().schema)
    assert "/sweep/peak_linkage_force_N" in paths
    assert any(t.startswith("drive_rpm_e") for t in timelines), timelines


def test_ctrl_c_keeps_the_finished_runs_as_a_valid_file_marked_incomplete(tmp_path):
    from explorer.core.processes import spawn

    out, log = tmp_path / "s.parquet", tmp_path / "err.txt"
    env = dict(os.environ, PYTHONPATH=str(ROOT), EXPLORER_PROGRESS="1")  # a log, no terminal: asked for
    with open(log, "w") as err:
        proc = spawn([sys.executable, "-m", "explorer", "sweep", str(FLOAT), "--vary", "drive.rpm=3000:6000:200000",
                      "-o", str(out), "--workers", "2"], stdout=subprocess.PIPE, stderr=err, text=True,
                     env=env, cwd=ROOT)
    try:
        # wait for the first progress line (runs are done), then interrupt as Ctrl-C does
        deadline = time.monotonic() + process_timeout(0.5)
        while "runs/s" not in log.read_text() and time.monotonic() < deadline and proc.poll() is None:
            time.sleep(0.2)
        assert "runs/s" in log.read_text(), log.read_text()
        proc.send_signal(signal.SIGINT)
        out_text, _ = proc.communicate(timeout=process_timeout(0.5))
    finally:
        kill_tree(proc.pid)
    assert proc.returncode == 130, out_text
    assert "INCOMPLETE" in out_text
    table = read_table(out)
    assert not table.complete and 0 < len(table) < 200000
    assert table.metadata["runs_planned"] == 200000 and table.metadata["runs_finished"] == len(table)
    runs = np.asarray(table.columns["run"])
    assert np.all(np.diff(runs) > 0)  # in run order, each once


# ---------------------------------------------------------------- the Python API
def test_api_returns_columns_arrow_and_pictures():
    result = explorer.sweep(CYCLOIDAL, vary={"drive.rpm": "500:3000:4"}, workers=1)
    assert result.complete and len(result) == 4
    assert set(result.columns) >= {"run", "drive_rpm", "run_failed"}
    arrow = result.to_arrow()
    assert arrow.num_rows == 4 and arrow.schema.metadata[b"explorer.complete"] == b"true"
    assert result.png()[:4] == b"\x89PNG"


def test_only_what_the_scenes_effects_compute():
    kin = explorer.loads_scene('[drive]\nrpm = 1000\n[lift]\nlaw = "cycloidal"\nheight = "8 mm"\nrise = "90 deg"\n'
                               'return = "90 deg"\n[valve]\nmass = "0.1 kg"\nlash = "0.1 mm"\n')
    result = explorer.sweep(kin, vary={"valve.lash": "0:0.2 mm:3"}, workers=1)
    assert list(result.columns) == ["run", "valve_lash_m", "run_failed"]
    forces = explorer.sweep(CYCLOIDAL, vary={"drive.rpm": "1000:2000:2"}, workers=1)
    assert "separations" not in forces.columns or "elastic" in explorer.load_scene(CYCLOIDAL).effects


def test_api_bad_input_raises_before_work():
    with pytest.raises(InputError, match="no \\[linkage\\] section"):
        explorer.sweep(explorer.loads_scene('[drive]\nrpm = 1000\n[lift]\nlaw = "cycloidal"\nheight = "8 mm"\n'
                                            'rise = "90 deg"\nreturn = "90 deg"\n'),
                       vary={"linkage.stiffness": "1e6:1e7:3"})
    with pytest.raises(InputError, match="nothing to sweep"):
        explorer.sweep(FLOAT)


def test_interrupt_from_the_progress_callback_gives_an_incomplete_table():
    calls = []

    def progress(done, total, seconds):
        calls.append(done)
        if len(calls) == 2:
            raise KeyboardInterrupt

    result = explorer.sweep(FLOAT, vary={"drive.rpm": "2000:5000:12"}, workers=1, progress=progress)
    assert not result.complete and len(result) == calls[-1] < 12
    assert result.metadata["runs_finished"] == len(result)


def test_pictures_for_a_map_and_a_tolerance_study(tmp_path):
    grid = explorer.sweep(FLOAT, vary={"drive.rpm": "2000:5000:3", "linkage.stiffness": "1e6:1e7:3"}, workers=1,
                          log=("linkage.stiffness",))
    assert len(grid) == 9
    from explorer.studies.sweep_plots import heatmaps_png, histograms_png, separating_share

    assert heatmaps_png(grid.table)[:4] == b"\x89PNG"
    tol = explorer.sweep(FLOAT, sample={"valve.lash": "uniform(0.2 mm, 0.3 mm)"}, runs=6, seed=3, workers=1)
    assert histograms_png(tol.table)[:4] == b"\x89PNG"
    share = separating_share(tol.table)
    assert share == np.mean(np.asarray(tol.columns["separations"]) > 0)


def test_import_explorer_does_not_load_the_sweep_machinery():
    code = ("import sys, explorer\n"
            "bad = [m for m in sys.modules if m.startswith(('explorer.sweep', 'pyarrow', 'distributed', 'dask'))]\n"
            "print(bad)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                       timeout=process_timeout(0.5))
    assert r.stdout.strip() == "[]", r.stdout + r.stderr


# ---------------------------------------------------------------- hostile specs
from hypothesis import given, settings, strategies as st  # noqa: E402

_PIECES = st.sampled_from(["1000", "6000", "0", "-5", "1e400", "nan", "inf", "0.3 mm", "3 kN/mm", "N", "mm", "", " ",
                           ":", ",", "log", "lin", "2.5", "1e7", "10**10**10", "(", ")", "'", "\"", "=", "\x00", "é",
                           "normal(", "uniform(", "1 rpm", "2 rad/s", "-0 mm"])


@settings(max_examples=300, deadline=None)
@given(key=st.sampled_from(["drive.rpm", "valve.lash", "linkage.stiffness", "seat.restitution", "x.y"]),
       parts=st.lists(_PIECES, max_size=8), log=st.booleans())
def test_any_grid_text_is_an_axis_or_one_input_error(key, parts, log):
    text = "".join(parts)
    try:
        axis = parse_axis(key, text, log=log)
    except InputError as exc:
        assert "\n" not in str(exc)
        return
    assert axis.values.size >= 1 and np.all(np.isfinite(axis.values))
    assert np.all(np.diff(axis.values) > 0) or "," in text  # a range is increasing; a list is as given


@settings(max_examples=200, deadline=None)
@given(key=st.sampled_from(["drive.rpm", "valve.lash", "spring.preload"]), parts=st.lists(_PIECES, max_size=8))
def test_any_sample_text_is_a_sample_or_one_input_error(key, parts):
    text = "".join(parts)
    try:
        sample = parse_sample(key, text)
    except InputError as exc:
        assert "\n" not in str(exc)
        return
    assert math.isfinite(sample.a) and math.isfinite(sample.b)
