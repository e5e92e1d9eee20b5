"""explorer.gears.envelope.first_crossing (the arm-body clearance check of the finger follower and
the rocker) against its oracle, the test written out here on every edge at every angle, as the
function did before its prefilter (_may_cross): the same index (or None), bit for bit, on random
star-shaped cams and random segments (hypothesis: crossing, clear, touching a vertex, through the
cam's centre), on segments touching the contour exactly, and on the built-in finger and rocker
with their arm moved in towards the cam until it crosses at various angles. The prefilter is also
checked angle by angle: no angle it passes over has a crossing edge."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from explorer.gears.envelope import _may_cross, _orient, first_crossing


def crossings(theta, contour, start, end) -> np.ndarray:
    """Per angle: does some edge properly cross the segment (every edge tested; the oracle)."""
    p = np.asarray(contour, dtype=float)
    q = np.roll(p, -1, axis=0)
    out = []
    for i, th in enumerate(np.asarray(theta, dtype=float)):
        c, s = math.cos(th), math.sin(th)
        rot = np.array([[c, -s], [s, c]])
        a, b = start[i], end[i]
        pa, qa = p @ rot.T, q @ rot.T
        d1, d2 = _orient(pa, qa, a), _orient(pa, qa, b)
        d3, d4 = _orient(a[None, :], b[None, :], pa), _orient(a[None, :], b[None, :], qa)
        out.append(bool(np.any((d1 * d2 < 0.0) & (d3 * d4 < 0.0))))
    return np.array(out, dtype=bool)


def oracle(theta, contour, start, end):
    hits = np.nonzero(crossings(theta, contour, start, end))[0]
    return int(hits[0]) if hits.size else None


def cam(n: int, bumps) -> np.ndarray:
    """A star-shaped closed contour about the origin, clockwise: r = 0.02 (1 + sum of harmonics)."""
    t = -np.arange(n) * (2.0 * math.pi / n)
    r = 0.02 * (1.0 + sum(a * np.cos(k * t + ph) for k, (a, ph) in enumerate(bumps, start=1)))
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def check(theta, contour, start, end):
    got = first_crossing(theta, contour, start, end)
    assert got == oracle(theta, contour, start, end)
    p = np.asarray(contour, dtype=float)
    passed_over = ~_may_cross(np.asarray(theta, float), p, np.roll(p, -1, axis=0), start, end)
    assert not (crossings(theta, contour, start, end) & passed_over).any()
    return got, passed_over


coordinate = st.floats(-0.06, 0.06)


@settings(max_examples=300, deadline=None)
@given(st.integers(3, 300), st.lists(st.tuples(st.floats(0.0, 0.15), st.floats(0.0, 6.3)), max_size=3),
       st.lists(st.tuples(st.floats(0.0, 6.3), coordinate, coordinate, coordinate, coordinate), min_size=1,
                max_size=12))
def test_random_cams_and_segments_as_the_oracle(n, bumps, cases):
    contour = cam(n, bumps)
    theta = np.array([c[0] for c in cases])
    start = np.array([[c[1], c[2]] for c in cases])
    end = np.array([[c[3], c[4]] for c in cases])
    check(theta, contour, start, end)


@settings(max_examples=200, deadline=None)
@given(st.integers(3, 200), st.floats(0.0, 6.3), st.integers(0, 10_000), st.floats(-3.0, 3.0),
       st.floats(0.5, 2.0), st.sampled_from(["from vertex", "through vertex", "to centre", "tangent"]))
def test_segments_at_the_contour_as_the_oracle(n, th, j, direction, length, kind):
    """Segments that touch or graze the contour exactly (a vertex of the turned contour as an end,
    or on the segment): where rounding decides, the prefilter must not."""
    contour = cam(n, [(0.1, 0.3)])
    c, s = math.cos(th), math.sin(th)
    vertex = np.array([[c, -s], [s, c]]) @ contour[j % n]
    u = np.array([math.cos(direction), math.sin(direction)]) * 0.02 * length
    if kind == "from vertex":
        a, b = vertex, vertex + u
    elif kind == "through vertex":
        a, b = vertex - u, vertex + u
    elif kind == "to centre":
        a, b = vertex * 2.0, np.zeros(2)
    else:  # along the tangent-ish direction at the vertex's radius
        a, b = vertex + np.array([-vertex[1], vertex[0]]) * length, vertex - np.array([-vertex[1], vertex[0]]) * length
    check(np.array([th, th + 1.0]), contour, np.array([a, a]), np.array([b, b]))


def test_clear_arms_are_passed_over_and_crossing_arms_found():
    contour = cam(720, [(0.1, math.pi)])  # the bump at cam angle 180 deg
    theta = np.linspace(0.0, 2.0 * math.pi, 50, endpoint=False)
    # a lever well outside the cam at every angle: no angle needs the full test
    start = np.tile([0.05, -0.04], (50, 1))
    end = np.tile([0.05, 0.04], (50, 1))
    got, passed_over = check(theta, contour, start, end)
    assert got is None and passed_over.all()
    # moved in so that the cam's bump (r = 0.022) reaches it about half a turn on
    start[:, 0] = end[:, 0] = 0.0215
    got, passed_over = check(theta, contour, start, end)
    assert got is not None and got > 0 and passed_over.sum() >= 15


@pytest.mark.parametrize("name", ["finger_follower", "ohc_rocker"])
def test_the_builtin_arms_moved_in_cross_where_the_oracle_says(name):
    """The shipped finger and rocker: clear (None, every angle passed over by the prefilter); their
    arm's segments moved towards the cam centre by a growing share cross it, first at the
    oracle's angle."""
    from explorer.scene.scene import load_scene

    from conftest import SCENES

    segments = _arm_segments(load_scene(SCENES / f"{name}.toml"))
    seen = set()
    for theta, contour, start, end in segments:
        got, passed_over = check(theta, contour, start, end)
        assert got is None and passed_over.mean() > 0.9
        for shrink in (0.95, 0.9, 0.8, 0.7, 0.5, 0.3):
            got, _ = check(theta, contour, start * shrink, end * shrink)
            seen.add(got)
    assert len(seen - {None}) >= 2, seen  # crossings found, at different angles


def _arm_segments(scene):
    """The arguments of every first_crossing call the scene's kinematics makes."""
    import explorer.gears.arm as arm
    from explorer import simulate

    calls = []
    real = arm.first_crossing

    def recording(theta, contour, start, end):
        calls.append((np.asarray(theta), np.asarray(contour), np.asarray(start), np.asarray(end)))
        return real(theta, contour, start, end)

    arm.first_crossing = recording
    try:
        simulate(scene)
    finally:
        arm.first_crossing = real
    assert calls
    return calls
