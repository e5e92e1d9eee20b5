"""No output of a built-in scene holds NaN unless the docs say what it means (issue #22 item 4).

Every built-in scene runs with every effect it lists; every column and every summary figure
(events and nested blocks included) is checked. A column may hold NaN only if it is in
explorer.result.NAN_MEANINGS, the documented allow-list (column -> what NaN means there), and each
entry there is explained in docs/reference/validity.md. Summary figures are never NaN (a figure
that is not defined is None, JSON null).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pytest

from explorer import load_scene, simulate
from explorer.result import NAN_MEANINGS

from conftest import ROOT, SCENES

BUILT_IN = sorted(SCENES.glob("*.toml"))
DOC = ROOT / "docs" / "reference" / "validity.md"

def nan_figures(value, path: str = "") -> list[str]:
    """Dotted paths of every NaN float in a (nested) summary."""
    if isinstance(value, Mapping):
        return [p for k, v in value.items() for p in nan_figures(v, f"{path}.{k}" if path else str(k))]
    if isinstance(value, (list, tuple)):
        return [p for i, v in enumerate(value) for p in nan_figures(v, f"{path}[{i}]")]
    if isinstance(value, (float, np.floating)) and math.isnan(value):
        return [path]
    return []


@pytest.fixture(scope="module")
def results():
    return {path.stem: simulate(load_scene(path)) for path in BUILT_IN}


def test_every_built_in_scene_is_checked(results):
    assert len(BUILT_IN) >= 15 and set(results) == {p.stem for p in BUILT_IN}


@pytest.mark.parametrize("name", [p.stem for p in BUILT_IN])
def test_no_undocumented_nan_in_columns(results, name):
    columns = results[name].columns
    assert len(columns) > 10
    undocumented = [c for c, v in columns.items() if np.any(np.isnan(np.asarray(v, dtype=float))) and c not in NAN_MEANINGS]
    assert undocumented == [], f"{name}: NaN in {undocumented} (not in explorer.result.NAN_MEANINGS)"


@pytest.mark.parametrize("name", [p.stem for p in BUILT_IN])
def test_no_nan_in_summary_figures(results, name):
    found = nan_figures(results[name].summary)
    assert found == [], f"{name}: NaN summary figures {found}"


def test_trip_gear_requirement_columns_are_numbers(results):
    """The reported case: trip_gear_dashpot.toml wrote NaN in required_spring_force_N and
    spring_margin_N while the released valve closes (now Trinks' closing force, test_trip_gear)."""
    c = results["trip_gear_dashpot"].columns
    for name in ("required_spring_force_N", "spring_margin_N"):
        assert name not in NAN_MEANINGS
        assert np.all(np.isfinite(c[name])), name


def test_allow_list_is_documented_and_used(results):
    """Each allowed column has its meaning in the docs, and some built-in scene shows it (a stale
    entry would let a NaN through unexplained)."""
    doc = DOC.read_text()
    for column, meaning in NAN_MEANINGS.items():
        assert f"`{column}`" in doc and meaning.split(":")[0] in doc, column
        assert any(np.any(np.isnan(np.asarray(r.columns.get(column, [0.0]), dtype=float))) for r in results.values()), column


def test_summary_walk_finds_nan():
    """The walker itself sees NaN in nested blocks, lists and numpy floats (it must be able to fail)."""
    summary = {"a": 1.0, "b": {"c": [0.0, float("nan")]}, "d": np.float64("nan"), "e": None}
    assert nan_figures(summary) == ["b.c[1]", "d"]
