"""A failed sweep run's figures are NaN in every format (docs/guide/sweep.md), never int64's
minimum from a NaN cast; shares are over the runs that finished and say how many failed."""

from __future__ import annotations

import warnings

import numpy as np

from explorer import cli
from explorer.studies.sweep_plots import separating_share, share_text
from explorer.studies.sweep_table import SweepTable, read_table

from conftest import SCENES

FLOAT = SCENES / "valve_float_demo.toml"


def test_count_columns_of_a_failed_run_are_nan_not_int64_min(tmp_path, capsys):
    out = tmp_path / "o.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # no "invalid value encountered in cast"
        assert cli.main(["sweep", str(FLOAT), "--vary", "drive.rpm=1,3000", "-o", str(out)]) == 0
    text = out.read_text()
    assert "-9223372036854775808" not in text
    table = read_table(out)
    failed = np.asarray(table.columns["run_failed"])
    assert list(failed) == [1, 0]
    for name in ("separations", "seat_impacts"):
        col = np.asarray(table.columns[name], float)
        assert np.isnan(col[0]) and col[1] >= 0 and col[1] == int(col[1])
    captured = capsys.readouterr()
    assert "1 runs failed" in captured.out + captured.err


def test_counts_stay_integers_when_every_run_finished():
    table = SweepTable.build({"run": np.array([0.0, 1.0]), "separations": np.array([0.0, 3.0]),
                              "run_failed": np.array([0.0, 0.0])}, {})
    assert table.columns["separations"].dtype == np.int64 and table.columns["run"].dtype == np.int64


def test_share_counts_only_finished_runs():
    table = SweepTable.build({"run": np.arange(4.0), "separations": np.array([np.nan, 2.0, 0.0, np.nan]),
                              "run_failed": np.array([1.0, 0.0, 0.0, 1.0])}, {})
    assert table.columns["separations"].dtype.kind == "f"
    share = separating_share(table)
    assert share == 0.5
    assert share_text(table, share) == "50.00 % of the runs separate (of 2 finished; 2 failed)"
    none = SweepTable.build({"run": np.arange(1.0), "separations": np.array([np.nan]),
                             "run_failed": np.array([1.0])}, {})
    assert separating_share(none) is None
