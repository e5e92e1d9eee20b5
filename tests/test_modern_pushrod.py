"""OHV pushrod train (explorer.gears.pushrod): issue #24's oracles for the rocker and pushrod.

- An independent vector loop written here: the pushrod's closure |O_r + a e(psi) - B_L(L)| = l
  solved by Newton for psi at each lifter lift L; the valve travel and ds/dL (implicit
  differentiation) from the test's own rocker. The lifter's lift over an arc cam comes from the
  arcs' support function (flat lifter, written here) or explorer.lift.contours' exact roller lift.
  To 1e-10.
- The backwards construction: the law -> the lifter's lift -> (the test's loop) -> the law again.
- Virtual work T w = F v to 1e-9; with friction the heat of the sliding contacts; the pushrod's
  force from the rocker's moments against the lifter's balance along its axis.
- Synthesis -> analysis round trip to 1e-12 m; bad geometry is one line naming the key.
"""

import math

import numpy as np
import pytest

from explorer.core.errors import InputError
from explorer.gears.pushrod import Lifter, make_pushrod_train
from explorer.lift.contours.arcs import make_arc_lift
from explorer.lift.curves import LawLift
from explorer.mechanics.contact import effective_modulus

TH = np.linspace(0.0, 2.0 * math.pi, 720, endpoint=False)
RB = 0.017
LIFT = LawLift(height=0.0105, start=math.radians(30), rise=math.radians(85), dwell=0.0, ret=math.radians(85),
               rise_law="polynomial-345", return_law="polynomial-345")
E_STAR = effective_modulus(210e9, 0.3, 210e9, 0.3)
PIVOT = (0.020, 0.260)
HALF = 0.13  # rad: the rocker square to the pushrod and the valve at mid-lift
CUP = (PIVOT[0] + 0.025 * math.cos(math.pi + HALF), PIVOT[1] + 0.025 * math.sin(math.pi + HALF))
PAD = (PIVOT[0] + 0.040 * math.cos(HALF), PIVOT[1] + 0.040 * math.sin(HALF))

LIFTERS = {
    "flat": Lifter("flat", socket_height=0.040, width=0.012),
    "crowned": Lifter("flat", radius=1.5, socket_height=0.040, width=0.012),
    "roller": Lifter("roller", radius=0.009, offset=0.001, socket_height=0.030, width=0.012),
}


def train(lifter="flat", law=LIFT, contour=None, **kw):
    args = dict(base_radius=RB, lifter=LIFTERS[lifter], rocker_pivot=PIVOT, cup=CUP, valve_pad_centre=PAD,
                valve_pad_radius=0.010, valve_axis=-0.5 * math.pi, tip_radius=0.004, law=law, contour=contour)
    args.update(kw)
    return make_pushrod_train(**args)


def e(angle):
    return np.array([math.cos(angle), math.sin(angle)])


class LoopRocker:
    """The train as this test sees it, from the rest layout alone."""

    def __init__(self, lifter: Lifter):
        self.o = np.array(PIVOT)
        self.lifter = lifter
        if lifter.kind == "roller":
            self.y_l = math.sqrt((RB + lifter.radius) ** 2 - lifter.offset**2) + lifter.socket_height
        else:
            self.y_l = RB + lifter.socket_height
        self.x_l = lifter.offset
        cup, pad = np.array(CUP), np.array(PAD)
        self.length = math.hypot(cup[0] - self.x_l, cup[1] - self.y_l)
        self.a = math.hypot(*(cup - self.o))
        self.rest = math.atan2(*(cup - self.o)[::-1])
        self.pad_local = pad - self.o  # at psi = rest
        self.u = np.array([0.0, -1.0])

    def pad_centre(self, psi):
        c, s = math.cos(psi - self.rest), math.sin(psi - self.rest)
        return self.o + np.array([c * self.pad_local[0] - s * self.pad_local[1],
                                  s * self.pad_local[0] + c * self.pad_local[1]])

    def solve(self, lift, psi):
        """Newton on g(psi) = |O + a e(psi) - B_L|^2 - l^2; returns psi and dpsi/dL."""
        ball = np.array([self.x_l, self.y_l + lift])
        for _ in range(60):
            d = self.o + self.a * e(psi) - ball
            g = d @ d - self.length**2
            dg = 2.0 * d @ (self.a * np.array([-math.sin(psi), math.cos(psi)]))
            step = g / dg
            psi -= step
            if abs(step) < 1e-14:
                break
        d = self.o + self.a * e(psi) - ball
        assert abs(d @ d - self.length**2) < 1e-16
        # dg/dL = -2 d . e_y, so dpsi/dL = 2 d_y / dg
        return psi, 2.0 * d[1] / (2.0 * d @ (self.a * np.array([-math.sin(psi), math.cos(psi)])))

    def travel(self, psi):
        return self.u @ (self.pad_centre(psi) - self.pad_centre(self.rest))

    def valve_per_rocker(self, psi):
        r = self.pad_centre(psi) - self.o
        return self.u @ np.array([-r[1], r[0]])


def flat_lift_over_arcs(contour, theta):
    """Support function of an arc cam along the lifter's axis, arc by arc, minus the base radius."""
    out = np.full(theta.size, np.nan)
    u = np.column_stack([np.sin(theta), np.cos(theta)])
    angle = np.arctan2(u[:, 1], u[:, 0])
    for k, arc in enumerate(contour.arcs):
        inside = np.mod((angle - contour.start_angle[k]) * np.sign(contour.sweep[k]), 2.0 * math.pi) \
            <= abs(contour.sweep[k])
        out[inside] = u[inside] @ np.array([arc.x, arc.y]) + arc.radius - RB
    return out


def arc_cam():
    from test_modern_flat_face import arc_cam as four_arcs

    return four_arcs(rb=RB, nose=0.007, lift=0.0065, flank=0.07)


@pytest.mark.parametrize("lifter", ["flat", "roller"])
def test_analysis_over_an_arc_cam_matches_the_vector_loop(lifter):
    contour = arc_cam()
    gear = train(lifter, law=None, contour=contour, check=False)
    probe = TH[::2]
    k = gear.kinematics(probe)
    if lifter == "flat":
        lift = flat_lift_over_arcs(contour, probe)
    else:
        f = LIFTERS["roller"]
        lift = make_arc_lift(contour, f.radius, f.offset, RB).derivatives(probe)[0]
    assert np.max(np.abs(k.lifter_lift[0] - lift)) < 1e-15
    loop = LoopRocker(LIFTERS[lifter])
    psi, rate = [], []
    last = loop.rest
    for value in lift:
        last, r = loop.solve(value, last)
        psi.append(last)
        rate.append(r)
    psi, rate = np.array(psi), np.array(rate)
    travel = np.array([loop.travel(p) for p in psi])
    assert travel.max() > 0.009
    assert np.max(np.abs(k.lift[0] - travel)) < 1e-10 * travel.max()
    ratio = np.array([loop.valve_per_rocker(p) for p in psi]) * rate
    assert np.max(np.abs(k.ratio - ratio)) < 1e-10 * ratio.max()
    assert 1.5 < ratio.min() and ratio.max() < 1.7


@pytest.mark.parametrize("lifter", list(LIFTERS))
def test_the_backwards_construction_gives_the_law_through_the_loop(lifter):
    gear = train(lifter)
    k = gear.kinematics(TH)
    loop = LoopRocker(LIFTERS[lifter])
    last = loop.rest
    travel = []
    for value in k.lifter_lift[0]:
        last, _ = loop.solve(value, last)
        travel.append(loop.travel(last))
    want = LIFT.derivatives(TH)[0]
    assert np.max(np.abs(np.array(travel) - want)) < 1e-10 * want.max()
    moving = np.abs(k.lifter_lift[1]) > 1e-3 * np.abs(k.lifter_lift[1]).max()
    assert np.max(np.abs(k.ratio[moving] - k.lift[1][moving] / k.lifter_lift[1][moving])) < 1e-10 * k.ratio.max()


@pytest.mark.parametrize("lifter", list(LIFTERS))
def test_synthesis_then_analysis_round_trip(lifter):
    gear = train(lifter)
    analysed = train(lifter, law=None, contour=gear.synthesised_contour())
    got = analysed.valve_lift(TH)
    want = LIFT.derivatives(TH)
    assert np.max(np.abs(got[0] - want[0])) < 1e-12
    assert np.max(np.abs(got[1] - want[1])) < 1e-8 * np.abs(want[1]).max()


@pytest.mark.parametrize("lifter", list(LIFTERS))
def test_virtual_work_and_the_heat_of_friction(lifter):
    gear = train(lifter)
    k = gear.kinematics(TH)
    force = 450.0 + 32_000.0 * k.lift[0]
    f = gear.contact_forces(k, force)
    assert np.max(np.abs(f.torque - force * k.lift[1])) < 1e-9 * np.abs(f.torque).max()
    f = gear.contact_forces(k, force, cam_friction=0.08, tip_friction=0.1)
    heat = np.abs(f.friction * k.cam_velocities.sliding) + 0.1 * force * np.abs(k.tip.velocities.sliding)
    assert np.max(np.abs(f.torque - force * k.lift[1] - heat)) < 1e-9 * np.abs(f.torque).max()
    # the pushrod's force (rocker moments) balances the cam's push along the lifter's axis
    rod = gear.pushrod_force(k, f)
    direction = k.upper_ball - k.lower_ball
    along = rod * direction[:, 1] / np.hypot(direction[:, 0], direction[:, 1])
    cam_push = f.normal * k.surface.normal[:, 1] + f.friction * k.surface.tangent[:, 1]
    assert np.max(np.abs(along - cam_push)) < 1e-9 * cam_push.max()
    assert np.all(rod > 0.0)


def test_hertz_at_the_lifter_and_tip():
    gear = train("roller")
    k = gear.kinematics(TH)
    f = gear.contact_forces(k, np.full(TH.size, 700.0))
    cam, tip = gear.hertz_stress(k, f, E_STAR)
    want = np.sqrt(f.normal * E_STAR * (1.0 / 0.009 + 1.0 / k.surface.radius) / (math.pi * 0.012))
    assert np.allclose(cam, want, rtol=1e-14)
    assert np.all(np.isfinite(tip)) and tip.min() > 0.0


def one_line(info, key):
    assert info.value.key == key, info.value
    assert "\n" not in str(info.value)
    return info.value.reason


def test_a_flat_lifter_takes_no_in_plane_offset():
    with pytest.raises(InputError) as info:
        make_pushrod_train(base_radius=RB, lifter=Lifter("flat", offset=0.002, socket_height=0.04), rocker_pivot=PIVOT,
                           cup=CUP, valve_pad_centre=PAD, valve_pad_radius=0.01, law=LIFT)
    one_line(info, "gear.lifter.offset")


def test_a_roller_lifter_undercut_names_its_radius():
    sharp = LawLift(height=0.0105, start=0.5, rise=math.radians(35), dwell=0.0, ret=math.radians(35),
                    rise_law="cycloidal", return_law="cycloidal")
    with pytest.raises(InputError) as info:
        train("roller", law=sharp)
    assert "undercut" in one_line(info, "gear.lifter.roller_radius")


def test_a_flat_lifter_cusp_names_the_base_radius():
    sharp = LawLift(height=0.0105, start=0.5, rise=math.radians(50), dwell=0.0, ret=math.radians(50),
                    rise_law="cycloidal", return_law="cycloidal")
    with pytest.raises(InputError) as info:
        train("flat", law=sharp)
    assert "cusp" in one_line(info, "follower.base_radius")


def test_the_pad_off_the_valve_tip():
    with pytest.raises(InputError) as info:
        train(tip_radius=0.0003)
    one_line(info, "gear.valve.tip_radius")


def test_pushrod_and_rocker_in_line_at_rest():
    lower = (0.0, RB + 0.040)
    # cup on the line from the lifter's ball through the pivot: no triangle to close
    cup = (PIVOT[0] - 0.1 * (PIVOT[0] - lower[0]), PIVOT[1] - 0.1 * (PIVOT[1] - lower[1]))
    with pytest.raises(InputError) as info:
        train(cup=cup)
    one_line(info, "gear.rocker.cup")


def test_the_ratio_jet_is_the_ratio_and_its_derivatives():
    gear = train("roller")
    fine = np.linspace(0.0, 2.0 * math.pi, 40_000, endpoint=False)
    k = gear.kinematics(fine)
    assert np.max(np.abs(k.ratio_jet[0] - k.ratio)) < 1e-15
    h = fine[1] - fine[0]
    for row in (1, 2, 3):
        diff = (np.roll(k.ratio_jet[row - 1], -1) - np.roll(k.ratio_jet[row - 1], 1)) / (2.0 * h)
        scale = np.abs(k.ratio_jet[row]).max()
        smooth = away_from(gear.law.breakpoints(), fine, 3.0 * h)  # the law's derivatives jump there
        assert np.max(np.abs(diff - k.ratio_jet[row])[smooth]) < 1e-6 * scale, row


def away_from(marks, theta, distance):
    gap = np.abs(np.mod(theta[:, None] - np.asarray(marks)[None, :] + math.pi, 2.0 * math.pi) - math.pi)
    return np.all(gap > distance, axis=1)


@pytest.mark.parametrize("rf", [1.5, 5.0, 10.0, 1e3])
def test_a_crowned_lifter_is_never_below_either_hertz_bound(rf):
    """The crowned lifter's face on the lobe: where the point contact's ellipse fits the width it is
    the answer; where it would run over the edges the contact is cut to the width and its peak is
    at least both the untruncated ellipse's p0 and the line contact's over the width (Johnson,
    Contact Mechanics, two-dimensional contact of cylinders; written here). At Rf = 5 m the ellipse
    overruns the 12 mm lobe on the flanks while its p0 (1050 MPa) is still above the line
    contact's (903 MPa): the larger is reported."""
    from explorer.mechanics.hertz import point_contact

    gear = make_pushrod_train(base_radius=RB, lifter=Lifter("flat", radius=rf, socket_height=0.040, width=0.012),
                              rocker_pivot=PIVOT, cup=CUP, valve_pad_centre=PAD, valve_pad_radius=0.010,
                              valve_axis=-0.5 * math.pi, tip_radius=0.004, law=LIFT)
    k = gear.kinematics(TH)
    f = gear.contact_forces(k, 700.0 + 3e4 * np.maximum(k.lift[0], 0.0))
    cam, _tip = gear.hertz_stress(k, f, E_STAR)
    point = point_contact(f.normal, 1.0 / rf + 1.0 / k.surface.radius, np.full(TH.size, 1.0 / rf), E_STAR)
    line = np.sqrt(f.normal / 0.012 * E_STAR * (1.0 / rf + 1.0 / k.surface.radius) / math.pi)
    fits = point.semi_major <= 0.006
    assert np.array_equal(cam[fits], point.peak_pressure[fits])
    assert np.all(cam >= np.maximum(point.peak_pressure, line) * (1.0 - 1e-14))


def test_a_loop_through_its_dead_point_names_the_cup_a_scene_key():
    """The pushrod's length is no scene key: it follows from the cup's rest position ([gear.rocker]
    cup, explorer.gears.modern_spec). A loop of pushrod and rocker that passes its dead point during
    the lift names that key (a layout found by drawing random ones)."""
    law = LawLift(height=0.009, start=0.5, rise=math.radians(80), dwell=0.0, ret=math.radians(80),
                  rise_law="polynomial-345", return_law="polynomial-345")
    with pytest.raises(InputError) as info:
        make_pushrod_train(base_radius=0.017, lifter=Lifter("flat", socket_height=0.03, width=0.012),
                           rocker_pivot=(0.0019893832949996054, 0.20336515815569378),
                           cup=(0.011213222130708744, 0.362284038488325),
                           valve_pad_centre=(0.043454158188915376, 0.2648009284409056), valve_pad_radius=0.01,
                           law=law, n=720)
    assert "dead point" in one_line(info, "gear.rocker.cup")
