"""Bucket tappet (flat-faced translating follower, flat or crowned): issue #24's oracles.

- The textbook closed forms (Norton, Cam Design and Manufacturing Handbook, ch. 7; Shigley &
  Uicker): contour X = (Rb + s) sin t + s' cos t, Y = (Rb + s) cos t - s' sin t, rho = Rb + s + s'',
  contact offset = ds/dtheta, to 1e-12 relative.
- The envelope property itself, brute force: every face line supports the whole contour polygon.
- Synthesis -> analysis round trip to 1e-12 m (the exact contour as a parametric curve), and an
  arc cam analysed against each arc's support function c . u + R, written here.
- The crown: the translating roller's formulas (explorer.lift.contours.translating) with roller
  radius Rf; Rf -> infinity converges to the flat face like 1/Rf.
- Statics: the power balance T w = F v (+ mu N |v_slide| with friction); Dowson's sliding and
  entrainment velocities of the flat face.
"""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from explorer.core.errors import InputError
from explorer.gears.flat_face import (
    BucketTappetGear,
    Tappet,
    analyse_bucket,
    crowned_face_surface,
    synthesise_bucket,
)
from explorer.gears.jet import Jet
from explorer.lift.contours.arcs import Arc, build_arc_contour
from explorer.lift.contours.parametric import SplineContour
from explorer.lift.contours.translating import profile_from_derivatives
from explorer.lift.curves import LawLift
from explorer.mechanics.contact import effective_modulus
from explorer.mechanics.hertz import point_contact

RB = 0.018
TH = np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False)
LIFT = LawLift(height=0.0093, start=math.radians(30), rise=math.radians(85), dwell=math.radians(4),
               ret=math.radians(95), rise_law="polynomial-345", return_law="modified-sine")
E_STAR = effective_modulus(210e9, 0.3, 210e9, 0.3)


def flat(**kw) -> BucketTappetGear:
    return synthesise_bucket(Tappet(base_radius=RB, **kw), LIFT)


def test_flat_face_contour_radius_and_offset_match_the_textbook_closed_forms():
    k = flat().kinematics(TH)
    s, s1, s2 = LIFT.derivatives(TH)[:3]
    x = (RB + s) * np.sin(TH) + s1 * np.cos(TH)
    y = (RB + s) * np.cos(TH) - s1 * np.sin(TH)
    scale = RB + s.max()
    assert np.max(np.abs(k.surface.contour[:, 0] - x)) < 1e-12 * scale
    assert np.max(np.abs(k.surface.contour[:, 1] - y)) < 1e-12 * scale
    assert np.max(np.abs(k.surface.radius - (RB + s + s2))) < 1e-12 * scale
    assert np.max(np.abs(k.contact_offset - s1)) < 1e-12 * np.abs(s1).max()
    assert np.all(k.pressure_angle == 0.0)
    assert np.array_equal(k.lift, LIFT.derivatives(TH))  # the valve moves by the law itself


def test_the_flat_face_is_the_general_line_envelope_at_90_deg():
    """flat_face_surface writes out what explorer.gears.envelope.line_envelope gives for the lines
    y = Rb + s (normal angle 90 deg): the same cam, to rounding."""
    from explorer.gears.envelope import line_envelope

    s = Jet(LIFT.derivatives(TH))
    general = line_envelope(TH, Jet.constant(np.full(TH.size, 0.5 * math.pi)), s + RB)
    flat_face = flat().surface(TH)
    for name in ("contour", "radius", "contact", "contact_rate", "normal"):
        assert np.max(np.abs(getattr(general, name) - getattr(flat_face, name))) < 1e-16 * 1e3 * RB, name


def test_every_face_line_supports_the_whole_contour():
    """Brute force, sharing nothing with the envelope formula: the cam drawn as a polygon of
    40 000 contour points; at each cam angle its highest point along the tappet's axis (the
    direction (sin t, cos t) in the cam frame) must be the face, Rb + s, to the polygon's
    chord error max(rho) dbeta^2 / 8 (2e-10 m here), and nothing may stand above the face."""
    gear = flat()
    dense = np.linspace(0.0, 2.0 * math.pi, 40_000, endpoint=False)
    surface = gear.surface(dense)
    polygon = surface.contour
    chord = surface.radius.max() * (dense[1] - dense[0]) ** 2 / 8.0
    probe = TH[::10]
    u = np.column_stack([np.sin(probe), np.cos(probe)])
    height = (u @ polygon.T).max(axis=1)
    face = RB + LIFT.derivatives(probe)[0]
    assert np.max(face - height) < chord
    assert np.max(height - face) < 1e-15


class ExactFlatContour:
    """The textbook contour as a parametric curve in the synthesis angle t, with its exact
    derivatives written out here: X' = (Rb + s + s'') (cos t, -sin t),
    X'' = (s' + s''') (cos t, -sin t) - (Rb + s + s'') (sin t, cos t)."""

    period = 2.0 * math.pi
    order = 2

    def jets(self, t, rows):
        t = np.asarray(t, dtype=float)
        s, s1, s2, s3 = LIFT.derivatives(t)
        c, n = np.cos(t), np.sin(t)
        rho = RB + s + s2
        out = np.array([
            [(RB + s) * n + s1 * c, (RB + s) * c - s1 * n],
            [rho * c, -rho * n],
            [(s1 + s3) * c - rho * n, -(s1 + s3) * n - rho * c],
        ])
        return out[:rows]


def test_synthesis_then_analysis_gives_back_the_lift_to_1e_12_m():
    analysed = analyse_bucket(Tappet(base_radius=RB), ExactFlatContour())
    got = analysed.lift.derivatives(TH)
    want = LIFT.derivatives(TH)
    assert np.max(np.abs(got[0] - want[0])) < 1e-12
    assert np.max(np.abs(got[1] - want[1])) < 1e-9 * np.abs(want[1]).max()


def test_a_contour_of_points_converges_to_the_lift():
    """Points of the synthesised cam through a quintic spline (explorer.lift.contours'): the lift
    comes back to the spline's accuracy, better with more points."""
    errors = []
    for count in (360, 1440):
        points = flat().surface(np.linspace(0.0, 2.0 * math.pi, count, endpoint=False)).contour
        got = analyse_bucket(Tappet(base_radius=RB), SplineContour(points)).lift.derivatives(TH)[0]
        errors.append(np.max(np.abs(got - LIFT.derivatives(TH)[0])))
    assert errors[1] < 1e-9 and errors[1] < errors[0] / 30.0


def arc_cam(rb=0.018, nose=0.006, lift=0.008, flank=0.09):
    """A symmetric four-arc cam: base circle, two convex flanks of radius `flank` tangent to it and
    to the nose circle, whose centre is at rb + lift - nose above the cam centre."""
    d = rb + lift - nose
    # flank centre c: |c| = flank - rb, |c - (0, d)| = flank - nose
    r1, r2 = flank - rb, flank - nose
    y = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
    x = math.sqrt(r1 * r1 - y * y)
    arcs = [Arc(0.0, 0.0, rb), Arc(-x, y, flank), Arc(0.0, d, nose), Arc(x, y, flank)]
    return build_arc_contour(arcs, tolerance=1e-12)


def support_of_arc_cam(contour, theta):
    """The support function of the arc cam in the tappet's direction u = (sin t, cos t), arc by arc:
    c . u + R for the arc whose normals span u; and its derivatives in t (u' = (cos t, -sin t))."""
    out = np.full((4, theta.size), np.nan)
    u = np.column_stack([np.sin(theta), np.cos(theta)])
    du = np.column_stack([np.cos(theta), -np.sin(theta)])
    for k, arc in enumerate(contour.arcs):
        a0, sweep = contour.start_angle[k], contour.sweep[k]
        angle = np.arctan2(u[:, 1], u[:, 0])
        offset = np.mod((angle - a0) * np.sign(sweep), 2.0 * math.pi)
        inside = offset <= abs(sweep)
        c = np.array([arc.x, arc.y])
        out[0, inside] = u[inside] @ c + arc.radius
        out[1, inside] = du[inside] @ c
        out[2, inside] = -(u[inside] @ c)
        out[3, inside] = -(du[inside] @ c)
    return out


def test_a_flat_face_over_an_arc_cam_is_each_arc_support_function():
    contour = arc_cam()
    gear = analyse_bucket(Tappet(base_radius=0.018), contour)
    want = support_of_arc_cam(contour, TH)
    want[0] -= 0.018
    got = gear.lift.derivatives(TH)
    assert not np.any(np.isnan(want))
    for row in range(4):
        assert np.max(np.abs(got[row] - want[row])) < 1e-12 * max(np.abs(want[row]).max(), 1e-3), row
    # the junctions of the arcs are the lift's breakpoints (rho jumps there: s'' jumps)
    assert gear.lift.breakpoints().size == 4


def test_crowned_face_is_the_translating_roller_of_the_crown_radius():
    rf = 0.04
    d = LIFT.derivatives(TH)
    surf = crowned_face_surface(TH, Jet(d), RB, rf)
    roller = profile_from_derivatives(TH, d, RB, rf, 0.0)
    assert np.max(np.abs(surf.contour - roller.contour)) < 1e-12 * (RB + 0.01)
    assert np.max(np.abs(surf.radius - roller.contour_radius)) < 1e-12 * np.abs(roller.contour_radius).max()
    k = synthesise_bucket(Tappet(base_radius=RB, face_radius=rf), LIFT).kinematics(TH)
    assert np.max(np.abs(k.pressure_angle - roller.pressure_angle)) < 1e-13


def test_crown_radius_to_infinity_is_the_flat_face():
    """rho and the contact offset of the crown converge to the flat face's like 1/Rf (the crown's
    correction is of order s'^2/Rf), and the closed form keeps that up to Rf = 1e9 m, where the
    roller formula's rho_pitch - Rf would have lost every digit."""
    k_flat = flat().kinematics(TH)
    gaps = []
    for rf in (1.0, 100.0, 1e4):
        k = synthesise_bucket(Tappet(base_radius=RB, face_radius=rf), LIFT).kinematics(TH)
        gaps.append(max(np.max(np.abs(k.surface.radius - k_flat.surface.radius)),
                        np.max(np.abs(k.contact_offset - k_flat.contact_offset))))
    assert 80.0 < gaps[0] / gaps[1] < 120.0 and 80.0 < gaps[1] / gaps[2] < 120.0
    k = synthesise_bucket(Tappet(base_radius=RB, face_radius=1e9), LIFT).kinematics(TH)
    far = np.max(np.abs(k.surface.radius - k_flat.surface.radius))
    assert far == pytest.approx(gaps[2] * 1e-5, rel=0.05)  # still the 1/Rf correction, not rounding
    assert np.max(np.abs(k.surface.contour - k_flat.surface.contour)) < 1e-12  # m: the 1/Rf offset, 3e-13 m


def test_a_cusp_is_one_line_naming_the_base_radius_and_the_cam_angle():
    sharp = LawLift(height=0.009, start=math.radians(40), rise=math.radians(50), dwell=0.0, ret=math.radians(50),
                    rise_law="cycloidal", return_law="cycloidal")
    with pytest.raises(InputError) as info:
        synthesise_bucket(Tappet(base_radius=0.015, file="bucket.toml"), sharp)
    err = info.value
    assert err.key == "follower.base_radius" and err.file == "bucket.toml"
    assert "cusp" in err.reason and "\n" not in str(err)
    theta = np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False)
    s = sharp.derivatives(theta)
    worst = math.degrees(theta[np.argmin(0.015 + s[0] + s[2])])
    assert f"cam angle {worst:.2f} deg" in err.reason
    need = -np.min(0.015 + s[0] + s[2])
    assert f"by more than {need * 1e3:.3g} mm" in err.reason
    synthesise_bucket(Tappet(base_radius=0.015 + need + 1e-4), sharp)  # the remedy it names is enough


def test_face_diameter_needed_is_twice_the_largest_ds_dtheta_plus_the_margin():
    gear = flat(face_margin=0.001)
    need, at = gear.face_diameter_needed(gear.kinematics(TH))
    s1 = LIFT.derivatives(TH)[1]
    assert need == pytest.approx(2.0 * np.abs(s1).max() + 0.001, rel=1e-14)
    assert at == TH[np.argmax(np.abs(s1))]
    flat(face_margin=0.001, face_diameter=need + 1e-6)
    with pytest.raises(InputError) as info:
        flat(face_margin=0.001, face_diameter=need - 1e-6)
    assert info.value.key == "gear.tappet.face_diameter" and "smaller than" in info.value.reason
    # with the lobe's width and its offset along the camshaft, the contact line's far end counts
    wide = flat(cam_width=0.014, offset=0.0015)
    need_wide, _ = wide.face_diameter_needed(wide.kinematics(TH))
    assert need_wide == pytest.approx(2.0 * math.hypot(np.abs(s1).max(), 0.0015 + 0.007), rel=1e-14)


@pytest.mark.parametrize("face_radius", [math.inf, 0.5])
@pytest.mark.parametrize("mu", [0.0, 0.08])
def test_power_balance_of_the_camshaft_torque(face_radius, mu):
    """T w = F v + mu N |v_slide| w: the torque from the contact force's moment, the power from
    the lift's derivative; the friction's share is the heat of the sliding contact."""
    gear = synthesise_bucket(Tappet(base_radius=RB, face_radius=face_radius), LIFT)
    k = gear.kinematics(TH)
    force = 350.0 + 28_000.0 * k.lift[0] + 0.02 * k.lift[2] * 3000.0
    f = gear.contact_forces(k, force, cam_friction=mu)
    heat = mu * f.normal * np.abs(k.velocities.sliding)
    assert np.max(np.abs(f.torque - force * k.lift[1] - heat)) < 1e-12 * np.abs(f.torque).max()
    if face_radius == math.inf:
        assert np.allclose(f.normal, force, rtol=1e-15, atol=0.0)  # the face's normal is the tappet's axis


def test_flat_face_sliding_and_entrainment_velocities():
    """Dowson & Higginson's flat tappet: sliding -(Rb + s), entrainment -(Rb + s + 2 s'')/2 per
    unit camshaft speed (the contact runs over the cam at rho and over the face at s'')."""
    k = flat().kinematics(TH)
    s = LIFT.derivatives(TH)
    assert np.max(np.abs(k.velocities.sliding + RB + s[0])) < 1e-15
    assert np.max(np.abs(k.velocities.entrainment + 0.5 * (RB + s[0] + 2.0 * s[2]))) < 1e-15


def test_hertz_stress_of_flat_and_crowned_faces():
    k = flat().kinematics(TH)
    force = np.full(TH.size, 800.0)
    sigma = flat().hertz_stress(k, force, E_STAR, width=0.014)
    assert np.allclose(sigma, np.sqrt(800.0 * E_STAR / (math.pi * 0.014 * k.surface.radius)), rtol=1e-14)
    crowned = synthesise_bucket(Tappet(base_radius=RB, face_radius=10.0, cam_width=0.014), LIFT)
    kc = crowned.kinematics(TH)
    got = crowned.hertz_stress(kc, force, E_STAR)
    point = point_contact(force, 0.1 + 1.0 / kc.surface.radius, np.full(TH.size, 0.1), E_STAR)
    assert np.array_equal(got, point.peak_pressure)
    edge = crowned.edge_loaded(kc, force, E_STAR)
    assert np.array_equal(edge, point.semi_major > 0.007) and edge.any() and not edge.all()


@given(st.floats(-1.0, 0.0), st.sampled_from(["base_radius", "face_radius"]))
def test_bad_sizes_are_input_errors(value, which):
    kw = {"base_radius": RB, "face_radius": 1.0}
    kw[which] = value
    with pytest.raises(InputError) as info:
        synthesise_bucket(Tappet(**kw), LIFT)
    assert which in info.value.key


def test_a_crown_needs_the_lobe_over_the_tappet_axis():
    with pytest.raises(InputError) as info:
        synthesise_bucket(Tappet(base_radius=RB, face_radius=1.0, cam_width=0.01, offset=0.006), LIFT)
    assert info.value.key == "gear.tappet.offset"


@pytest.mark.parametrize("rf", [100.0, 1e4, 1e6])
def test_a_crown_longer_than_the_lobe_is_at_least_the_line_contact_and_tends_to_the_flat_face(rf):
    """A crown whose Hertz ellipse would run over the lobe's edges is cut to the lobe's width: its
    peak pressure is at least that of the line contact over the width with the crown's curvature
    in the plane (Johnson, Contact Mechanics, two-dimensional contact of cylinders:
    p0 = sqrt(P' E* (1/Rf + 1/rho) / pi), written here), and as Rf -> inf it is the flat face's
    (as the kinematics are). The untruncated
    ellipse's p0 = 3P/(2 pi a b) falls to 0 as Rf -> inf: it may not be reported there."""
    force = np.full(TH.size, 800.0)
    flat_sigma = flat().hertz_stress(flat().kinematics(TH), force, E_STAR, width=0.014)
    gear = synthesise_bucket(Tappet(base_radius=RB, face_radius=rf, cam_width=0.014), LIFT)
    k = gear.kinematics(TH)
    got = gear.hertz_stress(k, force, E_STAR)
    line = np.sqrt(800.0 / 0.014 * E_STAR * (1.0 / rf + 1.0 / k.surface.radius) / math.pi)
    assert gear.edge_loaded(k, force, E_STAR).all()
    assert np.all(got >= line * (1.0 - 1e-14))
    point = point_contact(force, 1.0 / rf + 1.0 / k.surface.radius, np.full(TH.size, 1.0 / rf), E_STAR).peak_pressure
    assert np.all(got >= point)
    # the crown changes rho like 1/Rf (test_crown_radius_to_infinity_is_the_flat_face): the stress too
    assert np.max(np.abs(got / flat_sigma - 1.0)) < 0.2 / rf
