"""The [cam] section (arcs, inline points, CSV points), its errors, and the geometry columns and
undercut check of the kinematics effect, through scene files and the CLI."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import SCENES, run_cli
from explorer import InputError, load_scene, loads_scene, simulate
from explorer.effects.contour import cam_contour, pitch_curve
from explorer.lift.contours.schenker_fig2 import PAPER_DESIGN, arcs as schenker_arcs
from explorer.effects.lift import build_lift

HEAD = """
name = "t"
effects = ["kinematics"]
[drive]
rpm = 600
[lift]
law = "contour"
[follower]
base_radius = "{base}"
roller_radius = "{roller}"
offset = "{offset}"
"""


def eccentric_scene(base="40 mm", roller="15 mm", offset="0 mm", extra=""):
    """Eccentric: circle R = 50 mm, centre 10 mm below the shaft (min radius 40 mm)."""
    return HEAD.format(base=base, roller=roller, offset=offset) + """
[cam]
""" + extra + """
[[cam.arcs]]
x = "0 mm"
y = "-10 mm"
radius = "50 mm"
"""


def test_eccentric_scene_loads_and_simulates():
    scene = loads_scene(eccentric_scene())
    result = simulate(scene)
    th = np.radians(result.columns["cam_angle_deg"])
    # slider-crank oracle: centre at (10 sin th, -10 cos th) mm, rod R + r = 65 mm
    y = -0.01 * np.cos(th) + np.sqrt(0.065**2 - (0.01 * np.sin(th)) ** 2)
    assert np.allclose(result.columns["follower_lift_m"], y - 0.055, rtol=0, atol=1e-16)
    # the contour radius column is the arc's radius everywhere; the pitch radius R + r
    assert np.allclose(result.columns["contour_radius_m"], 0.05, rtol=1e-12)
    assert np.allclose(result.columns["pitch_radius_m"], 0.065, rtol=1e-12)
    assert "pressure_angle_deg" in result.columns


def test_rotation_turns_the_contour():
    a = build_lift(loads_scene(eccentric_scene()))
    b = build_lift(loads_scene(eccentric_scene(extra='rotation = "30 deg"')))
    th = np.linspace(0, 2 * np.pi, 50)
    # turning the cam by +30 deg in its own frame makes events come 30 deg earlier
    assert np.allclose(b.derivatives(th)[0], a.derivatives(th + np.radians(30))[0], atol=1e-15)


def test_points_inline_and_csv_give_the_same_lift(tmp_path):
    contour = np.array(schenker_arcs(PAPER_DESIGN), dtype=object)
    from explorer.lift.contours.arcs import build_arc_contour

    pts = build_arc_contour(list(contour)).points_by_arc_length(720) * 1e3
    inline = "points = [" + ", ".join(f"[{float(x)!r}, {float(y)!r}]" for x, y in pts) + "]"
    head = HEAD.format(base="22.3 mm", roller="10 mm", offset="0 mm")
    a = loads_scene(head + '[cam]\nunit = "mm"\n' + inline + "\n")
    csv = tmp_path / "cam.csv"
    csv.write_text("x_mm, y_mm\n" + "\n".join(f"{float(x)!r}, {float(y)!r}" for x, y in pts[::-1]) + "\n")  # other direction
    scene_file = tmp_path / "s.toml"
    scene_file.write_text(head + '[cam]\nunit = "mm"\nfile = "cam.csv"\n')
    b = load_scene(scene_file)
    th = np.linspace(0, 2 * np.pi, 500)
    la, lb = build_lift(a), build_lift(b)
    assert np.allclose(la.derivatives(th)[0], lb.derivatives(th)[0], rtol=0, atol=1e-12)
    # and close to the exact arc lift (720 points: see the accuracy study, ~1e-7 m)
    exact = build_lift(load_scene(SCENES / "schenker1902_fig2.toml"))
    assert np.max(np.abs(la.derivatives(th)[0] - exact.derivatives(th)[0])) < 3e-7


BAD_CAM = [
    # (cam text, follower overrides, expected key, expected words)
    ('[[cam.arcs]]\nx = "0 mm"\ny = "-10 mm"\nradius = "-50 mm"\n', {}, "cam.arcs[0].radius", "greater than zero"),
    ('[[cam.arcs]]\nx = "0 mm"\ny = "-10 mm"\nradius = "50 kg"\n', {}, "cam.arcs[0].radius", "not a length"),
    ('[[cam.arcs]]\nx = "0 mm"\ny = "-10 mm"\nradius = "50 mm"\nkind = "flat"\n', {}, "cam.arcs[0].kind", "unknown value"),
    ('[[cam.arcs]]\nx = "0 mm"\ny = "-10 mm"\nradius = "50 mm"\ncolour = 1\n', {}, "cam.arcs[0].colour", "unknown key"),
    ('[[cam.arcs]]\nx = "0 mm"\ny = "-60 mm"\nradius = "50 mm"\n', {}, "cam.arcs[0].x", "wind once"),
    ('arcs = []\n', {}, "cam.arcs", "list of arc tables"),
    ('unit = "mm"\n', {}, "cam", "exactly one of"),
    ('points = [[1, 2], [3, 4]]\n[[cam.arcs]]\nx = 0\ny = 0\nradius = 1\n', {}, "cam", "exactly one of"),
    ('points = [[40.0, 0.0], [0.0, 40.0], [-40.0, 0.0]]\nunit = "mm"\n', {}, "cam.points", "at least"),
    ('points = "many"\n', {}, "cam.points", "number pairs"),
    ('file = "nowhere.csv"\n', {}, "cam.file", "not found"),
    ('[[cam.arcs]]\nx = "0 mm"\ny = "-10 mm"\nradius = "50 mm"\n', {"base": "30 mm"}, "follower.base_radius", "40 mm"),
    ('[[cam.arcs]]\nx = "0 mm"\ny = "-10 mm"\nradius = "50 mm"\n', {"offset": "70 mm"}, "follower.offset", "offset"),
]


@pytest.mark.parametrize("cam,follower,key,words", BAD_CAM)
def test_bad_cam_sections(cam, follower, key, words):
    fields = dict(base="40 mm", roller="15 mm", offset="0 mm") | follower
    with pytest.raises(InputError) as info:
        loads_scene(HEAD.format(**fields) + "[cam]\n" + cam, source="bad.toml")
    assert info.value.key == key, info.value
    assert words in info.value.reason


def test_arcs_that_do_not_touch():
    arcs = schenker_arcs(PAPER_DESIGN)
    lines = ["[cam]"]
    for i, a in enumerate(arcs):
        dx = 0.05 if i == 3 else 0.0  # move CD by 50 um
        lines += ["[[cam.arcs]]", f'x = "{a.x * 1e3 + dx:.9f} mm"', f'y = "{a.y * 1e3:.9f} mm"',
                  f'radius = "{a.radius * 1e3:.6g} mm"', f'kind = "{"concave" if a.concave else "convex"}"']
    text = HEAD.format(base="22.3 mm", roller="10 mm", offset="0 mm") + "\n".join(lines) + "\n"
    with pytest.raises(InputError) as info:
        loads_scene(text)
    assert info.value.key in ("cam.arcs[3].x", "cam.arcs[4].x")
    assert "not tangent" in info.value.reason and "mm" in info.value.reason
    # with a looser tolerance the same cam is accepted
    loads_scene(text.replace("[cam]", '[cam]\ntolerance = "0.1 mm"'))


def test_cam_section_needs_the_contour_law():
    text = eccentric_scene().replace('law = "contour"', 'law = "cycloidal"\nheight = "5 mm"\nrise = "90 deg"')
    with pytest.raises(InputError) as info:
        loads_scene(text)
    assert info.value.key == "cam" and "contour" in info.value.reason


def test_roller_too_big_for_the_hollow_is_an_undercut(tmp_path):
    text = (SCENES / "schenker1902_fig2.toml").read_text()
    bad = tmp_path / "big_roller.toml"
    bad.write_text(text.replace('roller_radius = "10 mm"', 'roller_radius = "90 mm"').replace('base_radius = "22.3 mm"', 'base_radius = "22.3 mm"'))
    with pytest.raises(InputError) as info:
        load_scene(bad)
    assert info.value.key == "follower.roller_radius" and "undercut" in info.value.reason


def test_undercut_in_kinematics_names_the_angle_and_cli_exits_2(tmp_path):
    scene = tmp_path / "sharp.toml"
    scene.write_text("""
name = "sharp"
effects = ["kinematics"]
[drive]
rpm = 1000
[lift]
law = "cycloidal"
height = "20 mm"
start = "0 deg"
rise = "40 deg"
return = "40 deg"
[follower]
base_radius = "15 mm"
roller_radius = "14 mm"
""")
    with pytest.raises(InputError) as info:
        simulate(load_scene(scene))
    assert info.value.key == "follower.roller_radius"
    assert "undercut" in info.value.reason and "cam angle" in info.value.reason
    out = tmp_path / "out.csv"
    proc = run_cli("simulate", scene, "-o", out)
    assert proc.returncode == 2
    assert proc.stderr.strip().startswith(f"error: {scene}: follower.roller_radius: undercut")
    assert "Traceback" not in proc.stderr and not out.exists()


def test_geometry_columns_for_law_scenes_and_cam_contour():
    scene = load_scene(SCENES / "cycloidal_demo.toml")
    result = simulate(scene)
    for name in ("pressure_angle_deg", "pitch_radius_m", "contour_radius_m"):
        assert result.columns[name].shape == result.columns["cam_angle_deg"].shape
    # on the base circle: pressure angle 0, pitch radius base + roller
    base = result.columns["follower_lift_m"] == 0.0
    assert np.allclose(result.columns["pressure_angle_deg"][base], 0.0, atol=1e-12)
    assert np.allclose(result.columns["pitch_radius_m"][base], 0.042, rtol=1e-12)
    # the summary's figure is exact (tests/test_contour_extremes.py): at least the samples' largest,
    # and within the sampling's second-order error of it (0.1 deg steps: ~4e-6 relative here)
    sampled = np.abs(result.columns["pressure_angle_deg"]).max()
    assert sampled <= result.summary["max_abs_pressure_angle_deg"] == pytest.approx(sampled, rel=1e-5)
    pts = cam_contour(scene, n=360)
    assert pts.shape == (360, 2)
    pitch = pitch_curve(scene, n=360)
    assert np.allclose(np.hypot(*(pitch - pts).T), 0.012, rtol=1e-12)


def test_cam_contour_of_an_arc_cam_lies_on_its_arcs():
    """The envelope of the roller over the lift analysed from the arcs is the arcs themselves:
    every cam_contour point is on its arc (distance to the centre = radius) to ~1e-12 m."""
    scene = load_scene(SCENES / "schenker1902_fig2.toml")
    lift = build_lift(scene)
    pts = cam_contour(scene, lift, n=3600)
    theta = np.arange(3600) * 2 * np.pi / 3600
    active = lift.active_arc(theta)
    for k, arc in enumerate(lift.contour.arcs):
        sel = active == k
        dist = np.hypot(pts[sel, 0] - arc.x, pts[sel, 1] - arc.y)
        assert np.allclose(dist, arc.radius, rtol=0, atol=1e-11), arc.name


@settings(max_examples=30, deadline=None)
@given(
    radius=st.one_of(st.floats(-1e3, 1e3), st.just(float("nan")), st.just(float("inf"))),
    x=st.floats(-0.2, 0.2),
    unit=st.sampled_from(["mm", "m", "kg", "deg", "", "N"]),
)
def test_random_single_arcs_fail_cleanly_or_load(radius, x, unit):
    """Whatever the numbers, the result is a scene or one InputError - never another exception."""
    text = HEAD.format(base="10 mm", roller="5 mm", offset="0 mm") + (
        f'[cam]\n[[cam.arcs]]\nx = "{x} {unit}"\ny = "0 mm"\nradius = "{radius} {unit}"\n'
    )
    try:
        scene = loads_scene(text)
    except InputError as exc:
        assert exc.key.startswith(("cam", "follower"))
        return
    assert scene.cam.kind == "arcs"
    assert math.isclose(scene.follower.base_radius, scene.cam.min_radius, abs_tol=1e-6)


@pytest.mark.parametrize("radius,reason", [("2.2e-311 mm", "at least"), ("1e-4 mm", "at least"), ("11 m", "at most")])
def test_arc_radius_outside_any_cam_is_refused(radius, reason):
    """Subnormal radii once reached a ZeroDivisionError in the tangency arithmetic (hypothesis)."""
    text = HEAD.format(base="10 mm", roller="5 mm", offset="0 mm") + (
        f'[cam]\n[[cam.arcs]]\nx = "0 mm"\ny = "0 mm"\nradius = "{radius}"\n'
    )
    with pytest.raises(InputError) as info:
        loads_scene(text)
    assert info.value.key == "cam.arcs[0].radius" and reason in info.value.reason


def test_cam_spec_equality_and_description():
    from explorer.lift.contours.spec import describe

    a = load_scene(SCENES / "schenker1902_fig2.toml")
    b = load_scene(SCENES / "schenker1902_fig2.toml", ["drive.rpm=300"])
    c = load_scene(SCENES / "schenker1902_fig2.toml", ["cam.rotation=5"])
    assert a.cam == b.cam and hash(a.cam) == hash(b.cam)
    assert a.cam != c.cam
    info = describe(a.cam)
    assert info["kind"] == "arcs" and [x["name"] for x in info["arcs"]][4] == "DE dwell"
    # the arcs' sweeps about their own centres close the contour: the tangent turns once
    turning = sum(-x["sweep_deg"] if x["kind"] == "convex" else x["sweep_deg"] for x in info["arcs"])
    assert turning == pytest.approx(-360.0, abs=1e-9)
    assert info["min_radius_m"] == pytest.approx(0.0223, abs=1e-12)
