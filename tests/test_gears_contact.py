"""The 'contact' effect on the seeds' other gears: pivoted roller lever, rocking cam, rolling lever.

One statics (explorer.mechanics.contact) fed by each gear's contact geometry. Oracles:
- power balance T w = F v without friction (F the forces effect's valve force, v the kinematics'
  valve velocity; T from the contact geometry: the normal's moment arm, never from F v);
- with friction, the guide dissipation T w - F v = mu N |sin alpha| |v_roller| >= 0;
- Hertz at one angle by hand: the rocking cam on its top arc (concentric to the pivot, so the
  contour radius and the normal are known without the gear code), the rolling lever from the
  closed forms of its spiral faces (derived by hand from the polar forms, not by the code's jets),
  the pivoted lever's contour radius from a three-point circle on the synthesised contour;
- the rolling faces' pressure angle and radii against their own drawn polylines (faces());
- seed 004's self-locking warning, the trip gear's latch statics, and `explorer simulate` on each scene.
"""

import json
import math

import numpy as np
import pytest

from conftest import SCENES, run_cli
from explorer.effects.pipeline import simulate
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene
from explorer.core.units import AT

GEARS = ["pivoted_roller_lever", "rocking_cam", "rolling_lever"]
STATICS = ["kinematics", "lash", "forces", "contact"]
E_STEEL = 210e9 / (2.0 * (1.0 - 0.3**2))  # E* of steel on steel


def run(name, *overrides):
    effects = 'effects=["' + '", "'.join(STATICS) + '"]'
    return simulate(load_scene(SCENES / f"{name}.toml", [effects, *overrides]))


@pytest.fixture(scope="module")
def results():
    return {name: run(name) for name in GEARS}


@pytest.mark.parametrize("name", GEARS)
def test_power_balance_without_friction(results, name):
    """T w = F v_valve, sample by sample: the valve force of the forces effect, referred to the roller
    through the gear's instantaneous ratio, pushes along the contact normal; the normal's moment about
    the camshaft (for the rocking cam and the rolling lever about their pivot, times the four-bar's
    dchi/dtheta) must deliver exactly the power the valve takes. Rounding only: 1e-9 of the peak."""
    r = results[name]
    c = r.columns
    power_shaft = c["camshaft_torque_Nm"] * r.scene.drive.omega
    power_valve = c["contact_force_N"] * c["rigid_valve_velocity_m_s"]
    scale = np.max(np.abs(power_valve))
    assert scale > 1.0  # the valve really takes power
    assert np.max(np.abs(power_shaft - power_valve)) <= 1e-9 * scale
    # the torque changes sign: the spring gives back on the closing flank
    assert c["camshaft_torque_Nm"].max() > 0.0 > c["camshaft_torque_Nm"].min()


@pytest.mark.parametrize("name", GEARS)
def test_friction_dissipates_as_the_guide_model_says(name):
    """mu = tan 8 deg: the shaft's extra power is the guide friction mu N |sin alpha| times the driven
    point's speed |v_valve| / ratio, never negative; N solves N (cos a - mu |sin a| sgn v) = q F."""
    r = run(name, 'contact.friction_angle="8 deg"')
    c = r.columns
    geometry = build_lift(r.scene).gear.contact_geometry(np.radians(c["cam_angle_deg"]))
    mu = math.tan(math.radians(8.0))
    alpha = np.radians(c["pressure_angle_deg"])
    loaded = c["contact_force_N"] > 0.0
    v_roller = np.abs(c["rigid_valve_velocity_m_s"]) / geometry.ratio
    loss = c["camshaft_torque_Nm"] * r.scene.drive.omega - c["contact_force_N"] * c["rigid_valve_velocity_m_s"]
    expected = mu * c["cam_normal_force_N"] * np.abs(np.sin(alpha)) * v_roller
    scale = np.max(np.abs(c["contact_force_N"] * c["rigid_valve_velocity_m_s"]))
    assert np.max(np.abs(loss[loaded] - expected[loaded])) <= 1e-9 * scale
    assert np.all(loss[loaded] >= -1e-9 * scale) and expected[loaded].max() > 1e-3 * scale
    # the free-body equation along the travel, with the friction opposing the follower's motion
    sgn = np.sign(c["follower_velocity_m_s"])
    lhs = c["cam_normal_force_N"] * (np.cos(alpha) - mu * np.abs(np.sin(alpha)) * sgn)
    assert np.allclose(lhs[loaded], geometry.ratio[loaded] * c["contact_force_N"][loaded], rtol=1e-12)


def test_hertz_by_hand_on_the_rocking_cams_top_arc(results):
    """At 180 deg the roller rests on the top arc, concentric to the rocking cam's pivot C: contour
    radius 60 + 12 = 72 mm, roller 15 mm, the normal through C. Roller centre: circles of 87 mm about
    C = (150, 700) mm and 200 mm about O1 = (350, 780) mm, right of O1 -> C. The rocker (arm 200 mm
    at 180 deg, valve opening along -y) has s = 0.2 sin(psi) + const, so the ratio is |cos psi|."""
    r = results["rocking_cam"]
    c, s = r.columns, r.summary
    i = int(np.argmin(np.abs(c["cam_angle_deg"] - 180.0)))
    C, O1 = np.array([0.150, 0.700]), np.array([0.350, 0.780])
    rc, a = 0.087, 0.200
    dist = np.linalg.norm(O1 - C)
    along = (a**2 - rc**2 + dist**2) / (2 * dist)
    height = math.sqrt(a**2 - along**2)
    u = (C - O1) / dist
    perp = np.array([-u[1], u[0]])  # left of O1 -> C
    R = O1 + along * u - height * perp  # right side
    assert np.linalg.norm(R - C) == pytest.approx(rc, rel=1e-12)
    psi = math.atan2(R[1] - O1[1], R[0] - O1[0])
    n = (R - C) / rc
    travel = math.copysign(1.0, math.cos(psi)) * np.array([-math.sin(psi), math.cos(psi)])
    cos_alpha = float(n @ travel)
    assert c["pressure_angle_deg"][i] == pytest.approx(math.degrees(math.acos(cos_alpha)), abs=1e-9)
    normal = c["contact_force_N"][i] * abs(math.cos(psi)) / cos_alpha
    assert c["cam_normal_force_N"][i] == pytest.approx(normal, rel=1e-12)
    assert c["contour_radius_m"][i] == pytest.approx(0.072, rel=1e-12)
    # width rule b = P/(k D): exhaust k = 40 kgf/cm^2, roller diameter 30 mm, on the largest normal force
    width = c["cam_normal_force_N"].max() / (40.0 * AT * 0.030)
    assert s["required_cam_width_m"] == pytest.approx(width, rel=1e-12) and s["hertz_width_m"] == s["required_cam_width_m"]
    sigma = math.sqrt(normal * E_STEEL * (1 / 0.015 + 1 / 0.072) / (math.pi * width))
    assert c["hertz_stress_Pa"][i] == pytest.approx(sigma, rel=1e-9)


def _rolling_by_hand(gear, theta):
    """Closed forms of the rolling faces (derived by hand from the polar forms; see the test)."""
    d, rc, k = gear.law.distance, gear.law.contact_radius, gear.law.growth
    w = max(float(gear.rolling_swing(np.array([theta])).c[0][0]), 0.0)
    rho = rc + k * w
    radius_a = (rho**2 + k**2) ** 1.5 / (rho**2 + 2 * k**2)
    kappa_b = (1 + k**2 * (2 * rho - d) / rho**3) / ((d - rho) * (1 + k**2 / rho**2) ** 1.5)
    beta = gear.rest - gear.sense * (-w + (d / k) * math.log((d - rc) / (d - rc - k * w)))
    return w, rho, radius_a, kappa_b, beta


def test_hertz_by_hand_on_the_rolling_faces(results):
    """Rolling lever at the eccentric's dead centre (full swing). Face A, rho(phi) = rho_c + k w with
    |d rho/d phi| = k: R_A = (rho^2 + k^2)^1.5 / (rho^2 + 2 k^2). Face B, sigma = d - rho about B,
    turning by d beta/dw = rho/(d - rho): kappa_B = [1 + k^2 (2 rho - d)/rho^3] / ((d - rho)(1 + k^2/rho^2)^1.5).
    Pressure angle atan(rho/k); rocker on B (arm 50 mm at 180 deg, valve along -y): ratio |0.05 cos beta| / (d - rho).
    The face width is sized by the Hertz allowable (seed 004: rolling levers), so the peak stress equals it."""
    r = results["rolling_lever"]
    c, s = r.columns, r.summary
    gear = build_lift(r.scene).gear
    dead = min(gear.drive.dead_centres(), key=lambda t: -float(gear.rolling_swing(np.array([t])).c[0][0]))
    i = int(np.argmin(np.abs(np.radians(c["cam_angle_deg"]) - dead)))
    theta = math.radians(c["cam_angle_deg"][i])
    w, rho, radius_a, kappa_b, beta = _rolling_by_hand(gear, theta)
    assert w > 0.4  # deep in the rolling contact
    d, k = gear.law.distance, gear.law.growth
    alpha = math.atan(rho / k)
    assert abs(c["pressure_angle_deg"][i]) == pytest.approx(math.degrees(alpha), abs=1e-9)
    assert c["contour_radius_m"][i] == pytest.approx(radius_a, rel=1e-10)
    normal = c["contact_force_N"][i] * abs(0.05 * math.cos(beta)) / (d - rho) / math.cos(alpha)
    assert c["cam_normal_force_N"][i] == pytest.approx(normal, rel=1e-10)
    width = s["hertz_width_m"]
    sigma = math.sqrt(normal * E_STEEL * (1 / radius_a + kappa_b) / (math.pi * width))
    assert c["hertz_stress_Pa"][i] == pytest.approx(sigma, rel=1e-9)
    assert s["required_cam_width_rule"] == "hertz allowable"
    assert s["max_hertz_stress_Pa"] == pytest.approx(s["hertz_allowable_Pa"], rel=1e-12)


def test_hertz_on_the_pivoted_lever_with_a_three_point_circle(results):
    """Contour radius at the peak stress from the circle through three points of the synthesised
    contour (chords of 1e-4 rad: O(h^2) ~ 1e-8 relative), then sigma by hand with the roller's 25 mm."""
    r = results["pivoted_roller_lever"]
    c, s = r.columns, r.summary
    gear = build_lift(r.scene).gear
    i = int(np.argmax(c["hertz_stress_Pa"]))
    theta = math.radians(c["cam_angle_deg"][i])
    p = gear.geometry(np.array([theta - 1e-4, theta, theta + 1e-4])).contour
    a, b, cc = (np.linalg.norm(p[1] - p[0]), np.linalg.norm(p[2] - p[1]), np.linalg.norm(p[2] - p[0]))
    area2 = abs((p[1, 0] - p[0, 0]) * (p[2, 1] - p[0, 1]) - (p[1, 1] - p[0, 1]) * (p[2, 0] - p[0, 0]))
    radius = a * b * cc / (2.0 * area2)  # circumradius = abc / (4 area)
    assert abs(c["contour_radius_m"][i]) == pytest.approx(radius, rel=1e-6)
    width = c["cam_normal_force_N"].max() / (40.0 * AT * 0.050)
    assert s["hertz_width_m"] == pytest.approx(width, rel=1e-12)
    sigma = math.sqrt(c["cam_normal_force_N"][i] * E_STEEL * (1 / 0.025 + 1 / c["contour_radius_m"][i]) / (math.pi * width))
    assert c["hertz_stress_Pa"][i] == pytest.approx(sigma, rel=1e-12)


def _circumradius(p0, p1, p2):
    a, b, c = np.linalg.norm(p1 - p0), np.linalg.norm(p2 - p1), np.linalg.norm(p2 - p0)
    area2 = abs((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]))
    return a * b * c / (2.0 * area2)  # abc / (4 area)


def test_rocking_cam_contour_radius_against_its_drawn_contour(results):
    """The contour radius the contact effect uses (pitch curve's polar curvature less the roller's
    radius) against the circle through three neighbours of the drawn contour (contour_points, body
    frame, 20 001 points over the flank: chord error O(h^2) ~ 1e-7 relative), along the flank; and
    the contact's column is that radius at the contact's body angle."""
    r = results["rocking_cam"]
    gear = build_lift(r.scene).gear
    cont, roller = gear.contour, gear.roller_radius
    pts, ws = cont.contour_points(roller, n=20_001, margin=0.0)
    for j in range(500, 20_000, 1000):
        want = abs(1.0 / cont.pitch_curvature(np.array([cont.reference - cont.sense * ws[j]]))[0] - roller)
        assert _circumradius(pts[j - 1], pts[j], pts[j + 1]) == pytest.approx(want, rel=1e-5), ws[j]
    th = np.radians(r.columns["cam_angle_deg"])
    phi = gear.contact_details(th)["contact_body_angle"]
    expected = 1.0 / cont.pitch_curvature(phi) - roller
    assert np.allclose(r.columns["contour_radius_m"], expected, rtol=1e-12)
    assert r.columns["contour_radius_m"].min() < 0.0 < r.columns["contour_radius_m"].max()  # hollow and convex stretches


def test_rolling_faces_against_their_drawn_polylines(results):
    """Pressure angle and both face radii of the rolling lever against gear.faces() (the two faces
    drawn in their own body frames): the face A polyline turned to the ground at the current swing
    gives the common normal by a central chord; three-point circles give both radii."""
    r = results["rolling_lever"]
    gear = build_lift(r.scene).gear
    face_a, face_b, ws = gear.faces(n=40_001)
    (ax, ay), (bx, by) = gear.pivot, gear.valve_pivot
    gamma = math.atan2(by - ay, bx - ax)
    e_perp = np.array([-math.sin(gamma), math.cos(gamma)])
    for j in range(2000, 40_000, 4000):
        w = ws[j]
        theta = _theta_of_swing(gear, w)
        g = gear.contact_geometry(np.array([theta]))
        alpha_body = gear.closed_end + gear.sense * (w + gear.contact_swing)
        rot = np.array([[math.cos(alpha_body), -math.sin(alpha_body)], [math.sin(alpha_body), math.cos(alpha_body)]])
        chord = rot @ (face_a[j + 1] - face_a[j - 1])
        chord /= np.linalg.norm(chord)
        # the valve lever's point travels along e_perp (either sense): the pressure angle's size
        alpha = math.acos(abs(float(chord @ e_perp)))  # angle of the tangent to the travel = 90 - (normal to travel)
        assert abs(g.pressure_angle[0]) == pytest.approx(0.5 * math.pi - alpha, abs=1e-7)
        assert g.contour_radius[0] == pytest.approx(_circumradius(*face_a[j - 1 : j + 2]), rel=1e-5)
        assert g.counter_radius[0] == pytest.approx(_circumradius(*face_b[j - 1 : j + 2]), rel=1e-5)


def _theta_of_swing(gear, w):
    """Shaft angle on the opening stroke where the rolling swing is w (Brent on the closed form)."""
    from scipy.optimize import brentq

    up, _ = sorted(gear.contact_angles(), key=lambda t: -float(gear.rolling_swing(np.array([t + 1e-3])).c[1][0]))
    dead = max(gear.drive.dead_centres(), key=lambda t: float(gear.rolling_swing(np.array([t])).c[0][0]))
    end = dead if dead > up else dead + 2 * math.pi
    return brentq(lambda t: float(gear.rolling_swing(np.array([t])).c[0][0]) - w, up, end, xtol=1e-15)


@pytest.mark.parametrize("name", GEARS)
def test_self_locking_warning_names_the_angle(name):
    """A friction angle of 80 deg leaves no margin on any of the gears (largest pressure angles 18,
    33 and 64 deg): seed 004's self-locking, warned with the pressure angle and the cam angle.
    The margin is 10 deg less the largest |pressure angle| while the cam lifts the follower (its
    velocity > 0; on the closing flank the spring drives and the cam cannot lock), found here from
    the columns by hand."""
    r = run(name, 'contact.friction_angle="80 deg"')
    s, c = r.report(), r.columns
    lifting = c["follower_velocity_m_s"] > 0.0
    worst = np.max(np.abs(c["pressure_angle_deg"])[lifting])
    assert s["min_self_locking_margin_deg"] == pytest.approx(10.0 - worst, abs=1e-9)
    assert s["min_self_locking_margin_deg"] < 0.0
    i = int(np.argmin(np.abs(c["cam_angle_deg"] - s["min_self_locking_margin_cam_angle_deg"])))
    assert lifting[i] and abs(c["pressure_angle_deg"][i]) == pytest.approx(worst, abs=1e-12)
    w = [x for x in s["warnings"] if "self-locking" in x]
    assert len(w) == 1 and f"{worst:.3f} deg" in w[0] and "while the cam lifts" in w[0]
    assert f"{s['min_self_locking_margin_cam_angle_deg']:.2f} deg" in w[0]


@pytest.mark.parametrize("name", GEARS)
def test_no_self_locking_warning_without_friction(results, name):
    s = results[name].report()
    assert s["friction_angle_deg"] == 0.0 and s["min_self_locking_margin_deg"] > 0.0
    assert not any("self-locking" in x for x in s["warnings"])


def test_the_gear_effect_keeps_only_the_gear_quantities():
    """One implementation: the statics are the contact effect's; 'gear' alone reports none of them."""
    for name in GEARS:
        r = simulate(load_scene(SCENES / f"{name}.toml", ['effects=["kinematics", "gear"]']))
        for column in ("camshaft_torque_Nm", "hertz_stress_Pa", "self_locking_margin_deg", "pressure_angle_deg"):
            assert column not in r.columns, (name, column)
        assert not {"max_pressure_angle_deg", "max_camshaft_torque_Nm"} & set(r.summary["gear"])


def test_trip_gear_contact_is_the_latch_statics():
    """No cam surface: the trip gear's contact effect reports the latch face (numbers by hand in
    tests/test_trip_gear.py), none of the cam-roller statics."""
    r = simulate(load_scene(SCENES / "trip_gear_dashpot.toml", ['effects=["kinematics", "lash", "contact"]']))
    assert r.summary["contact_follower_type"] == "trip" and r.summary["latch_force_at_trip_N"] > 0.0
    assert "hertz_stress_Pa" not in r.columns and "max_pressure_angle_deg" not in r.summary


@pytest.mark.parametrize("name", GEARS)
def test_explorer_simulate_runs_the_statics(name, tmp_path):
    out, summary = tmp_path / "out.csv", tmp_path / "out.json"
    proc = run_cli("simulate", SCENES / f"{name}.toml", "--set", 'effects=["kinematics","lash","forces","contact"]',
                   "-o", out, "--summary", summary)
    assert proc.returncode == 0, proc.stderr
    data = json.loads(summary.read_text())
    assert data["effects"]["contact"]["requested"]
    for key in ("max_pressure_angle_deg", "min_self_locking_margin_deg", "max_camshaft_torque_Nm", "max_hertz_stress_Pa",
                "required_cam_width_m"):
        assert isinstance(data[key], float) and math.isfinite(data[key]) and data[key] > 0.0, key
    header = out.read_text().splitlines()[0].split(",")
    for column in ("pressure_angle_deg", "self_locking_margin_deg", "cam_normal_force_N", "camshaft_torque_Nm",
                   "hertz_stress_Pa"):
        assert column in header
