"""The browser explorer's speed sweep (issue #14.2): the figures against independent
computations, the markers, choosing a speed, and the progressive elastic part."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from conftest import SCENES, process_timeout
from explorer.effects.lift import build_lift
from explorer.effects.pipeline import simulate
from explorer.scene.scene import load_scene
from explorer.view.browser import speedsweep as ss

FLOAT = SCENES / "valve_float_demo.toml"
WAIT_S = process_timeout()


def _scene(path=FLOAT, *overrides):
    scene = load_scene(str(path), list(overrides))
    return scene, build_lift(scene)


@pytest.mark.parametrize("rpm", [137.0, 1500.0, 2890.0, 6100.0])
def test_rigid_sweep_equals_simulate_at_sample_speeds(rpm):
    """Oracle: `simulate` at that one speed (forces effect, per-step loop-free arrays of its own)
    on the same grid: the smallest contact force over the open steps and the largest linkage
    force. The sweep evaluates w^2 A + G instead of (m p + spring + ...) at each step, so the two
    agree to round-off: 1e-9 relative to the largest force."""
    scene, lift = _scene(FLOAT, 'effects=["forces"]')
    low, high = ss.rigid_sweep(scene, lift, [rpm, 2 * rpm])
    result = simulate(ss.at_speed(scene, rpm), lift=lift)
    cols = result.columns
    is_open = np.asarray(cols["rigid_valve_lift_m"] if "rigid_valve_lift_m" in cols else cols["valve_lift_m"]) > 0.0
    force = np.asarray(cols["contact_force_N"])[is_open]
    linkage = np.asarray(cols["linkage_force_N"])[is_open]
    scale = float(np.abs(force).max())
    assert low[0] == pytest.approx(force.min(), abs=1e-9 * scale)
    assert high[0] == pytest.approx(linkage.max(), abs=1e-9 * scale)
    # and the other speed of the same call is independent of the first
    other = simulate(ss.at_speed(scene, 2 * rpm), lift=lift).columns
    assert low[1] == pytest.approx(np.asarray(other["contact_force_N"])[is_open].min(), abs=1e-9 * scale * 4)


def test_rigid_sweep_agrees_with_the_studies_margin_sweep_and_the_float_speed():
    """A second oracle: explorer.studies.sweeps (the CLI's vectorised sweep, its own code) on the
    same grid, bit for bit up to summation order; and the first speed whose margin is <= 0
    brackets the exact float speed the sweep marks."""
    from explorer.studies.sweeps import contact_margin_sweep

    scene, lift = _scene(FLOAT, 'effects=["forces"]')
    sweep = ss.start_sweep(scene, lift, serial=1)
    ref = contact_margin_sweep(scene, sweep.rpm, lift=lift)
    np.testing.assert_allclose(sweep.min_contact_force, ref.min_contact_force, rtol=0, atol=1e-9)
    step = sweep.rpm[1] - sweep.rpm[0]
    first = ref.first_float_rpm()
    assert first is not None and first - step <= sweep.float_rpm <= first + 1e-9
    assert sweep.rpm.size == ss.RIGID_SPEEDS and sweep.elastic_total == 0
    assert sweep.span[1] >= 2 * scene.drive.rpm and sweep.span[1] >= 1.25 * sweep.float_rpm


def test_elastic_figures_equal_the_sweep_engines_row():
    """Oracle: explorer.studies.sweep_engine.reference_row (the `explorer sweep` CLI's row from
    `simulate`) at the same speed: first separation, seating velocity, largest deviation, exactly."""
    from explorer.studies.sweep_engine import reference_row, result_columns

    scene, lift = _scene()
    assert ss.has_elastic(scene)
    for rpm in (900.0, 2600.0):
        sep, seat, dev = ss.elastic_figures(scene, lift, rpm)
        at = ss.at_speed(scene, rpm)
        row = reference_row(at, result_columns(at))
        for mine, theirs in ((sep, row["first_separation_deg"]), (seat, row["seating_velocity_m_s"]),
                             (dev, row["max_deviation_m"])):
            assert (math.isnan(mine) and math.isnan(theirs)) or mine == theirs


def test_the_span_stays_while_the_speed_is_inside_and_grows_beyond():
    assert ss.sweep_span(1000.0, math.nan) == (4.0, 2000.0)
    assert ss.sweep_span(1000.0, 3000.0) == (7.6, 3800.0)  # 1.25 x 3000, up to two digits
    kept = (4.0, 2000.0)
    assert ss.sweep_span(1500.0, math.nan, kept) is kept  # choosing a speed keeps the plot's scale
    assert ss.sweep_span(2500.0, math.nan, kept)[1] == 5000.0


def test_the_markers_stand_at_the_exact_speeds_and_the_curves_are_unchanged():
    scene, lift = _scene()
    sweep = ss.start_sweep(scene, lift, serial=1)
    plots = {}
    for rpm in (500.0, 1234.5, 2900.0):
        rigid, *elastic = ss.sweep_plots(sweep, rpm)
        assert len(elastic) == 3  # first separation, seating velocity, deviation: each on its own axis
        for title, _, x, series, (now, floating), (lo, hi) in (rigid, *elastic):
            assert np.all(np.diff(x) > 0)
            assert now.sum() == 1.0 and x[np.argmax(now)] == rpm  # where the speed is, not the nearest sample
            assert floating.sum() == 1.0 and x[np.argmax(floating)] == sweep.float_rpm
            plots[title, rpm] = x[np.argmax(now)]
        # the rigid curves still pass through every computed sample, and the inserted samples
        # lie on the straight line between their neighbours
        _, _, x, series, _, (lo, hi) = rigid
        on_grid = np.isin(x, sweep.rpm)
        np.testing.assert_array_equal(series[0][1][on_grid], sweep.min_contact_force)
        np.testing.assert_allclose(series[0][1], np.interp(x, sweep.rpm, sweep.min_contact_force), rtol=1e-12, atol=1e-9)
        assert lo < sweep.min_contact_force.min() and hi > sweep.peak_linkage_force.max()
    assert plots["Speed sweep (rigid)", 500.0] < plots["Speed sweep (rigid)", 2900.0]  # the marker moves with the speed


def test_elastic_speeds_come_coarse_to_fine_and_only_those_computed_are_drawn():
    """#28.8: the speeds computed one at a time come in an order that spans the range soonest
    (the top speed, the lowest, then each as far as possible from those taken), so the first few
    already show the whole range; the plots draw the speeds computed so far, nothing else."""
    order = ss.coarse_to_fine(24)
    assert sorted(order) == list(range(24)) and list(order[:3]) == [23, 0, 11]
    for k in range(2, 24):  # after k speeds, the largest gap between computed neighbours is
        taken = np.sort(order[:k])  # within a factor 2 of the best possible for k points
        assert np.max(np.diff(taken)) <= 2 * math.ceil(23 / (k - 1))
    scene, lift = _scene(FLOAT, 'solver.method="taylor"')  # not the compiled solver's: one speed at a time
    sweep = ss.start_sweep(scene, lift, serial=1)
    assert not sweep.batched and sweep.elastic_total == ss.ELASTIC_SPEEDS
    assert sweep.next_elastic() == sweep.elastic_rpm[-1]  # the top speed first
    sweep = ss.with_elastic(ss.with_elastic(sweep, (10.0, -0.5, 1e-4)), (20.0, -0.7, 2e-4))
    assert sweep.max_deviation[-1] == 1e-4 and sweep.max_deviation[0] == 2e-4
    assert np.isnan(sweep.max_deviation[1:-1]).all()
    plots = {title.split(",")[0]: (y_label, x, series, lim) for title, y_label, x, series, _, lim in ss.sweep_plots(sweep, 1234.5)}
    y_label, x, series, (lo, hi) = plots["Speed sweep (elastic deviation"]
    assert y_label == "Δs [mm]" and len(series) == 1
    deviation = series[0][1]
    drawn = np.isin(x, sweep.elastic_rpm)
    np.testing.assert_array_equal(x[drawn], sweep.elastic_rpm[[0, -1]])  # the two computed, nothing between
    np.testing.assert_allclose(deviation[drawn], [0.2, 0.1])
    assert lo <= 0.1 and hi >= 0.2  # the figures computed so far are in view (mm)
    _, _, seat, (lo, hi) = plots["Speed sweep (elastic seating velocity"]
    assert lo <= -0.7 and hi >= -0.5 and hi < 0.0  # its own axis: not stretched to the other figures
    _, _, sep, (lo, hi) = plots["Speed sweep (elastic first separation"]
    assert lo <= 10.0 and hi >= 20.0 and sep[0][0] == "first separation [°]"  # degrees, unscaled


def test_elastic_figures_run_only_the_effects_they_need_and_equal_the_full_run():
    """#28.8: an elastic speed of the sweep runs kinematics, lash and elastic only (the rocking
    cam's forces and gear figures were 7/8 of each speed's time); oracle: the figures of
    `simulate` with every effect of the scene, equal bit for bit (no effect reads another's
    figures but its dependencies')."""
    for path in (SCENES / "rocking_cam.toml", SCENES / "rolling_lever.toml", SCENES / "trip_gear_dashpot.toml"):
        scene, lift = _scene(path)
        rpm = 2.0 * scene.drive.rpm
        full = simulate(ss.at_speed(scene, rpm), lift=lift)
        events = [e for e in full.events if e.effect == "elastic"]
        seps = [float(e["cam_angle_deg"]) for e in events if e["kind"] == "separation"]
        seats = [float(e["velocity_m_s"]) for e in events if e["kind"] == "seat"]
        expected = (seps[0] if seps else math.nan, min(seats) if seats else math.nan, full.summary["max_deviation_m"])
        got = ss.elastic_figures(scene, lift, rpm)
        assert all((math.isnan(e) and math.isnan(g)) or e == g for e, g in zip(expected, got)), (path.name, got, expected)


def test_the_rigid_model_is_checked_against_the_gears_own_forces():
    """#28.6: the sweep's F = w^2 A + G holds for the translating roller and the lever gears
    (equal to their forces effect's contact force at the scene's speed), not for the trip gear,
    whose latch carries the valve only from its pick-up to the trip: that scene gets no sweep and
    a note saying why, whatever is ticked (it used to say "tick 'forces'" with forces ticked)."""
    for name in ("valve_float_demo.toml", "pivoted_roller_lever.toml", "rocking_cam.toml", "rolling_lever.toml"):
        scene, lift = _scene(SCENES / name)
        assert ss.rigid_model_holds(scene, lift), name
    scene, lift = _scene(SCENES / "trip_gear_dashpot.toml")
    assert "forces" in scene.effects
    assert not ss.rigid_model_holds(scene, lift)
    for effects in (None, 'effects=["kinematics"]'):
        scene, lift = _scene(SCENES / "trip_gear_dashpot.toml", *([effects] if effects else []))
        none = ss.start_sweep(scene, lift, serial=1, result=simulate(scene, lift=lift))
        assert isinstance(none, ss.NoSweep) and "tick 'forces'" not in none.reason and "trip gear" in none.reason


def test_a_scene_without_forces_has_no_sweep():
    scene, lift = _scene(SCENES / "table_demo.toml")
    assert scene.spring is None  # no spring: no rigid contact force to sweep
    none = ss.start_sweep(scene, lift, serial=1)
    assert isinstance(none, ss.NoSweep) and "[spring]" in none.reason and "tick 'forces'" not in none.reason


def _worker_sweeps(first_overrides, second_overrides, started):
    """The (serial, sweep) the compute worker hands on: request 1, then request 2 once `started`
    holds for a sweep of request 1; waits until both are idle."""
    from explorer.view.browser.compute import ComputeWorker
    from explorer.view.browser.model import Request

    sweeps = []
    worker = ComputeWorker(on_ready=lambda p: None, on_error=lambda r, m: sweeps.append(("error", m)),
                           on_sweep=lambda serial, s: sweeps.append((serial, s))).start()
    try:
        worker.submit(Request(str(FLOAT), first_overrides, serial=1))
        deadline = time.monotonic() + 4 * WAIT_S
        while not any(s is not None and started(s) for _, s in sweeps[1:]) and time.monotonic() < deadline:
            time.sleep(0.01)
        worker.submit(Request(str(FLOAT), second_overrides, serial=2))
        assert worker.wait_idle(WAIT_S)
        while not worker.sweep_idle() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert worker.sweep_idle()
    finally:
        worker.stop()
    assert not any(serial == "error" for serial, _ in sweeps), sweeps
    return sweeps


def test_the_worker_fills_the_elastic_sweep_in_progressively_and_the_newest_wins():
    """In the compute child, between requests: the rigid sweep first, then (for a scene the
    compiled solver does not take) one elastic speed at a time; a new request in the middle starts
    the newer result's sweep and the old one stops."""
    taylor = 'solver.method="taylor"'
    sweeps = _worker_sweeps((taylor,), (taylor, "drive.rpm=1500"), lambda s: s.elastic_done >= 2)
    first = [s for serial, s in sweeps if serial == 1]
    done = [s.elastic_done for s in first]
    assert done[:3] == [0, 1, 2] and done == sorted(done)  # progressive, in order
    assert done[-1] < ss.ELASTIC_SPEEDS  # stopped by the newer request
    last = sweeps[-1][1]
    assert sweeps[-1][0] == 2 and last.serial == 2 and last.elastic_done == ss.ELASTIC_SPEEDS
    assert last.span == first[0].span  # same scene file, 1500 rpm inside: the plot keeps its scale
    assert np.isfinite(last.max_deviation).all()
    # the filled-in figures are simulate's at those speeds
    scene, lift = _scene(FLOAT, taylor, "drive.rpm=1500")
    k = ss.ELASTIC_SPEEDS // 2
    expected = ss.elastic_figures(scene, lift, last.elastic_rpm[k])
    got = (last.first_separation_deg[k], last.seating_velocity[k], last.max_deviation[k])
    assert all((math.isnan(e) and math.isnan(g)) or e == g for e, g in zip(expected, got))


def test_the_compiled_solver_fills_every_elastic_speed_in_one_step():
    """A scene the compiled exact solver takes (the float demo): after the rigid step, one step
    computes all ELASTIC_BATCH_SPEEDS elastic speeds. Oracle: simulate at those speeds (the
    compiled solver's rows equal it within rounding, tests/test_sweep_kernel.py: here 1e-9
    relative on the figures, 1e-9 deg on the separation angle)."""
    sweeps = _worker_sweeps((), ("drive.rpm=1500",), lambda s: True)
    last = sweeps[-1][1]
    assert sweeps[-1][0] == 2 and last.batched and last.elastic_total == ss.ELASTIC_BATCH_SPEEDS
    assert [s.elastic_done for serial, s in sweeps if serial == 2] == [0, ss.ELASTIC_BATCH_SPEEDS]
    scene, lift = _scene(FLOAT, "drive.rpm=1500")
    for k in (0, ss.ELASTIC_BATCH_SPEEDS // 3, ss.ELASTIC_BATCH_SPEEDS - 1):
        sep, seat, dev = ss.elastic_figures(scene, lift, last.elastic_rpm[k])
        assert (math.isnan(sep) and math.isnan(last.first_separation_deg[k])) or \
            last.first_separation_deg[k] == pytest.approx(sep, abs=1e-9)
        assert last.seating_velocity[k] == pytest.approx(seat, rel=1e-9, abs=1e-12)
        assert last.max_deviation[k] == pytest.approx(dev, rel=1e-9, abs=1e-12)
    assert np.isfinite(last.first_separation_deg[-1])  # the top speed floats


def test_choosing_a_speed_under_the_sweep_sets_the_requests_rpm():
    viser = pytest.importorskip("viser")
    from explorer.view.browser.app import ExplorerApp

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    app = ExplorerApp(server, str(FLOAT), playing=False)
    try:
        assert app.wait_applied(WAIT_S)
        deadline = time.monotonic() + WAIT_S
        # the loop thread shows the sweep: wait until it has put the speed into the slider
        while (app.sweep is None or app.sweep_rpm.value != app.current.scene.drive.rpm) and time.monotonic() < deadline:
            time.sleep(0.01)
        assert app.sweep is not None and app.sweep_rpm.value == app.current.scene.drive.rpm
        handles = app.sweep_view.handles
        assert len(handles) == 5 and not app.sweep_rpm.disabled  # forces, torque, 3 elastic figures
        before = np.asarray(handles[0].data[-2])
        app.sweep_rpm.value = 1800.0  # as a page's slider would
        assert app.wait_applied(WAIT_S)
        assert "drive.rpm=1800.0" in app.current.request.overrides
        assert app.current.scene.drive.rpm == 1800.0
        assert app.fields["drive.rpm"].value == 1800.0
        deadline = time.monotonic() + WAIT_S
        while np.array_equal(np.asarray(app.sweep_view.handles[0].data[-2]), before) and time.monotonic() < deadline:
            time.sleep(0.01)
        x, now = np.asarray(app.sweep_view.handles[0].data[0]), np.asarray(app.sweep_view.handles[0].data[-2])
        assert abs(x[np.argmax(now)] - 1800.0) <= x[1] - x[0]  # the marker moved to the speed chosen
    finally:
        app.stop()
        server.stop()
    assert app.loop_errors == 0 and app.worker.internal_errors == 0


@pytest.mark.parametrize("path,overrides", [(SCENES / "schenker1902_intake_valve.toml", ()),
                                            (FLOAT, ('effects=["forces", "contact"]',))])
def test_torque_sweep_equals_the_contact_effects_peak_at_sample_speeds(path, overrides):
    """Oracle: the contact effect's max_camshaft_torque_Nm of `simulate` at that speed (its own
    per-step normal force and arm). T = c(F) F is the same product per sample: 1e-9 relative."""
    scene, lift = _scene(path, *overrides)
    base = simulate(scene, lift=lift)
    rpms = [0.3 * scene.drive.rpm, scene.drive.rpm, 2.2 * scene.drive.rpm]
    got = ss.torque_sweep(scene, lift, base, rpms)
    for rpm, mine in zip(rpms, got):
        expected = simulate(ss.at_speed(scene, rpm), lift=lift).summary["max_camshaft_torque_Nm"]
        assert mine == pytest.approx(expected, rel=1e-9, abs=1e-12)
    sweep = ss.start_sweep(scene, lift, 1, result=base)
    assert sweep.peak_torque is not None and len(ss.sweep_plots(sweep, scene.drive.rpm)) >= 2
