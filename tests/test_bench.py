"""`explorer bench` (explorer/studies/bench.py, explorer/cli/bench.py): accuracy versus time.

Timings are measured but never asserted (machines differ). What is checked: that the numbers
the table reports are what they claim to be -- errors recomputed independently against an exact
closed-form-based solution, the converged reference agreeing with the exact solver, accuracy
improving with resolution, the Pareto front being non-dominated, schenker1902 skipped exactly
where it is unstable -- and that the command writes its files and fails cleanly on bad input.
"""

import csv
import io
import math

import numpy as np
import pytest

from conftest import process_timeout, run_cli
from explorer.studies.bench import ProgressBar, chart_png, model_and_drive, run_bench
from explorer.dynamics import schenker1902
from explorer.dynamics.solvers import solve
from explorer.core.errors import InputError
from explorer.scene.scene import loads_scene
from dynamics_cases import float_valve_scene

# A small valve with a soft spring at high speed: lift-off, separations, re-contacts and seat.
FLOAT_SCENE = float_valve_scene("bench float test", ["kinematics"], '[linkage]\nstiffness = "5e6 N/m"\n')


@pytest.fixture(scope="module")
def scene():
    return loads_scene(FLOAT_SCENE, source="<bench-test>")


@pytest.fixture(scope="module")
def report(scene):
    calls = []
    rep = run_bench(scene, quick=True, repeats=1, progress=lambda done, total, label: calls.append((done, total, label)),
                    differentiation=False)
    return rep, calls


def test_reference_is_converged_and_agrees_with_exact(report):
    rep, _ = report
    assert {"lift-off", "separation", "re-contact", "seat"} <= set(rep.reference_events)
    assert rep.reference_check_m < 1e-9  # scipy rtol 1e-12 vs exact: two methods, one answer


def test_errors_are_what_they_claim(report, scene):
    # Recompute two rows independently: the run at the default grid against exact at 10x the
    # steps (a different reference than the bench uses), sampled on the same times.
    rep, _ = report
    model, drive = model_and_drive(scene)
    revolution = 2 * math.pi / drive.omega
    fine = np.arange(36000) * (revolution / 36000)
    truth = solve(model, drive, fine, method="exact").s[::10]
    t = fine[::10]
    for method, options in (("schenker1902", {}), ("scipy", dict(scipy_method="DOP853", rtol=1e-8, atol=1e-11))):
        row = [r for r in rep.runs if r.method == method and r.steps == 3600 and (r.rtol in (None, 1e-8))][0]
        error = np.abs(solve(model, drive, t, method=method, **options).s - truth).max()
        assert row.max_error_m == pytest.approx(error, rel=1e-3, abs=1e-12)


def test_accuracy_improves_with_resolution_and_default_exact_meets_the_target(report):
    rep, _ = report
    sch = sorted((r for r in rep.runs if r.method == "schenker1902"), key=lambda r: r.steps)
    assert [r.max_error_m for r in sch] == sorted((r.max_error_m for r in sch), reverse=True)
    sci = {r.rtol: r.max_error_m for r in rep.runs if r.method == "scipy"}
    assert sci[1e-8] < sci[1e-4]
    exact_default = [r for r in rep.runs if r.method == "exact" and r.steps == 3600][0]
    assert exact_default.max_error_m < 1e-8  # issue 4: default settings within 1e-8 m
    assert exact_default.events == len(rep.reference_events)
    assert rep.ratio.exact_error_m == pytest.approx(exact_default.max_error_m, rel=1e-6, abs=1e-15)
    assert rep.ratio.scipy_error_m < 1e-8 and rep.ratio.ratio > 0


def test_pareto_front_is_non_dominated(report):
    rep, _ = report
    front = rep.pareto()
    for f in front:
        assert not any(r.cpu_time_s < f.cpu_time_s and r.max_error_m < f.max_error_m for r in rep.runs)
    for r in rep.runs:  # and every other run is dominated by (or equal to) a front member
        assert any(f.cpu_time_s <= r.cpu_time_s and f.max_error_m <= r.max_error_m for f in front)


def test_progress_reaches_the_end(report):
    _, calls = report
    done = [c[0] for c in calls]
    assert done == sorted(done) and calls[-1][0] == calls[-1][1] and calls[-1][2] == "done"


def test_table_csv_and_chart(report):
    rep, _ = report
    text = rep.table()
    assert "exact" in text and "schenker1902" in text and "DOP853 rtol 1e-08" in text and "faster" in text
    rows = list(csv.DictReader(io.StringIO(rep.csv_text())))
    assert len(rows) == len(rep.runs)
    assert float(rows[0]["max_error_m"]) == rep.runs[0].max_error_m
    png = chart_png(rep)
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_progress_bar_draws_one_line():
    stream = io.StringIO()
    bar = ProgressBar(stream, width=10)
    bar(0, 4, "start")
    bar(2, 4, "half")
    bar(4, 4, "done")
    out = stream.getvalue()
    assert "[#####.....] 2/4 half" in out and out.endswith("\n") and out.count("\n") == 1


def test_schenker_is_skipped_exactly_where_unstable():
    # 2e8 N/m on 0.1 kg: Tn = 0.14 ms, revolution 15 ms -> stable only from 272 steps on
    scene = loads_scene(FLOAT_SCENE.replace('stiffness = "5e6 N/m"', 'stiffness = "2e8 N/m"'), source="<stiff>")
    model, drive = model_and_drive(scene)
    needed = schenker1902.min_stable_steps(model, drive.omega)
    assert 90 < needed < 900
    rep = run_bench(scene, quick=True, repeats=1, differentiation=False)
    assert sorted(r.steps for r in rep.runs if r.method == "schenker1902") == [900, 3600]
    assert any("schenker1902 skipped at 90 steps" in n for n in rep.notes)


def test_scene_without_linkage_is_an_input_error():
    scene = loads_scene(FLOAT_SCENE.replace('[linkage]\nstiffness = "5e6 N/m"\n', ""), source="no-linkage.toml")
    with pytest.raises(InputError, match="linkage"):
        run_bench(scene, quick=True)


def test_command_writes_table_csv_and_charts(tmp_path, scenes_dir):
    out = tmp_path / "bench"
    scene = tmp_path / "float.toml"
    scene.write_text(FLOAT_SCENE)
    proc = run_cli("bench", scene, "--quick", "--repeats", "1", "--output-dir", out, timeout=process_timeout(2.5))
    assert proc.returncode == 0, proc.stderr
    assert "max error m" in proc.stdout and "faster" in proc.stdout
    assert "] 0/" in proc.stderr and "done" in proc.stderr  # the progress bar
    for name in ("bench_float.csv", "bench_float.png", "bench_float.txt", "bench_float_differentiation.csv",
                 "bench_float_differentiation.png"):
        assert (out / name).stat().st_size > 100, name
    assert (out / "bench_float.txt").read_text() in proc.stdout
    assert "Differentiating a measured lift" in proc.stdout


@pytest.mark.parametrize(
    "args, key",
    [
        (["--repeats", "0"], "--repeats"),
        (["--repeats", "101"], "--repeats"),
        (["--repeats", "100000000"], "--repeats"),
        (["--output-dir", "/nonexistent-dir/sub"], "--output-dir"),
    ],
)
def test_command_bad_options_fail_cleanly(tmp_path, args, key):
    scene = tmp_path / "float.toml"
    scene.write_text(FLOAT_SCENE)
    proc = run_cli("bench", scene, "--quick", *args)
    assert proc.returncode == 2
    assert proc.stderr.startswith("error: ") and key in proc.stderr and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == [scene]


def test_command_scene_without_linkage_fails_cleanly(tmp_path):
    scene = tmp_path / "rigid.toml"
    scene.write_text(FLOAT_SCENE.replace('[linkage]\nstiffness = "5e6 N/m"\n', ""))
    proc = run_cli("bench", scene, "--quick", "--output-dir", tmp_path)
    assert proc.returncode == 2 and proc.stderr.strip().count("\n") == 0
    assert "linkage" in proc.stderr and list(tmp_path.iterdir()) == [scene]


def test_run_all_lists_the_benchmarks_and_refuses_unknown_names():
    """`make bench` runs benchmarks/run_all.py: every bench_*.py is known to it by name."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "benchmarks" / "run_all.py"
    done = subprocess.run([sys.executable, str(script), "--only", "no_such_bench"], capture_output=True, text=True,
                          timeout=process_timeout())
    assert done.returncode == 2
    assert "dynamics" in done.stderr and "core" in done.stderr and "no_such_bench" in done.stderr
