"""The browser explorer: a viser server animating the gear, with controls, plots and read-outs.

The pattern of viser's examples and of mjlab's viewer: callbacks only record requests
(explorer.view.browser.requests); one frame loop (explorer.view.browser.loop) takes them, once a
frame, and applies them, in arrival order, under `server.atomic()`. Recomputations go to the
ComputeWorker (newest request wins), which runs each in a child process that is killed past its
time limit (explorer.view.browser.worker), so no value a page sends can stall the server; its
results come back as requests too. Websocket handshakes from other sites are refused
(explorer.view.browser.origin).

The page is made of parts with one job each, all the loop's:
- controls.PlaybackControls: Play, Speed, the cam-angle slider, magnification; the clock;
- fields.Fields: the scene list, reset, the parameter fields (typing, Enter, what they show)
  and the effects;
- gear_view.GearView: the parts in 3D, posed at the step shown;
- plots.Plots: s, v, p and forces over the revolution, the cursor, the slider under them;
- sweep_view.SweepView: the speed sweep under the plots;
- readouts.Readouts: the status box, the "Stale" lines, the Read-outs tab with the events;
- camera.Cameras: each page's camera framed for its canvas;
- checks_panel.ChecksPanel: the design checks' verdicts (when the app is given a CheckRunner),
  a click going to a rule's worst; their limits on the plots.
What can be derived is: what a plot or field shows is read from its handle. Whether a page's
value of a control is on its way is told by the inbox (requests.Inbox.write: the control's value
and viser's update time against those the loop last heard or wrote).
"""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path
from typing import Callable

from ...scene.builtin import builtin_scenes, find_scene
from . import origin
from .camera import Cameras
from .checks_panel import CheckChosen, ChecksArrived, ChecksPanel, with_limits
from .compute import ComputeWorker
from .controls import MAGNIFICATION_RANGE, SCRUB_HINT, PlaybackControls
from .fields import Fields
from .gear_view import GearView
from .loop import FrameLoop
from .model import COMPUTE_TIME_LIMIT_S, Prepared, Request, default_speed
from .plots import REPLOT_AFTER_S, Plots
from .readouts import Readouts, status_html
from .requests import (AdviceArrived, CameraMoved, ClientConnected, ClientLeft, Computed, Edited, EffectsTicked,
                       EventChosen, Failed, Inbox, Magnified, Played, ResetClicked, SceneChosen, Scrubbed,
                       SpeedChosen, Submitted, SweepArrived, SweepSpeedChosen, wire)
from .sweep_view import SweepView

# The caller creates the viser server before the app (`explorer serve`, the tests), after
# importing this module: the Origin check must be in place by then. ExplorerApp refuses a server
# started without it.
origin.install()

# What the page says about who else sees it (`explorer serve --shared` / `--per-client`)
SHARED_NOTE = ("Shared session: everyone connected to this server sees these controls and results, "
               "and a change made on one page changes them on all.")
OWN_NOTE = "Your own session: your changes are yours; others on this server do not see them."


class ExplorerApp:
    """Everything `explorer serve` shows, on an existing viser server (or one page of it:
    `client`). `kernels` (explorer.view.browser.kernels.KernelWarmup) tells whether the compiled
    solver is ready; None: it is taken to be (the tests compile it before they run). `checks`
    (explorer.view.verdicts.CheckRunner, e.g. explorer.checks.viewer.evaluate): the design checks
    of every new result in a Checks tab; None: no tab. `on_checked(prepared, summary)` gets each
    result's checks too (the rerun live stream adds them to the result's recording)."""

    def __init__(
        self,
        server,
        scene_path: str,
        overrides: tuple[str, ...] | list[str] = (),
        *,
        playing: bool = True,
        fps: float = 60.0,
        on_result: Callable[[Prepared], None] | None = None,
        scenes: list[Path] | None = None,
        time_limit: float | None = COMPUTE_TIME_LIMIT_S,
        client=None,
        kernels=None,
        checks=None,
        on_checked: Callable[[Prepared, object], None] | None = None,
    ):
        scene_path = str(find_scene(scene_path))  # a built-in scene named as the Scene list shows it
        port = server.get_port()
        if not origin.guarded(port):
            raise RuntimeError(
                "the viser server was started before explorer.view.browser.app was imported, without the "
                "Origin check: any web page could drive it. Import explorer.view.browser.app first.")
        host = server.get_host()
        if host not in ("0.0.0.0", "::", ""):
            origin.allow(port, host)  # the address the user gave (a name the browser will use)
        self._port = port
        self.server = server
        # Shared (client None): the server's GUI and scene, seen and changed by every page.
        # Per client: this page's own GUI, scene and camera; nobody else sees them
        # (PerClientExplorer makes one app per page and ends it when the page goes).
        self.client = client
        self.target = client if client is not None else server
        self.kernels = kernels
        self.checks = checks
        self.inbox = Inbox()
        self._ticking: int | None = None  # the thread applying a frame (its GUI writes are no requests)
        self._serial_lock = threading.Lock()
        self._serial = 0  # the newest request submitted or refused
        self.frames = 0  # frames applied by the loop (for the benchmark)

        # scene choices: built-ins plus the given file when it is elsewhere
        paths = list(scenes if scenes is not None else builtin_scenes())
        given = Path(scene_path).resolve()
        if given not in [p.resolve() for p in paths]:
            paths.insert(0, given)
        self.scene_paths: dict[str, str] = {}
        for p in paths:
            label = p.name if p.name not in self.scene_paths else str(p)
            self.scene_paths[label] = str(p)
        self.scene_label = next(k for k, v in self.scene_paths.items() if Path(v).resolve() == given)
        self.base_overrides: tuple[str, ...] = tuple(overrides)
        self.magnification_value: float | None = None  # None: the scene's default (until the user moves the slider)

        # what is shown (the loop's)
        self.current: Prepared | None = None
        self.applied_serial = -1
        self.handled_serial = -1  # newest request shown or refused
        self.error_text = ""  # the message the status box shows ("" when fine)
        self._error: tuple[int, str] | None = None  # (serial, message) of the failure shown
        self._loading = 0  # serial of a scene load whose result opens at its own playback speed
        self._compiled = kernels is None or kernels.ready()
        self._replot_at: float | None = None  # when to make the plots anew for a page that connected
        self._result_serial = -1  # the request whose result (not magnification) is shown: what checks judge

        self._build_gui(playing)
        if client is None:
            server.on_client_connect(self._client_connected)
            server.on_client_disconnect(lambda c: self.inbox.put(ClientLeft(c.client_id)))
        else:
            self._client_connected(client)
        self.worker = ComputeWorker(
            on_ready=lambda p: self.inbox.put(Computed(p)),
            on_error=lambda request, message: self.inbox.put(Failed(request, message, request.serial)),
            on_result=on_result,
            on_sweep=lambda serial, sweep: self.inbox.put(SweepArrived(serial, sweep)),
            on_advice=lambda serial, readout: self.inbox.put(AdviceArrived(serial, readout)),
            compiled=None if kernels is None else kernels.ready,
            checks=checks,
            on_checks=lambda serial, summary: self.inbox.put(ChecksArrived(serial, summary)),
            on_checked=on_checked,
            time_limit=time_limit).start()
        self._loading = self._submit()
        self.loop = FrameLoop(self.tick, fps, wake=self.inbox.arrived).start()

    # ------------------------------------------------------------------ the page

    def _build_gui(self, playing: bool) -> None:
        gui = self.target.gui
        inbox, echo = self.inbox, self._is_echo
        gui.configure_theme(control_width="large", dark_mode=False, show_logo=False, show_share_button=False)
        gui.main_panel.dock_right()
        gui.main_panel.set_width(380)
        gui.add_markdown("**Valve-Gear Explorer** — cam, roller, lever, spring, valve")
        self.share_note = gui.add_markdown(f"<small>{SHARED_NOTE if self.client is None else OWN_NOTE}</small>")
        self.status = gui.add_html(status_html(""))
        self.controls = PlaybackControls(gui, inbox, echo, playing)
        with gui.add_folder("Scene"):
            self.fields = Fields(gui, inbox, echo, list(self.scene_paths), self.scene_label)
        # plots and read-outs in their own panel on the left, beside the 3D view
        self.side_panel = gui.add_panel()
        plots_tab = self.side_panel.add_tab("Plots")
        self.plots = Plots(gui, plots_tab, SCRUB_HINT + " (click or drag)")
        self.sweep_view = SweepView(gui, plots_tab)
        self.readouts = Readouts(self.status, gui, self.side_panel.add_tab("Read-outs"), inbox, echo)
        self.checks_panel = ChecksPanel(gui, self.side_panel.add_tab("Checks"), inbox) if self.checks is not None else None
        self.side_panel.dock_left()
        self.side_panel.set_width(440)
        wire(self.plots.angle, inbox, lambda v, page, at: Scrubbed(float(v)), echo)
        wire(self.sweep_view.rpm, inbox, lambda v, page, at: SweepSpeedChosen(v), echo)
        self.gear = GearView(self.target.scene)
        self.cameras = Cameras(self.server, self.client)

        # the controls by their names on the page (tests and benchmarks drive them)
        c, f, r = self.controls, self.fields, self.readouts
        self.play, self.speed, self.angle, self.magnification = c.play, c.speed, c.angle, c.magnification
        self.scene, self.reset, self.effects = f.scene, f.reset, f.effects
        self.plot_angle, self.stale_plots, self.sweep_rpm = self.plots.angle, self.plots.stale, self.sweep_view.rpm
        self.readout, self.event_jump, self.events_table, self.stale_readout = r.readout, r.event_jump, r.events_table, r.stale

    def _is_echo(self) -> bool:
        """Whether this thread is the loop applying a frame (its writes fire callbacks too)."""
        return threading.get_ident() == self._ticking

    def _client_connected(self, client) -> None:
        # a page counts as connected once it has reported its camera, so its canvas' shape is
        # known: the loop frames the gear for it
        client.camera.on_update(lambda camera: self.inbox.put(CameraMoved(camera)))
        self.inbox.put(ClientConnected(client))

    # ------------------------------------------------------------------ state for callers

    @property
    def playback(self):
        return self.controls.playback

    @property
    def sweep(self):
        """The speed sweep shown (a SpeedSweep, a NoSweep, or None while none has come)."""
        return self.sweep_view.sweep

    @property
    def camera(self):
        return self.cameras.camera

    @property
    def client_cameras(self):
        return self.cameras.client_cameras

    @property
    def loop_errors(self) -> int:
        return self.loop.errors

    # ------------------------------------------------------------------ requests to compute

    def _next_serial(self) -> int:
        with self._serial_lock:
            self._serial += 1
            return self._serial

    def _submit(self) -> int:
        """Compute what the page now asks for; returns the request's serial."""
        serial = self._next_serial()
        user = self.fields.user
        self.worker.submit(Request(
            path=self.scene_paths[self.scene_label],
            overrides=self.base_overrides + tuple(user[k] for k in sorted(user)),
            magnification=self.magnification_value,
            serial=serial,
        ))
        return serial

    def reject(self, message: str) -> int:
        """Show why a value was not used, like a computation's error (any thread); it counts as
        the newest request, handled. Returns its serial."""
        serial = self._next_serial()
        self.inbox.put(Failed(None, message, serial))
        return serial

    # ------------------------------------------------------------------ the frame

    def tick(self, dt: float) -> None:
        """Apply the requests recorded since the last frame and advance the animation by dt
        seconds (one frame)."""
        self._ticking = threading.get_ident()
        try:
            items = self.inbox.take()
            frame = _Frame()
            for item in items:
                self._handle(item, frame)
            now = time.monotonic()
            self.fields.apply_due(now, self._submit, self.reject, self.current)
            if not self._compiled and self.kernels.ready():
                self._compiled = frame.resweep = True
            if frame.resweep:
                self.worker.resweep()  # the compiled solver is ready: every elastic speed at once
            replot = self._replot_at is not None and now >= self._replot_at and self.current is not None
            if replot:
                self._replot_at = None
            playback = self.controls.playback
            if frame.checks is not None and (self.checks_panel is None or frame.checks.serial != self._result_serial):
                frame.checks = None  # of a result no longer shown
            if frame.checks is not None and not isinstance(frame.checks.summary, str):
                self.plots.limits = lambda prepared, summary=frame.checks.summary: with_limits(
                    prepared.plots, summary, prepared.result)
            if frame.incoming is not None:
                self.handled_serial = max(self.handled_serial, frame.incoming.request.serial)
                if self._error is not None and self._error[0] < frame.incoming.request.serial:
                    self._error = None
            self.error_text = self._error[1] if self._error is not None else ""
            prepared = frame.incoming or self.current
            if prepared is not None and not frame.scrubbed:
                playback.advance(dt, prepared.result.summary["revolution_time_s"])
            with self.target.atomic():
                if frame.incoming is not None:
                    self._show(frame.incoming)
                self.fields.settle(now, self.current)
                if frame.checks is not None:
                    if self.current is not None and not replot:
                        self.plots.show(self.current, None if playback.playing else playback.angle_deg)  # the limits
                    self.checks_panel.show(frame.checks.serial, frame.checks.summary)
                    if frame.checks.serial != self._result_serial:  # a newer result came in this frame
                        self.checks_panel.checking(self.current.label)
                if replot:
                    self.plots.replot(self.current, None if playback.playing else playback.angle_deg)
                if frame.advice is not None and self.current is not None \
                        and frame.advice.serial == self.current.request.serial:
                    self.readouts.readout.content = frame.advice.readout
                self._say()
                if frame.sweep or frame.incoming is not None:
                    self.sweep_view.show(self.current, self.inbox.write, self._compiling(),
                                         speed_pending="drive.rpm" in self.fields.sent)
                if self.current is not None:
                    angle = playback.angle_deg
                    step = self.gear.pose(angle, force=frame.incoming is not None)
                    self.plots.cursor(self.current, None if playback.playing else angle, step,
                                      force=frame.incoming is not None)
                    self.controls.sync((self.controls.angle, self.plots.angle))
                    self.cameras.aim_pending(self.current)
            self.target.flush()
            self.frames += 1
            self.inbox.done(len(items))
        finally:
            self._ticking = None

    def _handle(self, item, frame: "_Frame") -> None:
        """Apply one recorded request (loop thread)."""
        fields, current = self.fields, self.current
        if isinstance(item, Edited):
            fields.edited(item, self._submit, self.reject, current)
        elif isinstance(item, Submitted):
            fields.submitted(self._submit, self.reject, current)
        elif isinstance(item, EffectsTicked):
            fields.effects_ticked(item.names, self._submit, current)
        elif isinstance(item, SceneChosen):
            if item.label in self.scene_paths:  # nothing else may be loaded from a page
                self.scene_label, self.base_overrides = item.label, ()
                fields.cleared()
                self.controls.speed_chosen = False
                self.magnification_value = None  # the new scene opens at its own
                self._loading = self._submit()
        elif isinstance(item, ResetClicked):
            fields.cleared()
            self._submit()
        elif isinstance(item, Magnified):
            if math.isfinite(item.value):
                self.magnification_value = min(max(item.value, MAGNIFICATION_RANGE[0]), MAGNIFICATION_RANGE[1])
                self._submit()
        elif isinstance(item, Played):
            self.controls.playback.playing = item.on
        elif isinstance(item, SpeedChosen):
            self.controls.chose_speed(item.label)
        elif isinstance(item, Scrubbed):
            if math.isfinite(item.angle):
                self.controls.scrub(item.angle)
                frame.scrubbed = True
        elif isinstance(item, EventChosen):
            shown = frame.incoming or current
            angle = dict(shown.events).get(item.label) if shown is not None else None
            if angle is not None:  # not the "—" entry, nor a list replaced meanwhile
                self.controls.scrub(angle)
                frame.scrubbed = True
        elif isinstance(item, SweepSpeedChosen):
            rpm = item.rpm
            if not isinstance(rpm, bool) and isinstance(rpm, (int, float)) and math.isfinite(rpm) and rpm > 0.0:
                # the same as typing it into Camshaft rpm
                fields.apply("drive.rpm", float(rpm), self._submit, self.reject, current, forced=True)
        elif isinstance(item, Computed):
            if frame.incoming is None or item.prepared.request.serial > frame.incoming.request.serial:
                frame.incoming = item.prepared
        elif isinstance(item, Failed):
            message = item.message
            if item.request is not None:
                message = fields.failed(item.request, frame.incoming or current, message)
            self.handled_serial = max(self.handled_serial, item.serial)
            # a value refused by the page may be newer than the computation failing now
            if self._error is None or item.serial > self._error[0]:
                self._error = (item.serial, message)
        elif isinstance(item, SweepArrived):
            self.sweep_view.arrived(item.serial, item.sweep)
            frame.sweep = True
        elif isinstance(item, AdviceArrived):
            frame.advice = item
        elif isinstance(item, ChecksArrived):
            frame.checks = item
        elif isinstance(item, CheckChosen):
            self._go_to_check(item.rule, frame)
        elif isinstance(item, ClientConnected):
            self.cameras.connected(item.client)
            self.plots.settle()
            self._replot_at = time.monotonic() + REPLOT_AFTER_S
        elif isinstance(item, ClientLeft):
            self.cameras.left(item.client_id)
        elif isinstance(item, CameraMoved):
            self.cameras.reported(item.camera)

    def _show(self, prepared: Prepared) -> None:
        """A new result (or a new magnification of the one shown): parts, plots, read-outs,
        fields, the camera of a new scene file, and its playback speed."""
        previous = self.current
        if previous is not None and prepared.request.serial < previous.request.serial:
            return
        self.current = prepared
        self.applied_serial = prepared.request.serial
        if previous is None or prepared.result is not previous.result:
            self._result_serial = prepared.request.serial
            if self.checks_panel is not None:
                self.checks_panel.checking(prepared.label)
        self.gear.show(prepared)
        # compared with what is shown, not with the worker's previous bundle (`new_result`): a
        # new result and a magnification change computed together come as one bundle
        if previous is None or prepared.result is not previous.result:
            playback = self.controls.playback
            self.plots.show(prepared, None if playback.playing else playback.angle_deg)
            self.readouts.show(prepared)
        self.fields.show(prepared, time.monotonic())
        self.controls.show_magnification(prepared.request.magnification)
        if previous is None or Path(previous.request.path) != Path(prepared.request.path):
            self.cameras.aim(prepared)
        if self._loading and prepared.request.serial >= self._loading:
            self._loading = 0
            self.controls.default_speed(default_speed(prepared.result.summary["revolution_time_s"]))

    def _go_to_check(self, rule: str, frame: "_Frame") -> None:
        """A line of the Checks panel clicked: the speed of its rule's worst value as if typed
        into Camshaft rpm (a new result at that speed), its cam angle as if scrubbed."""
        line = self.checks_panel.line(rule) if self.checks_panel is not None else None
        if line is None:
            return
        speed, angle = line.target()
        current = self.current
        shown_rpm = current.scene.drive.rpm if current is not None else None
        if speed is not None and (shown_rpm is None or abs(speed - shown_rpm) > 1e-9 * speed):
            self.fields.apply("drive.rpm", float(speed), self._submit, self.reject, current, forced=True)
        if angle is not None:
            self.controls.scrub(angle)
            frame.scrubbed = True

    def _compiling(self) -> str:
        return "" if self.kernels is None else self.kernels.note()

    def _say(self) -> None:
        """The status box and the "Stale" lines: an error, else a note, else ready."""
        note = self.fields.note or self._compiling()
        self.readouts.say(self.error_text, note)
        stale = self.current.label if self.error_text and self.current is not None else None
        self.readouts.mark_stale((self.plots.stale, self.readouts.stale), stale)

    # ------------------------------------------------------------------ control from Python

    def wait_applied(self, timeout: float = 30.0) -> bool:
        """Wait until the newest request has been computed and shown (or refused)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.worker.wait_idle(max(0.0, deadline - time.monotonic())):
                if self.inbox.settled() and not self.fields.waiting() \
                        and self.handled_serial >= self._serial:
                    # one more frame so that pose updates after the last apply are out
                    frames = self.frames
                    while self.frames < frames + 2 and time.monotonic() < deadline:
                        time.sleep(0.002)
                    return True
            time.sleep(0.002)
        return False

    def stop(self) -> None:
        self.loop.stop()
        self.worker.stop()  # ends the computing child process too
        if self.client is None:
            origin.forget(self._port)  # per client, the server's guard outlives this page


class _Frame:
    """What the requests of one frame amount to (besides the state they changed)."""

    def __init__(self):
        self.incoming: Prepared | None = None  # the newest result that came
        self.scrubbed = False  # the angle was set: the clock does not advance this frame
        self.sweep = False  # a sweep (or a step of it) came
        self.advice = None  # the read-out with the spring advice that came
        self.checks = None  # the design checks that came (checks_panel.ChecksArrived)
        self.resweep = False
