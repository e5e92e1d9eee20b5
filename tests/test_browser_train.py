"""The pushrod train in a real browser (issue #25, item 3): headless Chromium (Debian's, driven by
Playwright, the harness of tests/test_browser.py) opens the explorer on the pushrod train, sees
the magnification control at the train's default (its label says x20), and the lifter, pushrod
and rocker where their own computed motion puts them, moving as the cam angle changes; moving
the slider redraws them at the new magnification."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import ROOT
from test_browser import CHROMIUM, WAIT_MS, WAIT_S, _connected_page, _running_explorer, _wait_in_step

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium at /usr/bin/chromium (apt-get install chromium)"),
]

SCENE = ROOT / "assets" / "scenes" / "pushrod_train.toml"
MOVING = ("follower", "pushrod", "lever", "valve")


def _expected_drawn(app, step: int) -> dict[str, float]:
    """From the result's columns alone: the lifter's and the pushrod's drawn height above the
    rigid drawing (m (x - L)), at `step`."""
    from explorer.view import parts as meshes

    cur = app.current
    cols, m = cur.result.columns, cur.request.magnification
    rigid = meshes.part_poses(cur.scene, cur.result, magnification=0.0, lay=cur.layout, lift=cur.lift)
    L = cols["follower_lift_m"][step]
    return {f"/gear/{name}": (rigid[name][0][step, 2] + m * (cols[f"part_{part}_displacement_m"][step] - L))
            for name, part in (("follower", "lifter"), ("pushrod", "pushrod"))}


def test_the_pushrod_train_shows_each_mass_moving_magnified(tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api")
    from explorer.view.browser.model import step_index

    with _running_explorer(SCENE) as (server, app):
        assert app.wait_applied(WAIT_S)
        assert app.current.request.magnification == 20.0  # a train opens magnified
        with _connected_page(sync_api, tmp_path, server) as page:
            page.get_by_text("Magnification ×20").first.wait_for(timeout=WAIT_MS)
            cols = app.current.result.columns
            dev = np.abs(cols["part_lifter_displacement_m"] - cols["follower_lift_m"])
            heights = {}
            for step in (int(np.argmax(cols["valve_lift_m"])), int(np.argmax(dev))):
                app.angle.value = round(float(cols["cam_angle_deg"][step]), 1)
                shown = _wait_in_step(page, app, MOVING)
                i = step_index(app.playback.angle_deg, len(cols["cam_angle_deg"]))
                for node, z in _expected_drawn(app, i).items():
                    assert shown[node][2] == pytest.approx(z, abs=1e-6), node
                heights[step] = shown
            a, b = heights.values()
            for name in MOVING[:2]:
                assert abs(a[f"/gear/{name}"][2] - b[f"/gear/{name}"][2]) > 1e-4, name  # the parts move
            # the user's magnification: the label follows, the parts are drawn anew
            app.magnification.value = 5.0
            page.get_by_text("Magnification ×5").first.wait_for(timeout=WAIT_MS)
            assert app.wait_applied(WAIT_S) and app.current.request.magnification == 5.0
            shown = _wait_in_step(page, app, MOVING)
            i = step_index(app.playback.angle_deg, len(cols["cam_angle_deg"]))
            for node, z in _expected_drawn(app, i).items():
                assert shown[node][2] == pytest.approx(z, abs=1e-6), node
