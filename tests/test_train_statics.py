"""explorer.gears.train_statics at self-locked samples: the cam cannot drive the follower there
(the normal force is infinite, as the module says), and the friction and the camshaft torque
must be the limits of that, never NaN (0 x inf of a roller's zero friction, inf - inf of the
force's components): the pipeline refuses NaN in a force column but takes infinity."""

import numpy as np

from explorer.gears.train_statics import cam_forces


def locked(mu, sliding):
    """One sample whose contact normal is square to the follower's travel at the contact
    (drive n . V_c = 0: self-locked), a second one a normal sample (for comparison)."""
    contact = np.array([[0.0, 0.02], [0.0, 0.02]])
    normal = np.array([[1.0, 0.0], [0.0, 1.0]])
    tangent = np.column_stack([normal[:, 1], -normal[:, 0]])
    up = np.array([[0.0, 1.0], [0.0, 1.0]])
    return cam_forces(np.array([100.0, 100.0]), contact=contact, normal=normal, tangent=tangent, cam_jacobian=up,
                      cam_sliding=np.array([sliding, sliding]), cam_friction=mu, valve_axis=up, valve_jacobian=up)


def test_a_self_locked_roller_has_no_friction_and_an_infinite_torque():
    f = locked(0.0, -0.02)  # a roller: no sliding friction
    assert f.normal[0] == np.inf and f.friction[0] == 0.0
    # T = X x N n: X = (0, 0.02), n = (1, 0): -0.02 N, the limit N -> inf
    assert f.torque[0] == -np.inf
    assert f.normal[1] == 100.0 and f.friction[1] == 0.0 and f.torque[1] == 0.0


def test_a_self_locked_sliding_pad_has_infinite_friction_and_torque_not_nan():
    # n = (1, 0), t = (0, -1), sliding > 0 (sigma = +1): drive (n + 0.1 t) . (0, 1) = -0.1 <= 0: locked
    f = locked(0.1, 0.02)
    assert f.normal[0] == np.inf
    assert f.friction[0] == np.inf  # mu sigma N with sigma = +1
    assert not np.isnan(f.torque[0]) and np.isinf(f.torque[0])
    # T = N X x (n + mu t) = N (-0.02 + 0.1 * 0) -> -inf
    assert f.torque[0] == -np.inf
