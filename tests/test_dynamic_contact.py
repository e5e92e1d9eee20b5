"""The contact statics on the elastic train's cam force (the contact effect's dynamic_* figures).

With the elastic effect in a scene the cam carries the elastic train's force, not the rigid
train's: beyond the float speed the valve is thrown off and lands again, and the cam's load at the
landing is several times the rigid one. The contact effect runs after the elastic effect (the
effect table's `after`) and repeats its statics on that force with the design's width.

Oracles: the line-contact formulas written out here by hand (Johnson, Contact Mechanics, 1985,
eq. 4.45: p0 = sqrt(P' E* / (pi R)), P' = N / b, 1/R = 1/r_roller + 1/rho_contour, 1/E* = (1 - nu1^2)
/ E1 + (1 - nu2^2) / E2; the roller's normal force with guide friction N = P / (cos a - tan(rho) sin
a sgn v); the torque T = N (e cos a + y sin a), y = sqrt(rp^2 - e^2) + L), applied to the elastic
effect's own force column; and the stiff limit: as the linkage stiffens (well damped), the elastic
train becomes the rigid one, so the dynamic peaks converge to the rigid peaks, the difference
falling as 1/k (the quasi-static deflection F/k drives it)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from explorer.effects.pipeline import simulate
from explorer.effects.registry import EffectSpec, order, register_effect
from explorer.result import EffectOutput
from explorer.scene.scene import load_scene, loads_scene

SCENES = "assets/scenes"


def test_the_contact_statics_run_after_the_elastic_effect_only_when_the_scene_has_it():
    assert order(["kinematics", "lash", "forces", "contact", "elastic"]) == [
        "kinematics", "lash", "forces", "elastic", "contact"]
    assert "elastic" not in order(["kinematics", "lash", "forces", "contact"])  # `after` adds nothing


def test_a_toy_effect_reads_another_it_runs_after(tmp_path):
    """A plug-in's `after`: the toy reads the other toy's column when the scene lists both (in either
    order), and runs alone without it."""
    seen: list[bool] = []

    def first(ctx) -> EffectOutput:
        return EffectOutput(columns={"toy_first_m": np.asarray(ctx.columns["valve_lift_m"]) * 2.0})

    def second(ctx) -> EffectOutput:
        seen.append("toy-first" in ctx.done)
        lift = np.asarray(ctx.columns["valve_lift_m"])
        source = ctx.columns["toy_first_m"] if "toy-first" in ctx.done else lift
        return EffectOutput(summary={"toy_second_peak_m": float(np.max(source))})

    path = tmp_path / "toy.toml"
    text = ('effects = {effects}\n[drive]\nrpm = 1200\n[lift]\nlaw = "cycloidal"\nheight = "8 mm"\nrise = "90 deg"\n'
            'dwell = "30 deg"\n[follower]\nbase_radius = "30 mm"\nroller_radius = "8 mm"\n')
    with register_effect(EffectSpec("toy-first", first, depends=("kinematics",), columns=("toy_first_m",))), \
            register_effect(EffectSpec("toy-second", second, depends=("kinematics",), after=("toy-first",))):
        for effects, doubled in (('["toy-second", "toy-first"]', True), ('["toy-first", "toy-second"]', True),
                                 ('["toy-second"]', False)):
            path.write_text(text.format(effects=effects))
            result = simulate(load_scene(path))
            assert result.summary["toy_second_peak_m"] == pytest.approx(0.016 if doubled else 0.008, rel=1e-12)
            assert list(result.timings).index("toy-second") == len(result.timings) - 1
    assert seen == [True, True, False]


def test_dynamic_statics_equal_the_hand_formulas_on_the_elastic_force():
    """valve_float_demo (4000 rpm, above its float speed): every sample of the dynamic normal force,
    torque and Hertz stress from the elastic linkage force by the formulas above (E = 210 GPa, nu =
    0.3 for both bodies: the scene names none; 6 deg guide friction; width 14 mm; roller 12 mm;
    offset 0). Tolerance 1e-12 relative: the same operations in another order."""
    result = simulate(load_scene(f"{SCENES}/valve_float_demo.toml"))
    c, s = result.columns, result.summary
    force = np.asarray(c["linkage_force_N"])  # the elastic effect's (it replaced the rigid one)
    alpha = np.radians(c["pressure_angle_deg"])
    v = np.sign(c["follower_velocity_m_s"])
    den = np.cos(np.abs(alpha)) - math.tan(math.radians(6.0)) * np.sin(np.abs(alpha)) * v
    assert (den > 0.0).all()
    normal = np.where(force > 0.0, force / den, 0.0)
    e_star = 1.0 / (2.0 * (1.0 - 0.3**2) / 210e9)
    curvature = 1.0 / 0.012 + 1.0 / c["contour_radius_m"]
    sigma = np.sqrt(normal * e_star * curvature / (math.pi * 0.014))
    y = 0.042 + c["follower_lift_m"]
    torque = normal * y * np.sin(alpha)
    np.testing.assert_allclose(c["dynamic_cam_normal_force_N"], normal, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(c["dynamic_hertz_stress_Pa"], sigma, rtol=1e-12, atol=1e-3)
    np.testing.assert_allclose(c["dynamic_camshaft_torque_Nm"], torque, rtol=1e-12, atol=1e-12)
    i = int(np.argmax(sigma))
    assert s["max_dynamic_hertz_stress_Pa"] == pytest.approx(sigma[i], rel=1e-12)
    assert s["max_dynamic_hertz_stress_cam_angle_deg"] == c["cam_angle_deg"][i]
    assert s["dynamic_hertz_utilisation"] == pytest.approx(sigma[i] / s["hertz_allowable_Pa"], rel=1e-12)
    # above the float speed the landing loads the cam far beyond the rigid train's peak (1942 N
    # against 828 N), and a warning says what the stress is under that force
    assert s["max_dynamic_cam_normal_force_N"] > 2.0 * s["max_cam_normal_force_N"]
    assert s["max_dynamic_hertz_stress_Pa"] > 1.4 * s["max_hertz_stress_Pa"]
    assert any("under the elastic train's force: dynamic_hertz_stress_Pa 691.2 MPa" in w for w in result.warnings)
    assert s["dynamic_governing_hertz_stress"] == "dynamic_hertz_stress_Pa"
    # the rigid statics are those of the rigid force, as before (where it is negative, the rigid
    # train would need the cam to pull: passed through without friction, P / cos a)
    f = np.asarray(c["contact_force_N"])
    assert (f < 0.0).any()
    rigid = np.where(f > 0.0, f / den, f / np.cos(alpha))
    np.testing.assert_allclose(c["cam_normal_force_N"], rigid, rtol=1e-12, atol=1e-9)


def _stiff(stiffness: float) -> "object":
    """cycloidal_demo at 1000 rpm without lash, its linkage `stiffness` damped at half critical
    (the lift-off's transient dies within the ramp), 10 mm lift."""
    text = open(f"{SCENES}/cycloidal_demo.toml").read()
    damping = 2.0 * 0.5 * math.sqrt(stiffness * 0.12)
    for old, new in (('rpm = 3000', 'rpm = 1000'), ('lash = "0.3 mm"', 'lash = "0 mm"'),
                     ('height = "10.3 mm"', 'height = "10 mm"'),
                     ('stiffness = "2e6 N/m"', f'stiffness = "{stiffness!r} N/m"\ndamping = "{damping!r} N*s/m"')):
        assert old in text
        text = text.replace(old, new)
    return simulate(loads_scene(text, source="stiff.toml"))


def test_dynamic_figures_converge_to_the_rigid_ones_as_the_linkage_stiffens():
    """The stiff limit, first order in 1/k: each tenfold stiffer linkage cuts the difference of the
    peak torque and Hertz stress, and of the normal force at every sample of the open valve, to
    about a tenth (measured: the peaks 0.10, the samples 0.02 then 0.01; asserted < 0.2), and at 1e10 N/m they agree within 1e-5 relative.
    The normal force is compared off the valve's ends (0.5 mm of lift: the rigid train loads the
    seat's preload on the cam at once, the elastic one over the deflection preload / k) and off the
    nose (1 deg: the guide friction turns there, 2 x 15 N, when each valve's velocity does: the
    elastic one a fraction of a sample later)."""
    keys = ("max_camshaft_torque_Nm", "max_hertz_stress_Pa")
    peaks, samples = [], []
    for k in (1e8, 1e9, 1e10):
        result = _stiff(k)
        s, c = result.summary, result.columns
        peaks.append([abs(s[key.replace("max_", "max_dynamic_")] - s[key]) / s[key] for key in keys])
        away = (c["rigid_valve_lift_m"] > 0.5e-3) & (np.abs(c["cam_angle_deg"] - 90.0) > 1.0)
        rigid = c["cam_normal_force_N"][away]
        samples.append(np.max(np.abs(c["dynamic_cam_normal_force_N"][away] - rigid)) / np.max(rigid))
    d = np.column_stack([np.array(peaks), samples])
    assert (d[1] < 0.2 * d[0]).all() and (d[2] < 0.2 * d[1]).all(), d
    assert (d[2] < 1e-5).all(), d


def test_without_the_elastic_effect_there_are_no_dynamic_figures():
    text = open(f"{SCENES}/cycloidal_demo.toml").read().replace(
        'effects = ["kinematics", "lash", "forces", "contact", "elastic"]', 'effects = ["contact"]')
    result = simulate(loads_scene(text, source="rigid.toml"))
    assert not [k for k in result.summary if "dynamic" in k]
    assert not [k for k in result.columns if k.startswith("dynamic_")]


@pytest.mark.parametrize("name", ["pushrod_rocker", "bucket_tappet", "finger_follower"])
def test_a_gears_own_stresses_are_computed_on_the_elastic_force_too(name):
    """The gear's own contact figures (a rocker's tip, a bucket's face) run on the elastic force: each
    dynamic Hertz column is zero exactly where that force is (no load, no stress) and positive where
    it carries load at the cam."""
    result = simulate(load_scene(f"{SCENES}/{name}.toml"))
    c = result.columns
    force = np.asarray(c["linkage_force_N"])
    stresses = [k for k in c if k.startswith("dynamic_") and k.endswith("hertz_stress_Pa")]
    assert len(stresses) >= 2, stresses  # the generic one and the gear's own
    for key in stresses:
        assert (c[key][force == 0.0] == 0.0).all(), key
        assert result.summary[f"max_{key}"] > 0.0


def test_the_governing_stress_is_the_largest_hertz_column_with_its_warnings():
    """A crowned bucket's face (the ellipse, the gear's own column) carries more stress than the
    line contact of the same force: the utilisation is the face's, in the rigid and the dynamic
    figures, and an allowable between the two warns on the face, as the hertz_stress rules judge it
    (they take the gear's own stress)."""
    import explorer

    scene = load_scene(f"{SCENES}/bucket_tappet.toml", ['contact.allowable_stress="800 MPa"'])
    result = simulate(scene)
    s = result.summary
    assert s["max_dynamic_face_hertz_stress_Pa"] > 800e6 > s["max_dynamic_hertz_stress_Pa"]
    assert s["dynamic_governing_hertz_stress"] == "dynamic_face_hertz_stress_Pa"
    assert s["dynamic_hertz_utilisation"] == pytest.approx(s["max_dynamic_face_hertz_stress_Pa"] / 800e6, rel=1e-12)
    face = float(np.max(result.columns["face_hertz_stress_Pa"]))
    assert s["governing_hertz_stress"] == "face_hertz_stress_Pa"
    assert s["governing_hertz_utilisation"] == pytest.approx(face / 800e6, rel=1e-12) and face > 800e6
    assert any(w.startswith("contact stress face_hertz_stress_Pa") for w in result.warnings)
    assert any("elastic train's force: dynamic_face_hertz_stress_Pa" in w for w in result.warnings)
    report = explorer.check(scene, only=("hertz_stress", "dynamic_hertz_stress"), workers=1)
    assert report.result("hertz_stress").verdict == report.result("dynamic_hertz_stress").verdict == "fail"
    assert report.result("dynamic_hertz_stress").value == pytest.approx(s["max_dynamic_face_hertz_stress_Pa"],
                                                                        rel=1e-12)
