"""Analysis from a [cam] contour (law = "contour") for the finger follower and the rocker arm, with
and without the pushrod's lifter (explorer.gears.arm_train.ArmTrainGear; the geometry is
explorer.gears.arm's and explorer.gears.pushrod's), and the OHC rocker's built-in scene.

Oracles:
- Round trip through the scene: the built-in scene's synthesised cam, written as 2880 points (a
  periodic quintic spline through them, explorer.lift.contours.parametric.SplineContour), analysed
  as law = "contour", gives back the wanted valve lift. The analysis itself is exact (the gear-level
  round trip over the exact envelope is 1e-12 m: tests/test_modern_arm.py); what is left is the
  points' spline: its error is O(h^6) on the contour (6.7e-12 m measured at 2880 points, 7e-10 m
  at 720), so 1e-10 m. The law's jerk jumps at its breakpoints and a C4 spline cannot jump, so the
  velocity and acceleration are compared 3 deg away from them: 1e-9 and 1e-7 of their peaks
  (measured 6e-12 and 3.5e-9).
- An independent vector loop written here: the roller's centre on the arc's offset circle, O1 +
  Rot(psi) C_local = Rot(theta) (c + (R +- r) e(phi)) (+ on a convex arc, - in a concave one),
  solved by Newton at many cam angles, on a cam of tangent arcs given in the scene's [[cam.arcs]];
  the valve travel and the lever ratio from the test's own arm (tests/test_modern_arm.LoopArm), to
  1e-10 (Newton to rounding: the residual < 1e-14 m).
- Bad contours: drawn for another base circle (larger: the valve would hang open; smaller: the
  roller would sink through the base circle), a concave hollow narrower than the roller, a flat
  pad over a concave flank (the pad cannot touch it: the contour's analysis has no contact, as a
  synthesised cam's cusp) and law = "contour" without [cam]: one line naming the key, exit 2,
  nothing written; random arc cams load or are refused naming a key (hypothesis).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import run_cli
from explorer.core.errors import InputError
from explorer.effects.lift import build_lift
from explorer.effects.pipeline import simulate
from explorer.scene.scene import load_scene, loads_scene
from test_modern_arm import LoopArm, e, jmat, rot

SCENES = Path(__file__).resolve().parent.parent / "assets" / "scenes"
FINGER = SCENES / "finger_follower.toml"
OHC = SCENES / "ohc_rocker.toml"
PUSHROD = SCENES / "pushrod_rocker.toml"
FULL = np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False)
EVENT_KEYS = ("height", "start", "rise", "dwell", "return")


def scene_theta(result):
    return np.radians(np.asarray(result.columns["cam_angle_deg"], dtype=float))


def contour_text(text: str, cam: str) -> str:
    """The scene with its [lift] law replaced by law = "contour" and the [cam] section `cam`."""
    text = re.sub(r'^law = "[^"]*"', 'law = "contour"', text, count=1, flags=re.M)
    for key in EVENT_KEYS:
        text = re.sub(rf"^{key} = .*$", "", text, count=1, flags=re.M)
    return text.replace("[follower]", cam + "\n[follower]", 1)


def points_cam(csv: Path) -> str:
    return f'[cam]\nfile = "{csv}"\nunit = "mm"\nspline_degree = 5\n'


def arcs_cam(arcs) -> str:
    """[[cam.arcs]] tables of (x, y, radius, concave) in metres."""
    out = ["[cam]", 'tolerance = "1e-6 mm"']
    for x, y, radius, concave in arcs:
        out += ["[[cam.arcs]]", f'x = "{x * 1e3!r} mm"', f'y = "{y * 1e3!r} mm"', f'radius = "{radius * 1e3!r} mm"',
                f'kind = "{"concave" if concave else "convex"}"']
    return "\n".join(out) + "\n"


def lobe(rb=0.018, nose=0.007, lift=0.0055, flank=0.06, concave=None):
    """A cam of four tangent arcs: base circle, flank, nose, flank. Convex flanks of radius `flank`
    (tests/test_modern_arm.arc_cam's), or concave ones of radius `concave` (touching the base
    circle and the nose from outside)."""
    d = rb + lift - nose
    if concave is None:
        r1, r2 = flank - rb, flank - nose
        radius = flank
    else:
        r1, r2 = rb + concave, nose + concave
        radius = concave
    y = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
    x = math.sqrt(r1 * r1 - y * y)
    hollow = concave is not None
    return [(0.0, 0.0, rb, False), (-x, y, radius, hollow), (0.0, d, nose, False), (x, y, radius, hollow)]


# --------------------------------------------------------------------------------------------
# the OHC rocker's built-in scene
# --------------------------------------------------------------------------------------------


def test_the_ohc_rocker_scene_runs_every_effect_with_its_figures():
    """No pushrod (rocker-arm without [gear.lifter]): the roller on the rocker's arm, ratio about
    1.5 (the valve pad's arm 52.7 mm over the roller's 35.13 mm with the rocker level), 10 mm valve
    lift, 3000 camshaft rpm, the valve does not float and the train's first separation is well
    above its speed."""
    scene = load_scene(OHC)
    assert scene.follower.type == "rocker-arm" and "lifter" not in scene.gear.parts
    assert list(scene.effects) == ["kinematics", "lash", "forces", "contact", "elastic", "gear"]
    assert scene.drive.rpm == 3000
    result = simulate(scene)
    for name, column in result.columns.items():
        assert np.isfinite(np.asarray(column, dtype=float)).all(), name
    r = result.report()
    assert 1.45 <= r["min_valve_ratio"] and r["max_valve_ratio"] <= 1.52
    assert r["max_valve_ratio"] == pytest.approx(52.7 / 35.13, rel=1e-3)  # level rocker at rest: the arms' ratio
    assert r["max_valve_lift_m"] == pytest.approx(0.010, abs=1e-12)
    assert r["valve_floats"] is False and r["jump_speed_rpm"] > 1.3 * scene.drive.rpm
    assert r["max_hertz_stress_Pa"] < scene.contact.allowable_stress


def test_the_ohc_rocker_passes_explorer_check_at_its_speed(tmp_path):
    out = tmp_path / "check.json"
    proc = run_cli("check", OHC, "-o", out)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "verdict: PASS" in proc.stdout


# --------------------------------------------------------------------------------------------
# round trip: synthesis -> points -> analysis
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("path", [FINGER, OHC, PUSHROD], ids=lambda p: p.stem)
def test_the_synthesised_cam_as_points_gives_back_the_wanted_lift(path, tmp_path):
    text = path.read_text()
    synthesised = build_lift(loads_scene(text, "synthesis.toml"))
    points = synthesised.gear.surface(np.linspace(0.0, 2.0 * math.pi, 2880, endpoint=False)).contour
    csv = tmp_path / "cam.csv"
    np.savetxt(csv, points * 1e3, delimiter=",", fmt="%.17g")
    scene = loads_scene(contour_text(text, points_cam(csv)), "analysis.toml")
    analysed = build_lift(scene)
    got, want = analysed.derivatives(FULL), synthesised.derivatives(FULL)
    assert np.max(np.abs(got[0] - want[0])) < 1e-10
    marks = np.asarray(synthesised.breakpoints())
    gap = np.abs(np.mod(FULL[:, None] - marks[None, :] + math.pi, 2.0 * math.pi) - math.pi).min(axis=1)
    away = gap > math.radians(3.0)
    assert np.max(np.abs(got[1] - want[1])[away]) < 1e-9 * np.abs(want[1]).max()
    assert np.max(np.abs(got[2] - want[2])[away]) < 1e-7 * np.abs(want[2]).max()
    # the geometry's figures are the synthesised gear's: the ratio, and the contact point (its
    # direction from the roller's centre follows the velocity: 1e-8 m at the jerk jumps, 2.3e-9 m
    # measured; 1e-11 m away from them)
    k, reference = analysed.gear.kinematics(FULL), synthesised.gear.kinematics(FULL)
    assert np.max(np.abs(k.ratio - reference.ratio)) < 1e-8 * k.ratio.max()
    assert np.max(np.abs(k.surface.contact - reference.surface.contact)) < 1e-8
    assert np.max(np.abs(k.surface.contact - reference.surface.contact)[away]) < 1e-11


# --------------------------------------------------------------------------------------------
# an arc cam in the scene against the test's own vector loop
# --------------------------------------------------------------------------------------------


def loop_over_arcs(arm: LoopArm, contour, theta_grid, psi_start):
    """psi per cam angle: Newton on O1 + Rot(psi) C_local - Rot(th) (c + reach e(phi)) = 0 for
    each arc of the scene's ArcContour (reach = R + r convex, R - r concave), keeping, of the
    solutions whose contact angle phi lies on the arc's span (its start angle and sweep), the one
    nearest the arm's last angle."""
    out = []
    psi = psi_start
    r = arm.side.radius
    for th in theta_grid:
        r_th = rot(th)
        found = []
        for k, arc in enumerate(contour.arcs):  # the contour's order: its start angles and sweeps
            c = np.array([arc.x, arc.y])
            reach = arc.radius - r if arc.concave else arc.radius + r
            q = psi
            phi = math.atan2(*(r_th.T @ (arm.o1 + rot(q) @ arm.centre_local) - c)[::-1])
            for _ in range(60):
                centre = rot(q) @ arm.centre_local
                f = arm.o1 + centre - r_th @ (c + reach * e(phi))
                step = np.linalg.solve(np.column_stack([jmat(centre), -r_th @ (reach * jmat(e(phi)))]), f)
                q, phi = q - step[0], phi - step[1]
                if np.max(np.abs(step)) < 1e-13:
                    break
            if np.max(np.abs(arm.o1 + rot(q) @ arm.centre_local - r_th @ (c + reach * e(phi)))) > 1e-14:
                continue
            span = np.mod((phi - contour.start_angle[k]) * np.sign(contour.sweep[k]), 2.0 * math.pi)
            if span <= abs(contour.sweep[k]) + 1e-12 or span >= 2.0 * math.pi - 1e-12:
                found.append(q)
        assert found, f"no arc closes the loop at {math.degrees(th):.2f} deg"
        psi = min(found, key=lambda q: abs(math.remainder(q - psi, 2.0 * math.pi)))
        out.append(psi)
    return np.array(out)


@pytest.mark.parametrize("path, arcs", [
    (FINGER, lobe()),
    (OHC, lobe()),
    (OHC, lobe(lift=0.006, concave=0.030)),  # concave flanks, wider than the roller: it rolls through them
], ids=["finger", "ohc-rocker", "ohc-rocker-concave"])
def test_an_arc_cam_scene_matches_the_vector_loop(path, arcs):
    scene = loads_scene(contour_text(path.read_text(), arcs_cam(arcs)), "arcs.toml")
    lift = build_lift(scene)
    gear = lift.gear
    arm = LoopArm(gear)
    probe = FULL[::10]
    k = gear.kinematics(probe)
    psi = loop_over_arcs(arm, scene.cam.arcs, probe, gear.arm.rest)
    psi = psi + 2.0 * math.pi * np.round((k.arm_angle[0] - psi) / (2.0 * math.pi))
    assert np.max(np.abs(k.arm_angle[0] - psi)) < 1e-12
    travel = np.array([arm.travel(p) for p in psi])
    assert travel.max() > 5e-3  # the valve really opens
    assert np.max(np.abs(lift.derivatives(probe)[0] - travel)) < 1e-10 * travel.max()
    ratio = np.array([abs(arm.valve_per_arm(p)) for p in psi]) / gear.arm.cam_side.arm
    assert np.max(np.abs(k.ratio - ratio)) < 1e-10 * ratio.max()
    # the valve rests on its seat on the base circle: the contour's base circle is the scene's
    assert abs(lift.derivatives(FULL)[0].min()) < 1e-12
    if path == FINGER:  # every effect the scene lists runs on the analysed gear (~9 s: see docs)
        result = simulate(scene)
        for name, column in result.columns.items():
            assert np.isfinite(np.asarray(column, dtype=float)).all(), name
        ratio = gear.kinematics(scene_theta(result)).ratio  # the angles back from degrees: rounding
        assert np.max(np.abs(result.columns["valve_ratio"] - ratio)) < 1e-12 * ratio.max()


# --------------------------------------------------------------------------------------------
# bad contours
# --------------------------------------------------------------------------------------------

FLAT_PAD = ('cam_side = "roller"|width = "10 mm"              # roller width (Hertz)',
            'cam_side = "pad"\nface_angle = "-90 deg"|width = "10 mm"')

BAD = [
    ("finger-larger-base", FINGER, lobe(rb=0.0185), None, "follower.base_radius", "off its seat"),
    ("finger-smaller-base", FINGER, lobe(rb=0.0175), None, "follower.base_radius", "off its seat"),
    ("ohc-hollow-narrower-than-roller", OHC, lobe(lift=0.006, concave=0.005), None, "cam", "roller cannot follow"),
    ("finger-flat-pad-on-concave-flank", FINGER, lobe(lift=0.006, concave=0.030), FLAT_PAD, "cam", "pad cannot follow"),
    ("pushrod-larger-base", PUSHROD, lobe(rb=0.0175), None, "follower.base_radius", "lifter would rest"),
]


@pytest.mark.parametrize("name, path, arcs, edit, key, words", BAD, ids=[b[0] for b in BAD])
def test_a_bad_contour_is_one_line_naming_the_key(name, path, arcs, edit, key, words, tmp_path):
    text = path.read_text()
    if edit is not None:
        for a, b in zip(edit[0].split("|"), edit[1].split("|")):
            assert a in text
            text = text.replace(a, b)
        text = text.replace("roller_radius = \"9 mm\"\n", "")
    text = contour_text(text, arcs_cam(arcs))
    with pytest.raises(InputError) as info:
        loads_scene(text, "bad.toml")
    assert info.value.key == key and words in info.value.reason, info.value
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    out = tmp_path / "out.csv"
    proc = run_cli("simulate", bad, "-o", out)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().count("\n") == 0 and key in proc.stderr and "Traceback" not in proc.stderr
    assert not out.exists()


def test_law_contour_without_a_cam_names_the_section():
    text = contour_text(FINGER.read_text(), "")
    with pytest.raises(InputError) as info:
        loads_scene(text, "nocam.toml")
    assert info.value.key == "cam" and "\n" not in str(info.value)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rb=st.floats(14.0, 22.0), nose=st.floats(1.0, 15.0), lift=st.floats(0.5, 12.0), flank=st.floats(-60.0, 200.0))
def test_random_arc_cams_load_or_name_a_key(rb, nose, lift, flank):
    """A random four-arc cam (flank radius < 0: concave flanks of that size) in the OHC rocker's
    scene: it loads and its lift is finite, or one InputError names a key."""
    rb, nose, lift, flank = rb * 1e-3, nose * 1e-3, lift * 1e-3, flank * 1e-3
    try:
        arcs = lobe(rb, nose, lift, flank=max(flank, rb + 1e-3), concave=-flank if flank < 0.0 else None)
    except ValueError:
        return  # no such tangent arcs (a negative square root): nothing to give the scene
    if not all(math.isfinite(v) for arc in arcs for v in arc[:3]) or min(a[2] for a in arcs) <= 0.0:
        return
    text = contour_text(OHC.read_text(), arcs_cam(arcs))
    try:
        scene = loads_scene(text, "random.toml")
    except InputError as exc:
        assert exc.key.startswith(("gear.", "follower.", "cam")) and "\n" not in str(exc)
        return
    lift_curve = build_lift(scene)
    d = lift_curve.derivatives(FULL[::10])
    assert np.isfinite(d).all() and abs(d[0].min()) < 1e-6


# --------------------------------------------------------------------------------------------
# exports and drawing of an analysed gear, the OHC rocker's parts
# --------------------------------------------------------------------------------------------


def test_the_exports_of_an_analysed_cam_are_the_given_contour():
    """The cam to make of a contour scene is the contour itself: every exported point lies on one
    of the given arcs (|P - c| = R to rounding, 1e-12 m), the normals are unit vectors, and the
    point table, DXF and grinding table are written."""
    from explorer.view.exports import cam_source, dxf_text, grinding_table, point_table

    scene = loads_scene(contour_text(OHC.read_text(), arcs_cam(lobe())), "arcs.toml")
    src = cam_source(scene)
    g = src.at(np.linspace(0.0, 2.0 * math.pi, 720, endpoint=False))
    off = np.min([np.abs(np.hypot(g.contour[:, 0] - a.x, g.contour[:, 1] - a.y) - a.radius) for a in scene.cam.arcs.arcs],
                 axis=0)
    assert np.max(off) < 1e-12
    assert np.allclose(np.hypot(*g.normal.T), 1.0, atol=1e-12)
    assert "POLYLINE" in dxf_text(src, 1e-6)
    assert len(point_table(src, 360).splitlines()) > 360
    assert grinding_table(src, 0.2, 720) is not None


def test_the_ohc_rocker_is_drawn_without_a_pushrod():
    from explorer.view.parts import build_parts, part_poses

    scene = load_scene(OHC)
    result = simulate(scene.with_changes(effects=("kinematics",)))
    parts, poses = build_parts(scene, result), part_poses(scene, result)
    assert set(parts) == set(poses)
    assert {"cam", "camshaft", "rocker", "roller", "valve", "spring", "seat", "cam_contact", "tip_contact"} <= set(parts)
    assert not {"pushrod", "lifter"} & set(parts)


def test_the_base_circle_dwell_of_an_analysed_contour_is_exact():
    """Over the base circle the geometry's valve lift and velocity are +-1e-17 of rounding; each
    sign change of that noise was a take-up, a seating and a velocity zero (hundreds a revolution,
    a simulate of 8 s instead of 0.4 s). The analysed lift states the dwell exactly 0, as a law
    does: one lobe, one take-up, one seating and one velocity zero (the nose) at zero lash."""
    from explorer.mechanics.forces import velocity_zeros
    from explorer.mechanics.kinematics import lash_crossings

    scene = loads_scene(contour_text(OHC.read_text(), arcs_cam(lobe())), "arcs.toml")
    lift = build_lift(scene)
    theta = np.linspace(0.0, 2.0 * math.pi, 4096, endpoint=False)
    d = lift.derivatives(theta)
    rest = d[0] < 1e-12
    assert rest.sum() > 1000 and np.all(d[:, rest] == 0.0)  # the dwell: exactly zero, every row
    ups, downs = lash_crossings(lift, 1.0, 0.0)
    assert ups.size == 1 and downs.size == 1
    zeros = velocity_zeros(lift)
    assert zeros.size == 1 and lift.derivatives(zeros)[0, 0] == pytest.approx(np.max(d[0]), rel=1e-6)
