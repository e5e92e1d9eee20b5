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


# --- exactly zero sliding (the scrub's reversal) ---------------------------------------------------------
# Coulomb friction at zero sliding is set-valued (any |F_t| <= mu N). The statics take sgn(0) = 0: the
# frictionless balance, finite, which lies between the balances just before and just after the
# reversal. No division by the sliding velocity anywhere, so no NaN and no warning.


def _finger_nose():
    """The finger-follower scene's kinematics at its nose (105 deg: the 3-4-5 valve lift is at rest
    there, so the valve pad's sliding on the tip reverses) and the gear."""
    from explorer import load_scene
    from explorer.effects.lift import build_lift

    train = build_lift(load_scene("assets/scenes/finger_follower.toml")).gear
    k = train.kinematics(np.radians([104.9, 105.0, 105.1]))
    return train, k


def _forces(train, k, tip_sliding, mu_t=0.1, force=500.0):
    n = len(k.theta)
    return cam_forces(np.full(n, force), contact=k.surface.contact, normal=k.surface.normal,
                      tangent=k.surface.tangent, cam_jacobian=k.cam_jacobian, cam_sliding=k.cam_velocities.sliding,
                      cam_friction=0.0, valve_axis=np.tile(train.valve.axis, (n, 1)),
                      valve_jacobian=k.tip.arm_jacobian, tip_tangent=k.tip.tangent, tip_sliding=tip_sliding,
                      tip_friction=mu_t)


def test_finger_tip_friction_at_exactly_zero_sliding_is_the_frictionless_balance():
    import warnings

    train, k = _finger_nose()
    v = k.tip.velocities.sliding
    assert v[0] > 0.0 > v[2] and abs(v[1]) < 1e-20  # the reversal, at the nose (round-off there)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no 0/0, no division by the sliding velocity
        zero = _forces(train, k, np.zeros(3))
        plus, minus = _forces(train, k, np.full(3, 1e-9)), _forces(train, k, np.full(3, -1e-9))
        bare = _forces(train, k, np.zeros(3), mu_t=0.0)
    for f in (zero, plus, minus):
        assert np.all(np.isfinite(f.normal)) and np.all(np.isfinite(f.torque)) and np.all(np.isfinite(f.tip_friction))
    assert np.all(zero.tip_friction == 0.0) and np.array_equal(zero.normal, bare.normal)
    # N is linear in the tip's friction: at zero sliding the mean of the two sides' balances
    np.testing.assert_allclose(zero.normal, 0.5 * (plus.normal + minus.normal), rtol=1e-12)
    assert np.all(np.minimum(plus.normal, minus.normal) < zero.normal)
    assert np.all(zero.normal < np.maximum(plus.normal, minus.normal))
    # the two sides' friction column: mu F with the sliding's sign
    assert np.all(plus.tip_friction == 50.0) and np.all(minus.tip_friction == -50.0)


def test_sliding_pad_at_exactly_zero_sliding_is_finite_and_between_both_sides():
    """A pad on the cam (mu 0.1) at zero sliding: N = F (u . V_t) / (n . V_c), no friction; the two
    sides' N = F (u . V_t) / ((n -+ mu t) . V_c) bracket it."""
    contact = np.array([[0.0, 0.02]])
    normal = np.array([[np.sin(0.3), np.cos(0.3)]])
    tangent = np.column_stack([normal[:, 1], -normal[:, 0]])
    up = np.array([[0.0, 1.0]])

    def at(v):
        return cam_forces(np.array([100.0]), contact=contact, normal=normal, tangent=tangent, cam_jacobian=up,
                          cam_sliding=np.array([v]), cam_friction=0.1, valve_axis=up, valve_jacobian=up)

    zero, plus, minus = at(0.0), at(1e-9), at(-1e-9)
    assert zero.normal[0] == 100.0 / np.cos(0.3) and zero.friction[0] == 0.0 and np.isfinite(zero.torque[0])
    assert min(plus.normal[0], minus.normal[0]) < zero.normal[0] < max(plus.normal[0], minus.normal[0])


def test_finger_scene_at_the_scrub_reversal_stays_in_the_friction_cone():
    """simulate: at the sample of the reversal (105 deg) the tip's sliding is round-off (~1e-31 m/s)
    and its sign picks one side's friction -- an admissible Coulomb force at zero sliding (|F_t| <=
    mu N); every force column finite."""
    from explorer import load_scene, simulate

    c = simulate(load_scene("assets/scenes/finger_follower.toml")).columns
    i = int(np.argmin(np.abs(np.asarray(c["cam_angle_deg"]) - 105.0)))
    assert abs(c["tip_sliding_velocity_m_s"][i]) < 1e-20
    assert abs(c["tip_friction_force_N"][i]) <= 0.1 * c["tip_normal_force_N"][i] * (1 + 1e-12)
    for key in ("cam_normal_force_N", "tip_friction_force_N", "tip_normal_force_N", "contact_force_N"):
        assert np.all(np.isfinite(np.asarray(c[key], dtype=float))), key
