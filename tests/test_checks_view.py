"""The design checks in the viewers (issue #26.3): the hand-over (explorer.view.verdicts), the
adapter the checks layer gives the viewers (explorer.checks.viewer), the browser's Checks panel
driven from Python (a click is a recorded CheckChosen, as the button's callback records it) and
the recording's markers and limit lines read back from the .rrd file."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from conftest import SCENES, process_timeout, run_cli
from explorer.checks import check
from explorer.checks.registry import rules
from explorer.checks.viewer import evaluate, line as check_line
from explorer.scene.scene import load_scene
from explorer.view.verdicts import CheckLine, CheckSummary, Threshold

FLOAT = SCENES / "valve_float_demo.toml"
# the float demo over a range of speeds, shown at 2000 rpm: its seating velocity fails at a speed
# of the range that is not the one shown
RANGE = ("drive.operating_range=[1000, 4000]", "drive.rpm=2000")
WAIT_S = process_timeout()


def _line(verdict, speed=None, angle=None, **kw):
    return CheckLine(**{"rule": "r", "title": "Rule", "verdict": verdict, "value": 1.0, "shown": "1 m/s",
                        "speed_rpm": speed, "cam_angle_deg": angle, **kw})


# -- the hand-over ---------------------------------------------------------------------------------


@pytest.mark.parametrize("verdict, colour", [("pass", "green"), ("warn", "yellow"), ("fail", "red"),
                                             ("n/a", "gray"), ("off", "gray")])
def test_verdicts_have_traffic_light_colours(verdict, colour):
    assert _line(verdict).colour == colour


def test_a_click_asks_for_the_worst_speed_and_cam_angle():
    assert _line("fail", 3472.36, 176.17).target() == (3472.36, 176.17)
    assert _line("warn", None, 400.5).target() == (None, pytest.approx(40.5))  # a revolution later: the same angle
    assert _line("pass", 2000.0, math.nan).target() == (2000.0, None)  # not located: the speed only
    assert _line("fail", 0.0, 12.0).target() == (None, 12.0)  # no speed (a figure of the cam alone)
    assert _line("n/a", 2000.0, 12.0).target() == (None, None)  # not judged: nowhere to go
    assert _line("fail", 3000.0, 10.0).label() == "FAIL · Rule: 1 m/s at 3000 rpm, 10.00°"


def test_a_line_is_a_button_row_and_a_text_row_that_hold_all_of_it():
    """viser's buttons clip their label at the panel's edge: the button holds verdict and title
    (cut with an ellipsis past BUTTON_CHARS, the whole title then in the text row), the text row
    the worst, where and the limits (or why the rule cannot judge), the source its tooltip."""
    from explorer.view.browser.checks_panel import BUTTON_CHARS, button_text, detail_html, detail_text

    line = _line("fail", 3000.0, 10.0, limit="fail 1 m/s", source="a book, p. 3")
    assert (button_text(line), detail_text(line)) == ("FAIL · Rule", "1 m/s at 3000 rpm, 10.00° · limits fail 1 m/s")
    assert "title='source: a book, p. 3'" in detail_html(line) and "<b style='color:#c0392b'>1 m/s at 3000 rpm" \
        in detail_html(line)
    off = _line("n/a", reason="needs [lubricant]")
    assert (button_text(off), detail_text(off)) == ("n/a · Rule", "needs [lubricant]")
    long = _line("warn", None, 12.0, title="A plug-in rule whose title says at length what it judges and where")
    cut = button_text(long)
    assert len(cut) <= BUTTON_CHARS and cut.endswith("…") and cut.startswith("WARN · A plug-in rule whose title")
    assert detail_text(long) == f"{long.title} · 1 m/s at 12.00°"
    # every built-in rule's title fits its button whole
    for spec in rules():
        assert not button_text(_line("warn", title=spec.title)).endswith("…"), spec.title


def test_summary_verdict_counts_and_limits_by_column():
    limit = Threshold("valve_velocity_m_s", (-1.0,), "fail")
    lines = (_line("pass"), _line("warn"), CheckLine("s", "S", "fail", 2.0, "2 m/s", 3000.0, 170.0,
                                                     thresholds=(limit,)), _line("n/a"))
    summary = CheckSummary("scene", "1 rpm", lines)
    assert summary.verdict == "fail" and summary.counts() == {"pass": 1, "warn": 1, "fail": 1, "n/a": 1}
    assert summary.thresholds("valve_velocity_m_s") == [(lines[2], limit)]
    assert summary.thresholds("hertz_stress_Pa") == []
    assert CheckSummary("scene", "", (_line("n/a"),)).verdict == "n/a"
    with pytest.raises(ValueError):
        Threshold("x", (1.0,), "bad")


# -- the adapter ------------------------------------------------------------------------------------


def test_the_viewers_lines_are_the_reports_with_the_limits_on_the_columns():
    """Each line is `explorer check`'s result; the seating velocity's limits are lines at minus
    the limits on the valve velocity (it closes downwards), the pressure angle's at +-30 deg."""
    scene = load_scene(FLOAT, list(RANGE))
    report = check(scene)
    summary = evaluate(scene)
    assert summary.range_text.startswith("1000..4000 rpm, 200 speeds")
    assert [line.rule for line in summary.lines] == [r.name for r in report.results]
    for line, result in zip(summary.lines, report.results):
        assert (line.verdict, line.value, line.speed_rpm, line.cam_angle_deg) == \
               (result.verdict, result.value, result.speed_rpm, result.cam_angle_deg)
    seat = summary.line("seating_velocity")
    assert seat.verdict == "fail" and seat.colour == "red"
    assert {t.limit: t.values for t in seat.thresholds} == {"fail": (-1.0,), "warn": (-0.76,)}
    assert all(t.column == "valve_velocity_m_s" for t in seat.thresholds)
    angle = summary.line("pressure_angle")
    assert angle.thresholds == (Threshold("pressure_angle_deg", (pytest.approx(-30.0), pytest.approx(30.0)), "fail"),)
    assert summary.line("hertz_stress").thresholds[0].values == (pytest.approx(report.result("hertz_stress").fail),)
    # a rule with no limit drawn has none; every drawn rule names a column a result has
    assert check_line(report.result("float_margin")).thresholds == ()
    columns = set(simulate_columns(scene))
    assert {"pressure_angle_deg", "valve_velocity_m_s", "hertz_stress_Pa", "dynamic_hertz_stress_Pa"} <= columns
    drawn = {spec.name for spec in rules() if spec.plotted}
    assert drawn == {"pressure_angle", "seating_velocity", "hertz_stress", "dynamic_hertz_stress"}
    assert drawn <= {r.name for r in report.results}
    dynamic = summary.line("dynamic_hertz_stress").thresholds
    assert dynamic[0].column == "dynamic_hertz_stress_Pa"
    assert dynamic[0].values == (pytest.approx(report.result("dynamic_hertz_stress").fail),)


def simulate_columns(scene):
    from explorer.effects.pipeline import simulate

    return simulate(scene).columns


# -- the browser's plots ---------------------------------------------------------------------------------


def test_limits_are_dashed_lines_on_the_plots_of_their_columns():
    from explorer.view.browser import model
    from explorer.view.browser.checks_panel import PLOT_COLUMNS, with_limits

    prepared = model.prepare(model.Request(str(FLOAT), RANGE))
    titles = [p.title for p in prepared.plots]
    assert set(PLOT_COLUMNS) <= set(titles)  # the table follows build_plots' titles
    summary = evaluate(prepared.scene)
    drawn = with_limits(prepared.plots, summary)
    for before, after in zip(prepared.plots, drawn):
        if before.title != "Velocity v":
            assert after is before
            continue
        extra = after.series[len(before.series):]
        assert [label for label, _, _ in extra] == ["Seating velocity fail -1", "Seating velocity warn -0.76"]
        assert all(np.all(values == h) for (_, values, _), h in zip(extra, (-1.0, -0.76)))
        assert [colour for _, _, colour in extra] == ["#c0392b", "#d68910"]
        assert len(after.styles) == len(after.series) and after.styles[-1]["dash"]
    assert with_limits(prepared.plots, "error: no checks") == list(prepared.plots)
    # with the result: a plot for each limited quantity the page has no plot of, with its limits
    more = with_limits(prepared.plots, summary, prepared.result)
    assert [p.title for p in more] == titles + ["Pressure angle α", "Contact stress σ (Hertz)"]
    angle, stress = more[-2:]
    assert [label for label, _, _ in angle.series] == ["pressure angle", "Pressure angle fail -30", "Pressure angle fail 30"]
    cols = prepared.result.columns
    assert np.nanmax(angle.series[0][1]) == pytest.approx(np.max(cols["pressure_angle_deg"]))
    fail = summary.line("hertz_stress").thresholds[0].values[0]
    # the rigid and the elastic train's stress, each rule's allowable once (hertz_stress names three
    # columns, the line contact's, a crown's and a tip's: one line)
    assert [label for label, _, _ in stress.series] == [
        "Hertz", "Hertz, elastic train", "Contact (Hertz) stress fail 392.3",
        "Contact (Hertz) stress, elastic train fail 392.3"]
    assert stress.series[2][1][0] == pytest.approx(fail * 1e-6)  # MPa
    assert np.nanmax(stress.series[0][1]) == pytest.approx(np.max(cols["hertz_stress_Pa"]) * 1e-6)
    assert np.nanmax(stress.series[1][1]) == pytest.approx(np.max(cols["dynamic_hertz_stress_Pa"]) * 1e-6)
    # a scene whose checks limit neither gets neither plot
    assert len(with_limits(prepared.plots, CheckSummary("s", "", ()), prepared.result)) == len(titles)


# -- the browser app, driven from Python -------------------------------------------------------------


def _wait(predicate, what, timeout=WAIT_S):
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, what
        time.sleep(0.02)


def test_the_checks_panel_shows_each_rule_and_a_click_goes_to_its_worst():
    viser = pytest.importorskip("viser")
    from explorer.view.browser.app import ExplorerApp
    from explorer.view.browser.checks_panel import CheckChosen, button_text, detail_html

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = ExplorerApp(server, str(FLOAT), RANGE, playing=True, checks=evaluate)
    try:
        assert app.wait_applied(WAIT_S)
        first = app.current
        _wait(lambda: isinstance(app.checks_panel.summary, CheckSummary), "no checks arrived")
        summary = app.checks_panel.summary
        assert app.checks_panel.serial == first.request.serial
        # one button per rule, in its colour, and its text row; a rule that cannot judge is greyed out
        assert list(app.checks_panel.buttons) == list(app.checks_panel.details) == [line.rule for line in summary.lines]
        for line in summary.lines:
            button = app.checks_panel.buttons[line.rule]
            assert (button.color, button.label, button.disabled) == \
                   (line.colour, button_text(line), not line.judged)
            assert app.checks_panel.details[line.rule].content == detail_html(line)
        assert "FAIL" in app.checks_panel.header.content and "1000..4000 rpm" in app.checks_panel.header.content
        # the velocity plot carries the seating velocity's limits
        velocity = next(p for p in app.plots.drawn if p.title == "Velocity v")
        assert any(label.startswith("Seating velocity fail") for label, _, _ in velocity.series)
        assert len(app.plots.handles) == len(app.plots.drawn)
        assert [p.title for p in app.plots.drawn][-2:] == ["Pressure angle α", "Contact stress σ (Hertz)"]

        seat = summary.line("seating_velocity")
        assert seat.colour == "red" and seat.speed_rpm != first.scene.drive.rpm
        app.inbox.put(CheckChosen("seating_velocity"))
        _wait(lambda: app.current.scene.drive.rpm == seat.speed_rpm and app.wait_applied(0.5),
              "the click did not recompute at the worst's speed")
        assert app.playback.angle_deg == pytest.approx(seat.cam_angle_deg % 360.0)
        assert not app.playback.playing  # paused there, like a scrub
        assert app.fields["drive.rpm"].value == pytest.approx(seat.speed_rpm)
        _wait(lambda: app.angle.value == pytest.approx(round(seat.cam_angle_deg, 1)), "the slider did not follow")

        # a speed-independent rule moves the angle only
        angle = summary.line("pressure_angle")
        rpm = app.current.scene.drive.rpm
        submitted = app.worker.submitted
        app.inbox.put(CheckChosen("pressure_angle"))
        _wait(lambda: app.playback.angle_deg == pytest.approx(angle.cam_angle_deg), "no scrub to the pressure angle")
        assert app.wait_applied(WAIT_S)
        assert app.current.scene.drive.rpm == rpm and app.worker.submitted == submitted
        # the new result (at the worst's speed) is checked again: the same worst
        _wait(lambda: app.checks_panel.serial == app.current.request.serial, "the new result was not checked")
        assert app.checks_panel.summary.line("seating_velocity").speed_rpm == seat.speed_rpm
    finally:
        app.stop()
        server.stop()
    assert app.loop_errors == 0 and app.worker.internal_errors == 0


def test_bad_checks_in_the_scene_say_why_in_the_panel(tmp_path):
    viser = pytest.importorskip("viser")
    from explorer.view.browser.app import ExplorerApp

    scene = tmp_path / "bad_checks.toml"
    scene.write_text(FLOAT.read_text() + '\n[checks.seating_velocity]\nfail = "3 mm"\n')
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = ExplorerApp(server, str(scene), playing=False, checks=evaluate)
    try:
        assert app.wait_applied(WAIT_S)
        _wait(lambda: app.checks_panel.summary is not None, "no checks arrived")
        # the scene simulates (its [checks] are read by the checks only): the panel says what is wrong
        assert app.error_text == ""
        why = app.checks_panel.summary
        assert isinstance(why, str) and "checks.seating_velocity.fail" in why and "not a velocity" in why
        assert app.checks_panel.buttons == {} and "not a velocity" in app.checks_panel.header.content
    finally:
        app.stop()
        server.stop()
    assert app.loop_errors == 0 and app.worker.internal_errors == 0


# -- recordings ------------------------------------------------------------------------------------


def test_recorded_violations_are_markers_at_the_cam_angle_of_their_worst(tmp_path):
    pytest.importorskip("rerun")
    from explorer.view.rerun.read import read_rrd

    out = tmp_path / "checked.rrd"
    proc = run_cli("record", str(FLOAT), *sum((["--set", o] for o in RANGE), []), "--checks", "--no-parts",
                   "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    scene = load_scene(FLOAT, list(RANGE))
    summary = evaluate(scene)
    run = read_rrd(out)[0]
    marks = run.temporal["/events/checks"]
    bad = [line for line in summary.lines if line.verdict in ("warn", "fail")]
    assert len(bad) >= 4 and len(marks["TextLog:text"]) == len(bad)
    n = 3600  # the scene's steps per revolution
    for line in bad:
        k = next(i for i, text in enumerate(marks["TextLog:text"]) if f"({line.rule})" in text)
        angle = line.cam_angle_deg % 360.0 if line.cam_angle_deg is not None else 0.0
        assert marks["TextLog:level"][k] == {"warn": "WARN", "fail": "ERROR"}[line.verdict]
        assert marks["cam_angle_0.01deg"][k] == round(100 * angle)
        assert marks["step"][k] == math.floor(angle / 360.0 * n + 1e-9)
        assert line.shown in marks["TextLog:text"][k]
    # the limits beside the series they concern, in the series' units
    series = run.series
    np.testing.assert_array_equal(series["/valve/velocity/limit_seating_velocity_fail"]["value"], [-1.0, -1.0])
    np.testing.assert_array_equal(series["/valve/velocity/limit_seating_velocity_warn"]["value"], [-0.76, -0.76])
    np.testing.assert_allclose(series["/angles/pressure/limit_pressure_angle_fail_2"]["value"], [30.0, 30.0])
    assert series["/valve/velocity/limit_seating_velocity_fail"]["step"].tolist() == [0, n - 1]
    # without --checks: none
    plain = tmp_path / "plain.rrd"
    assert run_cli("record", str(FLOAT), "--no-parts", "-o", str(plain)).returncode == 0
    assert not any("limit_" in p or p == "/events/checks" for p in read_rrd(plain)[0].temporal)
