"""The masses of an elastic train in the 3D drawing and the recordings (issue #25, item 3:
explorer.view.train_motion and the views' items 7-8).

The oracle is the result's own columns: a part's displayed travel is the cam's drive plus the
magnification times (the part's column referred to the valve - the drive). The tests read the
drawn positions back from the poses (differences between two magnifications, so no drawing
dimension enters but the lever's arm) and compare with the columns at chosen steps: the highest
lift, the largest deviation of the part, a step on the base circle."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT
from explorer.effects.lift import build_lift
from explorer.effects.pipeline import simulate
from explorer.scene.builtin import builtin_scenes
from explorer.scene.scene import load_scene
from explorer.view import parts as meshes
from explorer.view.gear_views import view_of
from explorer.view.train_motion import TRAIN_MAGNIFICATION, carriers, default_magnification, train_shape

SCENES = ROOT / "assets" / "scenes"
M = 20.0


@pytest.fixture(scope="module")
def pushrod_train():
    scene = load_scene(SCENES / "pushrod_train.toml", ["solver.steps_per_revolution=720"])
    return scene, simulate(scene)


@pytest.fixture(scope="module")
def finger_hla():
    scene = load_scene(SCENES / "finger_hla_pumpup.toml", ["solver.steps_per_revolution=720", "hla.revolutions=3"])
    return scene, simulate(scene)


def _steps(result, column: str, drive) -> list[int]:
    """Highest lift, largest deviation of `column` from the drive, and the base circle."""
    c = result.columns
    dev = np.abs(np.asarray(c[column]) - drive)
    return [int(np.argmax(c["valve_lift_m"])), int(np.argmax(dev)), int(np.argmin(c["follower_lift_m"]))]


def _lever_rise(quat, arm: float) -> np.ndarray:
    """Height of the lever's follower end above the pivot, from its rotation about y."""
    phi = 2.0 * np.arctan2(quat[:, 2], quat[:, 0])
    return arm * np.sin(phi)


def test_carriers_lay_the_ends_on_the_ends_and_fill_from_the_cam_side():
    assert carriers(3, 3) == (0, 1, 2)
    assert carriers(1, 3) == (0, 0, 0)  # a finger alone: every station moves with it
    assert carriers(2, 3) == (0, 0, 1)  # no pushrod mass: the rod moves with the lifter
    assert carriers(5, 3) == (0, 1, 4)  # the valve side's lever always shows the last part
    assert carriers(0, 3) == () and carriers(2, 0) == ()


def test_each_mass_of_the_pushrod_train_is_posed_from_its_own_column(pushrod_train):
    scene, result = pushrod_train
    c = result.columns
    ratio = scene.follower.ratio
    L = np.asarray(c["follower_lift_m"])
    lay = meshes.layout(scene, result)
    rigid = meshes.part_poses(scene, result, magnification=0.0, lay=lay)  # m = 0: the rigid drive
    shown = meshes.part_poses(scene, result, magnification=M, lay=lay)
    assert {"pushrod", "lever", "follower", "roller", "adjuster"} <= set(shown)
    for part, names in (("lifter", ("follower", "roller")), ("pushrod", ("pushrod",))):
        x = np.asarray(c[f"part_{part}_displacement_m"])  # its own travel; its ratio is the follower's (1.5)
        for i in _steps(result, f"part_{part}_displacement_m", L):
            for name in names:
                dz = shown[name][0][i, 2] - rigid[name][0][i, 2]
                assert dz == pytest.approx(M * (x[i] - L[i]), abs=1e-12), (part, name, i)
    x = np.asarray(c["part_rocker_displacement_m"])
    rise, rise0 = _lever_rise(shown["lever"][1], lay.arm_follower), _lever_rise(rigid["lever"][1], lay.arm_follower)
    for i in _steps(result, "part_rocker_displacement_m", L):
        assert rise[i] == pytest.approx(L[i] + M * (x[i] - L[i]), abs=1e-12)
        assert rise0[i] == pytest.approx(L[i], abs=1e-12)
    # the parts really move apart: the lifter's computed deviation reaches tens of micrometres
    assert np.ptp(shown["follower"][0][:, 2] - rigid["follower"][0][:, 2]) > 1e-3
    # the valve: its own column, magnified alike
    s, s_rigid = np.asarray(c["valve_lift_m"]), np.asarray(c["rigid_valve_lift_m"])
    i = int(np.argmax(np.abs(s - s_rigid)))
    assert lay.stem_top_rest - shown["valve"][0][i, 2] == pytest.approx(max(s_rigid[i] + M * (s[i] - s_rigid[i]), 0.0),
                                                                         abs=1e-12)
    # the screw on the lever shows the pad's true gap to the stem, magnified: it touches the
    # stem (ball bottom = stem top) wherever the pad's joint carries load
    closed = np.asarray(c["contact_valve_closed"]) > 0.5 if "contact_valve_closed" in c else None
    if closed is not None and closed.any():
        gap = (scene.valve.lash + s - ratio * x)[closed]
        ball = shown["adjuster"][0][closed, 2] - lay.ball_radius
        np.testing.assert_allclose(ball - shown["valve"][0][closed, 2], M * gap, atol=1e-12)


def test_the_finger_and_the_plunger_of_the_lash_adjuster(finger_hla):
    scene, result = finger_hla
    c = result.columns
    L = np.asarray(c["follower_lift_m"])
    p = np.asarray(c["hla_plunger_travel_m"])
    x = np.asarray(c["part_finger_displacement_m"])
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    assert {"hla_body", "hla_plunger", "lever_pivot"} <= set(parts)
    rigid = meshes.part_poses(scene, result, magnification=0.0, lay=lay)
    shown = meshes.part_poses(scene, result, magnification=M, lay=lay)
    assert set(shown) == set(parts)
    for i in _steps(result, "hla_plunger_travel_m", 0.0) + [int(np.argmin(p))]:
        # plunger travel is into its body, which hangs over the pivot: up
        assert shown["hla_plunger"][0][i, 2] - rigid["hla_plunger"][0][i, 2] == pytest.approx(M * p[i], abs=1e-12)
        # one mass (the finger): roller, follower and rod move with it
        for name in ("roller", "follower", "pushrod"):
            assert shown[name][0][i, 2] - rigid[name][0][i, 2] == pytest.approx(M * (x[i] - L[i]), abs=1e-12)
    # the lever turns about its fixed pivot by the finger's own travel (which holds the
    # adjuster's part of the valve's lift): its follower end on the rod's top
    rise = _lever_rise(shown["lever"][1], lay.arm_follower)
    np.testing.assert_array_equal(shown["lever"][0], rigid["lever"][0])
    np.testing.assert_allclose(rise, L + M * (x - L), atol=1e-12)
    # the pump-up is visible: the plunger comes out of its body by tens of times its travel, at
    # x20 down to the pivot's shaft at its largest extension, never through it
    gap = shown["hla_plunger"][0][:, 2] - lay.pivot[2] - 0.7 * lay.lever_half_thickness
    assert np.ptp(gap) > 1e-3 and gap.min() == pytest.approx(0.3 * lay.lever_half_thickness, abs=1e-12)
    np.testing.assert_array_equal(np.ptp(shown["hla_body"][0], axis=0), 0.0)


@pytest.mark.parametrize("path", [p for p in builtin_scenes() if not any(train_shape(load_scene(p)))],
                         ids=lambda p: p.stem)
def test_a_scene_without_a_train_is_drawn_as_before(path):
    """No train: the magnification opens at 1, the parts and their poses are the view's own
    (item 3, bit for bit at any magnification), no pushrod or adjuster part appears."""
    scene = load_scene(path, ["solver.steps_per_revolution=360"])
    result = simulate(scene)
    assert default_magnification(scene) == 1.0
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    if scene.follower.type == "translating-roller":
        assert not {"pushrod", "hla_body", "hla_plunger"} & set(parts)
    for m in (1.0, 7.0):
        poses = meshes.part_poses(scene, result, magnification=m, lay=lay)
        own = view_of(scene).poses(scene, result, magnification=m, lay=lay)
        assert set(poses) == set(own)
        for name in own:
            np.testing.assert_array_equal(poses[name][0], own[name][0])
            np.testing.assert_array_equal(poses[name][1], own[name][1])


def test_a_train_scene_without_its_elastic_result_keeps_the_rigid_drawing():
    scene = load_scene(SCENES / "pushrod_train.toml", ["effects=[\"kinematics\"]", "solver.steps_per_revolution=360"])
    result = simulate(scene)
    assert "part_lifter_displacement_m" not in result.columns
    poses = meshes.part_poses(scene, result, magnification=M)
    np.testing.assert_array_equal(poses["pushrod"][0], poses["follower"][0])  # one rigid body again


def test_a_train_opens_magnified_and_the_recording_logs_each_mass(tmp_path, pushrod_train, finger_hla):
    from explorer.view.rerun.read import read_rrd
    from explorer.view.rerun.recording import with_parts, write_recordings

    for scene, _ in (pushrod_train, finger_hla):
        assert default_magnification(scene) == TRAIN_MAGNIFICATION
    runs = [with_parts("train", pushrod_train[1]), with_parts("hla", finger_hla[1])]
    assert [r.magnification for r in runs] == [TRAIN_MAGNIFICATION] * 2
    out = tmp_path / "train.rrd"
    write_recordings(out, runs)
    recorded = {r.name: r for r in read_rrd(out)}
    for run, moving in zip(runs, (("follower", "pushrod", "lever"), ("lever", "hla_plunger", "roller"))):
        rec = recorded[run.label]
        for name in moving:
            rows = rec.temporal[f"/parts/{name}"]
            positions = np.asarray(run.poses[name][0], dtype=float)
            assert len(rows["Transform3D:translation"]) == len(positions)
            # float32 in the file
            assert np.max(np.abs(rows["Transform3D:translation"] - positions)) <= 1e-6 * max(1.0, np.abs(positions).max())
            moved = np.ptp(rows["Transform3D:translation"], axis=0).max() + np.ptp(rows["Transform3D:quaternion"], axis=0).max()
            assert moved > 0.0, name
        assert "×20" in rec.static["/summary"]["TextDocument:text"][0]
    # the plunger's logged height, back to the column: m times the travel (float32: 1e-6 m)
    scene, result = finger_hla
    lay = meshes.layout(scene, result)
    z = recorded["hla"].temporal["/parts/hla_plunger"]["Transform3D:translation"][:, 2]
    rest = recorded["hla"].static["/parts/hla_body"]["Transform3D:translation"][0][2]  # the body stays
    np.testing.assert_allclose(z - rest, TRAIN_MAGNIFICATION * np.asarray(result.columns["hla_plunger_travel_m"]),
                               atol=2e-6)


TRAIN_TOML = '''
[linkage]
stiffness = "150 N/um"
damping = "50 N*s/m"
contact = "one-sided"
{elements}
[seat]
stiffness = "200 N/um"
damping = "400 N*s/m"
'''
ELEMENT = '''
[[linkage.elements]]
name = "{name}"
mass = "{mass}"
stiffness = "{stiffness}"
damping = "80 N*s/m"
{contact}
'''
HLA_TOML = '''
[hla]
plunger_mass = "12 g"
plunger_diameter = "12 mm"
clearance = "6 um"
leak_length = "8 mm"
viscosity = "10 mPa*s"
chamber_volume = "200 mm**3"
supply_pressure = "3 bar"
spring_rate = "5 N/mm"
spring_preload = "15 N"
lever = 0.7
revolutions = 2
'''


def _gear_train_scene(tmp_path, stem: str, elements, hla: bool = False):
    """A built-in modern-gear scene with its [linkage] replaced by a train of `elements`
    (name, mass, stiffness, contact) and optionally an adjuster."""
    import re

    text = (SCENES / f"{stem}.toml").read_text()
    text = re.sub(r"\n\[linkage\]\n(?:[^\[\n][^\n]*\n|\n)*", "\n", text)
    text = re.sub(r"^effects = .*$", 'effects = ["kinematics", "lash", "forces", "elastic"]', text, flags=re.M)
    body = "".join(ELEMENT.format(name=n, mass=m, stiffness=k, contact=f'contact = "{c}"' if c else "")
                   for n, m, k, c in elements)
    path = tmp_path / f"{stem}_train.toml"
    path.write_text(text + TRAIN_TOML.format(elements=body) + (HLA_TOML if hla else ""))
    return load_scene(path, ["solver.steps_per_revolution=720"])


def _d_dS(coordinate, S, i):
    """The rigid coordinate's derivative by the drive at step i, by central differences of the
    gear's own kinematics over the revolution (an oracle independent of the view's fit)."""
    return float((coordinate[i + 1] - coordinate[i - 1]) / (S[i + 1] - S[i - 1]))


def test_a_finger_on_an_adjuster_turns_by_its_own_motion_and_rides_on_the_plunger(tmp_path):
    scene = _gear_train_scene(tmp_path, "finger_follower", [("finger", "25 g", "100 N/um", "")], hla=True)
    result = simulate(scene)
    c = result.columns
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    assert {"hla_plunger", "lash_adjuster", "finger", "roller"} <= set(parts)
    rigid = meshes.part_poses(scene, result, magnification=0.0, lay=lay)
    shown = meshes.part_poses(scene, result, magnification=M, lay=lay)
    S = np.asarray(c["follower_lift_m"]) * scene.follower.ratio
    x = np.asarray(c["part_finger_displacement_m"])
    p = np.asarray(c["hla_plunger_travel_m"])
    psi = -2.0 * np.arctan2(rigid["finger"][1][:, 2], rigid["finger"][1][:, 0])
    shown_psi = -2.0 * np.arctan2(shown["finger"][1][:, 2], shown["finger"][1][:, 0])
    axis = np.array([0.0, 0.0, -1.0])  # the scene's valve axis, -90 deg: the plunger's travel into its body is down
    for i in (int(np.argmax(S)) - 40, int(np.argmax(S)) + 40):  # on the flanks, where the ratio is defined
        # the pivot's shift (M p along the valve's axis) moves the pad by M p; the turn does the rest
        expected = M * (x[i] - S[i] - p[i]) * _d_dS(psi, S, i)
        assert shown_psi[i] - psi[i] == pytest.approx(expected, rel=0.05, abs=1e-9)
        np.testing.assert_allclose(shown["hla_plunger"][0][i] - rigid["hla_plunger"][0][i], M * p[i] * axis, atol=1e-12)
        np.testing.assert_allclose(shown["finger"][0][i] - rigid["finger"][0][i], M * p[i] * axis, atol=1e-12)
    np.testing.assert_array_equal(np.ptp(shown["lash_adjuster"][0], axis=0), 0.0)  # the body stays


def test_the_pushrod_rocker_gear_moves_lifter_pushrod_and_rocker_each_by_its_own(tmp_path):
    scene = _gear_train_scene(tmp_path, "pushrod_rocker", [("lifter", "60 g", "160 N/um", ""),
                                                          ("pushrod", "40 g", "300 N/um", "bonded"),
                                                          ("rocker", "50 g", "45 N/um", "")])
    result = simulate(scene)
    c = result.columns
    lay = meshes.layout(scene, result)
    rigid = meshes.part_poses(scene, result, magnification=0.0, lay=lay)
    shown = meshes.part_poses(scene, result, magnification=M, lay=lay)
    S = np.asarray(c["follower_lift_m"]) * scene.follower.ratio
    theta = np.radians(np.asarray(c["cam_angle_deg"]))
    k = build_lift(scene).gear.kinematics(theta)
    lifter, rocker = np.asarray(k.lifter_lift[0]), np.asarray(k.rocker_angle[0])
    rise = shown["lifter"][0][:, 2] - rigid["lifter"][0][:, 2]
    rod = shown["pushrod"][0][:, 2] - rigid["pushrod"][0][:, 2]
    turn = 2.0 * (np.arctan2(rigid["rocker"][1][:, 2], rigid["rocker"][1][:, 0])
                  - np.arctan2(shown["rocker"][1][:, 2], shown["rocker"][1][:, 0]))
    for i in (int(np.argmax(S)) - 40, int(np.argmax(S)) + 40):
        for part, moved, coordinate in (("lifter", rise, lifter), ("pushrod", rod, lifter), ("rocker", turn, rocker)):
            x = np.asarray(c[f"part_{part}_displacement_m"])[i]
            assert moved[i] == pytest.approx(M * (x - S[i]) * _d_dS(coordinate, S, i), rel=0.05, abs=1e-9), part




@pytest.mark.parametrize("x", [1.0, 50.0])
def test_explorer_record_draws_each_mass_at_the_magnification_asked_for(tmp_path, pushrod_train, x):
    """`explorer record --magnification X`: the recorded lifter, pushrod and valve sit at their rigid
    poses plus X times their computed deviations from them (the result's columns), and the
    summary says X. The rigid pose is the drawing at X = 0; the file stores float32 (1e-6 m)."""
    from explorer.cli import main
    from explorer.view.rerun.read import read_rrd

    scene, result = pushrod_train
    out = tmp_path / "train.rrd"
    assert main(["record", str(SCENES / "pushrod_train.toml"), "--set", "solver.steps_per_revolution=720",
                 "--magnification", f"{x:g}", "-o", str(out)]) == 0
    (rec,) = read_rrd(out)
    c = result.columns
    L = np.asarray(c["follower_lift_m"])
    rigid = meshes.part_poses(scene, result, magnification=0.0)
    for part, names in (("lifter", ("follower", "roller")), ("pushrod", ("pushrod",))):
        deviation = np.asarray(c[f"part_{part}_displacement_m"]) - L  # its ratio is the follower's
        for name in names:
            z = rec.temporal[f"/parts/{name}"]["Transform3D:translation"][:, 2]
            np.testing.assert_allclose(z, rigid[name][0][:, 2] + x * deviation, rtol=0, atol=1e-6, err_msg=name)
            if x == 50.0:  # the deviation drawn: tens of micrometres times 50, well above float32's 1e-6
                assert np.ptp(z - rigid[name][0][:, 2]) > 1e-3, name
    s, s_rigid = np.asarray(c["valve_lift_m"]), np.asarray(c["rigid_valve_lift_m"])
    stem = rec.temporal["/parts/valve"]["Transform3D:translation"][:, 2]
    drawn = rigid["valve"][0][:, 2] - stem  # how far the stem is drawn below its rigid pose
    np.testing.assert_allclose(drawn, np.maximum(s_rigid + x * (s - s_rigid), 0.0) - s_rigid, rtol=0, atol=1e-6)
    assert f"×{x:g}" in rec.static["/summary"]["TextDocument:text"][0]


def test_explorer_record_help_teaches_the_magnification(capsys):
    from explorer.cli import main

    with pytest.raises(SystemExit) as stop:
        main(["record", "--help"])
    assert stop.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "--magnification X" in text and "rigid pose plus X times its computed deviation" in text
    assert "x20 for a train" in text and "--magnification 50 -o train.rrd" in text
