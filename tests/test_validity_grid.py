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
