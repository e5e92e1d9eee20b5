"""Eccentric rolling lever ("Waelzhebel", seed 000).

Oracles: numerical quadrature of the rolling law (the closed-form integral), the geometry of pure
rolling (both faces meet in the same ground point on the line of centres, with equal arc-length
rates and a common tangent), a static deflection through the exact forward kinematics (for the
valve-referred stiffness), and the four-bar's mirror property for the pick-up/release timing.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from explorer.core.errors import InputError
from explorer.gears import jet as J
from explorer.gears.jet import Jet
from explorer.gears.rolling import RollingLaw
from explorer.mechanics.kinematics import lash_crossings
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

SCENE = Path(__file__).resolve().parent.parent / "assets" / "scenes" / "rolling_lever.toml"
TWO_PI = 2.0 * math.pi


@pytest.fixture(scope="module")
def lift():
    return build_lift(load_scene(SCENE))


@pytest.mark.parametrize("growth", [0.05, -0.03, 1e-7, 0.0])
def test_rolling_integral_matches_quadrature(growth):
    law = RollingLaw(distance=0.2, contact_radius=0.08, growth=growth)
    for w in (0.05, 0.3, 0.5):
        want, _ = quad(lambda x: law.rho(x) / (law.distance - law.rho(x)), 0.0, w, epsabs=1e-15, epsrel=1e-13)
        assert float(law.integral(w)) == pytest.approx(want, rel=1e-11, abs=1e-15)
        # and the jet's derivative is the integrand (the ratio), exactly
        j = law.integral(Jet.variable(np.array([w])))
        assert j.c[1][0] == pytest.approx(law.ratio(w), rel=1e-13)


def test_pure_rolling_geometry(lift):
    """The faces, drawn in their own body frames, meet in one ground point on the line A-B at
    every position, with equal arc-length rates (no slip) and parallel tangents (touching)."""
    gear = lift.gear
    ax, ay = gear.pivot
    bx, by = gear.valve_pivot
    gamma = math.atan2(by - ay, bx - ax)
    w = Jet.variable(np.linspace(0.0, gear.max_rolling_swing(), 200))
    alpha = gear.closed_end + gear.sense * (w + gear.contact_swing)
    beta = gear.valve_lever_angle(w)
    rho = gear.law.rho(w)
    d = gear.law.distance
    # body-frame faces (as in RollingLeverGear.faces), as jets in w
    fa = (rho * J.cos(gamma - alpha), rho * J.sin(gamma - alpha))
    fb = ((d - rho) * J.cos(gamma + math.pi - beta), (d - rho) * J.sin(gamma + math.pi - beta))
    # to the ground frame: rotate by the lever angle, shift by the pivot
    ga = (ax + J.cos(alpha) * fa[0] - J.sin(alpha) * fa[1], ay + J.sin(alpha) * fa[0] + J.cos(alpha) * fa[1])
    gb = (bx + J.cos(beta) * fb[0] - J.sin(beta) * fb[1], by + J.sin(beta) * fb[0] + J.cos(beta) * fb[1])
    assert np.max(np.abs(ga[0].c[0] - gb[0].c[0])) < 1e-15 and np.max(np.abs(ga[1].c[0] - gb[1].c[0])) < 1e-15
    on_line = (ga[0].c[0] - ax) * math.sin(gamma) - (ga[1].c[0] - ay) * math.cos(gamma)
    assert np.max(np.abs(on_line)) < 1e-15
    speed_a = np.hypot(fa[0].c[1], fa[1].c[1])  # arc length per unit swing along each face
    speed_b = np.hypot(fb[0].c[1], fb[1].c[1])
    assert np.allclose(speed_a, speed_b, rtol=1e-12)
    # tangents of the two faces, turned into the ground frame, are parallel
    ta = (np.cos(alpha.c[0]) * fa[0].c[1] - np.sin(alpha.c[0]) * fa[1].c[1],
          np.sin(alpha.c[0]) * fa[0].c[1] + np.cos(alpha.c[0]) * fa[1].c[1])
    tb = (np.cos(beta.c[0]) * fb[0].c[1] - np.sin(beta.c[0]) * fb[1].c[1],
          np.sin(beta.c[0]) * fb[0].c[1] + np.cos(beta.c[0]) * fb[1].c[1])
    cross = (ta[0] * tb[1] - ta[1] * tb[0]) / (speed_a * speed_b)
    assert np.max(np.abs(cross)) < 1e-12


def test_velocity_ratio_is_rho_over_d_minus_rho(lift):
    gear = lift.gear
    w = Jet.variable(np.linspace(0.0, gear.max_rolling_swing(), 50))
    beta = gear.valve_lever_angle(w)
    assert np.allclose(-gear.sense * beta.c[1], gear.law.ratio(w.c[0]), rtol=1e-13)


def test_finite_pick_up_velocity_found_by_the_lash_effect(lift):
    """No lash, yet a finite velocity at pick-up (Schenker): the lift curve is zero before contact
    and the contact branch from there on; the crossing is found exactly with the contact velocity."""
    gear = lift.gear
    ups, downs = lash_crossings(lift, 1.0, 0.0)
    marks = gear.contact_angles()
    assert ups[0] == pytest.approx(marks[np.argmax(gear.virtual_lift(marks).c[1])], abs=1e-14)
    v_up = lift.derivatives(ups)[1][0]
    assert v_up == pytest.approx(gear.virtual_lift(ups).c[1][0], rel=1e-12)
    assert v_up > 1e-3  # finite, not zero
    before = lift.derivatives(ups - 1e-6)
    assert np.all(before == 0.0)


def test_valve_referred_stiffness_by_static_deflection(lift):
    """A torque tau twists the rolling lever by tau / k_t; pushing that rotation through the exact
    forward kinematics moves the valve by ds: k = F / ds with F = tau / (ds/dalpha) (virtual work).
    Against the formula k_t / (ds/dalpha)^2, to the O(tau) linearisation error."""
    gear = lift.gear
    theta = np.array([float(gear.drive.dead_centres()[0]) - 0.4])  # well inside the contact
    k = gear.stiffness(theta)
    force = 1.0
    ds_dalpha = k["ds_dalpha"][0]
    tau = force * ds_dalpha
    dalpha = tau / gear.lever_stiffness
    w = gear.rolling_swing(theta).c[0]
    s = lambda ww: float(np.ravel(gear.valve.travel(gear.valve_lever_angle(np.asarray(ww))))[0])
    ds = s(w - gear.sense * dalpha) - s(w)  # the lever yields against the load
    assert force / abs(ds) == pytest.approx(k["lever"][0], rel=1e-5)


def test_most_elasticity_sits_in_the_rolling_lever():
    from explorer.effects.pipeline import simulate

    result = simulate(load_scene(SCENE))
    g = result.summary["gear"]
    assert g["share_of_compliance_in_lever"] > 0.99
    assert g["rod_stiffness_at_max_lift_N_m"] > 100 * g["lever_stiffness_at_max_lift_N_m"]
    assert result.summary["impact_velocity_opening_m_s"] == pytest.approx(g["pick_up"][0]["velocity_m_s"], rel=1e-12)


def test_pick_up_and_release_are_mirror_images_about_the_line_O_B(lift):
    gear = lift.gear
    marks = gear.contact_angles()
    # the open dead centre lies between pick-up and release
    opened = marks[np.argmax(gear.virtual_lift(marks).c[1])]
    closed = marks[np.argmin(gear.virtual_lift(marks).c[1])]
    dead = gear.drive.dead_centres()
    top = max(dead, key=lambda t: float(lift.derivatives(np.array([t]))[0][0]))
    alpha_c = gear.drive.angle(np.array([opened]))[0]
    alpha_d = gear.drive.angle(np.array([top]))[0]

    def pin_angle(a):
        return math.atan2(gear.pivot[1] + gear.drive.arm * math.sin(a), gear.pivot[0] + gear.drive.arm * math.cos(a))

    measured = np.angle(np.exp(1j * (opened + closed - 2 * top)))
    assert measured == pytest.approx(2 * np.angle(np.exp(1j * (pin_angle(alpha_c) - pin_angle(alpha_d)))), abs=1e-10)


BAD = [
    ({"gear.rolling_lever.growth": '"400 mm"'}, "gear.rolling_lever.growth"),
    ({"gear.rolling_lever.contact_swing": '"45 deg"'}, "gear.rolling_lever.contact_swing"),
    ({"gear.rolling_lever.contact_radius": '"250 mm"'}, "gear.rolling_lever.contact_radius"),
    ({"gear.eccentric.rod": '"200 mm"'}, "gear.eccentric.rod"),
    ({"gear.valve.type": '"rod-and-lever"'}, "gear.valve.type"),
]


@pytest.mark.parametrize("overrides, key", BAD, ids=[b[1] for b in BAD])
def test_bad_geometry_names_the_part(overrides, key):
    with pytest.raises(InputError) as info:
        load_scene(SCENE, [f"{k}={v}" for k, v in overrides.items()])
    assert info.value.key == key
