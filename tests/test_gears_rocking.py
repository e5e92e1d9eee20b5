"""Rocking cam driven by an eccentric (seed 004 "Schwingdaumen"; seed 000 section 4).

Oracles: the loop closures themselves (rod and lever lengths), the closed form of the ideal
(infinitely long) eccentric rod, the mirror-image property of the four-bar (two shaft angles with
the same rocking angle are symmetric about the line O -> rod pin), the relative instant centre
of rocking cam and roller lever (Kennedy), a dense-polyline tangency check, and Richardson-
extrapolated central differences as an independent check of the jets through Newton's method.
"""

import math
from pathlib import Path

import numpy as np
import pytest

from explorer.errors import InputError
from explorer.gears.jet import Jet
from explorer.gears.linkage import EccentricDrive, IdealEccentricDrive, RockerDrive
from explorer.gears.rocking import RockingContour, build_rocking_gear, fit_contour, swing_increments
from explorer.scene import load_scene

SCENE = Path(__file__).resolve().parent.parent / "assets" / "scenes" / "rocking_cam.toml"
TWO_PI = 2.0 * math.pi


class GearLift:
    """A rocking gear's lift jet as a lift curve, for kinematics.lash_crossings."""

    def __init__(self, gear):
        self.gear = gear

    def derivatives(self, th):
        return self.gear.lift_jet(np.asarray(th)).c

    def breakpoints(self):
        return self.gear.flank_angles()


def make_gear(drive, rise=0.012, lift_start=math.radians(12), flank=math.radians(26)):
    contour = RockingContour(dwell_radius=0.075, rise=rise, lift_start=lift_start, flank=flank, law="cycloidal", sense=1)
    lever_pivot, arm = (0.35, 0.78), 0.2
    return build_rocking_gear(
        drive=drive, cam_pivot=(0.15, 0.7), contour=contour, roller_radius=0.015, lever_pivot=lever_pivot,
        lever_arm=arm, roller_branch=-1,
        make_valve=lambda psi0: RockerDrive(pivot=lever_pivot, arm=0.2, angle=math.pi, axis=-math.pi / 2, rest=psi0),
    )


FOUR_BAR = EccentricDrive(radius=0.05, phase=math.radians(-113.5), rod=0.7, pivot=(0.15, 0.7), arm=0.15, branch=1)


def ideal_like(drive: EccentricDrive) -> IdealEccentricDrive:
    """The infinitely long rod with the four-bar's rod direction and mid-swing."""
    chis = [float(drive.angle(np.array([c]))[0]) for c in drive.dead_centres()]
    chi_mid = 0.5 * (chis[0] + chis[1])
    bx = drive.pivot[0] + drive.arm * math.cos(chi_mid)
    by = drive.pivot[1] + drive.arm * math.sin(chi_mid)
    lam = math.atan2(by, bx)
    offset = drive.arm * math.cos(chi_mid - lam)
    branch = 1 if math.sin(chi_mid - lam) >= 0 else -1
    return IdealEccentricDrive(radius=drive.radius, phase=drive.phase, direction=lam, pivot=drive.pivot,
                               arm=drive.arm, offset=offset, branch=branch)


@pytest.fixture(scope="module")
def gear():
    return make_gear(FOUR_BAR)


@pytest.fixture(scope="module")
def ideal_gear():
    return make_gear(ideal_like(FOUR_BAR))


def test_four_bar_closes_and_reverses_at_its_dead_centres():
    th = np.linspace(0.0, TWO_PI, 721)
    bx, by = FOUR_BAR.pin(th)
    ex, ey = FOUR_BAR.centre(th)
    assert np.max(np.abs(np.hypot(bx - ex, by - ey) - FOUR_BAR.rod)) < 1e-13
    assert np.max(np.abs(np.hypot(bx - 0.15, by - 0.7) - FOUR_BAR.arm)) < 1e-13
    for td in FOUR_BAR.dead_centres():
        chi = FOUR_BAR.angle(Jet.variable(np.array([td])))
        assert abs(chi.c[1][0]) < 1e-12  # the lever stands still: a reversal


def test_ideal_rod_follows_its_closed_form():
    drive = ideal_like(FOUR_BAR)
    th = np.linspace(0.0, TWO_PI, 361)
    chi = drive.angle(th)
    lhs = drive.arm * np.cos(chi - drive.direction)
    rhs = drive.radius * np.cos(th + drive.phase - drive.direction) + drive.offset
    assert np.max(np.abs(lhs - rhs)) < 1e-15


def test_long_rod_tends_to_the_ideal_rod():
    """The four-bar's rocking angle approaches the ideal rod's as the rod grows (pivot moved
    along so the mid-swing stays put): error roughly halves when the rod doubles (O(e/l))."""
    errs = []
    for scale in (1.0, 2.0, 4.0):
        rod = 0.7 * scale
        drive = EccentricDrive(radius=0.05, phase=0.3, rod=rod, pivot=(0.15, 0.7 * scale), arm=0.15, branch=1)
        th = np.linspace(0.0, TWO_PI, 361)
        errs.append(np.max(np.abs(drive.angle(th) - ideal_like(drive).angle(th))))
    assert 0.3 < errs[1] / errs[0] < 0.7 and 0.3 < errs[2] / errs[1] < 0.7


def test_equal_eccentric_arcs_give_unequal_swings(ideal_gear, gear):
    """Seed 004. Ideal rod: arm cos(chi - lambda) = radius cos(theta') + offset, so each arc's
    swing follows in closed form; they differ from arc to arc (small near the dead centres,
    largest mid-stroke). The four-bar does the same, slightly skewed."""
    drive = ideal_gear.drive
    theta, increments = swing_increments(ideal_gear, ideal_gear.dead_centre - math.pi, ideal_gear.dead_centre, 12)
    chi = drive.direction + drive.branch * np.arccos(
        (drive.radius * np.cos(theta + drive.phase - drive.direction) + drive.offset) / drive.arm)
    assert np.allclose(increments, np.diff(chi), atol=1e-14)
    swing = np.abs(increments)
    assert swing.max() / swing.min() > 5.0
    assert np.sum(increments) == pytest.approx(np.ptp(chi), rel=1e-12)
    _, four_bar = swing_increments(gear, gear.dead_centre - math.pi, gear.dead_centre, 12)
    assert np.abs(four_bar).max() / np.abs(four_bar).min() > 5.0


def test_ideal_eccentric_gives_mirror_symmetric_motion_p1_equals_p2(ideal_gear):
    """Why Schenker's 2R/M asymmetry is impossible here: with the rod's direction fixed, chi is
    even about the dead centre, the lift depends only on chi, so s is even, v odd and p even:
    p1 (largest deceleration while opening) equals p2 (while closing), whatever the contour."""
    td = ideal_gear.dead_centre
    u = np.linspace(0.0, 2.5, 500)
    plus = ideal_gear.lift_jet(td + u).c
    minus = ideal_gear.lift_jet(td - u).c
    scale = np.max(np.abs(plus), axis=1)
    for k, sign in enumerate((1, -1, 1, -1)):
        assert np.max(np.abs(plus[k] - sign * minus[k])) <= 1e-11 * scale[k], k
    p1, p2 = minus[2].min(), plus[2].min()
    assert p1 == pytest.approx(p2, rel=1e-11)
    assert p1 < 0.0  # the flank really decelerates the valve


def test_four_bar_timing_asymmetry_is_fixed_by_the_linkage(gear):
    """Two shaft angles with the same rocking angle are mirror images about the line O -> B
    (B the rod pin): theta_open + theta_close - 2 theta_dead = 2 [angle B(chi_open) - angle B(chi_dead)].
    Checked at the valve's opening and closing angles, found on the analytic lift."""
    from explorer.kinematics import lash_crossings

    ups, downs = lash_crossings(GearLift(gear), 1.0, 0.0005)
    td = gear.dead_centre
    measured = np.angle(np.exp(1j * (ups[0] + downs[0] - 2 * td)))
    chi_open = gear.drive.angle(ups)[0]
    chi_dead = gear.drive.angle(np.array([td]))[0]
    predicted = 2.0 * np.angle(np.exp(1j * (gear.rod_pin_angle(np.array([chi_open]))[0]
                                            - gear.rod_pin_angle(np.array([chi_dead]))[0])))
    assert measured == pytest.approx(predicted, abs=1e-10)
    assert abs(measured) > 1e-3  # a real rod is not exactly symmetric


def test_lift_is_a_function_of_the_rocking_angle_only(gear):
    """Mirror pairs (same chi on both sides of the dead centre) have the same lift: one contour
    serves opening and closing."""
    td = gear.dead_centre
    a = np.linspace(td - 2.0, td - 0.05, 40)
    chi = gear.drive.angle(a)
    # the partner: the other shaft angle with the same chi (mirror about O -> B(chi))
    partner = 2.0 * gear.rod_pin_angle(chi) - 2.0 * gear.drive.phase - a
    assert np.allclose(np.angle(np.exp(1j * (gear.drive.angle(partner) - chi))), 0.0, atol=1e-12)
    assert np.max(np.abs(gear.lift_jet(partner).c[0] - gear.lift_jet(a).c[0])) < 1e-13


def test_contact_lies_on_pitch_curve_and_lever_circle_and_roller_is_tangent(gear):
    th = np.linspace(0.0, TWO_PI, 181)
    (rx, ry), phi, chi, rho = gear.roller_centre(th)
    assert np.max(np.abs(np.hypot(rx.c[0] - gear.lever_pivot[0], ry.c[0] - gear.lever_pivot[1]) - gear.lever_arm)) < 1e-13
    # brute force: the contour polyline (in the rocking body's frame) one roller radius away
    contour, _ = gear.contour.contour_points(gear.roller_radius, n=40_001, margin=0.6)
    for k in range(0, len(th), 6):
        c, s = math.cos(chi.c[0][k]), math.sin(chi.c[0][k])
        dx, dy = rx.c[0][k] - gear.cam_pivot[0], ry.c[0][k] - gear.cam_pivot[1]
        local = np.array([c * dx + s * dy, -s * dx + c * dy])  # roller centre in the body frame
        d = np.min(np.hypot(*(contour - local).T))
        assert d == pytest.approx(gear.roller_radius, abs=2e-8)


def test_lever_rate_from_the_instant_centre(gear):
    """Kennedy: the relative instant centre of rocking cam (pivot C) and roller lever (pivot O1)
    lies on C-O1 and on the contact normal; omega_lever / omega_cam = lambda / (lambda - 1)."""
    th = np.linspace(0.0, TWO_PI, 361)
    d = gear.contact_details(th)
    psi = gear.lever_angle(th)
    (rx, ry), phi, chi, rho = gear.roller_centre(th)
    # contact normal from the pitch-curve tangent at fixed chi
    pv = Jet.variable(phi.c[0])
    r = gear.contour.radius(pv)
    px, py = r * np.cos(pv.c[0] + chi.c[0]), r * np.sin(pv.c[0] + chi.c[0])
    tx = r.c[1] * np.cos(pv.c[0] + chi.c[0]) - r.c[0] * np.sin(pv.c[0] + chi.c[0])
    ty = r.c[1] * np.sin(pv.c[0] + chi.c[0]) + r.c[0] * np.cos(pv.c[0] + chi.c[0])
    nx, ny = -ty, tx
    cx, cy = gear.cam_pivot
    ox, oy = gear.lever_pivot
    # I = C + lam (O1 - C) = R + mu n
    ax, ay = ox - cx, oy - cy
    det = -ax * ny + ay * nx
    lam = (-(rx.c[0] - cx) * ny + (ry.c[0] - cy) * nx) / det
    ratio = lam / (lam - 1.0)
    moving = np.abs(chi.c[1]) > 1e-6
    assert np.max(np.abs(psi.c[1][moving] - ratio[moving] * chi.c[1][moving])) < 1e-12


def test_jets_against_richardson_differences(gear):
    """Independent check of the Newton-on-jets derivatives inside the flank: Richardson-
    extrapolated central differences of the lift value (test oracle only), to ~1e-7 relative."""
    flanks = gear.flank_angles()
    th = np.array([0.5 * (flanks[0] + flanks[1]) + 0.1, 0.5 * (flanks[2] + flanks[3]) - 0.1])
    f = lambda t: gear.lift_jet(np.atleast_1d(t)).c[0]

    def d1(t, h):
        return (f(t + h) - f(t - h)) / (2 * h)

    def d2(t, h):
        return (f(t + h) - 2 * f(t) + f(t - h)) / h**2

    def d3(t, h):
        return (f(t + 2 * h) - 2 * f(t + h) + 2 * f(t - h) - f(t - 2 * h)) / (2 * h**3)

    jets = gear.lift_jet(th).c
    for k, (fd, h) in enumerate(((d1, 1e-3), (d2, 2e-3), (d3, 1e-2)), start=1):
        rich = (4 * fd(th, h / 2) - fd(th, h)) / 3
        assert np.allclose(jets[k], rich, rtol=2e-6, atol=1e-9 * np.abs(jets[k]).max()), k


def test_dwell_keeps_the_valve_shut_exactly(gear):
    th = np.linspace(0.0, TWO_PI, 721)
    w = gear.swing(th).c[0]
    closed = w < gear.contour.lift_start - 1e-9
    lift = gear.lift_jet(th).c
    assert closed.any() and np.all(np.abs(lift[:, closed]) < 1e-15)


def test_fit_contour_reaches_target_lift_and_open_angle(gear):
    fitted = fit_contour(gear, target_lift=0.010, target_open_angle=math.radians(150.0), lash=0.0005)
    from explorer.kinematics import lash_crossings

    ups, downs = lash_crossings(GearLift(fitted), 1.0, 0.0005)
    open_angle = np.mod(downs[0] - ups[0], TWO_PI)
    top = fitted.lift_jet(np.array([fitted.dead_centre])).c[0][0] - 0.0005
    assert top == pytest.approx(0.010, rel=1e-8)
    assert open_angle == pytest.approx(math.radians(150.0), abs=1e-8)


def test_scene_summary_reports_symmetry_and_equal_arcs():
    from explorer.effects import simulate

    result = simulate(load_scene(SCENE))
    g = result.summary["gear"]
    sym = g["symmetry"]
    assert sym["timing_asymmetry_deg"] == pytest.approx(sym["timing_asymmetry_from_linkage_deg"], abs=1e-8)
    arcs = g["swing_per_equal_eccentric_arc_deg"]
    assert sum(arcs) == pytest.approx(g["swing_deg"], rel=1e-9)
    assert max(arcs) / min(arcs) > 5.0
    # the linkage's leftover asymmetry is far from Schenker's optimum 2R/M
    assert abs(sym["deceleration_difference_m_s2"]) < 0.1 * sym["schenker_2R_over_M_m_s2"]


BAD = [
    ({"gear.eccentric.rod": '"300 mm"'}, "gear.eccentric.rod"),  # rod too short: cannot close
    ({"gear.eccentric.lever_pivot": '["20 mm", "30 mm"]'}, "gear.eccentric.lever_pivot"),
    ({"gear.rocking_cam.lift_start": '"45 deg"'}, "gear.rocking_cam.lift_start"),  # flank never reached
    ({"gear.lever.arm": '"40 mm"'}, "gear.lever.arm"),  # roller lever cannot reach the dwell arc
    ({"follower.roller_radius": '"40 mm"'}, "follower.roller_radius"),  # undercut
    ({"gear.valve.axis": '"90 deg"'}, "gear.valve.axis"),
    ({"lift.law": '"cycloidal"', "lift.height": '"10 mm"', "lift.rise": '"60 deg"'}, "lift.law"),
]


@pytest.mark.parametrize("overrides, key", BAD, ids=[b[1] for b in BAD])
def test_bad_geometry_names_the_part(overrides, key):
    with pytest.raises(InputError) as info:
        load_scene(SCENE, [f"{k}={v}" for k, v in overrides.items()])
    assert info.value.key == key
