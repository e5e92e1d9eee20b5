"""Pivoted roller lever (seed 004, Schenker Fig. 3): synthesis against independent geometry.

Oracles: the roller circle tangent to the synthesised contour (brute force on a dense polyline,
no shared code with the envelope formula); seed 004's velocity construction by the instant
centre; the "arcs about O and O1" analysis; a contour-only Newton analysis (round trip); the
power balance of the camshaft torque; the prescribed law itself through the forward linkage.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from explorer.core.errors import InputError
from explorer.gears import jet as J
from explorer.gears.linkage import RockerDrive
from explorer.gears.pivoted import (
    PivotedRollerGear,
    analyse_contour,
    analyse_pitch,
)
from explorer.lift.curves import LawLift
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

SCENE = Path(__file__).resolve().parent.parent / "assets" / "scenes" / "pivoted_roller_lever.toml"
TH = np.linspace(0.0, 2.0 * math.pi, 1440, endpoint=False)


def rocker_gear(roller_radius=0.02, law="cycloidal"):
    lift = LawLift(height=0.0206, start=math.radians(20), rise=math.radians(80), dwell=math.radians(10),
                   ret=math.radians(70), rise_law=law, return_law="polynomial-345")
    pivot, arm = (-0.12, 0.07), 0.12
    psi0 = PivotedRollerGear.rest_angle_for(0.05, roller_radius, pivot, arm, 1)
    drive = RockerDrive(pivot=pivot, arm=0.1, angle=math.pi, axis=-math.pi / 2, rest=psi0)
    return PivotedRollerGear(lift, 0.05, roller_radius, pivot, arm, 1, drive)


@pytest.fixture(scope="module")
def fig3_gear():
    return build_lift(load_scene(SCENE)).gear


@pytest.fixture(scope="module", params=["rocker", "fig3"])
def gear(request, fig3_gear):
    return rocker_gear() if request.param == "rocker" else fig3_gear


def test_linkage_inverse_then_forward_reproduces_the_law_with_all_derivatives(gear):
    """psi = drive^-1(L) by circle intersections; drive(psi) must give back L, L', L'', L'''
    (jets through acos, atan2 and sqrt twice): to rounding."""
    psi = gear.lever_angle(TH)
    s = gear.drive.travel(psi)
    want = gear.lift.derivatives(TH)
    scale = np.max(np.abs(want), axis=1, keepdims=True)
    assert np.max(np.abs(s.c - want) / scale) < 1e-9


def test_instant_centre_velocity_equals_the_derivative_of_position(gear):
    """Seed 004: the contact normal through the roller meets the line O-O1 in the instant centre,
    which fixes psi'. Compared with the analytic psi' of the synthesis chain."""
    g = gear.geometry(TH)
    rate = PivotedRollerGear.instant_centre_rate(gear.pivot, g.roller_centre, g.normal_ground)
    assert np.max(np.abs(rate - g.lever_rate)) < 1e-12 * max(1.0, np.abs(g.lever_rate).max())
    assert np.abs(g.lever_rate).max() > 0.05  # the lever really moves


def _segment_distances(points, a, b):
    """Distance from each point (M,2) to the polyline with segments a->b (K,2): (M,) minima."""
    ab = b - a
    out = np.empty(len(points))
    for i, p in enumerate(points):
        t = np.clip(np.einsum("kj,kj->k", p - a, ab) / np.einsum("kj,kj->k", ab, ab), 0.0, 1.0)
        out[i] = np.min(np.hypot(*(a + t[:, None] * ab - p).T))
    return out


def test_roller_circle_is_tangent_to_the_synthesised_contour(gear):
    """Brute force: the contour drawn as a polyline of 40 000 points; at each cam angle the
    nearest contour point lies exactly one roller radius from the roller centre (tangent, no
    interference). Chord error of the polyline: <= h^2 / (8 rho) ~ 1e-9 m here."""
    dense = np.linspace(0.0, 2.0 * math.pi, 40_000, endpoint=False)
    contour = gear.geometry(dense).contour
    a, b = contour, np.roll(contour, -1, axis=0)
    probe = np.linspace(0.0, 2.0 * math.pi, 97, endpoint=False) + 0.0123
    centres = gear.geometry(probe).pitch  # roller centre in the cam frame
    dist = _segment_distances(centres, a, b)
    assert np.max(np.abs(dist - gear.roller_radius)) < 5e-9


def test_seed_004_arcs_about_O_and_O1_give_back_cam_angle_and_lever_angle(gear):
    """Analysis by the seed's construction: each pitch point (radius rho) is under the roller
    where the circle of radius rho about O meets the lever circle about O1. It must return the
    cam angle at which the synthesis put it there, and the same lever angle with the same
    derivatives with respect to the cam angle."""
    phi = np.linspace(0.0, 2.0 * math.pi, 360, endpoint=False) + 0.01
    px, py = gear.pitch(phi)
    theta, psi = analyse_pitch(px, py, gear.pivot, gear.arm, gear.branch)
    assert np.max(np.abs(np.angle(np.exp(1j * (theta.c[0] - phi))))) < 1e-12
    psi_t = J.reparametrize(psi, theta)
    want = gear.lever_angle(phi)
    for k, tol in ((0, 1e-12), (1, 1e-10), (2, 1e-8), (3, 1e-6)):
        assert np.max(np.abs(psi_t.c[k] - want.c[k])) < tol * max(1.0, np.abs(want.c[k]).max()), k


def test_round_trip_synthesis_then_contour_analysis(gear):
    """From the contour alone (no pitch curve, no lever law): find, for each cam angle, the roller
    circle on the lever's arc tangent to the contour (2-D Newton from a perturbed start), push the
    lever angle through the valve drive and compare with the prescribed law: <= 1e-9 m."""
    theta = np.linspace(0.0, 2.0 * math.pi, 240, endpoint=False)
    psi_true = gear.lever_angle(theta).c[0]
    phi, psi = analyse_contour(lambda pj: gear.contour_jets(pj.c[0]), theta, psi_true + 0.004, theta + 0.01,
                               gear.pivot, gear.arm, gear.roller_radius)
    lift = gear.drive.travel(psi)
    assert np.max(np.abs(np.angle(np.exp(1j * (phi - theta))))) < 1e-10
    assert np.max(np.abs(lift - gear.lift.derivatives(theta)[0])) < 1e-9


def test_camshaft_torque_from_contact_geometry_equals_power_balance(gear):
    """Frictionless: the normal force F_n = F |ds/dpsi| / (a cos alpha) acting at the contact point
    along the normal has the moment F_n (C x n) about O, which must equal F dL/dtheta (T w = F v)."""
    g = gear.geometry(TH)
    force = 1000.0
    normal = force * np.abs(g.valve_per_lever) / (gear.arm * np.cos(g.pressure_angle))
    moment = normal * (g.contact[:, 0] * g.normal_ground[:, 1] - g.contact[:, 1] * g.normal_ground[:, 0])
    power = force * gear.lift.derivatives(TH)[1]
    assert np.max(np.abs(moment - power)) < 1e-9 * force


def test_pressure_angle_against_polyline_normals(gear):
    """The pressure angle from the analytic normal agrees with the normal of the contour polyline
    (a central chord), to the chord's O(h^2) accuracy."""
    h = 1e-5
    th = np.linspace(0.0, 2.0 * math.pi, 180, endpoint=False) + 0.003
    g = gear.geometry(th)
    ahead, behind = gear.geometry(th + h).contour, gear.geometry(th - h).contour
    chord = ahead - behind
    normal = np.column_stack([-chord[:, 1], chord[:, 0]]) / np.hypot(chord[:, 0], chord[:, 1])[:, None]
    c, s = np.cos(th), np.sin(th)
    ng = np.column_stack([c * normal[:, 0] - s * normal[:, 1], s * normal[:, 0] + c * normal[:, 1]])
    psi = g.lever_angle
    lifting = gear.lifting_sign()
    tx, ty = -np.sin(psi) * lifting, np.cos(psi) * lifting
    alpha = np.arctan2(tx * ng[:, 1] - ty * ng[:, 0], tx * ng[:, 0] + ty * ng[:, 1])
    assert np.max(np.abs(alpha - g.pressure_angle)) < 1e-7


def test_valve_ratio_matches_the_lever_arms_for_the_rocker():
    """Rocker with the valve pin on the same lever: ratio = valve arm / roller arm x geometry; at
    rest (pin motion along the axis) exactly 0.1/0.12."""
    gear = rocker_gear()
    g = gear.geometry(np.array([0.0]))  # base circle: lever at rest
    assert g.ratio[0] == pytest.approx(0.1 / 0.12, rel=1e-12)


def test_scene_gear_effect_reports_consistent_values():
    from explorer.effects.pipeline import simulate

    result = simulate(load_scene(SCENE))
    gear = result.summary["gear"]
    assert gear["instant_centre_check_rad"] < 1e-12
    # the valve lift follows the law: 20 mm after 0.6 mm lash
    assert result.summary["max_valve_lift_m"] == pytest.approx(0.020, abs=1e-12)
    # Fig. 3's lever ratio 1:1 (the straight valve lever d-e-f with equal arms)
    assert 0.99 < gear["min_lever_ratio"] <= gear["max_lever_ratio"] <= 1.0 + 1e-12
    # the contact effect's pressure angle, referred to the lever
    assert result.summary["max_pressure_angle_deg"] < 30.0
    torque = result.columns["camshaft_torque_Nm"]
    power = result.columns["contact_force_N"] * result.columns["rigid_valve_velocity_m_s"] / result.scene.omega
    assert np.max(np.abs(torque - power)) < 1e-9


BAD = [
    ({"gear.lever.pivot": '["-30 mm", "20 mm"]'}, "gear.lever.arm"),  # the roller cannot reach the cam
    ({"gear.lever.pivot": '["-150 mm", "-20 mm"]', "gear.lever.arm": '"183 mm"'}, "gear.lever.pivot"),  # arm cuts the cam
    ({"gear.lever.pivot": '["-50 mm", "40 mm"]', "gear.lever.arm": '"120 mm"'}, "gear.lever.pivot"),  # pivot in the sweep
    ({"follower.roller_radius": '"45 mm"', "lift.rise": '"30 deg"', "lift.return": '"30 deg"'}, "follower.roller_radius"),
    ({"gear.valve.rod": '"200 mm"'}, "gear.valve.rod"),  # the rod cannot reach the valve lever
    ({"gear.valve.arm_out": '"12 mm"'}, "gear.valve.arm_out"),  # the valve pin passes its dead point
    ({"gear.valve.axis": '"90 deg"'}, "gear.valve.axis"),  # valve would close as the roller lifts
    ({"follower.ratio": "2.0"}, "follower.ratio"),
]


@pytest.mark.parametrize("overrides, key", BAD, ids=[b[1] + str(i) for i, b in enumerate(BAD)])
def test_bad_geometry_names_the_part(overrides, key):
    with pytest.raises(InputError) as info:
        load_scene(SCENE, [f"{k}={v}" for k, v in overrides.items()])
    assert info.value.key == key


def test_missing_gear_section():
    import tomllib

    from explorer.scene.scene import scene_from_dict

    data = tomllib.loads(SCENE.read_text())
    del data["gear"]
    with pytest.raises(InputError) as info:
        scene_from_dict(data, "x.toml")
    assert info.value.key == "gear"


from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(
    base=st.floats(0.03, 0.08), roller=st.floats(0.005, 0.03), lift_h=st.floats(0.002, 0.03),
    rise=st.floats(40.0, 140.0), pivot_angle=st.floats(0.0, 360.0), pivot_distance=st.floats(1.5, 4.0),
    side=st.sampled_from([1, -1]), law=st.sampled_from(["cycloidal", "polynomial-345", "modified-sine"]),
    valve_angle=st.sampled_from([math.pi, 0.5 * math.pi, -0.5 * math.pi]),
)
def test_random_geometries_keep_the_identities(base, roller, lift_h, rise, pivot_angle, pivot_distance, side, law,
                                               valve_angle):
    """Any geometry is either refused with an InputError or synthesised exactly: the law comes
    back through the linkage, the instant centre gives psi', the roller touches the contour."""
    rp = base + roller
    pivot = (pivot_distance * rp * math.cos(math.radians(pivot_angle)), pivot_distance * rp * math.sin(math.radians(pivot_angle)))
    arm = math.hypot(*pivot) * 0.9
    lift = LawLift(height=lift_h, start=0.3, rise=math.radians(rise), dwell=0.0, ret=math.radians(rise),
                   rise_law=law, return_law=law)
    try:
        psi0 = PivotedRollerGear.rest_angle_for(base, roller, pivot, arm, side)
        rx, ry = pivot[0] + arm * math.cos(psi0), pivot[1] + arm * math.sin(psi0)
        lifting = float(np.sign(rx * -math.sin(psi0) + ry * math.cos(psi0)))
        pin = psi0 + valve_angle + 0.5 * math.pi
        axis = math.atan2(lifting * math.sin(pin), lifting * math.cos(pin))
        drive = RockerDrive(pivot=pivot, arm=0.8 * arm, angle=valve_angle, axis=axis, rest=psi0)
        gear = PivotedRollerGear(lift, base, roller, pivot, arm, side, drive)
        gear.check(n=720)
    except InputError:
        assume(False)
    th = np.linspace(0.0, 2.0 * math.pi, 360, endpoint=False)
    psi = gear.lever_angle(th)
    want = lift.derivatives(th)
    s = gear.drive.travel(psi)
    assert np.max(np.abs(s.c[0] - want[0])) < 1e-12
    assert np.max(np.abs(s.c[1] - want[1])) < 1e-9 * max(1.0, np.abs(want[1]).max())
    g = gear.geometry(th)
    rate = PivotedRollerGear.instant_centre_rate(gear.pivot, g.roller_centre, g.normal_ground)
    assert np.max(np.abs(rate - g.lever_rate)) < 1e-9 * max(1.0, np.abs(g.lever_rate).max())
    # the contour point is a roller radius from the roller centre, along the normal, and the
    # normal is perpendicular to the contour's own tangent there (envelope condition)
    cx, cy = gear.contour_jets(th)
    tangent = np.column_stack([cx.c[1], cy.c[1]])
    offset = g.pitch - np.column_stack([cx.c[0], cy.c[0]])
    assert np.allclose(np.hypot(offset[:, 0], offset[:, 1]), roller, atol=1e-14)
    dot = np.sum(tangent * offset, axis=1) / np.maximum(np.hypot(tangent[:, 0], tangent[:, 1]), 1e-300)
    assert np.max(np.abs(dot)) < 1e-12
