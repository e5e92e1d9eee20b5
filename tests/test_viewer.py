"""The browser explorer without a browser: drive the GUI handles from Python (assigning `.value`
fires the callbacks, as a click would) and check what the server would draw against the motion
computed independently by `simulate` + `meshes.part_poses`."""

from __future__ import annotations

import math
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

from explorer import load_scene, meshes
from explorer.effects import simulate
from explorer.viewer import model

from conftest import ROOT, SCENES, run_cli

viser = pytest.importorskip("viser")

DEMO = SCENES / "cycloidal_demo.toml"
FORCES_SCENE = SCENES / "schenker1902_intake_valve.toml"


@pytest.fixture
def app():
    from explorer.viewer.app import ExplorerApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    application = ExplorerApp(server, str(DEMO), playing=False)
    assert application.wait_applied(30)
    yield application
    application.stop()
    server.stop()
    assert application.loop_errors == 0 and application.worker.internal_errors == 0


def _node(app, name):
    return app.server.scene.get_handle_by_name(f"/gear/{name}")


def _expected(path, overrides=(), magnification=1.0):
    scene = load_scene(path, list(overrides))
    result = simulate(scene)
    return scene, result, meshes.part_poses(scene, result, magnification=magnification)


def test_scrubbing_places_every_part_at_the_computed_motion(app):
    scene, result, poses = _expected(DEMO)
    n = len(result.columns["cam_angle_deg"])
    for angle in (0.0, 37.3, 75.0, 121.9, 359.9):
        app.angle.value = angle
        assert app.wait_applied(10)
        i = model.step_index(angle, n)
        assert result.columns["cam_angle_deg"][i] == pytest.approx(angle, abs=360.0 / n / 2 + 1e-9)
        for name, (pos, quat) in poses.items():
            handle = _node(app, name)
            np.testing.assert_allclose(handle.position, pos[i], atol=1e-7, err_msg=name)
            np.testing.assert_allclose(handle.wxyz, quat[i], atol=1e-7, err_msg=name)
        # the valve's height is the computed valve lift, the follower's the computed follower lift
        lay = meshes.layout(scene, result)
        assert lay.stem_top_rest - _node(app, "valve").position[2] == pytest.approx(result.columns["valve_lift_m"][i], abs=1e-7)
        assert _node(app, "roller").position[2] - lay.prime_y == pytest.approx(result.columns["follower_lift_m"][i], abs=1e-7)
        # the spring mesh is the spring at the computed length
        spring = _node(app, "spring").vertices
        expected_spring = meshes.spring_vertices(lay, lay.spring_rest_length - result.columns["valve_lift_m"][i],
                                                 **model.SPRING_RESOLUTION)
        np.testing.assert_allclose(spring, expected_spring, atol=1e-6)
        assert app.angle.value == pytest.approx(angle)
    assert not app.playback.playing  # scrubbing pauses


def test_animation_moves_the_slider_without_feeding_back(app):
    submitted = app.worker.submitted
    app.speed.value = "1/10"
    app.play.value = True
    time.sleep(0.4)
    assert app.playback.playing  # the loop's own slider updates were not taken for scrubbing
    seen = {app.angle.value}
    for _ in range(10):
        time.sleep(0.02)
        seen.add(app.angle.value)
    assert len(seen) > 3  # the slider moves with the animation
    assert app.worker.submitted == submitted  # no recomputation was triggered by the animation
    app.play.value = False
    time.sleep(0.1)
    frozen = app.playback.angle_deg
    time.sleep(0.1)
    assert app.playback.angle_deg == frozen and frozen > 0.0
    # paused, slider and the drawn step sit exactly at the playback angle
    assert app.angle.value == pytest.approx(round(frozen, 1) % 360.0)
    n = len(app.current.result.columns["cam_angle_deg"])
    i = model.step_index(frozen, n)
    np.testing.assert_allclose(_node(app, "cam").wxyz, app.current.poses["cam"][1][i], atol=1e-7)


def test_scene_swap_replaces_the_cam_geometry_and_the_plots(app):
    before = np.array(_node(app, "cam").vertices)
    titles_before = [label for _, labels in app._plot_signature for label in labels]
    app.scene.value = FORCES_SCENE.name
    assert app.wait_applied(30)
    scene = load_scene(FORCES_SCENE)
    result = simulate(scene)
    expected = meshes.build_parts(scene, result)["cam"].vertices
    after = np.array(_node(app, "cam").vertices)
    assert after.shape != before.shape or not np.allclose(after, before)
    np.testing.assert_allclose(after, expected, atol=1e-7)
    # fields now show the new scene, plots gained its force columns
    assert app.fields["drive.rpm"].value == pytest.approx(scene.drive.rpm)
    assert app.effects["forces"].value is True
    labels = [label for _, labels in app._plot_signature for label in labels]
    assert "linkage force" in labels and "linkage force" not in titles_before
    assert "forces" in app.readout.content


@pytest.mark.parametrize(
    "key, value, needle",
    [
        ("valve.lash", "5 kg", "valve.lash"),
        ("drive.rpm", -5.0, "drive.rpm: must be greater than zero"),
        ("solver.steps_per_revolution", 10, "too few steps"),
        ("spring.rate", "lots", "spring.rate"),
        ("lift.law", "contour", "cam"),
    ],
)
def test_bad_values_are_rejected_with_a_visible_message(app, key, value, needle):
    app.angle.value = 90.0
    assert app.wait_applied(10)
    valve_before = np.array(_node(app, "valve").position)
    serial = app.applied_serial
    app.fields[key].value = value
    assert app.wait_applied(10)
    assert needle in app.error_text and app.error_text.startswith("error: ")
    assert needle.split(":")[0] in app.status.content and 'role="alert"' in app.status.content
    assert app.applied_serial == serial  # the last good motion stays on screen
    np.testing.assert_array_equal(_node(app, "valve").position, valve_before)
    assert app._thread.is_alive() and app.worker._thread.is_alive()
    # a good value clears the message
    app.fields[key].value = {"valve.lash": "0.3 mm", "drive.rpm": 3000.0, "solver.steps_per_revolution": 3600,
                             "spring.rate": "25 N/mm", "lift.law": "cycloidal"}[key]
    assert app.wait_applied(10)
    assert app.error_text == "" and "ready" in app.status.content


def test_parameter_changes_recompute_and_the_newest_wins(app):
    # eight threads hammer the rpm field as GUI callbacks would; the final motion is the last value
    values = [500.0 + 7.0 * k for k in range(400)]
    chunks = [values[i::8] for i in range(8)]
    barrier = threading.Barrier(8)

    def hammer(chunk):
        barrier.wait()
        for v in chunk:
            app.fields["drive.rpm"].value = v

    threads = [threading.Thread(target=hammer, args=(c,)) for c in chunks]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    last = 4242.0
    app.fields["drive.rpm"].value = last
    assert app.wait_applied(30)
    assert app.current.scene.drive.rpm == pytest.approx(last)
    assert app.worker.computed <= app.worker.submitted
    assert app.error_text == ""
    # the drawn motion is the motion at that speed (a lash/kinematics result does not depend on
    # rpm in angle, so check the time column that does)
    _, result, _ = _expected(DEMO, ["drive.rpm=4242.0"])
    np.testing.assert_allclose(app.current.result.columns["valve_velocity_m_s"], result.columns["valve_velocity_m_s"])


def test_magnification_enlarges_the_lash_gap(app):
    scene, result, _ = _expected(DEMO)
    app.angle.value = 0.0  # base circle: valve closed, follower at zero lift, gap = lash
    app.magnification.value = 10.0
    assert app.wait_applied(10)
    lay = app.current.layout
    gap = _node(app, "adjuster").position[2] - lay.ball_radius - _node(app, "valve").position[2]
    assert gap == pytest.approx(10.0 * scene.valve.lash, abs=1e-7)
    app.magnification.value = 1.0
    assert app.wait_applied(10)
    gap = _node(app, "adjuster").position[2] - lay.ball_radius - _node(app, "valve").position[2]
    assert gap == pytest.approx(scene.valve.lash, abs=1e-7)


def test_effect_checkbox_adds_the_force_effect(app):
    app.effects["forces"].value = True
    assert app.wait_applied(30)
    assert app.error_text == ""
    assert "forces" in app.current.scene.effects
    assert "forces" in app.current.result.summary["effects"]
    labels = [label for _, labels in app._plot_signature for label in labels]
    assert any(label.endswith("force") for label in labels)


def test_default_speed_gives_a_few_seconds_per_revolution():
    assert model.default_speed(60.0 / 3000.0) == "1/200"  # 20 ms -> 4 s
    assert model.default_speed(60.0 / 240.0) == "1/20"  # 0.25 s -> 5 s (1/20) beats 12.5 s (1/50)
    pb = model.Playback(angle_deg=350.0, playing=True, speed=0.5)
    assert pb.advance(0.1, 1.0) == pytest.approx((350.0 + 360.0 * 0.05) % 360.0)


def test_decimation_keeps_spikes_and_the_ends():
    x = np.linspace(0.0, 360.0, 36000, endpoint=False)
    y = np.sin(np.radians(x))
    y[12345] = 50.0  # a one-sample impact spike
    xs, (ys,) = model.decimate(x, [y], 720)
    assert len(xs) == 720 and ys.max() == 50.0 and ys.min() == pytest.approx(-1.0, abs=1e-6)
    assert xs[0] == 0.0 and xs[-1] == x[-1] and np.all(np.diff(xs) >= 0)


def test_override_strings_read_back_exactly():
    from explorer.scene import apply_overrides

    for key, value in [("drive.rpm", 1234.5), ("valve.lash", "0.3 mm"), ("effects", ["kinematics", "forces"]),
                       ("solver.steps_per_revolution", 720), ("valve.lash", 'x"y\\z')]:
        data = apply_overrides({}, [model.override(key, value)], "f")
        node = data
        for part in key.split(".")[:-1]:
            node = node[part]
        assert node[key.split(".")[-1]] == value


def test_serve_rejects_a_bad_scene_with_one_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\n[drive]\nrpm = -1\n")
    out = run_cli("serve", bad, "--port", "0")
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and out.stderr.startswith("error: ")
    assert "Traceback" not in out.stderr


def test_serve_prints_the_url_and_stops_cleanly_on_ctrl_c():
    proc = subprocess.Popen(
        [sys.executable, "-m", "explorer", "serve", str(DEMO), "--port", "0", "--paused"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        deadline = time.monotonic() + 60
        url = None
        while time.monotonic() < deadline and url is None:
            line = proc.stdout.readline()
            if "Valve-Gear Explorer: http://127.0.0.1:" in line:
                url = line.split()[2]
        assert url is not None
        import urllib.request

        with urllib.request.urlopen(url, timeout=10) as response:
            assert response.status == 200 and b"<html" in response.read().lower()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
        assert proc.returncode == 0, err
        assert "Traceback" not in err
    finally:
        if proc.poll() is None:
            proc.kill()


def test_only_loopback_counts_as_local():
    from explorer.cli_serve import _is_loopback

    assert _is_loopback("127.0.0.1") and _is_loopback("::1") and _is_loopback("localhost")
    assert not _is_loopback("0.0.0.0") and not _is_loopback("192.168.1.4") and not _is_loopback("example.org")


def test_reset_returns_to_the_scene_file(app):
    app.fields["drive.rpm"].value = 777.0
    app.fields["valve.lash"].value = "0.9 mm"
    assert app.wait_applied(10)
    assert app.current.scene.drive.rpm == pytest.approx(777.0)
    app.reset.value = True  # what a click sends: fires on_click
    assert app.wait_applied(10)
    scene = load_scene(DEMO)
    assert app.current.request.overrides == ()
    assert app.current.scene.drive.rpm == pytest.approx(scene.drive.rpm)
    assert app.fields["drive.rpm"].value == pytest.approx(scene.drive.rpm)
    assert app.fields["valve.lash"].value == "0.3 mm"


def test_every_new_result_goes_to_the_live_stream_once():
    from explorer.viewer.app import ExplorerApp

    logged = []
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    application = ExplorerApp(server, str(DEMO), playing=False,
                              on_result=lambda prepared: logged.append((prepared.result, prepared.label)))
    try:
        assert application.wait_applied(30)
        application.fields["drive.rpm"].value = 1234.0
        assert application.wait_applied(30)
        application.magnification.value = 5.0  # same result, only drawn differently: not logged again
        assert application.wait_applied(30)
        application.angle.value = 50.0
        assert application.wait_applied(30)
    finally:
        application.stop()
        server.stop()
    assert [label for _, label in logged] == ["cycloidal_demo.toml", "cycloidal_demo.toml  drive.rpm=1234.0"]
    assert logged[1][0].scene.drive.rpm == pytest.approx(1234.0)


def test_serve_records_to_rerun_and_finishes_the_file_on_ctrl_c(tmp_path):
    pytest.importorskip("explorer.recording_live")
    target = tmp_path / "live.rrd"
    proc = subprocess.Popen(
        [sys.executable, "-m", "explorer", "serve", str(DEMO), "--port", "0", "--paused", "--rerun-save", str(target)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        deadline = time.monotonic() + 60
        seen = ""
        while time.monotonic() < deadline and "Valve-Gear Explorer: http" not in seen:
            seen += proc.stdout.readline()
        assert "Valve-Gear Explorer: http" in seen
        time.sleep(1.0)  # the first result is computed and handed to the stream
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err
        assert target.exists() and target.stat().st_size > 0
    finally:
        if proc.poll() is None:
            proc.kill()


def test_readout_lists_every_effect_event_and_warning():
    path = SCENES / "valve_float_demo.toml"
    if not path.exists():
        pytest.skip("valve_float_demo.toml not shipped")
    result = simulate(load_scene(path))
    text = model.readout_markdown(result)
    for name, info in result.summary["effects"].items():
        assert f"| {name} | {1e3 * info['compute_time_s']:.2f} ms |" in text
    for event in result.summary["events"][:14]:
        assert f"| {event['kind']} | {event['cam_angle_deg']:.2f}° |" in text
    for warning in result.summary["warnings"]:
        assert f"- ⚠ {warning}" in text
    assert text.index("**Warnings**") < text.index("**Key figures**")
