"""Synthesis (translating.py): envelope, curvature, pressure angle, undercut; and the
synthesis -> analysis round trip through the Newton analysis of a parametric contour."""

import math

import numpy as np
import pytest

from explorer.core.errors import InputError
from explorer.lift.contours.parametric import SynthesizedContour, make_parametric_lift
from explorer.lift.contours.translating import (
    check_undercut,
    pitch_geometry,
    translating_profile,
)
from explorer.lift.curves import LawLift

LAWS = ["cycloidal", "harmonic", "polynomial-345", "polynomial-4567", "modified-trapezoid", "modified-sine"]


def law_lift(law="cycloidal", return_law=None, height=0.01, start=0.3, rise=1.3, dwell=0.2, ret=1.1):
    return LawLift(height, start, rise, dwell, ret, law, return_law or law)


def circumradius(p0, p1, p2):
    """Radius of the circle through three points (independent of any derivative formula)."""
    a = np.hypot(*(p1 - p0).T)
    b = np.hypot(*(p2 - p1).T)
    c = np.hypot(*(p2 - p0).T)
    cross = (p1 - p0)[:, 0] * (p2 - p0)[:, 1] - (p1 - p0)[:, 1] * (p2 - p0)[:, 0]
    return a * b * c / (2.0 * np.abs(cross))


@pytest.mark.parametrize("offset", [0.0, 0.007, -0.011])
@pytest.mark.parametrize("roller", [0.004, 0.012])
def test_envelope_every_contour_point_is_one_roller_radius_from_the_pitch_curve(offset, roller):
    lift = law_lift("polynomial-345", "cycloidal")
    theta = np.linspace(0.0, 2 * math.pi, 361)[:-1]
    prof = translating_profile(lift, theta, 0.03, roller, offset)
    # distance from each contour point to its own roller centre is exactly r ...
    assert np.allclose(np.hypot(*(prof.contour - prof.pitch).T), roller, rtol=0, atol=1e-15)
    # ... and no point of a dense pitch curve comes closer: the roller never cuts the cam.
    dense = translating_profile(lift, np.linspace(0.0, 2 * math.pi, 20001)[:-1], 0.03, roller, offset).pitch
    nearest = np.min(np.hypot(prof.contour[:, None, 0] - dense[None, :, 0], prof.contour[:, None, 1] - dense[None, :, 1]), axis=1)
    assert np.all(nearest > roller - 1e-12)
    # a polyline of spacing h misses the true minimum distance by at most h^2 / (8 r)
    h = np.max(np.hypot(*np.diff(dense, axis=0).T))
    assert np.all(nearest - roller <= h * h / (8 * roller) + 1e-15)


@pytest.mark.parametrize("offset", [0.0, 0.009])
def test_envelope_is_tangent_to_the_roller(offset):
    """The contour tangent (central differences of contour points, an independent construction)
    is perpendicular to the line from the contact point to the roller centre."""
    lift = law_lift("cycloidal")
    h = 1e-5
    theta = np.linspace(0.1, 6.2, 400)
    prof = translating_profile(lift, theta, 0.03, 0.01, offset)
    plus = translating_profile(lift, theta + h, 0.03, 0.01, offset).contour
    minus = translating_profile(lift, theta - h, 0.03, 0.01, offset).contour
    tangent = plus - minus
    radial = prof.pitch - prof.contour
    cos = np.sum(tangent * radial, axis=1) / (np.hypot(*tangent.T) * np.hypot(*radial.T))
    # central differences: error ~ h^2 relative, far below 1e-6
    assert np.max(np.abs(cos)) < 1e-6


@pytest.mark.parametrize("law", ["cycloidal", "polynomial-4567", "harmonic"])
@pytest.mark.parametrize("offset", [0.0, -0.008])
def test_curvature_matches_three_point_circles(law, offset):
    lift = law_lift(law)
    theta = np.linspace(0.0, 2 * math.pi, 2001)[:-1]
    h = 2e-4
    r = 0.008
    mid = translating_profile(lift, theta, 0.03, r, offset)
    before = translating_profile(lift, theta - h, 0.03, r, offset)
    after = translating_profile(lift, theta + h, 0.03, r, offset)
    rho_pitch = circumradius(before.pitch, mid.pitch, after.pitch)
    rho_contour = circumradius(before.contour, mid.contour, after.contour)
    # away from the law's jerk/acceleration jumps the three-point circle converges as h^2
    smooth = np.ones_like(theta, dtype=bool)
    for b in lift.breakpoints():
        smooth &= np.abs(np.mod(theta - b + math.pi, 2 * math.pi) - math.pi) > 3 * h
    finite = smooth & (np.abs(mid.pitch_radius) < 1.0)  # nearly straight stretches: 3 points say little
    assert np.allclose(rho_pitch[finite], np.abs(mid.pitch_radius[finite]), rtol=2e-4)
    assert np.allclose(rho_contour[finite], np.abs(mid.contour_radius[finite]), rtol=2e-4)
    # base circle: radii are exactly base + r and base
    base = np.mod(theta - lift.start, 2 * math.pi) > lift.rise + lift.dwell + lift.ret + 1e-9
    assert np.allclose(mid.pitch_radius[base], 0.03 + r, rtol=1e-12)
    assert np.allclose(mid.contour_radius[base], 0.03, rtol=1e-12)


@pytest.mark.parametrize("offset", [0.0, 0.006, -0.01])
def test_pressure_angle_by_instant_centre(offset):
    """Independent oracle: the contact normal (from the contour's own tangent, by differences)
    cuts the line through the cam centre perpendicular to the follower axis at the instant centre
    I of cam and follower, and the follower speed is omega * x_I, i.e. L' = x_I."""
    lift = law_lift("modified-sine", "polynomial-345")
    theta = np.linspace(0.05, 6.2, 300)
    h = 1e-5
    r = 0.01
    prof = translating_profile(lift, theta, 0.03, r, offset)
    tangent_cam = (translating_profile(lift, theta + h, 0.03, r, offset).contour
                   - translating_profile(lift, theta - h, 0.03, r, offset).contour)
    c, s = np.cos(theta), np.sin(theta)
    tg = np.column_stack([c * tangent_cam[:, 0] - s * tangent_cam[:, 1], s * tangent_cam[:, 0] + c * tangent_cam[:, 1]])
    normal = np.column_stack([-tg[:, 1], tg[:, 0]])
    normal /= np.hypot(*normal.T)[:, None] * np.sign(normal[:, 1])[:, None]  # pointing up, away from the cam
    angle = np.arctan2(-normal[:, 0], normal[:, 1])
    assert np.allclose(angle, prof.pressure_angle, rtol=0, atol=1e-7)
    centre = np.column_stack([np.full_like(theta, offset), 0.03 * 0 + math.sqrt((0.03 + r) ** 2 - offset**2) + lift.derivatives(theta)[0]])
    x_instant = centre[:, 0] - centre[:, 1] * normal[:, 0] / normal[:, 1]
    assert np.allclose(x_instant, lift.derivatives(theta)[1], rtol=0, atol=1e-8)


def test_pitch_geometry_equals_full_profile():
    lift = law_lift("modified-trapezoid")
    theta = np.linspace(0, 2 * math.pi, 997)
    prof = translating_profile(lift, theta, 0.025, 0.007, 0.004)
    phi, rho = pitch_geometry(lift.derivatives(theta), 0.025, 0.007, 0.004)
    assert np.allclose(phi, prof.pressure_angle, rtol=0, atol=1e-15)
    assert np.allclose(rho, prof.pitch_radius, rtol=1e-13)


def test_undercut_detected_with_angle():
    # a steep 20 mm cycloidal rise over 40 deg on a 15 mm base circle: the nose is sharp
    lift = law_lift("cycloidal", height=0.02, start=0.0, rise=math.radians(40), dwell=0.0, ret=math.radians(40))
    theta = np.arange(3600) * 2 * math.pi / 3600
    prof = translating_profile(lift, theta, 0.015, 0.014, 0.0)
    convex = prof.pitch_radius > 0
    smallest = prof.pitch_radius[convex].min()
    assert smallest < 0.014  # the oracle: the roller really is larger than the sharpest convex pitch radius
    with pytest.raises(InputError) as info:
        check_undercut(prof, 0.014, "x.toml")
    assert info.value.key == "follower.roller_radius"
    assert "undercut" in info.value.reason
    i = int(np.argmin(np.where(convex & (prof.pitch_radius <= 0.014), prof.pitch_radius, np.inf)))
    assert f"{math.degrees(theta[i]):.3f} deg" in info.value.reason
    # a roller smaller than the sharpest convex pitch radius passes
    check_undercut(prof, 0.9 * smallest, "x.toml")


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("offset,roller", [(0.0, 0.0), (0.0, 0.01), (0.008, 0.006), (-0.012, 0.015)])
def test_round_trip_synthesis_then_analysis(law, offset, roller):
    """Contour from synthesis, analysed by Newton iteration for the contact: the lift comes back
    to <= 1e-9 m (in practice to rounding, ~1e-17 m), and L' with it."""
    lift = law_lift(law, "polynomial-345" if law != "polynomial-345" else "cycloidal", height=0.012)
    contour = SynthesizedContour(lift, 0.03, roller, offset)
    analysed = make_parametric_lift(contour, roller, offset, 0.03)
    theta = np.random.default_rng(7).uniform(0, 2 * math.pi, 2000)
    got, want = analysed.derivatives(theta), lift.derivatives(theta)
    assert np.max(np.abs(got[0] - want[0])) <= 1e-9
    assert np.max(np.abs(got[1] - want[1])) <= 1e-9
    assert np.all(np.isnan(got[2:]))  # the envelope carries C'' only: L'' is not invented


def test_round_trip_reports_a_folded_contour():
    from explorer.lift.contours.parametric import ContourFollowError

    lift = law_lift("cycloidal", height=0.02, start=0.0, rise=math.radians(40), dwell=0.0, ret=math.radians(40))
    contour = SynthesizedContour(lift, 0.015, 0.014, 0.0)  # undercut: the envelope has a swallowtail
    with pytest.raises(ContourFollowError, match="folds back"):
        make_parametric_lift(contour, 0.014, 0.0, 0.015)
