"""3D parts of today's valve trains (explorer.view.modern_parts): the drawn machine moves as the
kinematics say. Checked in world coordinates, through the poses' quaternions: the cam under the
contact marker, the roller on the cam, the valve's tip on the pad, the pushrod between its balls,
the arm carrying its pad centre."""

import math

import numpy as np
import pytest
import trimesh

from explorer.view import modern_parts as M
from test_modern_arm import finger, rocker
from test_modern_flat_face import flat
from test_modern_pushrod import train

TH = np.linspace(0.0, 2.0 * math.pi, 120, endpoint=False)

CASES = {
    "bucket": (lambda: flat(cam_width=0.014, face_diameter=0.03), M.bucket_drawing, M.bucket_poses),
    "finger roller": (lambda: finger(), M.arm_drawing, M.arm_poses),
    "finger pad": (lambda: finger("pad", 0.03), M.arm_drawing, M.arm_poses),
    "rocker roller": (lambda: rocker(), M.arm_drawing, M.arm_poses),
    "pushrod roller": (lambda: train("roller"), M.pushrod_drawing, M.pushrod_poses),
    "pushrod flat": (lambda: train("flat"), M.pushrod_drawing, M.pushrod_poses),
}


def rotation(q):
    return trimesh.transformations.quaternion_matrix(q)[:3, :3]


def posed(mesh, pose, i):
    pos, q = pose
    return mesh.vertices @ rotation(q[i]).T + pos[i]


@pytest.fixture(scope="module", params=list(CASES))
def case(request):
    make, draw, poses = CASES[request.param]
    gear = make()
    return request.param, gear, draw(gear), poses(gear, TH)


def test_every_part_has_a_mesh_and_a_pose_per_step(case):
    _name, _gear, drawing, poses = case
    assert set(poses) == set(drawing.parts)
    for name, (pos, wxyz) in poses.items():
        assert pos.shape == (TH.size, 3) and wxyz.shape == (TH.size, 4), name
        assert np.allclose(np.linalg.norm(wxyz, axis=1), 1.0, atol=1e-14)
        assert drawing.parts[name].volume > 0.0, name
        assert tuple(drawing.parts[name].visual.face_colors[0][:3]) == M.MODERN_PART_COLORS[name]


def test_the_posed_cam_is_under_the_contact_marker(case):
    """The cam mesh turned by its pose passes through the kinematic contact, to the spacing of
    its 720 outline points (about 0.2 mm on these cams)."""
    _name, gear, drawing, poses = case
    cam = drawing.parts["cam"]
    for i in range(0, TH.size, 7):
        vertices = posed(cam, poses["cam"], i)[:, [0, 2]]  # the cam's outline in the gear's plane
        marker = poses["cam_contact"][0][i][[0, 2]]
        gap = np.min(np.linalg.norm(vertices - marker, axis=1))
        assert gap < 0.6e-3, (i, gap)


def test_the_roller_touches_the_cam(case):
    name, gear, drawing, poses = case
    if "roller" not in poses:
        pytest.skip("no roller")
    radius = gear.arm.cam_side.radius if hasattr(gear, "arm") else gear.lifter.radius
    cam = drawing.parts["cam"]
    for i in range(0, TH.size, 7):
        centre = poses["roller"][0][i][[0, 2]]
        d = np.linalg.norm(posed(cam, poses["cam"], i)[:, [0, 2]] - centre, axis=1)
        assert abs(d.min() - radius) < 0.2e-3, (i, d.min())


def test_the_valve_tip_stays_on_the_pad(case):
    name, gear, drawing, poses = case
    if "tip_contact" not in poses:
        pytest.skip("the bucket sits on the valve")
    u = gear.valve.axis
    u_world = np.array([u[0], 0.0, u[1]])
    valve = drawing.parts["valve"]
    for i in range(0, TH.size, 5):
        tip = np.min(posed(valve, poses["valve"], i) @ u_world)  # the stem's end face, towards the pad
        assert tip == pytest.approx(poses["tip_contact"][0][i] @ u_world, abs=1e-12)


def test_arm_and_pushrod_carry_their_points(case):
    name, gear, drawing, poses = case
    if name.startswith("pushrod"):
        k = gear.kinematics(TH)
        pos, q = poses["pushrod"]
        for i in range(0, TH.size, 9):
            top = rotation(q[i]) @ np.array([0.0, 0.0, gear.pushrod_length]) + pos[i]
            assert np.allclose(top[[0, 2]], k.upper_ball[i], atol=1e-12)
    if hasattr(gear, "arm"):
        k = gear.kinematics(TH)
        part = gear.kind  # "finger" or "rocker"
        pos, q = poses[part]
        d = gear.valve.drive
        local = np.array([d.arm * math.cos(d.angle), 0.0, d.arm * math.sin(d.angle)])
        cx, cy = gear.valve.centre(k.arm_angle[0])
        for i in range(0, TH.size, 9):
            world = rotation(q[i]) @ local + pos[i]
            assert np.allclose(world[[0, 2]], [cx[i], cy[i]], atol=1e-12)


def test_the_bucket_is_drawn_cam_on_top_and_follows_the_lift():
    gear = flat(cam_width=0.014, face_diameter=0.03)
    poses = M.bucket_poses(gear, TH, lash=0.0003)
    k = gear.kinematics(TH)
    z = poses["tappet"][0][:, 2]
    assert np.allclose(z, -(gear.tappet.base_radius + k.lift[0]), atol=1e-15)  # below the camshaft
    drop = -poses["valve"][0][:, 2]
    assert np.allclose(drop, np.maximum(k.lift[0] - 0.0003, 0.0) + 0.0003, atol=1e-15)
