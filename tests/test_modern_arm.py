"""Finger follower and OHC rocker (explorer.gears.arm, explorer.gears.valve_end): issue #24's oracles.

- An independent vector-loop solution written here: the working surface's closure on the cam,
  O1 + a e(psi) = Rot(theta) (c + (R + r) e(phi)) for a roller or curved pad on an arc cam (and
  the flat pad's n(psi + gamma) = Rot(theta) e(phi), n . (X - O1) = d), solved by Newton on the
  loop equations at many cam angles; the valve travel u . (C_v(psi) - C_v(psi0)) and the lever
  ratio from the test's own arm; velocity by implicit differentiation of the loop. To 1e-10.
- The same loop on the cam the module synthesised (its exact contour), against the lift law.
- Virtual work: T w = F v (frictionless) and the cam's normal force N = F v / v_n, to 1e-9; with
  friction, T w = F v + the heat of the sliding contacts.
- Limits: pad radius -> infinity is the flat pad (like 1/Rp); a finger whose pivot, roller and pad
  lie on one line square to the valve is a lever of ratio a_v/a at small lift.
- Synthesis -> analysis round trip to 1e-12 m; bad geometry is one line naming the key.
"""

import math

import numpy as np
import pytest

from explorer.core.errors import InputError
from explorer.gears.arm import CamSide, make_arm, make_arm_gear
from explorer.lift.contours.arcs import Arc, build_arc_contour
from explorer.lift.curves import LawLift
from explorer.mechanics.contact import effective_modulus

TH = np.linspace(0.0, 2.0 * math.pi, 720, endpoint=False)
RB = 0.018
LIFT = LawLift(height=0.0093, start=math.radians(30), rise=math.radians(75), dwell=0.0, ret=math.radians(75),
               rise_law="polynomial-345", return_law="polynomial-345")
# a flat pad needs a gentler lift (rho = h + h_beta_beta > 0) than a roller
GENTLE = LawLift(height=0.0093, start=math.radians(30), rise=math.radians(105), dwell=0.0, ret=math.radians(105),
                 rise_law="polynomial-345", return_law="polynomial-345")
E_STAR = effective_modulus(210e9, 0.3, 210e9, 0.3)

# end-pivot finger under the cam: lash adjuster ball at O1, roller between, pad over the valve
FINGER = dict(pivot=(-0.032, -0.036), branch=-1, valve_axis=-0.5 * math.pi, tip_radius=0.0035)
# centre-pivot OHC rocker over the cam: roller on its left arm, valve under its right arm
ROCKER = dict(pivot=(0.035, 0.030), branch=-1, valve_axis=-0.5 * math.pi, tip_radius=0.004)


def finger(side="roller", radius=0.009, law=LIFT, contour=None, check=True, **kw):
    if side == "roller":
        cam_side = CamSide("roller", math.hypot(0.032, 0.009), radius, width=0.010)
        ref = math.atan2(0.009, 0.032)
    else:
        cam_side = CamSide("pad", math.hypot(0.032, 0.016), radius, face_angle=-0.5 * math.pi, width=0.010)
        ref = math.atan2(0.020, 0.032)
    args = dict(FINGER, base_radius=RB, cam_side=cam_side, valve_arm=math.hypot(0.056, 0.010),
                valve_angle=math.atan2(0.010, 0.056) - ref, valve_pad_radius=0.012, law=law, contour=contour,
                check=check)
    args.update(kw)
    return make_arm_gear(**args)


def rocker(side="roller", radius=0.008, law=LIFT, contour=None, **kw):
    if side == "roller":
        cam_side = CamSide("roller", math.hypot(0.035, 0.004), radius, width=0.010)
    else:
        cam_side = CamSide("pad", math.hypot(0.035, 0.012), radius, face_angle=math.radians(-110.0), width=0.010)
    rest = make_arm(base_radius=RB, pivot=ROCKER["pivot"], cam_side=cam_side, branch=ROCKER["branch"]).rest
    # the valve pad straight out to the right of the pivot
    args = dict(ROCKER, base_radius=RB, cam_side=cam_side, valve_arm=0.055, valve_angle=-rest,
                valve_pad_radius=0.012, law=law, contour=contour, kind="rocker")
    args.update(kw)
    return make_arm_gear(**args)


GEARS = {
    "finger roller": lambda **kw: finger("roller", **kw),
    "finger curved pad": lambda **kw: finger("pad", 0.030, **kw),
    "finger flat pad": lambda **kw: finger("pad", math.inf, **{"law": GENTLE, **kw}),
    "rocker roller": lambda **kw: rocker("roller", **kw),
    "rocker curved pad": lambda **kw: rocker("pad", 0.040, **kw),
}


# --------------------------------------------------------------------------------------------
# the test's own vector loop
# --------------------------------------------------------------------------------------------


def rot(theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def e(angle):
    return np.array([math.cos(angle), math.sin(angle)])


def jmat(v):
    return np.array([-v[1], v[0]])


class LoopArm:
    """The arm as this test sees it: pivot, the circle's centre (or the flat face) and the valve
    pad's centre in the arm's frame (x along the reference direction), valve axis u."""

    def __init__(self, gear):
        arm, side, valve = gear.arm, gear.arm.cam_side, gear.valve
        self.o1 = np.array(arm.pivot)
        self.side = side
        if side.kind == "roller":
            self.centre_local = np.array([side.arm, 0.0])
        elif math.isfinite(side.radius):
            self.centre_local = np.array([side.arm, 0.0]) + side.radius * e(side.face_angle)
        self.pad_local = valve.drive.arm * e(valve.drive.angle)
        self.u = e(valve.drive.axis)
        self.rest = arm.rest

    def pad_centre(self, psi):
        return self.o1 + rot(psi) @ self.pad_local

    def travel(self, psi):
        return self.u @ (self.pad_centre(psi) - self.pad_centre(self.rest))

    def valve_per_arm(self, psi):
        return self.u @ jmat(self.pad_centre(psi) - self.o1)


def loop_on_arcs(arm: LoopArm, contour, theta_grid, psi_start):
    """(psi, dpsi/dtheta) per cam angle by Newton on the loop, continuing from the last solution,
    trying every arc and keeping, of the solutions whose contact lies on the arc's span, the one
    nearest the arm's last angle (the loop also closes with the arm on the circles' other
    intersection)."""
    out_psi, out_rate = [], []
    psi = psi_start
    for th in theta_grid:
        candidates = []
        for k, arc in enumerate(contour.arcs):
            c = np.array([arc.x, arc.y])
            if arm.side.kind == "pad" and not math.isfinite(arm.side.radius):
                sol = _flat_loop(arm, c, arc.radius, th, psi)
            else:
                sol = _circle_loop(arm, c, arc.radius, th, psi)
            if sol is None:
                continue
            q, phi, rate = sol
            offset = np.mod((phi - contour.start_angle[k]) * np.sign(contour.sweep[k]), 2.0 * math.pi)
            if offset <= abs(contour.sweep[k]) + 1e-12 or offset >= 2.0 * math.pi - 1e-12:
                candidates.append((q, rate))
        assert candidates, f"no arc solves the loop at {math.degrees(th):.2f} deg"
        # the loop also closes on the circles' other intersection: keep the arm where it was
        best = min(candidates, key=lambda c: abs(math.remainder(c[0] - psi, 2.0 * math.pi)))
        psi = best[0]
        out_psi.append(best[0])
        out_rate.append(best[1])
    return np.array(out_psi), np.array(out_rate)


def _circle_loop(arm, c, radius, th, psi):
    """F(psi, phi) = O1 + Rot(psi) C_local - Rot(th) (c + (R + r) e(phi)) = 0."""
    reach = radius + arm.side.radius
    r_th = rot(th)
    phi = math.atan2(*(r_th.T @ (arm.o1 + rot(psi) @ arm.centre_local) - c)[::-1])
    for _ in range(60):
        centre = rot(psi) @ arm.centre_local
        f = arm.o1 + centre - r_th @ (c + reach * e(phi))
        jac = np.column_stack([jmat(centre), -r_th @ (reach * jmat(e(phi)))])
        step = np.linalg.solve(jac, f)
        psi, phi = psi - step[0], phi - step[1]
        if np.max(np.abs(step)) < 1e-13:  # quadratic convergence: the error is now ~1e-26, below rounding
            break
    if np.max(np.abs(arm.o1 + rot(psi) @ arm.centre_local - r_th @ (c + reach * e(phi)))) > 1e-14:
        return None
    # implicit differentiation: J [dpsi, dphi] = -dF/dth, dF/dth = -J Rot(th) (c + reach e(phi))
    centre = rot(psi) @ arm.centre_local
    jac = np.column_stack([jmat(centre), -r_th @ (reach * jmat(e(phi)))])
    rate = np.linalg.solve(jac, jmat(r_th @ (c + reach * e(phi))))
    return psi, phi, rate[0]


def _flat_loop(arm, c, radius, th, psi):
    """Flat face: its normal n(psi + gamma) is the arc's normal e(phi) turned by th, phi = psi +
    gamma - th; f(psi) = n . (Rot(th) c + R n - O1) - d = 0 (1-D Newton)."""
    gamma, d = arm.side.face_angle, arm.side.arm * math.cos(arm.side.face_angle)
    r_th_c = rot(th) @ c
    for _ in range(60):
        n = e(psi + gamma)
        f = n @ (r_th_c - arm.o1) + radius - d
        df = jmat(n) @ (r_th_c - arm.o1)
        step = f / df
        psi -= step
        if abs(step) < 1e-13:
            break
    n = e(psi + gamma)
    if abs(n @ (r_th_c - arm.o1) + radius - d) > 1e-15:
        return None
    # d/dth: jmat(n).(r_th_c - O1) dpsi + n . J r_th_c = 0
    rate = -(n @ jmat(r_th_c)) / (jmat(n) @ (r_th_c - arm.o1))
    return psi, psi + gamma - th, rate


def arc_cam(rb=RB, nose=0.007, lift=0.0055, flank=0.06):
    d = rb + lift - nose
    r1, r2 = flank - rb, flank - nose
    y = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
    x = math.sqrt(r1 * r1 - y * y)
    return build_arc_contour([Arc(0.0, 0.0, rb), Arc(-x, y, flank), Arc(0.0, d, nose), Arc(x, y, flank)], tolerance=1e-12)


@pytest.mark.parametrize("name", list(GEARS))
def test_analysis_over_an_arc_cam_matches_the_vector_loop(name):
    contour = arc_cam()
    gear = GEARS[name](law=None, contour=contour, check=False)
    arm = LoopArm(gear)
    probe = TH[::2]
    k = gear.kinematics(probe)
    psi, rate = loop_on_arcs(arm, contour, probe, gear.arm.rest)
    psi = psi + 2.0 * math.pi * np.round((k.arm_angle[0] - psi) / (2.0 * math.pi))
    assert np.max(np.abs(k.arm_angle[0] - psi)) < 1e-12
    travel = np.array([arm.travel(p) for p in psi])
    scale = np.abs(travel).max()
    assert scale > 1e-3  # the valve really opens
    assert np.max(np.abs(k.lift[0] - travel)) < 1e-10 * scale
    ratio = np.array([abs(arm.valve_per_arm(p)) for p in psi]) / gear.arm.cam_side.arm
    assert np.max(np.abs(k.ratio - ratio)) < 1e-10 * ratio.max()
    velocity = np.array([arm.valve_per_arm(p) for p in psi]) * rate
    assert np.max(np.abs(k.lift[1] - velocity)) < 1e-10 * np.abs(velocity).max()


def loop_on_contour(arm: LoopArm, contour, theta_grid, t_start, psi_start):
    """Newton on the loop over a parametric contour X(t) (cam frame) with its normal from X'(t):
    unknowns psi and t; a finite-difference Jacobian (only the rate of convergence depends on it)."""
    sign = -1.0  # the synthesised contour runs clockwise in the cam frame

    def residual(psi, t, th):
        j = contour.jets(np.array([t]), 2)[:, :, 0]
        x, dx = j[0], j[1]
        n = sign * np.array([dx[1], -dx[0]]) / np.hypot(*dx)
        if arm.side.kind == "pad" and not math.isfinite(arm.side.radius):
            face = e(psi + arm.side.face_angle)
            return np.array([face @ (rot(th) @ x - arm.o1) - arm.side.arm * math.cos(arm.side.face_angle),
                             face @ jmat(rot(th) @ n)])
        return arm.o1 + rot(psi) @ arm.centre_local - rot(th) @ (x + arm.side.radius * n)

    out = []
    psi, t = psi_start, t_start
    for th in theta_grid:
        t = th  # the contour's parameter is the synthesis angle: the natural start
        for _ in range(50):
            f = residual(psi, t, th)
            h = 1e-7
            jac = np.column_stack([(residual(psi + h, t, th) - f) / h, (residual(psi, t + h, th) - f) / h])
            step = np.linalg.solve(jac, f)
            psi, t = psi - step[0], t - step[1]
            if np.max(np.abs(step)) < 1e-15:
                break
        assert np.max(np.abs(residual(psi, t, th))) < 1e-15
        out.append(psi)
    return np.array(out)


@pytest.mark.parametrize("name", list(GEARS))
def test_the_synthesised_cam_gives_the_law_through_the_vector_loop(name):
    gear = GEARS[name](check=False)
    arm = LoopArm(gear)
    probe = TH[::6]
    psi = loop_on_contour(arm, gear.synthesised_contour(), probe, probe[0], gear.arm.rest)
    travel = np.array([arm.travel(p) for p in psi])
    want = gear.law.derivatives(probe)
    assert np.max(np.abs(travel - want[0])) < 1e-10 * want[0].max()
    k = gear.kinematics(probe)
    ratio = np.array([abs(arm.valve_per_arm(p)) for p in psi]) / gear.arm.cam_side.arm
    assert np.max(np.abs(k.ratio - ratio)) < 1e-10 * ratio.max()
    assert np.array_equal(k.lift, want)


@pytest.mark.parametrize("name", list(GEARS))
def test_synthesis_then_analysis_round_trip(name):
    gear = GEARS[name]()
    analysed = GEARS[name](law=None, contour=gear.synthesised_contour())
    got = analysed.valve_lift(TH)
    want = gear.law.derivatives(TH)
    assert np.max(np.abs(got[0] - want[0])) < 1e-12
    assert np.max(np.abs(got[1] - want[1])) < 1e-8 * np.abs(want[1]).max()


@pytest.mark.parametrize("name", list(GEARS))
def test_virtual_work_torque_and_normal_force(name):
    """Frictionless: T w = F v, i.e. T = F ds/dtheta, and N = F v / v_n with v_n the cam's velocity
    along the contact normal, n . J X (the normal ratio from kinematics alone)."""
    gear = GEARS[name]()
    k = gear.kinematics(TH)
    force = 400.0 + 30_000.0 * k.lift[0]
    f = gear.contact_forces(k, force)
    assert np.max(np.abs(f.torque - force * k.lift[1])) < 1e-9 * np.abs(f.torque).max()
    x, n = k.surface.contact, k.surface.normal
    normal_velocity = n[:, 0] * -x[:, 1] + n[:, 1] * x[:, 0]
    moving = np.abs(normal_velocity) > 1e-6 * np.abs(normal_velocity).max()
    assert np.max(np.abs(f.normal[moving] - force[moving] * k.lift[1][moving] / normal_velocity[moving])) \
        < 1e-9 * f.normal.max()
    assert np.max(np.abs(f.normal - force * k.normal_ratio)) < 1e-9 * f.normal.max()


@pytest.mark.parametrize("name", list(GEARS))
def test_power_balance_with_friction_is_the_heat_of_the_sliding_contacts(name):
    gear = GEARS[name]()
    k = gear.kinematics(TH)
    force = 400.0 + 30_000.0 * k.lift[0]
    f = gear.contact_forces(k, force, cam_friction=0.07, tip_friction=0.12)
    heat = np.abs(f.friction * k.cam_velocities.sliding) + 0.12 * force * np.abs(k.tip.velocities.sliding)
    assert np.max(np.abs(f.torque - force * k.lift[1] - heat)) < 1e-9 * np.abs(f.torque).max()
    assert np.all(heat >= 0.0) and heat.max() > 0.0
    if gear.arm.cam_side.kind == "roller":
        assert np.all(f.friction == 0.0) and np.all(k.cam_velocities.sliding == 0.0)


def test_pad_radius_to_infinity_is_the_flat_pad():
    flat = finger("pad", math.inf, law=GENTLE).kinematics(TH)
    gaps = []
    for radius in (1.0, 100.0, 1e4):
        k = finger("pad", radius, law=GENTLE, check=False).kinematics(TH)
        gaps.append(max(np.max(np.abs(k.surface.contour - flat.surface.contour)),
                        np.max(np.abs(k.arm_angle[0] - flat.arm_angle[0])) * 0.05))
    assert 70.0 < gaps[0] / gaps[1] < 130.0 and 70.0 < gaps[1] / gaps[2] < 130.0
    # the valve's motion is the law in both (synthesis): the cam differs, the valve does not
    assert np.array_equal(k.lift, flat.lift)


def test_an_aligned_finger_is_a_lever_of_fixed_ratio_at_small_lift():
    """Pivot, roller centre and pad centre on one horizontal line, the valve vertical: at rest the
    ratio is a_v/a exactly, the valve travel is a_v sin(dpsi), and for a small lift the ratio stays
    a_v/a to dpsi^2/2 (the lever's cosine)."""
    a, a_v, r = 0.030, 0.051, 0.009
    small = LawLift(height=2e-5, start=0.5, rise=1.2, dwell=0.0, ret=1.2, rise_law="cycloidal", return_law="cycloidal")
    gear = make_arm_gear(base_radius=RB, pivot=(-a, -(RB + r)), cam_side=CamSide("roller", a, r), branch=-1,
                         valve_arm=a_v, valve_angle=0.0, valve_pad_radius=0.01, valve_axis=-0.5 * math.pi, law=small)
    assert gear.arm.rest == pytest.approx(0.0, abs=1e-15)
    k = gear.kinematics(TH)
    dpsi = k.arm_angle[0] - gear.arm.rest
    assert np.max(np.abs(k.lift[0] - a_v * np.sin(-dpsi))) < 1e-15
    rest = k.lift[0] == 0.0
    assert np.allclose(k.ratio[rest], a_v / a, rtol=1e-14)
    bound = a_v / a * (0.5 * dpsi**2) * (1.0 + 1e-6) + 1e-15
    assert np.all(np.abs(k.ratio - a_v / a) <= bound)
    assert np.abs(dpsi).max() > 1e-4  # it did move


def test_tip_scrub_rate_and_sliding_from_the_positions():
    """The scrub's rate is the derivative of the scrub (central differences over the grid); the
    pad's sliding on the tip is -psi' t . J (X - O) (the arm's material velocity along the tip)."""
    gear = finger()
    fine = np.linspace(0.0, 2.0 * math.pi, 20_000, endpoint=False)
    k = gear.kinematics(fine)
    h = fine[1] - fine[0]
    diff = (np.roll(k.tip.scrub, -1) - np.roll(k.tip.scrub, 1)) / (2.0 * h)
    inner = slice(10, -10)
    assert np.max(np.abs(diff - k.tip.scrub_rate)[inner]) < 1e-5 * np.abs(k.tip.scrub_rate).max()
    x = k.tip.point
    o = np.array(gear.arm.pivot)
    material = k.arm_angle[1][:, None] * np.column_stack([-(x[:, 1] - o[1]), x[:, 0] - o[0]])
    along = np.einsum("ij,ij->i", material, k.tip.tangent)
    assert np.max(np.abs(k.tip.velocities.sliding + along)) < 1e-15
    assert np.abs(k.tip.scrub).max() > 1e-4


def test_hertz_stress_at_cam_and_tip():
    gear = finger()
    k = gear.kinematics(TH)
    force = np.full(TH.size, 600.0)
    f = gear.contact_forces(k, force)
    cam, tip = gear.hertz_stress(k, f, E_STAR)
    curvature = 1.0 / 0.009 + 1.0 / k.surface.radius
    assert np.allclose(cam, np.sqrt(f.normal * E_STAR * curvature / (math.pi * 0.010)), rtol=1e-14)
    chord = 2.0 * np.sqrt(0.0035**2 - k.tip.scrub**2)
    assert np.allclose(tip, np.sqrt(600.0 * E_STAR / (0.012 * math.pi * chord)), rtol=1e-14)


# --------------------------------------------------------------------------------------------
# bad geometry: one line naming the key
# --------------------------------------------------------------------------------------------


def one_line(info, key):
    assert info.value.key == key, info.value
    assert "\n" not in str(info.value)
    return info.value.reason


def test_pad_not_reaching_the_tip():
    with pytest.raises(InputError) as info:
        finger(tip_radius=0.0005)
    assert "does not reach the valve tip" in one_line(info, "gear.valve.tip_radius")


def test_roller_through_the_base_circle():
    with pytest.raises(InputError) as info:
        finger(cam_side=CamSide("roller", 0.010, 0.009))
    assert "base circle" in one_line(info, "gear.arm.arm")


def test_an_arm_that_cannot_reach_the_cam():
    with pytest.raises(InputError) as info:
        finger(cam_side=CamSide("roller", 0.12, 0.009))
    assert "cannot reach" in one_line(info, "gear.arm.arm")


def test_arm_crossing_the_cam():
    """A finger whose pivot sits beside the cam's nose path: the arm from the pivot to the roller
    is swept by the lobe."""
    with pytest.raises(InputError) as info:
        make_arm_gear(base_radius=RB, pivot=(-0.020, 0.012), cam_side=CamSide("roller", 0.034, 0.009), branch=-1,
                      valve_arm=0.06, valve_angle=0.0, valve_pad_radius=0.012, law=LIFT)
    assert "through the cam" in one_line(info, "gear.arm.pivot")


def test_a_flat_pad_cusp_names_the_base_radius_and_the_angle():
    sharp = LawLift(height=0.0093, start=0.5, rise=math.radians(45), dwell=0.0, ret=math.radians(45),
                    rise_law="cycloidal", return_law="cycloidal")
    with pytest.raises(InputError) as info:
        finger("pad", math.inf, law=sharp)
    reason = one_line(info, "follower.base_radius")
    assert "cusp" in reason and "cam angle" in reason


def test_roller_undercut_names_the_roller_radius():
    sharp = LawLift(height=0.0093, start=0.5, rise=math.radians(30), dwell=0.0, ret=math.radians(30),
                    rise_law="cycloidal", return_law="cycloidal")
    with pytest.raises(InputError) as info:
        finger(law=sharp, radius=0.012)
    assert "undercut" in one_line(info, "gear.arm.roller_radius")


def test_a_valve_axis_that_would_close_the_valve():
    with pytest.raises(InputError) as info:
        finger(valve_axis=0.5 * math.pi)
    assert "reverse the axis" in one_line(info, "gear.valve.axis")


@pytest.mark.parametrize("name", ["finger roller", "rocker curved pad"])
def test_the_ratio_jet_is_the_ratio_and_its_derivatives(name):
    """Rows 1-3 of the ratio's jet against central differences of rows 0-2 on a fine grid."""
    gear = GEARS[name]()
    fine = np.linspace(0.0, 2.0 * math.pi, 40_000, endpoint=False)
    k = gear.kinematics(fine)
    assert np.array_equal(k.ratio_jet[0], k.ratio) or np.max(np.abs(k.ratio_jet[0] - k.ratio)) < 1e-15
    h = fine[1] - fine[0]
    for row in (1, 2, 3):
        diff = (np.roll(k.ratio_jet[row - 1], -1) - np.roll(k.ratio_jet[row - 1], 1)) / (2.0 * h)
        scale = np.abs(k.ratio_jet[row]).max()
        smooth = away_from(gear.law.breakpoints(), fine, 3.0 * h)  # the law's derivatives jump there
        assert np.max(np.abs(diff - k.ratio_jet[row])[smooth]) < 1e-6 * scale, row


def away_from(marks, theta, distance):
    gap = np.abs(np.mod(theta[:, None] - np.asarray(marks)[None, :] + math.pi, 2.0 * math.pi) - math.pi)
    return np.all(gap > distance, axis=1)


def test_a_contour_drawn_for_another_base_circle_names_follower_base_radius():
    """Analysis over a given contour: the arm rests where follower.base_radius says, or one line
    names that key and the rest's offset (gears.contour_follow.check_base_circle, shared with the
    pushrod train's lifter)."""
    finger(law=None, contour=arc_cam(), check=False)  # drawn for RB: accepted
    with pytest.raises(InputError) as info:
        finger(law=None, contour=arc_cam(rb=RB + 0.0005), check=False)
    assert info.value.key == "follower.base_radius" and "the valve would rest" in info.value.reason
    assert "\n" not in str(info.value)
