"""Analysis of circular-arc cams: closed form per arc against brute-force geometry, exact
derivatives, breakpoints, validation of the arc chain; jets; point-list splines."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from explorer.core import jets
from explorer.lift.contours.arcs import Arc, ContourError, build_arc_contour, make_arc_lift
from explorer.lift.contours.parametric import SplineContour, make_parametric_lift
from explorer.lift.contours.schenker_fig2 import PAPER_DESIGN, arcs as schenker_arcs


def brute_force_height(points: np.ndarray, theta: np.ndarray, roller: float, offset: float) -> np.ndarray:
    """Independent oracle: the roller centre sits as low as it can without the roller disc
    containing any contour point, i.e. y = max over points P (ground frame, |Px - e| <= r) of
    Py + sqrt(r^2 - (Px - e)^2). Uses nothing of the arc formulas but the sampled points."""
    out = np.empty(theta.size)
    for i, th in enumerate(theta):
        c, s = math.cos(th), math.sin(th)
        x = c * points[:, 0] - s * points[:, 1]
        y = s * points[:, 0] + c * points[:, 1]
        dx = x - offset
        near = np.abs(dx) <= roller
        out[i] = np.max(y[near] + np.sqrt(roller * roller - dx[near] ** 2))
    return out


def eccentric(radius=0.05, shift=0.01, angle=-math.pi / 2):
    return build_arc_contour([Arc(shift * math.cos(angle), shift * math.sin(angle), radius)])


def test_eccentric_closed_form():
    """A circle of radius R whose centre is a from the shaft: roller centre y = c_y +
    sqrt((R + r)^2 - (e - c_x)^2) with c = R(theta) c0 (slider-crank), L = y - y0."""
    R, a, r, e = 0.05, 0.01, 0.015, 0.004
    contour = eccentric(R, a)
    assert contour.min_radius() == pytest.approx(R - a, abs=1e-15)
    lift = make_arc_lift(contour, r, e, R - a)
    th = np.linspace(0, 2 * np.pi, 1000)
    cx, cy = a * np.sin(th), -a * np.cos(th)
    y = cy + np.sqrt((R + r) ** 2 - (e - cx) ** 2)
    assert np.allclose(lift.derivatives(th)[0], y - lift.y0, rtol=0, atol=1e-16)
    # zero offset: the slider-crank lift, analytic derivatives written out by hand
    lift0 = make_arc_lift(contour, r, 0.0, R - a)
    rho = R + r
    sq = np.sqrt(rho**2 - (a * np.sin(th)) ** 2)
    d1 = a * np.sin(th) - a * a * np.sin(th) * np.cos(th) / sq
    assert np.allclose(lift0.derivatives(th)[1], d1, rtol=0, atol=1e-16)


@pytest.mark.parametrize("e", [0.0, 0.006, -0.009])
def test_arc_derivatives_against_high_order_differences(e):
    """Jets against 8th-order central differences of the lift itself (an independent check of
    the chain rule away from the breakpoints; differences only in the test)."""
    contour = build_arc_contour(schenker_arcs(PAPER_DESIGN))
    lift = make_arc_lift(contour, 0.006, e, PAPER_DESIGN.base_radius) if e else make_arc_lift(contour, 0.01, 0.0, PAPER_DESIGN.base_radius)
    h = 1e-3
    th = np.linspace(0, 2 * np.pi, 721)[:-1]
    bp = lift.breakpoints()
    away = np.all(np.abs(np.mod(th[:, None] - bp[None, :] + np.pi, 2 * np.pi) - np.pi) > 5 * h, axis=1)
    th = th[away]
    w = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
    offsets = np.arange(-4, 5) * h
    d = lift.derivatives(th)
    for k in range(3):
        samples = np.stack([lift.derivatives(th + o)[k] for o in offsets])
        numeric = (w[:, None] * samples).sum(axis=0) / h
        scale = np.abs(d[k + 1]).max()
        assert np.max(np.abs(numeric - d[k + 1])) < 1e-7 * scale


@pytest.mark.parametrize("e,r", [(0.0, 0.01), (0.005, 0.006), (-0.004, 0.012)])
def test_arc_lift_against_brute_force(e, r):
    """Schenker's cam (convex and concave arcs) sampled at 200 000 points (spacing h ~ 1.3 um):
    the max-over-points oracle misses the true height by at most (h/2)^2/2 (1/r + 1/R_min),
    below 1e-10 m here; asserted 1e-9 m."""
    contour = build_arc_contour(schenker_arcs(PAPER_DESIGN))
    lift = make_arc_lift(contour, r, e, PAPER_DESIGN.base_radius)
    points = contour.points_by_arc_length(200_000)
    theta = np.random.default_rng(3).uniform(0, 2 * np.pi, 90)
    theta = np.concatenate([theta, lift.breakpoints()])
    oracle = brute_force_height(points, theta, r, e) - lift.y0
    assert np.max(np.abs(lift.derivatives(theta)[0] - oracle)) < 1e-9


def test_breakpoints_are_where_the_contact_crosses_junctions():
    contour = build_arc_contour(schenker_arcs(PAPER_DESIGN))
    lift = make_arc_lift(contour, 0.01, 0.0, PAPER_DESIGN.base_radius)
    bp = lift.breakpoints()
    assert len(bp) == contour.n
    for k, theta in enumerate(lift.junction_angles):
        # both neighbouring arcs give the same lift and slope there (tangent arcs: C1 lift), to
        # rounding: AB has a 1 m radius, so its centre carries ~1e-16 m errors, amplified ~100x
        left = lift.arc_candidate((k - 1) % contour.n, np.array([theta]))[:, 0]
        right = lift.arc_candidate(k, np.array([theta]))[:, 0]
        assert abs(left[0] - right[0]) < 1e-13 and abs(left[1] - right[1]) < 1e-12
        # ... and the contact point is the junction itself
        phi = lift.contact_angle_on_arc(k, np.array([theta]))[0]
        assert abs(np.mod(phi - contour.start_angle[k] + np.pi, 2 * np.pi) - np.pi) < 1e-12
        # the acceleration jumps (different radii) except where equal radii would make it smooth
        assert abs(left[2] - right[2]) > 1e-6


def test_active_arc_is_the_one_holding_the_contact():
    contour = build_arc_contour(schenker_arcs(PAPER_DESIGN))
    lift = make_arc_lift(contour, 0.01, 0.0, PAPER_DESIGN.base_radius)
    th = np.linspace(0, 2 * np.pi, 3000, endpoint=False)
    active = lift.active_arc(th)
    for k in range(contour.n):
        sel = th[active == k]
        phi = lift.contact_angle_on_arc(k, sel)
        prog = np.mod((phi - contour.start_angle[k]) * np.sign(contour.sweep[k]), 2 * np.pi)
        assert np.all(prog <= abs(contour.sweep[k]) + 1e-9)


def test_arcs_given_in_either_direction_give_the_same_lift():
    arcs = schenker_arcs(PAPER_DESIGN)
    a = make_arc_lift(build_arc_contour(arcs), 0.01, 0.0, 0.0223)
    b_contour = build_arc_contour(arcs[::-1])
    assert b_contour.reversed_input
    b = make_arc_lift(b_contour, 0.01, 0.0, 0.0223)
    th = np.linspace(0, 2 * np.pi, 777)
    assert np.allclose(a.derivatives(th), b.derivatives(th), rtol=0, atol=1e-12)


def test_validation_messages():
    arcs = schenker_arcs(PAPER_DESIGN)
    moved = list(arcs)
    moved[2] = Arc(arcs[2].x + 1e-4, arcs[2].y, arcs[2].radius, name="BC")
    with pytest.raises(ContourError, match="not tangent") as info:
        build_arc_contour(moved)
    assert info.value.index == 2
    with pytest.raises(ContourError, match="positive"):
        build_arc_contour([Arc(0, 0, -1.0)])
    flipped = list(arcs)
    flipped[6] = Arc(arcs[6].x, arcs[6].y, arcs[6].radius, concave=False, name="FG")
    with pytest.raises(ContourError):
        build_arc_contour(flipped)
    contour = build_arc_contour(arcs)
    with pytest.raises(ContourError, match="undercut") as info:
        make_arc_lift(contour, 0.09, 0.0, 0.0223)  # larger than the 86.1 mm hollow FG
    assert info.value.field == "roller_radius"


def test_origin_outside_is_rejected():
    with pytest.raises(ContourError, match="wind once"):
        build_arc_contour([Arc(0.1, 0.0, 0.05)])


@settings(max_examples=40, deadline=None)
@given(
    radius=st.floats(0.02, 0.08),
    shift_frac=st.floats(0.0, 0.8),
    angle=st.floats(-math.pi, math.pi),
    roller=st.floats(0.0, 0.03),
    offset_frac=st.floats(-0.5, 0.5),
)
def test_eccentric_lift_is_nonnegative_and_touches_zero(radius, shift_frac, angle, roller, offset_frac):
    """Property: on any eccentric, with the base circle = the nearest point to the shaft, the
    lift is >= 0 and its minimum (about where the nearest point passes the follower) is ~0."""
    shift = shift_frac * radius
    contour = eccentric(radius, shift, angle)
    base = contour.min_radius()
    e = offset_frac * (base + roller)
    lift = make_arc_lift(contour, roller, e, base)
    d = lift.derivatives(np.linspace(0, 2 * np.pi, 4001))
    assert d[0].min() > -1e-12
    # the minimum lies within grid resolution of 0: L' vanishes there, so L_min <= h^2 max|L''|
    assert d[0].min() < (2 * np.pi / 4000) ** 2 * np.abs(d[2]).max() + 1e-15


def test_jets_against_closed_forms():
    t = np.linspace(0.1, 2.0, 50)
    f = np.stack([t**3, 3 * t**2, 6 * t, 6 * np.ones_like(t)])
    g = np.stack([np.exp(t)] * 4)
    prod = jets.mul(f, g)
    want = np.exp(t) * np.stack([t**3, t**3 + 3 * t**2, t**3 + 6 * t**2 + 6 * t, t**3 + 9 * t**2 + 18 * t + 6])
    assert np.allclose(prod, want, rtol=1e-13)
    assert np.allclose(jets.div(prod, g), f, rtol=1e-12)
    sq = jets.sqrt(np.stack([t**2, 2 * t, 2 * np.ones_like(t), 0 * t]))
    assert np.allclose(sq, np.stack([t, np.ones_like(t), 0 * t, 0 * t]), atol=1e-13)
    # atan2(sin t, cos t) = t
    c, s = jets.rotation(t)
    assert np.allclose(jets.atan2(s, c), np.stack([t, np.ones_like(t), 0 * t, 0 * t]), atol=1e-13)
    # inverse function: y = t^3, x = t  <->  y(x) = x^3; and x = t^2 (t > 0), y = t: y = sqrt(x)
    y = np.stack([t, np.ones_like(t), 0 * t, 0 * t])
    x = np.stack([t**2, 2 * t, 2 * np.ones_like(t), 0 * t])
    r = jets.reparametrize(y, x)
    X = t**2
    assert np.allclose(r, np.stack([np.sqrt(X), 0.5 * X**-0.5, -0.25 * X**-1.5, 0.375 * X**-2.5]), rtol=1e-12)


def test_point_list_accuracy_improves_with_density():
    """A periodic quintic spline through points of an exact contour: for an analytic contour
    (harmonic rise and return over 180 deg each = a pure cosine lift) the lift error falls like
    h^6 (theory: x64 per halving; asserted > x40); for a 4-5-6-7 law, whose contour's third
    derivative jumps (the law's fourth does), like h^4 (theory x16; asserted > x10).
    Oracle: the law itself."""
    from explorer.lift.contours.parametric import points_accuracy
    from explorer.lift.curves import LawLift

    smooth = LawLift(0.008, 0.0, math.pi, 0.0, math.pi, "harmonic", "harmonic")
    err = [row["max_lift_error_m"] for row in points_accuracy(smooth, 0.03, 0.01, 0.0, counts=(90, 180), samples=720)]
    assert err[1] < err[0] / 40
    law = LawLift(0.008, 0.5, 1.6, 0.3, 1.6, "polynomial-4567", "polynomial-4567")
    table = points_accuracy(law, 0.03, 0.01, 0.0, counts=(90, 180, 360, 720), samples=1800)
    lift_err = [row["max_lift_error_m"] for row in table]
    assert lift_err[-1] < 1e-10
    for a, b in zip(lift_err, lift_err[1:]):
        assert b < a / 10
    # the acceleration converges two orders slower (h^2: x4 per halving)
    accel_err = [row["max_accel_error_rel"] for row in table]
    assert accel_err[-1] < accel_err[0] / 40


def test_point_list_lift_of_arc_cam_converges_in_lift_not_in_acceleration_jumps():
    """Measured arc cams: the spline smooths the curvature jumps, so lift and velocity converge
    but the acceleration next to a junction stays off by a large part of the jump however dense
    the points - the reason arc cams are given as arcs. Oracle: the exact arc lift."""
    contour = build_arc_contour(schenker_arcs(PAPER_DESIGN))
    exact = make_arc_lift(contour, 0.01, 0.0, PAPER_DESIGN.base_radius)
    th = np.linspace(0, 2 * np.pi, 3600, endpoint=False)
    want = exact.derivatives(th)
    errs = []
    for n in (720, 2880):
        spl = make_parametric_lift(SplineContour(contour.points_by_arc_length(n)), 0.01, 0.0, PAPER_DESIGN.base_radius)
        got = spl.derivatives(th)
        errs.append([np.abs(got[k] - want[k]).max() / np.abs(want[k]).max() for k in range(3)])
    assert errs[1][0] < errs[0][0] / 8 and errs[1][0] * 0.0206 < 1e-8  # lift: metres
    assert errs[1][1] < errs[0][1] / 4  # velocity
    assert errs[1][2] > 0.2  # acceleration near the jumps: no convergence
