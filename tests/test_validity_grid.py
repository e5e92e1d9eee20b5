"""The validity verdict of an entered cam does not depend on the run's sample grid (an audit's
finding: a cycloidal rise and return of 0.1 deg, an undercut with a pitch-curve radius of 1.9 um,
was accepted at 3600 steps because the step grid has no angle inside the event). The kinematics
effect now asks lift_fault, the check of every computed cam: the law's breakpoints, a grid of
7200 angles and SEGMENT_SAMPLES angles inside every stretch between breakpoints."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from explorer.core.errors import InputError
from explorer.effects.contour import geometry_columns
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

from conftest import SCENES

CYCLOIDAL = SCENES / "cycloidal_demo.toml"
STEPS = (360, 3600, 36000)


def short_event(rise_deg: float, return_deg: float | None = None, dwell_deg: float = 40.0):
    return load_scene(CYCLOIDAL, [f'lift.dwell="{dwell_deg!r} deg"', f'lift.rise="{rise_deg!r} deg"',
                                  f'lift.return="{(rise_deg if return_deg is None else return_deg)!r} deg"'])


def verdict(scene, steps: int) -> str | None:
    """The kinematics effect's refusal text of the translating roller's cam on a grid of `steps`
    cam angles (as explorer.effects.pipeline samples a revolution), None when it is accepted."""
    lift = build_lift(scene)
    theta = np.arange(steps) * (2.0 * math.pi / steps)
    try:
        geometry_columns(scene, theta, lift.derivatives(theta), 0.0, lift)
    except InputError as exc:
        return f"{exc.key}: {exc.reason}"
    return None


@pytest.mark.parametrize("event_deg", [0.1, 0.5, 2.0])
def test_short_event_undercut_is_refused_at_every_grid(event_deg):
    """The audit's three cases (accepted before at 3600, 3600 and 360 steps): refused as an undercut
    at 360, 3600 and 36000 steps alike, with the same line."""
    scene = short_event(event_deg)
    lines = {verdict(scene, n) for n in STEPS}
    assert len(lines) == 1, lines
    line = lines.pop()
    assert line is not None and line.startswith("follower.roller_radius: undercut: roller radius 12 mm")


def test_normal_scene_passes_at_a_coarse_grid():
    """The demo as shipped (rise and return of tens of degrees) is accepted at 360 steps."""
    scene = load_scene(CYCLOIDAL)
    for n in STEPS[:2]:
        assert verdict(scene, n) is None


def test_polydyne_with_a_short_ramp_is_refused():
    """The audit's polydyne with a 0.1 deg ramp (true minimum pitch radius 7.0 um) is refused at load."""
    with pytest.raises(InputError, match="undercut"):
        load_scene(SCENES / "polydyne_demo.toml", ['lift.ramp="0.1 deg"'])


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rise=st.floats(0.1, 30.0), ret=st.floats(0.1, 30.0), steps=st.sampled_from([90, 360, 720, 1000, 3600, 36000]))
def test_verdict_does_not_depend_on_steps(rise, ret, steps):
    """Any rise and return from the smallest the scene takes (0.1 deg) to 30 deg: one verdict, one line."""
    scene = short_event(rise, ret)
    assert verdict(scene, steps) == verdict(scene, 360)


class _Marks:
    """A lift reduced to its breakpoints (sample_angles reads nothing else)."""

    def __init__(self, marks):
        self.marks = np.asarray(marks, dtype=float)

    def breakpoints(self):
        return self.marks


def _sample_angles_by_sorting(lift, n, per_segment):
    """sample_angles as it was first written (the oracle): every angle concatenated and np.unique."""
    grid = np.arange(int(n)) * (2.0 * math.pi / int(n))
    marks = np.unique(np.mod(np.asarray(lift.breakpoints(), dtype=float).reshape(-1), 2.0 * math.pi))
    parts = [grid, marks]
    if marks.size and per_segment > 0:
        ends = np.append(marks, marks[0] + 2.0 * math.pi)
        t = np.arange(1, int(per_segment) + 1) / (int(per_segment) + 1.0)
        parts.append(np.mod((ends[:-1, None] + np.diff(ends)[:, None] * t).reshape(-1), 2.0 * math.pi))
    return np.unique(np.concatenate(parts))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.one_of(st.floats(-20.0, 20.0), st.sampled_from([0.0, -0.0, math.pi, 2.0 * math.pi, -1e-300,
                                                                   math.radians(45.0), math.nan])),
                max_size=8),
       st.sampled_from([1, 7, 360, 7200]), st.sampled_from([0, 1, 3, 256]))
def test_sample_angles_are_the_sorted_union(marks, n, per_segment):
    """sample_angles merges the breakpoints and the stretches' angles into the sorted grid
    (grid_with) instead of sorting them all: the same floats, bit for bit, breakpoints on grid
    angles, outside [0, 2 pi), -0.0 and NaN included."""
    from explorer.lift.validity import sample_angles

    lift = _Marks(marks)
    got = sample_angles(lift, n, per_segment)
    want = _sample_angles_by_sorting(lift, n, per_segment)
    assert got.dtype == want.dtype and got.shape == want.shape
    assert np.array_equal(got, want, equal_nan=True) and np.array_equal(np.signbit(got), np.signbit(want))


@pytest.mark.parametrize("name", ["cycloidal_demo", "spline_demo", "schenker1902_fig2", "polydyne_spline"])
def test_sample_angles_of_the_scenes_are_the_sorted_union(name):
    from explorer.lift.validity import SAMPLES, SEGMENT_SAMPLES, sample_angles

    lift = build_lift(load_scene(SCENES / f"{name}.toml"))
    got = sample_angles(lift)
    assert np.array_equal(got, _sample_angles_by_sorting(lift, SAMPLES, SEGMENT_SAMPLES))
    assert got.size > SAMPLES
