"""`explorer export`: every format read back and measured against the exact cam.

Oracles: the cam contour of Schenker's Fig. 2 is circular arcs (explorer.lift.contours.arcs), so its
exported polylines are checked against the circles themselves; the law cam (cycloidal demo)
against the closed form |pitch| = base + roller + L(theta) (no offset) and dense exact samples.
Distances to a polyline are exact point-to-segment distances; "dense" exact samples are spaced
~0.5 um apart, whose own chord error (spacing^2 / 8 rho) is ~1e-12 m.
"""

from __future__ import annotations

import io
import math
import re

import numpy as np
import pytest
import trimesh

from conftest import SCENES
from explorer import cli
from explorer.view import exports
from explorer.effects.lift import build_lift
from explorer.scene.scene import load_scene

DEMO = SCENES / "cycloidal_demo.toml"
FIG2 = SCENES / "schenker1902_fig2.toml"
ERROR_LINE = re.compile(r"^error: [^:\n]+: [^:\n]+: .+$")


def polyline_distance(points: np.ndarray, poly: np.ndarray, k: int = 8) -> np.ndarray:
    """Distance of each point to the closed polyline `poly` (exact, via the segments next to the
    k nearest vertices; the polylines here are fine enough that the nearest segment is among them)."""
    from scipy.spatial import cKDTree

    _, idx = cKDTree(poly).query(points, k=k)
    n = len(poly)
    best = np.full(len(points), np.inf)
    for shift in (-1, 0):
        a = poly[(idx + shift) % n]
        b = poly[(idx + shift + 1) % n]
        d = exports._segment_distance(points[:, None, :], a, b).min(axis=1)
        best = np.minimum(best, d)
    return best


def dense_exact(src, which="contour", n=400_000):
    theta = np.unique(np.concatenate([np.linspace(0, 2 * math.pi, n, endpoint=False), src.breakpoints()]))
    return getattr(src.at(theta), which)


def arc_distance(points: np.ndarray, arcs) -> np.ndarray:
    """Distance of points to the nearest of the cam's circles (the exact contour's carriers)."""
    d = np.full(len(points), np.inf)
    for arc in arcs:
        d = np.minimum(d, np.abs(np.hypot(points[:, 0] - arc.x, points[:, 1] - arc.y) - arc.radius))
    return d


def header_and_rows(text: str) -> tuple[list[str], list[str]]:
    """(comment lines, the rest) of an exported table: '#' lines, then the header, then the rows."""
    lines = text.splitlines()
    n = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    return lines[:n], lines[n:]


def load_table(out) -> np.ndarray:
    """The numbers of an exported table (a path or its text), below its comments and header."""
    text = out if isinstance(out, str) else out.read_text()
    _, rest = header_and_rows(text)
    return np.loadtxt(io.StringIO("\n".join(rest[1:])), delimiter=",", ndmin=2)


def export(tmp_path, scene, fmt, *options, name=None):
    out = tmp_path / (name or f"cam.{ 'csv' if fmt == 'grind' else fmt}")
    assert cli.main(["export", str(scene), "--format", fmt, "-o", str(out), *map(str, options)]) == 0
    return out


def test_point_table_is_the_closed_form(tmp_path):
    """Rows: |pitch| = base + roller + L (offset 0), contour = pitch - r n, unit normals normal to
    the contour, curvatures against a converged central difference of the exact points."""
    scene = load_scene(DEMO)
    out = export(tmp_path, DEMO, "csv", "--points", 720)
    table = load_table(out)
    theta = np.radians(table[:, 0])
    contour, pitch, normal = table[:, 1:3], table[:, 3:5], table[:, 5:7]
    f = scene.follower
    lift = build_lift(scene).derivatives(theta)[0]
    assert len(table) >= 720
    np.testing.assert_allclose(np.hypot(*pitch.T), f.base_radius + f.roller_radius + lift, rtol=0, atol=1e-15)
    np.testing.assert_allclose(contour, pitch - f.roller_radius * normal, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.hypot(*normal.T), 1.0, atol=1e-15)
    src = exports.cam_source(scene)
    # converged central differences of the exact curve: Richardson's extrapolation of steps h and
    # h/2 (truncation ~h^4 ~ 1e-12 with the law's derivative scale, rounding ~1e-16/h^2 ~ 1e-10)
    h = 1e-3

    def differences(step):
        p_minus, p_plus = src.at(theta - step).contour, src.at(theta + step).contour
        return (p_plus - p_minus) / (2 * step), (p_plus - 2 * contour + p_minus) / step**2

    (t1, s1), (t2, s2) = differences(h), differences(h / 2)
    tangent, second = (4 * t2 - t1) / 3, (4 * s2 - s1) / 3
    moving = np.hypot(*tangent.T) > 1e-6  # where the contact point moves with theta
    assert np.max(np.abs(np.sum(tangent * normal, axis=1))[moving] / np.hypot(*tangent.T)[moving]) < 1e-8
    # signed curvature of a clockwise-running curve: -(x'y'' - y'x'') / |p'|^3 (> 0 convex)
    curvature = -(tangent[:, 0] * second[:, 1] - tangent[:, 1] * second[:, 0]) / np.hypot(*tangent.T) ** 3
    smooth = moving & (np.min(np.abs(theta[:, None] - src.breakpoints()[None, :]), axis=1) > 2 * h)
    np.testing.assert_allclose(table[smooth, 7], curvature[smooth], rtol=1e-7, atol=1e-7)
    base = np.abs(theta - math.radians(200)) < math.radians(20)  # on the base circle
    np.testing.assert_allclose(table[base, 7], 1 / f.base_radius, rtol=1e-13)
    np.testing.assert_allclose(table[base, 8], 1 / (f.base_radius + f.roller_radius), rtol=1e-13)


@pytest.mark.parametrize("tolerance", [1e-6, 1e-5])
def test_dxf_law_cam_within_tolerance(tmp_path, tolerance):
    import ezdxf

    out = export(tmp_path, DEMO, "dxf", "--tolerance", f"{tolerance * 1e3} mm")
    doc = ezdxf.readfile(out)
    assert doc.header["$INSUNITS"] == 4  # millimetres
    src = exports.cam_source(load_scene(DEMO))
    for layer, which in (("CAM", "contour"), ("PITCH", "pitch")):
        (poly,) = doc.modelspace().query(f'LWPOLYLINE[layer=="{layer}"]')
        assert poly.closed
        xy = np.array([(x, y) for x, y, *_ in poly.get_points()]) * 1e-3
        exact = dense_exact(src, which)
        worst = polyline_distance(exact, xy).max()
        assert worst <= tolerance
        assert worst > 0.1 * tolerance  # the chords use the tolerance: not a needlessly dense polyline
        # every vertex on the exact curve (the DXF's decimal text round-trips doubles)
        assert polyline_distance(xy, exact).max() < 1e-11


def test_dxf_arc_cam_against_its_circles(tmp_path):
    import ezdxf

    tolerance = 1e-6
    out = export(tmp_path, FIG2, "dxf", "--tolerance", "0.001 mm")
    scene = load_scene(FIG2)
    (poly,) = ezdxf.readfile(out).modelspace().query('LWPOLYLINE[layer=="CAM"]')
    xy = np.array([(x, y) for x, y, *_ in poly.get_points()]) * 1e-3
    arcs = scene.cam.arcs.arcs
    assert arc_distance(xy, arcs).max() < 1e-11  # vertices on the arcs (the arc-cam lift is exact)
    # the arcs themselves, densely sampled, against the chords
    contour = scene.cam.arcs
    samples = []
    for start, angle0, sweep, arc in zip(contour.start, contour.start_angle, contour.sweep, arcs):
        phi = angle0 + np.linspace(0.0, sweep, max(2000, int(abs(sweep) * arc.radius / 1e-7)))
        samples.append(np.column_stack([arc.x + arc.radius * np.cos(phi), arc.y + arc.radius * np.sin(phi)]))
    samples = np.vstack(samples)
    np.testing.assert_allclose(samples[0], contour.start[0], atol=1e-9)  # (the sampling starts on the contour)
    assert polyline_distance(samples, xy).max() <= tolerance


def rim(mesh, z: float) -> np.ndarray:
    """The contour polygon of an extruded cam: its vertices in the plane z, without the cap's
    centre vertex, in order of polar angle (the cams here are star-shaped about the shaft)."""
    v = np.unique(mesh.vertices[np.abs(mesh.vertices[:, 2] - z) < 1e-9 * max(1.0, abs(z))][:, :2], axis=0)
    v = v[np.hypot(*v.T) > 1e-6]
    return v[np.argsort(np.arctan2(v[:, 1], v[:, 0]))]


def test_stl_solid_within_tolerance(tmp_path):
    scene = load_scene(DEMO)
    out = export(tmp_path, DEMO, "stl", "--tolerance", "0.002 mm", "--width", "12 mm")
    mesh = trimesh.load(out, file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    z = mesh.vertices[:, 2]
    np.testing.assert_allclose([z.min(), z.max()], [-6.0, 6.0], atol=1e-5)  # mm, float32
    exact = dense_exact(exports.cam_source(scene))
    for face in (-6.0, 6.0):
        xy = rim(mesh, face) * 1e-3
        # STL stores float32: half an ulp of 52 mm is 1.9e-9 m per coordinate
        assert polyline_distance(xy, exact).max() < 5e-9
        assert polyline_distance(exact, xy).max() <= 2e-6 + 5e-9
    # volume: the polygon's area times the width (shoelace)
    xy = rim(mesh, 6.0) * 1e-3
    area = 0.5 * abs(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
    assert mesh.volume * 1e-9 == pytest.approx(area * 0.012, rel=1e-5)


def test_glb_solid_in_metres(tmp_path):
    scene = load_scene(FIG2)
    out = export(tmp_path, FIG2, "glb", "--tolerance", "0.01 mm")
    mesh = trimesh.load(out, file_type="glb", force="mesh")
    mesh.merge_vertices(merge_tex=True, merge_norm=True)  # caps and side carry their own vertices (sharp edges when shaded)
    assert mesh.is_watertight
    half = 0.5 * (mesh.vertices[:, 2].max() - mesh.vertices[:, 2].min())
    xy = rim(mesh, mesh.vertices[:, 2].max())
    assert half > 0.005  # metres: the 3D view's cam width
    assert arc_distance(xy, scene.cam.arcs.arcs).max() < 1e-8  # float32 vertices in glTF: ~5e-9 m at 0.07 m
    exact = dense_exact(exports.cam_source(scene))
    assert polyline_distance(exact, xy).max() <= 1e-5 + 1e-8


def test_grinding_table_with_the_roller_is_the_lift(tmp_path):
    """Wheel radius = roller radius, no offset: the wheel is the roller, the grinder angle the cam
    angle, and the wheel centre base + roller + L."""
    scene = load_scene(DEMO)
    r = scene.follower.roller_radius
    out = export(tmp_path, DEMO, "grind", "--grinding-wheel-radius", f"{r * 1e3} mm", "--points", 1440)
    table = load_table(out)
    alpha = np.radians(table[:, 0])
    np.testing.assert_allclose(table[:, 0], np.arange(1440) * 0.25, atol=1e-12)
    np.testing.assert_allclose(np.radians(table[:, 2]), alpha, atol=1e-12)
    lift = build_lift(scene).derivatives(alpha)[0]
    np.testing.assert_allclose(table[:, 1], scene.follower.base_radius + r + lift, rtol=0, atol=1e-13)


def test_grinding_table_wheel_touches_the_arcs(tmp_path):
    """Schenker's arc cam, 40 mm wheel: at every row the wheel circle touches the cam's circles
    and cuts into none (distance from the wheel centre to the contour = wheel radius)."""
    scene = load_scene(FIG2)
    wheel = 0.04
    out = export(tmp_path, FIG2, "grind", "--grinding-wheel-radius", "40 mm", "--points", 720)
    table = load_table(out)
    alpha, centre = np.radians(table[:, 0]), table[:, 1]
    # the wheel centre in the cam frame: on the ground y axis, rotated back by the grinder angle
    psi = 0.5 * math.pi - alpha
    wc = np.column_stack([centre * np.cos(psi), centre * np.sin(psi)])
    exact = dense_exact(exports.cam_source(scene), n=200_000)
    from scipy.spatial import cKDTree

    nearest, _ = cKDTree(exact).query(wc)
    assert np.max(np.abs(nearest - wheel)) < 1e-8  # the dense samples' spacing limits this (~1e-6 m apart)
    # touching: the closest exact point from the circle-circle distance, against the arcs
    arcs = scene.cam.arcs.arcs
    gaps = np.array([[math.hypot(p[0] - a.x, p[1] - a.y) - (wheel + a.radius) if not a.concave
                      else (a.radius - wheel) - math.hypot(p[0] - a.x, p[1] - a.y) for a in arcs] for p in wc])
    assert np.all(np.min(np.abs(gaps), axis=1) < 1e-10)  # tangent to (at least) one arc at every row


def test_grinding_table_row_count_and_header(tmp_path):
    out = export(tmp_path, FIG2, "grind", "--grinding-wheel-radius", "0.05 m", "--points", 8)
    comments, lines = header_and_rows(out.read_text())
    assert lines[0] == "grinder_angle_deg,wheel_centre_m,cam_angle_deg"
    assert len(lines) == 1 + 8
    assert comments[0].endswith("cut for: translating-roller, roller of radius 10 mm (another follower on this "
                                "contour gives another lift)")


BAD = [
    (["--format", "dxf", "--tolerance", "0 mm"], "--tolerance", "positive"),
    (["--format", "dxf", "--tolerance", "1 kg"], "--tolerance", "length"),
    (["--format", "dxf", "--tolerance", "1e-12 m"], "--tolerance", "between"),
    (["--format", "dxf", "--tolerance", "nan mm"], "--tolerance", ""),
    (["--format", "csv", "--width", "10 mm"], "--width", "not used"),
    (["--format", "stl", "--grinding-wheel-radius", "10 mm"], "--grinding-wheel-radius", "not used"),
    (["--format", "grind"], "--grinding-wheel-radius", "needs the wheel radius"),
    (["--format", "grind", "--grinding-wheel-radius", "-5 mm"], "--grinding-wheel-radius", "positive"),
    (["--format", "csv", "--points", "3"], "--points", "between"),
    (["--format", "stl", "--width", "1e5 m"], "--width", "10 m"),
    (["--format", "csv", "--wheel-margin", "0.1"], "--wheel-margin", "not used"),
    (["--format", "grind", "--grinding-wheel-radius", "5 mm", "--wheel-margin", "1.5"], "--wheel-margin", "[0, 1)"),
    (["--format", "grind", "--grinding-wheel-radius", "5 mm", "--wheel-margin", "nan"], "--wheel-margin", "[0, 1)"),
]


@pytest.mark.parametrize("args,key,reason", BAD)
def test_bad_options_one_line_nothing_written(tmp_path, capsys, args, key, reason):
    out = tmp_path / "x.out"
    assert cli.main(["export", str(DEMO), "-o", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert ERROR_LINE.match(err) and f": {key}: " in err and reason in err, err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_bad_scene_and_paths(tmp_path, capsys):
    directory = tmp_path / "solid.stl"  # named as the format's file would be: only its kind is wrong
    directory.mkdir()
    cases = [
        ([str(SCENES / "pivoted_roller_lever.toml"), "--format", "dxf"], "follower.type"),
        ([str(FIG2), "--format", "grind", "--grinding-wheel-radius", "150 mm"], "concave flank of radius 86.1 mm"),
        ([str(DEMO), "--format", "stl", "-o", str(directory)], "is a directory"),
        ([str(DEMO), "--format", "dxf", "-o", str(tmp_path / "missing" / "x.dxf")], "does not exist"),
        ([str(DEMO), "--format", "dxf", "--set", "lift.rise=\"20 deg\"", "--set", "lift.return=\"20 deg\""], "undercut"),
    ]
    for args, text in cases:
        before = sorted(tmp_path.iterdir())
        assert cli.main(["export", *args]) == 2
        err = capsys.readouterr().err.strip()
        assert ERROR_LINE.match(err) and text in err, err
        assert sorted(tmp_path.iterdir()) == before


def test_tolerance_too_fine_for_the_point_budget():
    src = exports.cam_source(load_scene(DEMO))
    with pytest.raises(exports.InputError, match="needs more than 1000 points"):
        exports.chord_polyline(lambda t: src.at(t).contour, 1e-9, src.breakpoints(), max_points=1000)


def test_csv_to_stdout(capfd):
    assert cli.main(["export", str(DEMO), "--format", "csv", "--points", "16", "-o", "-"]) == 0
    text = capfd.readouterr().out
    table = load_table(text)
    assert table.shape[1] == 10 and len(table) >= 16


def test_real_command_one_line(tmp_path):
    """What a user sees: `python -m explorer export` with a bad option, in a subprocess."""
    from conftest import run_cli

    proc = run_cli("export", DEMO, "--format", "grind", "-o", tmp_path / "g.csv")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.count("\n") == 1 and ERROR_LINE.match(proc.stderr.strip()), proc.stderr
    assert list(tmp_path.iterdir()) == []
    proc = run_cli("export", DEMO, "--format", "dxf", "-o", tmp_path / "cam.dxf")
    assert proc.returncode == 0 and (tmp_path / "cam.dxf").read_text().startswith("  0\nSECTION")


@pytest.mark.parametrize("wheel_mm", [100.0, 300.0])
def test_grinding_a_convex_cam_with_any_wheel(tmp_path, wheel_mm):
    """A convex cam (the spline demo) grinds with any wheel; a breakpoint that coincides with a
    grid angle (204 deg) once made a zero step that read as the path winding back."""
    scene_path = SCENES / "spline_demo.toml"
    out = export(tmp_path, scene_path, "grind", "--grinding-wheel-radius", f"{wheel_mm} mm", "--points", 720)
    table = load_table(out)
    psi = 0.5 * math.pi - np.radians(table[:, 0])
    wc = table[:, 1:2] * np.column_stack([np.cos(psi), np.sin(psi)])
    from scipy.spatial import cKDTree

    nearest, _ = cKDTree(dense_exact(exports.cam_source(load_scene(scene_path)), n=200_000)).query(wc)
    assert np.max(np.abs(nearest - wheel_mm * 1e-3)) < 1e-8


# -- face followers: what the columns hold, and the follower the cam is cut for ----------------
BUCKET = SCENES / "bucket_tappet.toml"


def _flat_bucket(tmp_path):
    """bucket_tappet.toml with its crown left out: a flat face."""
    text = BUCKET.read_text()
    assert 'face_radius = "3 m"' in text
    path = tmp_path / "flat_bucket.toml"
    path.write_text("\n".join(line for line in text.splitlines() if not line.startswith("face_radius")) + "\n")
    return path


def test_crowned_bucket_csv_exports_the_crown_centre(tmp_path):
    """A crowned face's centre path, checked three independent ways: (1) crown centre = contact +
    Rf n from the file's own columns; (2) its distance from the cam axis is Rb + Rf + L(theta) (the
    crown's centre rides the tappet's axis at that height, the lift from the law itself); (3) it is
    the pitch curve of a translating roller of radius Rf (explorer.lift.contours.cam_profile's
    closed forms, a different code path), curvature included; and the crown's circle about each
    centre touches the exact contour without cutting it (the envelope property)."""
    from scipy.spatial import cKDTree

    from explorer.lift.contours.cam_profile import TranslatingCam

    scene = load_scene(BUCKET)
    out = export(tmp_path, BUCKET, "csv", "--points", 720)
    comments, lines = header_and_rows(out.read_text())
    names = lines[0].split(",")
    assert not any(n.startswith("pitch") for n in names)  # the header no longer speaks of a roller
    assert names == ["cam_angle_deg", "contour_x_m", "contour_y_m", "face_centre_x_m", "face_centre_y_m", "normal_x",
                     "normal_y", "contour_curvature_1_m", "face_centre_curvature_1_m", "pressure_angle_deg"]
    col = dict(zip(names, load_table(out).T))
    rf, rb = 3.0, scene.follower.base_radius
    theta = np.radians(col["cam_angle_deg"])
    contour = np.column_stack([col["contour_x_m"], col["contour_y_m"]])
    normal = np.column_stack([col["normal_x"], col["normal_y"]])
    centre = np.column_stack([col["face_centre_x_m"], col["face_centre_y_m"]])
    # (1) 3 m times a unit normal written to 17 digits: a few 1e-16 m relative of 3 m
    np.testing.assert_allclose(centre, contour + rf * normal, rtol=0, atol=1e-14)
    # (2) the lift from the law, not from the gear's kinematics
    lift = build_lift(scene).derivatives(theta)[0]
    np.testing.assert_allclose(np.hypot(*centre.T), rb + rf + lift, rtol=0, atol=1e-14)
    # (3) a translating roller of radius Rf on the same lift: its pitch curve and curvature
    roller = TranslatingCam(build_lift(scene), rb, rf, 0.0, "", "").at(theta)
    np.testing.assert_allclose(centre, roller.pitch, rtol=0, atol=1e-14)
    np.testing.assert_allclose(col["face_centre_curvature_1_m"], roller.pitch_curvature, rtol=1e-12, atol=0)
    # the crown circle touches the dense exact contour (spacing ~0.4 um: the chord sag on a
    # 3 m circle is far below 1e-10 m) and never reaches inside it
    dense = dense_exact(exports.cam_source(scene), n=400_000)
    nearest, _ = cKDTree(dense).query(centre)
    np.testing.assert_allclose(nearest, rf, rtol=0, atol=1e-10)
    assert comments[0].endswith("cut for: bucket-tappet, crowned (curved) face of radius 3000 mm (another follower on "
                                "this contour gives another lift)")


def test_flat_bucket_csv_has_no_pitch_columns(tmp_path):
    """A flat face has no centre to trace: no columns that would repeat the contour, a header that
    says so, and the file names the flat face it is cut for; the DXF has no centre layer."""
    import ezdxf

    scene = _flat_bucket(tmp_path)
    out = export(tmp_path, scene, "csv", "--points", 36)
    comments, lines = header_and_rows(out.read_text())
    assert lines[0] == ("cam_angle_deg,contour_x_m,contour_y_m,normal_x,normal_y,contour_curvature_1_m,"
                        "pressure_angle_deg")
    assert "cut for: bucket-tappet, flat face" in comments[0]
    assert any("no pitch columns" in c for c in comments)
    table = load_table(out)
    col = dict(zip(lines[0].split(","), table.T))
    # the flat face's contact: |contour|^2 = (Rb + s)^2 + s'^2 (Norton's closed form)
    d = build_lift(load_scene(scene)).derivatives(np.radians(col["cam_angle_deg"]))
    np.testing.assert_allclose(np.hypot(col["contour_x_m"], col["contour_y_m"]),
                               np.hypot(0.018 + d[0], d[1]), rtol=0, atol=1e-15)
    doc = ezdxf.readfile(export(tmp_path, scene, "dxf"))
    assert {e.dxf.layer for e in doc.modelspace()} == {"CAM", "NOTES"}


@pytest.mark.parametrize("scene, says", [
    (BUCKET, "bucket-tappet, crowned (curved) face of radius 3000 mm"),
    (DEMO, "translating-roller, roller of radius 12 mm"),
    (SCENES / "finger_follower.toml", "finger-follower, roller of radius 9 mm"),
])
def test_every_file_names_the_follower_it_is_cut_for(tmp_path, scene, says):
    """A cam is cut for its own follower (a 3 m crown's cam read by a flat tappet lifts e^2/2R
    less): the csv's and the grinding table's first comment line, and the DXF's note (TEXT on
    layer NOTES) and custom header property CUT_FOR, say which, so the file alone tells a machinist."""
    import ezdxf

    for fmt, options in (("csv", ("--points", 16)), ("grind", ("--points", 16, "--grinding-wheel-radius", "5 mm"))):
        comments, _ = header_and_rows(export(tmp_path, scene, fmt, *options, name=f"{fmt}.csv").read_text())
        assert f"cut for: {says} " in comments[0]
    doc = ezdxf.readfile(export(tmp_path, scene, "dxf", "--tolerance", "10 um"))
    (text,) = doc.modelspace().query('TEXT[layer=="NOTES"]')
    assert f"cut for: {says} " in text.dxf.text
    assert f"cut for: {says} " in doc.header.custom_vars.get("CUT_FOR")


# -- the grinding wheel at the concave flank's radius ---------------------------------------------
FLANK_MM = 86.1  # Schenker's hollow FG: the contour's concave arc (schenker1902_fig2.toml, [[cam.arc]])


@pytest.mark.parametrize("wheel_mm, margin, outcome", [
    (FLANK_MM * (1 - 0.06), None, "clean"),  # 6 % below: outside the default 5 % margin
    (FLANK_MM * (1 - 1e-6), None, "warned"),  # just below: groundable, but no room for the wheel's tolerance
    (FLANK_MM * (1 - 1e-6), "0", "clean"),  # the margin is the user's: 0 accepts it silently
    (FLANK_MM, None, "refused"),  # at the limit: conforms to the flank, refused
    (FLANK_MM * (1 + 1e-6), None, "refused"),  # just above: cuts the flank
])
def test_grinding_wheel_at_the_concave_flank(tmp_path, capsys, wheel_mm, margin, outcome):
    """A wheel the size of the smallest concave radius is refused (it was accepted to the
    rounding of -1/curvature before), one within --wheel-margin below it warned of, in one line on
    stderr and in the table's header; the arc's radius is the oracle."""
    out = tmp_path / "g.csv"
    options = ["--wheel-margin", margin] if margin is not None else []
    code = cli.main(["export", str(FIG2), "--format", "grind", "--points", "16", "--grinding-wheel-radius",
                     f"{wheel_mm!r} mm", "-o", str(out), *options])
    err = capsys.readouterr().err
    if outcome == "refused":
        assert code == 2 and not out.exists()
        (line,) = err.splitlines()
        assert ERROR_LINE.match(line) and "cannot grind the concave flank of radius 86.1 mm" in line
        return
    assert code == 0
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    comments, _ = header_and_rows(out.read_text())
    if outcome == "warned":
        (line,) = warnings
        assert "within 0.05 of the concave flank's radius 86.1 mm" in line
        assert comments[1] == "# " + line
    else:
        assert warnings == [] and not any("warning" in c for c in comments)


def test_smallest_concave_radius_is_refined_between_samples():
    """The polydyne cam's smallest concave radius lies between samples: refined from 28 800
    samples it equals the minimum of 4 million samples to 1e-10 relative (their own sampling
    error, 2nd order in the 1.6e-6 rad spacing, ~1e-11), and is never above the sampled one."""
    from explorer.lift.contours.cam_profile import angles_with

    src = exports.cam_source(load_scene(SCENES / "polydyne_demo.toml"))
    coarse = angles_with(28_800, src.breakpoints())
    k = src.at(coarse).contour_curvature
    radius, _ = exports.smallest_concave_radius(src, coarse, k)
    dense = angles_with(4_000_000, src.breakpoints())
    reference = -1.0 / src.at(dense).contour_curvature.min()
    assert radius <= -1.0 / k.min()
    assert abs(radius - reference) < 1e-10 * reference


def test_a_flat_tappet_on_the_crowned_cam_lifts_more_by_e2_over_2r(tmp_path):
    """Why a file must name its follower, measured: the bucket cam is cut for its 3 m crown; a flat
    tappet on the same contour rests on its highest point along the axis (the support function of
    the exported contour, here of 400 000 exact points: h(theta) = max p . (sin, cos) - Rb), which
    is the crown's contact point or higher, and that point stands e^2/(2 Rf) above the crown's
    lowest point (a circle's sag at offset e). So the flat tappet lifts MORE, by e^2/(2 Rf) to
    leading order (21.2 um at the widest contact offset, 11.3 mm): measured 21.40 um at 72.5 deg;
    the next order is ~1 % here (0.16 um), the tolerance 2 %. It never lifts less (1e-12 m)."""
    scene = load_scene(BUCKET)
    src = exports.cam_source(scene)
    dense = src.at(np.linspace(0.0, 2 * math.pi, 400_000, endpoint=False)).contour
    theta = np.linspace(0.0, 2 * math.pi, 720, endpoint=False)
    flat = np.array([np.max(dense[:, 0] * math.sin(t) + dense[:, 1] * math.cos(t)) for t in theta])
    flat -= scene.follower.base_radius
    crowned = build_lift(scene).derivatives(theta)[0]
    sag = src.gear.kinematics(theta).contact_offset ** 2 / (2.0 * 3.0)
    more = flat - crowned
    assert np.all(more > -1e-12)
    assert np.max(np.abs(more - sag)) < 0.02 * sag.max()
    assert 20e-6 < more.max() < 22e-6
