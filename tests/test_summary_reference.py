"""docs/reference/summary.md lists every key of the run's summary (`explorer simulate --summary`):
every key a built-in scene produces is documented there, and every documented key is produced by
a built-in scene, or is marked "(only ...)" on the page and produced here by a small override of
a built-in scene that brings its condition (CONDITIONAL).

Keys are dotted paths into the JSON report (Result.report: the summary, effects, events,
warnings): a list's elements are "[]" (`hla.per_revolution[].seated`), and the keys of the
open-ended mappings are one placeholder each (OPEN: `elastic_event_counts.<kind>`; a cam order,
any key of digits, is `<n>`). A new key without its row on the page fails (a); a row whose key
no run produces any more fails (b).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from explorer import load_scene, simulate
from explorer.scene.builtin import builtin_scenes, scenes_dir

PAGE = Path(__file__).resolve().parents[1] / "docs" / "reference" / "summary.md"

# the mappings whose keys are names, not fixed keys (the page writes each as one placeholder)
OPEN = {
    "effects": "<effect>",
    "elastic_event_counts": "<kind>",
    "rigid_mass_parts_kg": "<part>",
    "contact_openings": "<joint>",
    "contact_first_opening_deg": "<joint>",
}
DIGITS = re.compile(r"^\d+$")

# Documented keys that no built-in scene produces as shipped: the override of a built-in scene
# that produces each (its condition, which the page states as "(only ...)").
CONDITIONAL: dict[tuple[str, tuple[str, ...]], tuple[str, ...]] = {
    ("schenker1902_fig2", ('solver.method="scipy"',)): (
        "elastic_solver.rtol", "elastic_solver.atol", "elastic_solver.max_step_s", "elastic_solver.nfev",
        "elastic_solver.njev", "elastic_solver.ivp_calls", "elastic_solver.rest_phases",
        "elastic_solver.double_crossings"),
    ("schenker1902_fig2", ('solver.method="schenker1902"',)): (
        "elastic_solver.variant", "elastic_solver.masses", "elastic_solver.substeps",
        "elastic_solver.step_over_period", "elastic_solver.stability_limit"),
    # the chain's scipy reference (pushrod_train: a train of parts with a spring of masses, ~0.2 s)
    ("pushrod_train", ('solver.method="scipy"',)): ("elastic_solver.rhs_evaluations",),
    ("valve_float_demo", ("spring_design.trip_closing_time=0.05",)): (
        "spring_design.trinks", "spring_design.trinks.closing_time_s", "spring_design.trinks.lift_m",
        "spring_design.trinks.valve_weight_N", "spring_design.trinks.acceleration_m_s2",
        "spring_design.trinks.closing_force_N"),
    # friction outweighs the inertia at this speed: no split balances the sides
    ("valve_float_demo", ("spring_design.target_rpm=0.001",)): ("spring_design.event_comparison.asymmetric_note",),
    # the finger's own stiffness, in series with [linkage] through its changing ratio (k(t): taylor)
    ("finger_follower", ("gear.finger.stiffness=2e7", 'solver.method="taylor"')): (
        "gear.valve_referred_side_stiffness_N_m",),
    # a solid height the train's spring of masses reaches: its coil-clash events name the element
    ("pushrod_train", ("spring.elements=4", 'spring.mass="40 g"', 'spring.free_length="60 mm"',
                       'spring.solid_height="%s"')): ("events[].element",),
}


def _walk(value, path: str, out: set[str]) -> None:
    if isinstance(value, dict):
        placeholder = OPEN.get(path)
        for key, item in value.items():
            name = placeholder or ("<n>" if DIGITS.match(str(key)) else str(key))
            child = f"{path}.{name}" if path else name
            out.add(child)
            _walk(item, child, out)
    elif isinstance(value, list):
        for item in value:
            _walk(item, f"{path}[]", out)


def key_paths(report: dict) -> set[str]:
    """The dotted paths of a JSON report (module docstring)."""
    out: set[str] = set()
    _walk(report, "", out)
    return out


def _ancestors(key: str) -> list[str]:
    """The key and the blocks it is in: "a.b[].c" -> ["a.b[].c", "a.b", "a"]."""
    out = [key]
    while True:
        cut = max(key.rfind("."), key.rfind("[]"))
        if cut <= 0:
            return out
        key = key[:cut].removesuffix("[]")
        out.append(key)


def report_of(path, overrides=()) -> dict:
    return json.loads(simulate(load_scene(path, list(overrides))).json_text())


def documented() -> dict[str, str]:
    """{key: its table rows} of the page: a backticked key in the first column of a table row (a
    key several effects or gears write has a row in each of their tables)."""
    rows: dict[str, str] = {}
    for line in PAGE.read_text(encoding="utf-8").splitlines():
        m = re.match(r"^\|\s*`([^`]+)`\s*\|", line)
        if m:
            rows[m.group(1)] = rows.get(m.group(1), "") + line + "\n"
    return rows


def _solid_height(path) -> str:
    """A solid height the train's spring reaches at pushrod_train's speed, yet clear of the static
    lift (the scene loader refuses a spring the lift alone drives solid): 0.3 mm beyond it."""
    scene = load_scene(path)
    sp = scene.spring
    lift = report_of(path)["max_valve_lift_m"]
    return f"{(0.060 - sp.preload / sp.rate - lift - 0.3e-3) * 1e3:.6g} mm"  # free length 60 mm


@pytest.fixture(scope="module")
def builtin_keys() -> dict[str, set[str]]:
    """{key: the built-in scenes that produce it}, every built-in scene run once."""
    out: dict[str, set[str]] = {}
    for path in builtin_scenes():
        for key in key_paths(report_of(path)):
            out.setdefault(key, set()).add(path.stem)
    return out


@pytest.fixture(scope="module")
def conditional_keys() -> dict[tuple, set[str]]:
    """{override: the keys its run produces}, each CONDITIONAL override run once."""
    out = {}
    for scene, overrides in CONDITIONAL:
        path = scenes_dir() / f"{scene}.toml"
        given = tuple(o % _solid_height(path) if "%s" in o else o for o in overrides)
        out[(scene, overrides)] = key_paths(report_of(path, given))
    return out


def test_the_page_parses():
    rows = documented()
    assert len(rows) > 300
    assert "max_valve_velocity_m_s" in rows and "hla.per_revolution[].seated" in rows


def test_every_produced_key_is_documented(builtin_keys, conditional_keys):
    rows = documented()
    produced = dict(builtin_keys)
    for (scene, overrides), keys in conditional_keys.items():
        for key in keys:
            produced.setdefault(key, set()).add(f"{scene} with {', '.join(overrides)}")
    missing = {key: sorted(scenes)[:3] for key, scenes in produced.items() if key not in rows}
    assert not missing, ("keys of the summary that docs/reference/summary.md does not document (add a row: "
                         f"`key` | unit | meaning): {missing}")


def test_every_documented_key_is_produced(builtin_keys, conditional_keys):
    rows = documented()
    listed = {key for keys in CONDITIONAL.values() for key in keys}
    stale = sorted(set(rows) - set(builtin_keys) - listed)
    assert not stale, f"summary.md documents keys no built-in scene produces and CONDITIONAL does not list: {stale}"
    for key in listed:
        assert key not in builtin_keys, f"{key} is produced by {sorted(builtin_keys[key])}: not conditional"
        assert any("(only" in rows.get(p, "") for p in _ancestors(key)), \
            f"summary.md must say when {key} appears: '(only ...)' in its row or its block's"
    for (scene, overrides), keys in CONDITIONAL.items():
        absent = sorted(set(keys) - conditional_keys[(scene, overrides)])
        assert not absent, f"{scene} with {overrides} does not produce {absent}"


def test_open_mappings_and_orders_are_normalised():
    """The placeholders: names under the open mappings and cam orders each one key."""
    report = {"effects": {"kinematics": {"compute_time_s": 0.1}, "lash": {"compute_time_s": 0.2}},
              "train_modes_cam_orders": [{"exciting_accel_m_s2": {"9": 1.0, "10": 2.0}}],
              "elastic_event_counts": {"seat": 1, "lift-off": 2}}
    assert key_paths(report) == {
        "effects", "effects.<effect>", "effects.<effect>.compute_time_s",
        "train_modes_cam_orders", "train_modes_cam_orders[].exciting_accel_m_s2",
        "train_modes_cam_orders[].exciting_accel_m_s2.<n>",
        "elastic_event_counts", "elastic_event_counts.<kind>"}


def test_ancestors():
    assert _ancestors("hla.per_revolution[].seated") == ["hla.per_revolution[].seated", "hla.per_revolution", "hla"]


def test_a_new_key_fails(builtin_keys):
    """What the guard does with a key no row documents: it names it."""
    rows = documented()
    produced = set(builtin_keys) | {"max_valve_snap_m_s4", "hla.per_revolution[].new_figure"}
    assert sorted(produced - set(rows)) == ["hla.per_revolution[].new_figure", "max_valve_snap_m_s4"]
