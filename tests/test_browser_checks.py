"""The Checks panel in a real browser (issue #26.3; Debian's headless Chromium driven by
Playwright, the harness of tests/test_browser.py): a scene whose seating velocity fails at a speed
of its operating range other than the one shown; the person opens the Checks tab, sees that
rule's line in red (and a passing one in green), clicks it, and the page's Camshaft rpm field and
cam-angle slider move to the speed and the cam angle of the worst seating velocity. Set
EXPLORER_UPDATE_SCREENSHOT=1 to copy the picture to docs/img/checks_panel.png."""

from __future__ import annotations

import contextlib
import os
import time

import pytest

from conftest import ROOT, SCENES
from explorer.view.browser.checks_panel import DETAIL_CLASS, button_text, detail_text
from test_browser import ARGS, CHROMIUM, TWO_FRAMES, WAIT_MS, WAIT_S, _connected_page, _row_input  # noqa: F401

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium at /usr/bin/chromium (apt-get install chromium)"),
]

RANGE = ("drive.operating_range=[1000, 4000]", "drive.rpm=2000")


@contextlib.contextmanager
def _checked_explorer(scene, overrides):
    import viser

    from explorer.checks.viewer import evaluate
    from explorer.view.browser.app import ExplorerApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = ExplorerApp(server, str(scene), overrides, playing=False, checks=evaluate)
    try:
        yield server, app
    finally:
        app.stop()
        server.stop()
    assert app.loop_errors == 0 and app.worker.internal_errors == 0


def _wait_until(predicate, what):
    deadline = time.monotonic() + WAIT_S
    while not predicate():
        assert time.monotonic() < deadline, what
        time.sleep(0.05)


RGB_OF = "(e) => getComputedStyle(e).backgroundColor.match(/\\d+/g).slice(0, 3).map(Number)"
# how far an element's text runs past what it shows, in px (0: all of it is shown): its own and its
# descendants' scroll width over their client width (a clipped button label scrolls), and its
# box past the right edge of the control panel (the tab's scroll container)
OVERRUN = """(e) => {
  const panel = e.closest('.mantine-Tabs-panel') || document.body;
  const own = [e, ...e.querySelectorAll('*')].filter((x) => x.clientWidth > 0)
    .map((x) => x.scrollWidth - x.clientWidth);
  return Math.max(0, ...own, e.getBoundingClientRect().right - panel.getBoundingClientRect().right);
}"""


def test_every_rule_line_is_readable_in_the_panel(tmp_path):
    """The panel is 440 px wide and viser's buttons clip their label there (the line of the
    longest built-in title, the opening velocity at the end of the lash ramp, lost its value and
    where): each rule's button shows its whole button_text, and the text row under it the whole
    rest of the line, wrapped within the panel."""
    sync_api = pytest.importorskip("playwright.sync_api")
    from explorer.checks.registry import rules
    from explorer.view.verdicts import CheckSummary

    longest = max(rules(), key=lambda spec: len(spec.title))
    with _checked_explorer(SCENES / "valve_float_demo.toml", RANGE) as (server, app):
        _wait_until(lambda: isinstance(app.checks_panel.summary, CheckSummary), "the checks never arrived")
        summary = app.checks_panel.summary
        judged = summary.line(longest.name)
        assert judged.judged and judged.where() and len(judged.label()) > 70  # the line that was cut
        with _connected_page(sync_api, tmp_path, server, width=1400, height=1000) as page:
            page.get_by_role("tab", name="Checks").click()
            page.get_by_role("button", name=button_text(judged)).wait_for(timeout=WAIT_MS)
            for line in summary.lines:
                button = page.get_by_role("button", name=button_text(line), exact=True)
                button.scroll_into_view_if_needed()
                assert button.is_visible() and button.inner_text().strip() == button_text(line)
                assert button.evaluate(OVERRUN) <= 0.5, (line.rule, button.evaluate(OVERRUN))
                detail = page.locator(f".{DETAIL_CLASS}[data-rule='{line.rule}']")
                assert detail.is_visible() and " ".join(detail.inner_text().split()) == detail_text(line)
                assert detail.evaluate(OVERRUN) <= 0.5, line.rule
                # the text row sits under its own button, inside the panel
                b, d = button.bounding_box(), detail.bounding_box()
                assert b["y"] + b["height"] <= d["y"] + 1 and d["y"] - (b["y"] + b["height"]) < 12, line.rule
            # the whole of the longest line is on the page: its button row and its text row
            shown = page.get_by_role("button", name=button_text(judged)).inner_text() + " " + \
                page.locator(f".{DETAIL_CLASS}[data-rule='{longest.name}']").inner_text()
            for piece in (judged.verdict.upper(), longest.title, judged.shown, judged.where(), judged.limit):
                assert piece in shown, piece


def test_a_red_check_line_clicked_moves_the_speed_and_the_frame_to_its_worst(tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api")
    from explorer.view.verdicts import CheckSummary

    with _checked_explorer(SCENES / "valve_float_demo.toml", RANGE) as (server, app):
        assert app.wait_applied(WAIT_S)
        _wait_until(lambda: isinstance(app.checks_panel.summary, CheckSummary), "the checks never arrived")
        seat = app.checks_panel.summary.line("seating_velocity")
        assert seat.verdict == "fail" and seat.speed_rpm != app.current.scene.drive.rpm
        with _connected_page(sync_api, tmp_path, server, width=1400, height=1000) as page:
            page.get_by_role("tab", name="Checks").click()
            line = page.get_by_role("button", name="Seating velocity")
            line.wait_for(timeout=WAIT_MS)
            page.get_by_text("FAIL (").first.wait_for(timeout=WAIT_MS)  # the header's verdict
            red = line.evaluate(RGB_OF)
            green = page.get_by_role("button", name="Pressure angle").evaluate(RGB_OF)
            assert red[0] > red[1] + 80 and red[0] > red[2] + 80, red  # red
            assert green[1] > green[0] + 60 and green[1] > green[2] + 30, green  # green
            detail = page.locator(f".{DETAIL_CLASS}[data-rule='seating_velocity']")
            assert seat.shown in detail.inner_text() and f"{seat.speed_rpm:.6g} rpm" in detail.inner_text()
            angle_id = page.locator("label", has_text="Cam angle [°]").first.get_attribute("for")
            thumb = page.locator(f"[id='{angle_id}'] [role=slider]")
            angle_before = thumb.get_attribute("aria-valuenow")
            # a person: points at the line, waits a moment, clicks
            line.scroll_into_view_if_needed()
            box = line.bounding_box()
            page.mouse.move(box["x"] + 0.3 * box["width"], box["y"] + 0.5 * box["height"], steps=8)
            page.wait_for_timeout(300)
            page.mouse.down()
            page.wait_for_timeout(120)
            page.mouse.up()
            _wait_until(lambda: app.current.scene.drive.rpm == seat.speed_rpm and app.wait_applied(0.5),
                        "the click did not recompute at the worst's speed")
            assert app.playback.angle_deg == pytest.approx(seat.cam_angle_deg % 360.0)
            # the page shows it: the Camshaft rpm field and the cam-angle slider (the frame)
            rpm_field = _row_input(page, "Camshaft rpm")  # a number field of step 1: whole rpm shown
            page.wait_for_function("([e, v]) => Math.abs(parseFloat(e.value.replace(/,/g, '')) - v) <= 0.5",
                                   arg=[rpm_field.element_handle(), seat.speed_rpm], timeout=WAIT_MS)
            shown = f"{round(seat.cam_angle_deg % 360.0, 1):g}"
            page.wait_for_function("([t, v]) => Math.abs(parseFloat(document.querySelector(t)"
                                   "?.getAttribute('aria-valuenow')) - v) < 0.051",
                                   arg=[f"[id='{angle_id}'] [role=slider]", float(shown)], timeout=WAIT_MS)
            assert thumb.get_attribute("aria-valuenow") != angle_before
            page.mouse.move(5, 995)
            assert page.evaluate(TWO_FRAMES)
            shot = tmp_path / "checks_panel.png"
            page.screenshot(path=str(shot), timeout=WAIT_MS)
    if os.environ.get("EXPLORER_UPDATE_SCREENSHOT"):  # the panel and the gear, in 128 colours
        from PIL import Image

        Image.open(shot).convert("RGB").crop((0, 0, 1010, 1000)).quantize(colors=128).save(
            ROOT / "docs" / "img" / "checks_panel.png", optimize=True)
