"""Schenker (1902) Fig. 2 exhaust cam, computed exactly from its arcs.

Tolerances: the paper's figures are read off a drawing and given to 2-3 digits, so the
computed values must match to half a unit of the last digit given (0.005 m/s, 0.5 m/s^2).
The design (explorer/lift/contours/schenker_fig2.py) rounds its radii to 0.01 mm; what rounding
costs is inside those tolerances and is checked here, not assumed."""

import math

import numpy as np
import pytest

from conftest import SCENES, run_cli
from explorer import load_scene, simulate
from explorer.lift.contours import schenker_fig2 as fig2
from explorer.effects.lift import build_lift
from explorer.scene.builtin import default_scene
from explorer.core.units import G0

SCENE = SCENES / "schenker1902_fig2.toml"
W = 240 * 2 * math.pi / 60


@pytest.fixture(scope="module")
def scene():
    return load_scene(SCENE)


@pytest.fixture(scope="module")
def lift(scene):
    return build_lift(scene)


@pytest.fixture(scope="module")
def figures(lift):
    return fig2.figures(fig2.PAPER_DESIGN, lift)


def angle_of(lift, name):
    return float(lift.junction_angles[[a.name for a in lift.contour.arcs].index(name)])


def test_scene_arcs_are_the_documented_design(scene):
    want = fig2.arcs(fig2.PAPER_DESIGN)
    got = scene.cam.arcs.arcs
    assert [a.name for a in got] == [a.name for a in want]
    for a, b in zip(got, want):
        assert a.concave == b.concave
        assert a.radius == pytest.approx(b.radius, abs=1e-15)
        assert math.hypot(a.x - b.x, a.y - b.y) < 1e-12  # centres written to 1e-9 mm
    assert scene.cam.arcs.gap.max() < 1e-11
    assert scene.follower.base_radius == pytest.approx(0.0223)
    assert scene.follower.roller_radius == pytest.approx(0.010)
    assert scene.follower.offset == 0.0 and scene.follower.ratio == 1.0


def test_it_is_the_default_scene():
    assert default_scene().name == "schenker1902_fig2.toml"


def test_event_lift_and_time(lift):
    """Cam lift 20.6 mm; the roller leaves the base circle at 20 deg and is back at 180 deg:
    160 deg between the flank tangent points, t' = 60*160/(240*360) = 0.111 s."""
    th = np.linspace(0, 2 * np.pi, 36001)
    d = lift.derivatives(th)
    assert d[0].max() == pytest.approx(0.0206, abs=1e-12)
    up = np.radians(20.0)
    down = np.radians(180.0)
    assert np.all(np.abs(d[0][(th < up - 1e-9) | (th > down + 1e-9)]) < 1e-15)
    assert np.all(d[0][(th > up + 1e-6) & (th < down - 1e-6)] > 0)
    bp = np.degrees(lift.breakpoints())
    assert min(bp) == pytest.approx(20.0, abs=1e-9) and max(bp) == pytest.approx(180.0, abs=1e-9)
    t_event = (down - up) / W
    assert t_event == pytest.approx(60 * 160 / (240 * 360), rel=1e-12)
    assert round(t_event, 3) == 0.111


def test_paper_figures(figures):
    assert figures["v_max"] == pytest.approx(0.82, abs=0.005)
    assert figures["v_min"] == pytest.approx(-1.27, abs=0.005)
    assert figures["a_before_F"] == pytest.approx(-117.0, abs=0.5)
    assert figures["a_after_F"] == pytest.approx(159.0, abs=0.5)
    assert figures["a_min_rise"] == pytest.approx(-35.0, abs=0.5)
    # the grid (36000 steps) agrees with the exact values
    assert figures["v_max_grid"] == pytest.approx(figures["v_max"], abs=1e-6)
    assert figures["v_min_grid"] == pytest.approx(figures["v_min"], abs=1e-3)


def test_fit_return_gives_the_stated_exact_radii():
    rb, r4, r5 = fig2.fit_return(0.010)
    assert (rb * 1e3, r4 * 1e3, r5 * 1e3) == pytest.approx((22.3038, 9.4609, 86.1001), abs=1e-4)
    v, a_left, a_right = fig2.return_figures(rb, 0.010, r4, r5)
    assert (v, a_left, a_right) == pytest.approx((-1.27, -117.0, 159.0), rel=1e-9)


def test_fit_rise_gives_the_stated_radii():
    """fit_rise from the scene's R1 = 1 m lands on the radii the scene rounds to 0.01 mm/0.01 deg."""
    design = fig2.fit_rise(fig2.PAPER_DESIGN, 1.0)
    assert design.r_bc * 1e3 == pytest.approx(28.66, abs=0.005)
    assert design.r_cd * 1e3 == pytest.approx(15.84, abs=0.005)
    assert math.degrees(design.rise) == pytest.approx(76.98, abs=0.005)
    f = fig2.figures(design, steps=3600)
    assert f["v_max"] == pytest.approx(0.82, abs=1e-4) and f["a_min_rise"] == pytest.approx(-35.0, abs=0.01)


def test_velocity_cusp_and_acceleration_jump_at_F(lift):
    theta_f = angle_of(lift, "FG (centre o2)")
    assert math.degrees(theta_f) == pytest.approx(147.487, abs=1e-3)
    eps = 1e-7
    before, at, after = lift.derivatives(np.array([theta_f - eps, theta_f, theta_f + eps]))[1:3].T
    # velocity continuous (contour tangent-continuous) ...
    assert W * abs(before[0] - after[0]) < 1e-6
    # ... with different one-sided slopes: the cusp (kink) of the v-curve
    assert W**2 * before[1] == pytest.approx(-117.0, abs=0.5)
    assert W**2 * after[1] == pytest.approx(159.0, abs=0.5)
    # and it is the velocity minimum: v decreases into F and increases out of it
    th = theta_f + np.array([-0.02, -0.01, 0.0, 0.01, 0.02])
    v = lift.derivatives(th)[1]
    assert np.argmin(v) == 2 and v[1] > v[2] < v[3]


def test_dwell_has_zero_acceleration_that_appears_and_vanishes_abruptly(lift):
    d_angle, e_angle = angle_of(lift, "DE dwell"), angle_of(lift, "EF (centre o1)")
    assert math.degrees(e_angle - d_angle) == pytest.approx(24.05, abs=0.01)
    inside = np.linspace(d_angle + 1e-6, e_angle - 1e-6, 200)
    d = lift.derivatives(inside)
    assert np.allclose(d[0], 0.0206, rtol=0, atol=1e-15)
    assert np.all(np.abs(d[1:]) < 1e-12)
    eps = 1e-9
    before_d = lift.derivatives(np.array([d_angle - eps]))[2, 0] * W**2
    after_e = lift.derivatives(np.array([e_angle + eps]))[2, 0] * W**2
    assert before_d == pytest.approx(-35.0, abs=0.5)  # S: vanishes from -35 to 0
    assert after_e == pytest.approx(-57.4, abs=0.1)  # T: reappears at -57, then grows to -117 at U (F)
    ef = np.linspace(e_angle + 1e-6, angle_of(lift, "FG (centre o2)") - 1e-6, 50)
    assert np.all(np.diff(lift.derivatives(ef)[2]) < 0)


def test_v_max_lies_at_the_inflection_of_bc(lift, figures):
    b, c = angle_of(lift, "BC"), angle_of(lift, "CD")
    assert b < math.radians(figures["v_max_angle_deg"]) < c
    k = [a.name for a in lift.contour.arcs].index("BC")
    acc = lift.arc_candidate(k, np.array([b, c]))[2] * W**2
    assert acc[0] > 0 > acc[1]  # BC carries the sign change of the acceleration
    assert figures["a_bc_start"] == pytest.approx(-figures["a_bc_end"], abs=0.05)  # a slow, symmetric transition


def test_masses_loads_and_linkage(scene):
    assert scene.valve.mass == pytest.approx(2.9 * G0)
    assert scene.valve.oscillating_mass == pytest.approx(2.6 * G0)
    assert scene.valve.lash == pytest.approx(0.0006)
    w0 = scene.spring.preload + scene.loads.closing_total + scene.loads.friction
    assert w0 == pytest.approx(385 * G0)  # W0 while the valve opens
    assert scene.linkage.stiffness == pytest.approx(1.8e6 * G0)
    assert scene.linkage.stiffness * 0.001 == pytest.approx(1800 * G0)  # 1 mm = 1800 kgf
    assert w0 / scene.linkage.stiffness == pytest.approx(0.000214, abs=5e-7)  # S0 = W/k
    assert scene.effects == ("kinematics", "lash", "forces", "elastic")  # opens with what the README shows


def test_simulation_and_cli(scene, tmp_path):
    result = simulate(scene)
    s = result.summary
    assert s["max_valve_lift_m"] == pytest.approx(0.020, abs=1e-12)
    assert s["max_valve_velocity_m_s"] == pytest.approx(0.82, abs=0.005)
    assert s["min_valve_velocity_m_s"] == pytest.approx(-1.27, abs=0.005)
    # lash: the roller meets the valve with a finite speed v1 and leaves it with v2 (impacts)
    assert s["impact_velocity_opening_m_s"] == pytest.approx(0.157, abs=5e-4)
    assert s["impact_velocity_closing_m_s"] == pytest.approx(0.193, abs=5e-4)
    assert s["lash_take_up_angles_deg"] == pytest.approx([31.14], abs=5e-3)
    assert s["seating_angles_deg"] == pytest.approx([170.84], abs=5e-3)
    # the pitch radius on the nose EF is R4 + r; the hollow FG is concave with radius R5
    assert s["min_convex_contour_radius_m"] == pytest.approx(0.00946, rel=1e-9)
    assert s["min_concave_contour_radius_m"] == pytest.approx(0.0861, rel=1e-9)
    out, summary = tmp_path / "fig2.csv", tmp_path / "fig2.json"
    proc = run_cli("simulate", SCENE, "-o", out, "--summary", summary)
    assert proc.returncode == 0, proc.stderr
    header = out.read_text().splitlines()[0].split(",")
    for name in ("pressure_angle_deg", "pitch_radius_m", "contour_radius_m", "valve_velocity_m_s"):
        assert name in header


def test_only_the_roller_centre_geometry_matters():
    """As the scene's comment says: a 12 mm roller with every convex radius 2 mm smaller and the
    hollow 2 mm larger has the same offset circles, hence the same lift (to rounding)."""
    from dataclasses import replace

    other = replace(fig2.PAPER_DESIGN, base_radius=0.0203, roller_radius=0.012, r_ab=0.998, r_bc=0.02666,
                    r_cd=0.01384, r_ef=0.00746, r_fg=0.0881)
    th = np.linspace(0, 2 * np.pi, 5000)
    a, b = fig2.lift_of(fig2.PAPER_DESIGN).derivatives(th), fig2.lift_of(other).derivatives(th)
    assert np.max(np.abs(a[0] - b[0])) < 1e-12
    assert np.max(np.abs(a[2] - b[2])) < 1e-9 * np.abs(a[2]).max()


def test_readme_reproduces_f1_f2_and_the_3600_step_figures():
    """Issue #13.9: the documented command (docs/theory/schenker1902.md) gives F1/F2 = 20.48 / 288.27 kgf (his 21 / 288) from the
    shipped scene with the §4 steam load, and its 3600-step figures are what the default run
    reports: the exact one-sided values at F (test_paper_figures'), not the samples'."""
    import json

    from conftest import ROOT, run_cli

    readme = (ROOT / "docs" / "theory" / "schenker1902.md").read_text()
    command = """explorer simulate --set 'loads.closing.steam_on_stem_and_valve="46 kgf"'"""
    assert command in readme and "20.48 and 288.27 kgf" in readme
    proc = run_cli("simulate", "--set", 'loads.closing.steam_on_stem_and_valve="46 kgf"')
    assert proc.returncode == 0, proc.stderr
    s = json.loads(proc.stdout)
    kgf = 9.80665
    assert s["opening_side"]["required_spring_force_N"] / kgf == pytest.approx(20.48, abs=0.005)
    assert s["closing_side"]["required_spring_force_N"] / kgf == pytest.approx(288.27, abs=0.005)
    default = json.loads(run_cli("simulate").stdout)
    assert "`min_valve_velocity_m_s` −1.2699" in readme and "−116.99 / +158.99 at any" in readme
    assert round(default["min_valve_velocity_m_s"], 4) == -1.2699  # the exact extremes (valve_extremes)
    assert (round(default["min_valve_accel_m_s2"], 2), round(default["max_valve_accel_m_s2"], 2)) == (-116.99, 158.99)
    assert default["opening_side"]["required_spring_force_N"] / kgf == pytest.approx(-23.5, abs=0.05)
    assert default["closing_side"]["required_spring_force_N"] / kgf == pytest.approx(244.3, abs=0.05)


def test_the_scene_file_holds_the_arcs_the_design_gives():
    """assets/scenes/schenker1902_fig2.toml's [[cam.arcs]] are toml_arcs() of the paper's design,
    verbatim (centres to 1e-9 mm): the file is the design, not a copy that can drift."""
    from pathlib import Path

    from explorer.lift.contours.schenker_fig2 import toml_arcs

    scene = Path(__file__).resolve().parents[1] / "assets" / "scenes" / "schenker1902_fig2.toml"
    assert toml_arcs().strip() in scene.read_text()


def test_the_summary_lists_where_the_cams_acceleration_jumps(figures):
    """Schenker's lesson: where two arcs meet the acceleration jumps (the jerk unbounded there,
    whatever the samples' max_abs_valve_jerk_m_s3 says). The summary's valve_accel_jumps gives
    each junction's one-sided limits; the oracle is each arc's own formula at the junction
    (fig2.figures: arc_candidate, exact), 1e-8 rel (the summary's limits are taken 1e-12 rad
    either side: the jerk moves them by ~1e-10 rel). At F -116.99 -> +158.99 m/s^2, the paper's
    -117 / +159; before D his p1 = -35; E starts the return's arc at -57.42."""
    jumps = simulate(load_scene(SCENE)).summary["valve_accel_jumps"]
    at = {round(j["cam_angle_deg"], 3): (j["before_m_s2"], j["after_m_s2"]) for j in jumps}
    f = max(at, key=lambda x: at[x][1] - at[x][0])  # the largest upward jump
    assert at[f][0] == pytest.approx(figures["a_before_F"], rel=1e-8)
    assert at[f][1] == pytest.approx(figures["a_after_F"], rel=1e-8)
    assert (round(at[f][0]), round(at[f][1])) == (-117, 159)
    d = [x for x in at if at[x][0] == pytest.approx(figures["a_before_D"], rel=1e-8) and at[x][1] == 0.0]
    e = [x for x in at if at[x][0] == 0.0 and at[x][1] == pytest.approx(figures["a_after_E"], rel=1e-8)]
    assert len(d) == 1 and len(e) == 1 and round(figures["a_before_D"]) == -35
    assert len(jumps) == 5  # the five junctions on the open valve where the curvature changes


def test_a_smooth_law_has_no_jump_and_a_harmonic_cam_has_two():
    # cycloidal: acceleration continuous everywhere (its jerk jumps): none listed. The harmonic
    # law's acceleration jumps from 0 to h pi^2 / (2 beta^2) w^2 where the rise starts and back
    # from there to 0 where the return ends (at the nose, rise into return without a dwell, it is
    # continuous); with no lash the valve sees both: closed form, 1e-9 rel
    path = SCENES / "cycloidal_demo.toml"
    assert simulate(load_scene(path)).summary["valve_accel_jumps"] == []
    scene = load_scene(path, ['lift.law="harmonic"', 'valve.lash="0 mm"', 'effects=["kinematics"]'])
    jumps = simulate(scene).summary["valve_accel_jumps"]
    h, beta, w = 10.3e-3, math.radians(70.0), scene.drive.omega
    edge = h * math.pi**2 / (2.0 * beta**2) * w**2
    assert [round(j["cam_angle_deg"], 9) for j in jumps] == [20.0, 160.0]
    assert jumps[0]["before_m_s2"] == 0.0 and jumps[0]["after_m_s2"] == pytest.approx(edge, rel=1e-9)
    assert jumps[1]["before_m_s2"] == pytest.approx(edge, rel=1e-9) and jumps[1]["after_m_s2"] == 0.0
