"""Speed sweeps of the rigid contact margin: vectorised equals the per-speed loop, and the sweep
brackets the exact float speed."""


import numpy as np
import pytest

from explorer.core.errors import InputError
from explorer.mechanics.forces import TrainLoads, float_speed
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene
from explorer.studies.sweeps import contact_margin_loop, contact_margin_sweep


@pytest.fixture
def float_scene(scenes_dir):
    return load_scene(scenes_dir / "valve_float_demo.toml")


def test_vectorised_equals_loop(float_scene):
    rpms = np.linspace(500, 6000, 237)
    fast = contact_margin_sweep(float_scene, rpms)
    slow = contact_margin_loop(float_scene, rpms)
    assert np.array_equal(fast.cam_angle_deg, slow.cam_angle_deg)
    assert np.allclose(fast.min_contact_force, slow.min_contact_force, rtol=0, atol=1e-9)


def test_sweep_brackets_the_exact_float_speed(float_scene):
    """The grid minimum can only be >= the true minimum, so the first swept speed with margin <= 0
    lies at or above the exact float speed, and within one speed step plus the grid's miss."""
    sc = float_scene
    lift = build_lift(sc)
    exact = float_speed(lift, TrainLoads.from_scene(sc), sc.follower.ratio, sc.valve.lash).rpm
    rpms = np.linspace(1000, 6000, 1001)  # 5 rpm steps
    first = contact_margin_sweep(sc, rpms, lift=lift).first_float_rpm()
    assert first is not None and first >= exact
    assert first - exact < 5.0 + 1e-3 * exact


def test_sweep_margin_at_zero_speed_limit_is_the_static_load(float_scene):
    """At (almost) zero speed the margin is the smallest static load P0 + k s + R sgn + D."""
    sw = contact_margin_sweep(float_scene, [1e-6])
    loads = TrainLoads.from_scene(float_scene)
    # smallest static load: closing side just before seating, s -> 0: P0 - R + D
    assert sw.min_contact_force[0] == pytest.approx(loads.preload - loads.friction + loads.closing, rel=1e-3)


@pytest.mark.parametrize("bad", [[], [0.0], [-100.0], [float("nan")]])
def test_sweep_rejects_bad_speeds(float_scene, bad):
    with pytest.raises(InputError):
        contact_margin_sweep(float_scene, bad)
