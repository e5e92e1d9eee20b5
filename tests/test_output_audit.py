"""The files the program writes, read as an expert user would: headers, units, column order as
the docs say, and the same figure equal wherever two outputs report it.

Oracles: the docs' own tables (docs/guide/sweep.md), and `simulate`'s summary of the same scene at
the same speed for a sweep's row (the same quantity computed by the other path)."""

from __future__ import annotations

import io
import math
from collections.abc import Mapping
import re
import warnings

import numpy as np
import pytest

import explorer
from conftest import ROOT, SCENES
from explorer import load_scene, simulate

SWEEP_DOC = ROOT / "docs" / "guide" / "sweep.md"


def documented_sweep_table() -> tuple[list[str], set[str]]:
    """(the header the docs spell out for valve_float_demo.toml, every column name in the docs'
    column table: each backticked name without a dot, the summary keys a cell cites left out)."""
    text = SWEEP_DOC.read_text()
    start = text.index("writes, in this order")
    line = text[start:text.index("run_failed`;", start) + len("run_failed")]
    header = [n.strip() for n in line[line.index("`run,") + 1:].replace("\n", " ").split(",")]
    table = text[text.index("| effect | columns |"):]
    table = table[:table.index("\n\n")]
    names = {n for n in re.findall(r"`([A-Za-z_0-9.]+)`", table) if "." not in n and not n.startswith(("impact_", "jump_"))}
    return header, names


def _sweep(scene, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return explorer.sweep(SCENES / scene, workers=1, **options)


def test_sweep_header_is_the_documented_one():
    """The docs' example command's header, column for column: run, the varied keys (--vary, then
    --sample), the figures, run_failed last."""
    header, _ = documented_sweep_table()
    r = _sweep("valve_float_demo.toml", vary={"drive.rpm": "3000:5000:3"},
               sample={"valve.lash": "normal(0.25 mm, 0.02 mm)"}, runs=1, seed=1)
    assert list(r.columns) == header


@pytest.mark.parametrize("scene", sorted(p.name for p in SCENES.glob("*.toml")))
def test_every_sweep_column_is_in_the_docs_table(scene):
    """Every figure column of every built-in scene's sweep is in the docs' table (the [hla]
    section's four were not), run first and run_failed last."""
    _, names = documented_sweep_table()
    from explorer.studies.sweep_engine import result_columns

    columns = result_columns(load_scene(SCENES / scene))
    assert columns[-1] == "run_failed"
    assert [c for c in columns if c not in names] == []


# the sweep's column -> simulate's summary key of the same quantity
SAME = {"min_contact_force_N": "min_contact_force_N", "float_speed_rpm": "jump_speed_rpm",
        "max_camshaft_torque_Nm": "max_camshaft_torque_Nm", "first_separation_deg": "first_separation_deg",
        "separations": "float_separations", "flight_time_s": "float_flight_time_s", "max_deviation_m": "max_deviation_m",
        "peak_linkage_force_N": "peak_linkage_force_N", "peak_camshaft_back_pressure_N": "peak_camshaft_back_pressure_N",
        "residual_deviation_m": "residual_deviation_m", "residual_amplitude_m": "residual_amplitude_m",
        "pump_up_valve_lift_m": "hla.pump_up_valve_lift_m", "hla_lash_taken_up_m": "hla.lash_taken_up_m",
        "hla_plunger_travel_per_revolution_m": "hla.plunger_travel_per_revolution_m",
        "hla_chamber_pressure_max_Pa": "hla.chamber_pressure_max_Pa"}


@pytest.mark.parametrize("scene, engine_tolerance", [
    ("bucket_tappet.toml", 1e-9),  # compiled path: ~1e-9 relative by its docs (another order of the same operations)
    ("pushrod_rocker.toml", 1e-12),
    ("spring_surge.toml", 1e-12),  # shared path, the spring chain: NaN residuals where the summary has none
    ("finger_hla_pumpup.toml", 1e-12),
    ("rocking_cam.toml", 1e-12),  # simulate path
    ("polydyne_demo.toml", 1e-9),
])
def test_sweep_row_at_the_scene_speed_is_simulates_summary(scene, engine_tolerance):
    """A sweep row at the scene's own speed holds simulate's figures where both report the same
    quantity (NaN in the table = null or absent in the summary), to 1e-12 relative (compiled path:
    its documented ~1e-9)."""
    sc = load_scene(SCENES / scene)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        row = {k: v[0] for k, v in explorer.sweep(SCENES / scene, vary={"drive.rpm": repr(float(sc.drive.rpm))},
                                                   workers=1).columns.items()}
    summary = simulate(sc).summary
    assert row["run_failed"] == 0
    compared = 0
    for column, key in SAME.items():
        if column not in row:
            continue
        want = summary
        for part in key.split("."):
            want = want.get(part) if isinstance(want, Mapping) else None
        if want is None:
            assert math.isnan(row[column]), column
            continue
        compared += 1
        assert abs(float(row[column]) - float(want)) <= engine_tolerance * max(1.0, abs(float(want))), column
    assert compared >= 6


def test_tolerance_study_histograms_show_the_input_whole_counts_and_how_many_runs():
    """The sampled input comes first (the distribution drawn: its mean within 4 standard errors of
    the asked 0.25 mm), a count column one bar per integer, and a figure that is NaN in some runs
    (first_separation_deg where the valve stays on the cam) says how many of the runs it shows."""
    from explorer.studies.sweep_plots import histograms

    r = _sweep("valve_float_demo.toml", vary={"drive.rpm": "1000,4000"},
               sample={"valve.lash": "normal(0.25 mm, 0.02 mm)"}, runs=20, seed=1)
    panels = {p.name: p for p in histograms(r)}
    first = histograms(r)[0]
    assert first.name == "valve_lash_m" and "sampled input" in first.title
    assert abs(first.data.mean() - 0.25e-3) < 4 * 0.02e-3 / math.sqrt(40)
    sep = panels["separations"]
    np.testing.assert_array_equal(np.asarray(sep.bins) % 1.0, 0.5)  # edges between the integers
    assert np.histogram(sep.data, sep.bins)[0].sum() == 40
    nan = int(np.isnan(r.columns["first_separation_deg"]).sum())
    assert 0 < nan < 40  # 1000 rpm stays on the cam, 4000 floats
    assert f"{40 - nan} of 40 runs" in panels["first_separation_deg"].title


def test_recording_summary_writes_undefined_figures_as_the_json_summary_does():
    """The recording's summary page (/summary, markdown) wrote Python's None and True where the
    JSON summary and the docs (reference/validity.md) say null and true."""
    from explorer.view.rerun.recording import summary_markdown

    result = simulate(load_scene(SCENES / "valve_float_demo.toml"))
    assert result.summary["min_concave_contour_radius_m"] is None and result.summary["valve_floats"] is True
    page = summary_markdown(result, "Valve float demo")
    assert "| min_concave_contour_radius_m | null |" in page
    assert "| valve_floats | true |" in page
    assert "| None |" not in page and "| True |" not in page and "| False |" not in page
    # the numbers stay the summary's to the 6 digits shown
    assert f"| min_contact_force_N | {result.summary['min_contact_force_N']:.6g} |" in page


def test_spectrum_table_states_its_convention_and_the_rows_follow_it(tmp_path):
    """The spectrum's header says S'' = mean + sum amplitude cos(n theta + phase), amplitude the
    peak; checked against Fourier integrals of the analytic drive acceleration by quadrature (scipy
    quad between the lift's breakpoints, independent of the FFT): a_n = (1/pi) int S'' cos(n theta),
    b_n = (1/pi) int S'' sin(n theta), and amplitude cos(phase) = a_n, -amplitude sin(phase) = b_n,
    to 1e-7 of the largest harmonic (the FFT's aliasing of the jerk's jumps, ~1e-8, and the
    printed digits)."""
    from scipy.integrate import quad

    from explorer import cli
    from explorer.effects.lift import build_lift

    table = tmp_path / "s.csv"
    assert cli.main(["spectrum", str(SCENES / "cycloidal_demo.toml"), "--orders", "6", "-o", str(table)]) == 0
    lines = table.read_text().splitlines()
    assert lines[1].startswith("# S''(theta) = ") and "amplitude cos(n theta + phase)" in lines[1]
    assert "the peak" in lines[1] and "not RMS" in lines[1]
    assert lines[1].startswith("# S''(theta) = 0 m/s^2 + ")  # a closed event: L' returns to its start, mean 0
    rows = np.loadtxt(io.StringIO("\n".join(lines[3:])), delimiter=",")
    scene = load_scene(SCENES / "cycloidal_demo.toml")
    lift = build_lift(scene)
    factor = scene.follower.ratio * scene.omega**2
    cuts = np.unique(np.concatenate([[0.0, 2 * math.pi], np.mod(lift.breakpoints(), 2 * math.pi)]))

    def integral(f):
        return sum(quad(lambda t: factor * float(lift.derivatives(np.array([t]))[2][0]) * f(t), a, b,
                        epsabs=1e-12, epsrel=1e-12, limit=200)[0] for a, b in zip(cuts[:-1], cuts[1:]))

    top = rows[:, 2].max()
    for n, _, amplitude, phase in rows:
        a = integral(lambda t: math.cos(n * t)) / math.pi
        b = integral(lambda t: math.sin(n * t)) / math.pi
        assert abs(amplitude * math.cos(phase) - a) < 1e-7 * top, n
        assert abs(-amplitude * math.sin(phase) - b) < 1e-7 * top, n


@pytest.mark.parametrize("rows, lines", [(7, 1), (5, 2), (1, 2)])
def test_a_charts_suptitle_leaves_the_panels_titles_free(rows, lines):
    """The sweep's pictures printed their suptitle over the top panels' titles (tight_layout
    ignores a suptitle): after charts.png the suptitle's box overlaps no panel title's."""
    from explorer.studies.charts import figure, png

    with figure(rows, 2, figsize=(10.4, 2.6 * rows + 0.6), dpi=100, squeeze=False) as (fig, grid):
        for ax in grid.ravel():
            ax.set_title("seating_velocity_m_s", fontsize=9)
        fig.suptitle("\n".join(["Valve float demo: 60 runs"] * lines), fontsize=10)
        assert png(fig)[:4] == b"\x89PNG"
        renderer = fig.canvas.get_renderer()
        top = fig._suptitle.get_window_extent(renderer)
        for ax in grid[0]:
            box = ax.title.get_window_extent(renderer)
            assert box.y1 < top.y0, (box, top)
