"""Bad geometry for today's valve trains: any layout is either a working gear or one InputError
line naming a key, never another exception (hypothesis draws the layouts)."""

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from explorer.core.errors import InputError
from explorer.gears.arm import CamSide, make_arm_gear
from explorer.gears.flat_face import Tappet, synthesise_bucket
from explorer.gears.pushrod import Lifter, make_pushrod_train
from explorer.lift.curves import LawLift

LIFT = LawLift(height=0.009, start=0.5, rise=math.radians(80), dwell=0.0, ret=math.radians(80),
               rise_law="polynomial-345", return_law="polynomial-345")
MM = st.floats(-0.06, 0.06, allow_nan=False)
SIZE = st.floats(-0.005, 0.07, allow_nan=False)


def one_line_or_gear(build):
    try:
        return build()
    except InputError as exc:
        assert "\n" not in str(exc) and exc.key and exc.reason
        return None


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(MM, MM, SIZE, SIZE, st.sampled_from([1, -1]), SIZE, st.floats(-math.pi, math.pi), SIZE,
       st.sampled_from(["roller", "pad", "flat"]))
def test_any_arm_layout_is_a_gear_or_one_line(px, py, arm, radius, branch, valve_arm, valve_angle, pad, kind):
    if kind == "roller":
        side = CamSide("roller", arm, radius)
    elif kind == "pad":
        side = CamSide("pad", arm, radius, face_angle=-0.5 * math.pi)
    else:
        side = CamSide("pad", arm, math.inf, face_angle=-0.5 * math.pi)
    gear = one_line_or_gear(lambda: make_arm_gear(base_radius=0.018, pivot=(px, py), cam_side=side, branch=branch,
                                                  valve_arm=valve_arm, valve_angle=valve_angle, valve_pad_radius=pad,
                                                  law=LIFT, n=720))
    if gear is not None:
        k = gear.kinematics(np.linspace(0.0, 2.0 * math.pi, 90, endpoint=False))
        assert np.all(np.isfinite(k.lift[:3])) and np.all(np.isfinite(k.ratio))


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(MM, st.floats(0.05, 0.4), MM, st.floats(0.05, 0.4), MM, st.floats(0.05, 0.4), SIZE,
       st.sampled_from(["flat", "roller"]), SIZE)
def test_any_pushrod_layout_is_a_gear_or_one_line(ox, oy, cx, cy, vx, vy, pad, kind, radius):
    lifter = Lifter("flat", socket_height=0.03) if kind == "flat" else Lifter("roller", radius=radius, socket_height=0.03)
    gear = one_line_or_gear(lambda: make_pushrod_train(base_radius=0.017, lifter=lifter, rocker_pivot=(ox, oy),
                                                       cup=(cx, cy), valve_pad_centre=(vx, vy), valve_pad_radius=pad,
                                                       law=LIFT, n=720))
    if gear is not None:
        k = gear.kinematics(np.linspace(0.0, 2.0 * math.pi, 90, endpoint=False))
        assert np.all(np.isfinite(k.lift[:3])) and np.all(np.isfinite(k.ratio))


@settings(max_examples=40, deadline=None)
@given(st.floats(-0.01, 0.05), st.floats(-1.0, 20.0), st.floats(-0.02, 0.05), st.floats(-0.01, 0.03),
       st.floats(-0.01, 0.05))
def test_any_tappet_is_a_gear_or_one_line(base, crown, face, width, offset):
    one_line_or_gear(lambda: synthesise_bucket(Tappet(base_radius=base, face_radius=crown, face_diameter=face,
                                                      cam_width=width, offset=offset), LIFT, n=720))
