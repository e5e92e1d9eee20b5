"""The explorer in a real browser: Debian's headless Chromium (never a downloaded one) driven by
Playwright loads the page, connects, shows the parts where the server put them, follows a slider
moved with the mouse, and renders a non-blank picture.

Set EXPLORER_UPDATE_SCREENSHOT=1 to copy the picture to docs/screenshot.png (the README's)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT

CHROMIUM = Path("/usr/bin/chromium")
ARGS = [
    "--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
    "--ignore-gpu-blocklist", "--disable-background-networking", "--disable-component-update",
    "--disable-sync", "--no-first-run",
]

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium at /usr/bin/chromium (apt-get install chromium)"),
]


def _node_position(page, name):
    return page.evaluate(
        "(name) => { const n = window.__viserMutable.nodeRefFromName[name];"
        " return n ? [n.position.x, n.position.y, n.position.z] : null; }",
        name,
    )


def test_page_shows_the_gear_follows_a_slider_and_renders(tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api")
    import viser

    from explorer import meshes
    from explorer.scenes import default_scene
    from explorer.viewer.app import ExplorerApp
    from explorer.viewer.model import step_index

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = ExplorerApp(server, str(default_scene()), playing=False)
    try:
        assert app.wait_applied(60)
        # start in mid-lift, where lever, spring and valve are visibly displaced
        s = app.current.result.columns["valve_lift_m"]
        rising = np.nonzero((s > 0.55 * s.max()) & (np.gradient(s) > 0))[0]
        start_angle = float(app.current.result.columns["cam_angle_deg"][rising[0] if rising.size else 0])
        app.angle.value = round(start_angle, 1)
        assert app.wait_applied(10)
        url = f"http://127.0.0.1:{server.get_port()}/"
        with sync_api.sync_playwright() as pw:
            context = pw.chromium.launch_persistent_context(
                str(tmp_path / "profile"), executable_path=str(CHROMIUM), headless=True, args=ARGS,
                viewport={"width": 1600, "height": 1000},
            )
            try:
                page = context.new_page()
                page.goto(url)
                page.wait_for_function(
                    "() => window.__viserMutable?.nodeRefFromName?.['/gear/valve'] !== undefined", timeout=60000
                )
                page.get_by_text("Connected").first.wait_for(timeout=30000)
                # the page holds the poses the server computed
                page.wait_for_timeout(1500)
                for name in ("valve", "roller", "adjuster", "follower"):
                    np.testing.assert_allclose(
                        _node_position(page, f"/gear/{name}"), app.server.scene.get_handle_by_name(f"/gear/{name}").position,
                        atol=1e-6, err_msg=name,
                    )
                valve_before = _node_position(page, "/gear/valve")

                # a person clicks the cam-angle slider in the middle of the longest closed stretch
                s_all = app.current.result.columns["valve_lift_m"]
                closed = np.concatenate([s_all, s_all]) == 0.0
                run = best = best_end = 0
                for j, c in enumerate(closed):
                    run = run + 1 if c else 0
                    if run > best:
                        best, best_end = run, j
                target = (best_end - best / 2.0) % len(s_all) * 360.0 / len(s_all)
                slider_id = page.locator("label", has_text="Cam angle").first.get_attribute("for")
                box = page.locator(f"[id='{slider_id}']").bounding_box()
                page.mouse.click(box["x"] + target / 360.0 * box["width"], box["y"] + 0.5 * box["height"])
                page.wait_for_function(
                    "(z) => Math.abs(window.__viserMutable.nodeRefFromName['/gear/valve'].position.z - z) > 1e-6",
                    arg=valve_before[2], timeout=60000,
                )
                assert app.playback.angle_deg == pytest.approx(target, abs=6.0)
                assert app.wait_applied(10)
                valve_after = _node_position(page, "/gear/valve")
                result, lay = app.current.result, app.current.layout
                i = step_index(app.playback.angle_deg, len(result.columns["cam_angle_deg"]))
                shown = meshes.displayed_valve_lift(result, app.current.request.magnification)[i]
                assert lay.stem_top_rest - valve_after[2] == pytest.approx(shown, abs=1e-6)
                assert valve_after[2] > valve_before[2]  # the valve went back up to its seat

                # for the picture: the elastic linkage with forces, magnified ten times, at the
                # widest separation of valve and linkage during the lift (when the scene allows it)
                for name in ("forces", "elastic"):
                    app.effects[name].value = True
                app.magnification.value = 10.0
                assert app.wait_applied(60)
                if app.error_text:  # a scene without [linkage] or [spring]: keep its own effects
                    for name in ("forces", "elastic"):
                        app.effects[name].value = name in app.current.scene.effects
                    assert app.wait_applied(60)
                cols, scene = app.current.result.columns, app.current.scene
                lash = scene.valve.lash if scene.valve is not None else 0.0
                linkage = scene.follower.ratio * cols["follower_lift_m"] - lash
                gap = np.where(linkage > 0.1 * linkage.max(), cols["valve_lift_m"] - linkage, -np.inf)
                picture_angle = float(cols["cam_angle_deg"][int(np.argmax(gap))]) if gap.max() > 0 else start_angle
                app.angle.value = round(picture_angle, 1)
                assert app.wait_applied(10)
                z_server = float(app.server.scene.get_handle_by_name("/gear/valve").position[2])
                page.wait_for_function(
                    "(z) => Math.abs(window.__viserMutable.nodeRefFromName['/gear/valve'].position.z - z) < 1e-6",
                    arg=z_server, timeout=30000,
                )
                # dismiss the "software WebGL" notice
                page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")
                page.mouse.move(700, 950)  # no tooltip in the picture
                page.wait_for_timeout(1500)
                shot = tmp_path / "screenshot.png"
                page.screenshot(path=str(shot))
            finally:
                context.close()
    finally:
        app.stop()
        server.stop()

    import matplotlib.image

    image = matplotlib.image.imread(str(shot))[..., :3]
    assert image.shape[0] >= 900 and image.shape[1] >= 1500
    # not blank: the 3D viewport (between the panels) holds many colours, among them the cam's
    viewport = image[150:850, 500:1150]
    colours = np.unique((viewport * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colours) > 200
    assert viewport.std() > 0.05
    cam = np.array(meshes.PART_COLORS["cam"]) / 255.0
    assert np.any(np.linalg.norm(viewport - cam, axis=-1) < 0.25)  # shaded orange cam pixels
    if os.environ.get("EXPLORER_UPDATE_SCREENSHOT"):
        (ROOT / "docs").mkdir(exist_ok=True)
        shutil.copyfile(shot, ROOT / "docs" / "screenshot.png")
