"""The browser explorer: a viser server animating the gear, with controls, plots and read-outs.

Threading (the pattern of viser's examples): GUI callbacks run on viser's thread pool, several
at once, so they only *record* what was asked (under a lock) and hand recomputations to the
ComputeWorker (newest request wins), which runs each in a child process that is killed past its
time limit (explorer.view.browser.worker), so no value a page sends can stall the server. Websocket
handshakes from other sites are refused (explorer.view.browser.origin). One loop thread owns every
scene and GUI update: it takes the recorded requests, advances the playback clock and applies
one frame under `server.atomic()`. When the loop itself assigns a GUI value (the scrub slider following the
animation, fields set to the values a result used), the `on_update` that viser fires synchronously
is recognised by a thread-local flag and ignored, so nothing feeds back.

Fields: a page sends every keystroke of a text or number input. Those are recorded, not applied;
the loop applies a field's newest value once its typing has paused for TYPING_PAUSE_S. After
each result the loop sets every field to the value the result used, except a field the user is
editing (typed text not applied yet, an edit newer than the result, or a value the loop did not
put there and no request carried: a page's value whose callback is still on its way).
"""

from __future__ import annotations

import contextlib
import math
import threading
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .. import parts as meshes
from ...lift import registry as laws
from ...effects import registry as effect_table
from . import origin
from .compute import ComputeWorker
from .model import (
    COMPUTE_TIME_LIMIT_S,
    PARAMETERS,
    SPEEDS,
    SPRING_RESOLUTION,
    Playback,
    Prepared,
    Request,
    default_speed,
    override,
    step_index,
)

# The caller creates the viser server before the app (`explorer serve`, the tests), after
# importing this module: the Origin check must be in place by then. ExplorerApp refuses a server
# started without it.
origin.install()

GEAR = "/gear"  # scene-tree root of the moving parts; nodes are /gear/<part>
PLOT_CURSOR_HZ = 8.0  # the plots' angle cursor is redrawn at most this often

# Bounds on what a page may ask for. The page's widgets enforce them too, but any page (or script)
# on the websocket can send any value, so the callbacks check again. 100 000 steps per revolution
# (28 times the default) take about 1 s and 100 MB; the scene reader's own maxima are far larger.
MAX_GUI_STEPS = 100_000
MAX_TEXT_LENGTH = 100
MAGNIFICATION_RANGE = (1.0, 50.0)
# A value typed into a field on the page is applied once the typing pauses this long (newest
# wins), never per keystroke: viser sends every change of a text or number input.
TYPING_PAUSE_S = 0.6
# The error box shows at most this many lines' height and scrolls beyond: a long message must not
# push the controls below it off an 800 px page.
ERROR_BOX_MAX_EM = 7.5
PLOT_SLIDER_ORDER = 1e6  # after every plot: the plots are added and removed as results change
SWEEP_ORDER = 2e6  # the speed sweep below the plots and their slider
NO_EVENT = "—"
# What the page says about who else sees it (`explorer serve --shared` / `--per-client`)
SHARED_NOTE = ("Shared session: everyone connected to this server sees these controls and results, "
               "and a change made on one page changes them on all.")
OWN_NOTE = "Your own session: your changes are yours; others on this server do not see them."


def _user_overrides(overrides) -> dict[str, str]:
    """key -> "key=value" for the overrides the GUI makes (parameters and effects)."""
    out = {}
    for text in overrides:
        key = text.split("=", 1)[0]
        if key in PARAMETERS or key == "effects":
            out[key] = text
    return out


PLOT_X_LABEL = "cam angle θ [°]"
SWEEP_X_LABEL = "camshaft speed [rpm]"
WIDTH_SWEEP = (2.5, 1.8, 1.8)


def sweep_scales(span: tuple[float, float], y_range: tuple[float, float]) -> dict:
    # y set from Python: uPlot's autorange fails on the NaN of elastic speeds not yet computed
    return {"x": {"time": False, "auto": False, "range": [0.0, float(span[1])]},
            "y": {"auto": False, "range": [float(y_range[0]), float(y_range[1])]},
            "cursor": {"auto": False, "range": [0.02, 1.0]}}


def sweep_plot_options(title: str, y_label: str, series, span: tuple[float, float],
                       y_range: tuple[float, float] = (0.0, 1.0)) -> dict:
    """uPlot options of a speed-sweep plot: x the camshaft speed over the sweep's range; two
    markers drawn like the cam-angle cursor (a spike on a scale whose visible range starts above
    0): the current speed (black) and the rigid float speed (red, dashed)."""
    out = [{"label": SWEEP_X_LABEL}]
    for k, (label, _, colour) in enumerate(series):
        out.append({"label": label, "stroke": colour, "width": WIDTH_SWEEP[k % len(WIDTH_SWEEP)]})
    out.append({"label": "current speed", "stroke": "#111111", "width": 1.5, "scale": "cursor"})
    out.append({"label": "rigid float speed", "stroke": "#e74c3c", "width": 1.5, "dash": [6, 4], "scale": "cursor"})
    return dict(
        series=tuple(out), title=title,
        scales=sweep_scales(span, y_range),
        axes=({"label": SWEEP_X_LABEL, "size": 30, "labelSize": 16, "labelGap": 0},
              {"label": y_label, "size": 58, "labelSize": 16, "labelGap": 0}),
        padding=(14, 18, 0, 0), aspect=2.0,
        legend={"show": True, "live": True},
        cursor={"focus": {"prox": 12}},
        focus={"alpha": 0.35},
    )


def plot_options(plot) -> dict:
    """uPlot options of one plot (viser passes them to the page as they are, JSON only: no
    JavaScript callbacks). Both axes are named with their unit; the series carry their dashes
    (explorer.view.browser.model.DASHES); the legend follows the pointer and shows the values under
    it (a click on a legend entry hides or shows that curve); a curve near the pointer is
    highlighted; the top padding keeps the highest tick label ("1,000") inside the plot."""
    series = [{"label": PLOT_X_LABEL}]
    for k, (label, _, colour) in enumerate(plot.series):
        style = plot.styles[k] if k < len(plot.styles) else {"width": 1.5}
        series.append({"label": label, "stroke": colour, **style})
    # the cursor: a one-sample spike on its own 0..1 scale whose base lies below the visible
    # range, so only a vertical line at the current angle shows
    series.append({"label": "now", "stroke": "#111111", "width": 1.5, "scale": "cursor"})
    return dict(
        series=tuple(series), title=plot.title,
        scales={"x": {"time": False, "auto": False, "range": [0, 360]},
                "cursor": {"auto": False, "range": [0.02, 1.0]}},
        axes=({"label": PLOT_X_LABEL, "size": 30, "labelSize": 16, "labelGap": 0},
              {"label": plot.y_label, "size": 58, "labelSize": 16, "labelGap": 0}),
        padding=(14, 18, 0, 0), aspect=2.0,
        legend={"show": True, "live": True},
        cursor={"focus": {"prox": 12}},
        focus={"alpha": 0.35},
    )


def _same(a, b) -> bool:
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return float(a) == float(b)
    return a == b


def part_node(name: str) -> str:
    return f"{GEAR}/{name}"


def _color(name: str) -> tuple[int, int, int]:
    try:
        return meshes.PART_COLORS[name]  # knows the other gears' parts too
    except KeyError:
        return (150, 150, 155)


# The camera: a narrower lens than three.js' 75 degrees (less distortion of a machine drawing),
# and until a page reports its canvas, a canvas a little taller than wide, as the 3D view between
# the two side panels of a laptop-sized window is.
CAMERA_FOV = math.radians(45.0)
ASSUMED_ASPECT = 0.75


def _same_camera(position, look_at, frame) -> bool:
    reach = float(np.linalg.norm(np.subtract(frame.position, frame.look_at)))
    return bool(np.allclose(position, frame.position, atol=1e-4 * reach)
                and np.allclose(look_at, frame.look_at, atol=1e-4 * reach))


def camera_frame(prepared: Prepared, aspect: float = ASSUMED_ASPECT) -> meshes.CameraFrame:
    """The camera that sees every part over the whole revolution, in a canvas of `aspect`."""
    lo, hi = prepared.bounds
    return meshes.frame_bounds(lo, hi, fov=CAMERA_FOV, aspect=aspect)


class ExplorerApp:
    """Everything `explorer serve` shows, on an existing viser server."""

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
    ):
        from ...scene.builtin import builtin_scenes, find_scene

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
        self.fps = fps
        self._lock = threading.Lock()
        self._echo = threading.local()  # set while the loop assigns GUI values itself
        self._stop = threading.Event()
        self.frames = 0  # frames applied by the loop (for the benchmark)
        self.loop_errors = 0  # exceptions caught in the loop (should stay 0)

        # scene choices: built-ins plus the given file when it is elsewhere
        paths = list(scenes if scenes is not None else builtin_scenes())
        given = Path(scene_path).resolve()
        if given not in [p.resolve() for p in paths]:
            paths.insert(0, given)
        self.scene_paths: dict[str, str] = {}
        for p in paths:
            label = p.name if p.name not in self.scene_paths else str(p)
            self.scene_paths[label] = str(p)
        self._scene_label = next(k for k, v in self.scene_paths.items() if Path(v).resolve() == given)

        # requested state (written by callbacks under the lock)
        self._base_overrides: tuple[str, ...] = tuple(overrides)
        self._user: dict[str, str] = {}  # parameter key -> override text
        self._magnification = 1.0
        self._serial = 0
        self._refresh_serial = 0  # the first result at or after this serial sets the scene choice
        self._typed: dict[str, tuple[Any, float]] = {}  # key -> (value typed on a page, when): not applied yet
        self._edit_serial: dict[str, int] = {}  # key -> serial of the request carrying the user's newest edit
        self._edited: dict[int, tuple[str, ...]] = {}  # serial -> keys the user changed in that request
        self._good_user: dict[str, str] = {}  # the user overrides of the result shown
        self._note = ""  # a one-line remark in the status box that is no error
        self._held_effects: list[str] | None = None  # effects ticked that wait for a linkage stiffness
        self._field_shown: dict[str, Any] = {}  # key -> what the loop last put into that field
        self._field_sent: dict[str, Any] = {}  # key -> the user's newest value sent for computing
        self._status_shown = None
        self._scrub: float | None = None
        self._pause_requested = False
        self._incoming: Prepared | None = None
        self._error: tuple[int, str] | None = None
        self.playback = Playback(playing=playing)
        self._speed_chosen = False
        self._sweep_incoming: tuple[int, Any] | None = None  # (serial, SpeedSweep or None) from the worker

        # applied state (loop thread only)
        self.current: Prepared | None = None
        self.applied_serial = -1
        self.handled_serial = -1  # newest request shown or rejected
        self.error_text = ""  # the message the status box shows ("" when fine)
        self._handles: dict[str, Any] = {}
        self._shown_meshes: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._last_index = -1
        self._last_spring = math.nan
        self._last_cursor = 0.0
        self._play_shown = playing  # what the loop last put in the Play box and the slider
        self._slider_shown = [0.0, 0.0]  # what the loop last put into each cam-angle slider
        self._cursor_index = -1
        self._plot_handles: list[Any] = []
        self._plot_signature: list[tuple] = []
        self.sweep: Any = None  # the SpeedSweep shown (loop thread)
        self._sweep_handles: list[Any] = []
        self._sweep_signature: tuple = ()
        self._sweep_rpm_shown = math.nan  # what the loop last put into the sweep's speed slider
        self._event_angles: dict[str, float] = {}  # "Go to event" entry -> cam angle (under the lock)
        self._stale_shown = None
        self.camera: meshes.CameraFrame | None = None  # the initial camera (new pages, Reset View)
        self.client_cameras: dict[int, meshes.CameraFrame] = {}  # what each page was last aimed at
        self._earlier_aims: dict[int, tuple] = {}  # and the aims before that, newest last
        self._aim_pending: set[int] = set()  # pages that connected since the last frame

        self._build_gui()
        # a page counts as connected once it has reported its camera, so its canvas' shape is
        # known: the loop frames the gear for it
        if client is None:
            server.on_client_connect(self._client_connected)
            server.on_client_disconnect(self._client_disconnected)
        else:
            self._client_connected(client)
        self.worker = ComputeWorker(on_ready=self._on_ready, on_error=self._on_error, on_result=on_result,
                                    on_sweep=self._on_sweep, time_limit=time_limit).start()
        self._submit(refresh=True)
        self._thread = threading.Thread(target=self._loop, name="explorer-loop", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ GUI construction

    def _build_gui(self) -> None:
        gui = self.target.gui
        gui.configure_theme(control_width="large", dark_mode=False, show_logo=False, show_share_button=False)
        gui.main_panel.dock_right()
        gui.main_panel.set_width(380)
        gui.add_markdown("**Valve-Gear Explorer** — cam, roller, lever, spring, valve")
        self.share_note = gui.add_markdown(f"<small>{SHARED_NOTE if self.client is None else OWN_NOTE}</small>")
        self.status = gui.add_html(self._status_html(""))

        with gui.add_folder("Playback"):
            self.play = gui.add_checkbox("Play", initial_value=self.playback.playing, hint="play / pause the animation")
            self.speed = gui.add_dropdown("Speed", [label for label, _ in SPEEDS], initial_value="1/100",
                                          hint="playback speed relative to the real camshaft speed")
            self.angle = gui.add_slider("Cam angle [°]", min=0.0, max=360.0, step=0.1, initial_value=0.0,
                                        hint="scrub: pauses the animation at this angle")
            self.magnification = gui.add_slider("Magnification", min=MAGNIFICATION_RANGE[0], max=MAGNIFICATION_RANGE[1],
                                                step=1.0, initial_value=1.0,
                                                hint="enlarges the lash gap and the valve's deviation from rigid motion")

        with gui.add_folder("Scene"):
            self.scene = gui.add_dropdown("Scene", list(self.scene_paths), initial_value=self._scene_label)
            # right under the scene: an 800 px page shows it even with an error above
            self.reset = gui.add_button("Reset to scene file", hint="every field back to the scene file's values")
            law_names = list(laws.names())
            self.fields: dict[str, Any] = {}
            for key, (label, kind, unit) in PARAMETERS.items():
                if kind == "choice":
                    handle = gui.add_dropdown(label, law_names, initial_value=law_names[0])
                elif kind == "number":
                    handle = gui.add_number(label, 1.0, step=1.0)
                elif kind == "integer":
                    handle = gui.add_number(label, 3600, min=1, max=MAX_GUI_STEPS, step=1)
                else:
                    handle = gui.add_text(f"{label} [{unit}]", "", hint=f"a quantity with units, e.g. '1.5 {unit}'")
                handle.on_update(self._field_callback(key))
                self.fields[key] = handle
                self._field_shown[key] = handle.value
            self.effects: dict[str, Any] = {}
            with gui.add_folder("Effects"):
                for name in effect_table.names():
                    handle = gui.add_checkbox(name, initial_value=name == "kinematics")
                    handle.on_update(self._effects_changed)
                    self.effects[name] = handle

        # plots and read-outs in their own panel on the left, beside the 3D view
        self.side_panel = gui.add_panel()
        self._plots_tab = self.side_panel.add_tab("Plots")
        with self._plots_tab:
            self.stale_plots = gui.add_markdown("", visible=False, order=-2.0)
            self.plot_note = gui.add_markdown("", visible=False, order=-1.0)
            # viser's uPlot sends no clicks or pointer positions back to Python: the nearest thing
            # to clicking a plot is this slider right under the plots, on their angle scale
            self.plot_angle = gui.add_slider(PLOT_X_LABEL, min=0.0, max=360.0, step=0.1, initial_value=0.0,
                                             order=PLOT_SLIDER_ORDER,
                                             hint="scrub: click or drag to show this angle (pauses the animation)")
            # the speed sweep under the plots: its plots are added as sweeps arrive (at
            # SWEEP_ORDER + 1, + 3, + 5); this slider sits right under the rigid one, on its speed scale
            # (viser's uPlot reports no clicks, as for the cam angle above)
            self.sweep_note = gui.add_markdown("**Speed sweep:** computing…", order=SWEEP_ORDER)
            self.sweep_rpm = gui.add_slider("Speed [rpm]", min=0.0, max=1.0, step=1.0, initial_value=0.0,
                                            order=SWEEP_ORDER + 2, disabled=True,
                                            hint="choose a camshaft speed: the gear, plots and read-outs move to it")
            self.sweep_progress = gui.add_markdown("", order=SWEEP_ORDER + 10)
        self._readout_tab = self.side_panel.add_tab("Read-outs")
        with self._readout_tab:
            self.stale_readout = gui.add_markdown("", visible=False)
            self.readout = gui.add_markdown("computing…")
            self.event_jump = gui.add_dropdown("Go to event", (NO_EVENT,), initial_value=NO_EVENT,
                                               hint="shows the gear at the event's cam angle (pauses the animation)")
            self.events_table = gui.add_html("")
        self.side_panel.dock_left()
        self.side_panel.set_width(440)

        self.play.on_update(self._play_changed)
        self.speed.on_update(self._speed_changed)
        self.angle.on_update(self._angle_changed)
        self.plot_angle.on_update(self._angle_changed)
        self.sweep_rpm.on_update(self._sweep_speed_chosen)
        self.event_jump.on_update(self._event_chosen)
        self.magnification.on_update(self._magnification_changed)
        self.scene.on_update(self._scene_changed)
        self.reset.on_click(self._reset_clicked)

    @staticmethod
    def _status_html(message: str, note: str = "") -> str:
        import html

        if not message and note:
            return ('<div role="status" style="color:#7a4f01;background:#fff4e0;border:1px solid #f0d19a;'
                    'border-radius:4px;padding:4px 6px;font-size:0.85em">' f"{html.escape(note)}</div>")
        if not message:
            return '<div style="color:#2e7d32;font-size:0.85em">ready</div>'

        # a long message scrolls inside its box: the controls below stay where they are
        return (
            '<div role="alert" class="explorer-error" style="color:#b71c1c;background:#fdecea;'
            'border:1px solid #f5c6cb;border-radius:4px;padding:4px 6px;font-size:0.85em;white-space:pre-wrap;'
            f'max-height:{ERROR_BOX_MAX_EM}em;overflow-y:auto;overflow-wrap:anywhere">'
            f"{html.escape(message)}</div>"
        )

    # ------------------------------------------------------------------ callbacks (record only)

    def _is_echo(self) -> bool:
        return bool(getattr(self._echo, "on", False))

    @contextlib.contextmanager
    def _programmatic(self):
        self._echo.on = True
        try:
            yield
        finally:
            self._echo.on = False

    def _field_callback(self, key: str):
        def callback(event) -> None:
            if self._is_echo():
                return
            value = event.target.value
            if PARAMETERS[key][1] != "choice" and getattr(event, "client", None) is not None:
                # typed on a page: every keystroke arrives here. Record it; the loop applies it
                # once the typing pauses (newest wins), and never writes into this field meanwhile
                with self._lock:
                    self._typed[key] = (value, time.monotonic())
                return
            self._apply_edit(key, value)

        return callback

    def _apply_edit(self, key: str, value) -> None:
        label, kind, _ = PARAMETERS[key]
        try:
            value = self._checked(kind, value, self.fields[key])
        except ValueError as exc:
            self._reject(f"error: {label}: {exc}; {self._in_use(key)}")
            return
        edited = (key,)
        with self._lock:
            self._typed.pop(key, None)
            self._user[key] = override(key, value)
            self._field_sent[key] = value
            if key == "linkage.stiffness" and self._held_effects is not None:
                # the stiffness the elastic effect waited for: apply both together
                self._user["effects"] = override("effects", self._held_effects)
                self._held_effects = None
                self._note = ""
                edited = (key, "effects")
        self._submit(edited=edited)

    def _apply_typed(self) -> None:
        """Apply the values whose typing has paused (loop thread)."""
        now = time.monotonic()
        with self._lock:
            due = [(key, value) for key, (value, when) in self._typed.items() if now - when >= TYPING_PAUSE_S]
        for key, value in due:
            with self._lock:
                if self._typed.get(key, (None, None))[0] != value:
                    continue  # typed on meanwhile
                del self._typed[key]
            self._apply_edit(key, value)

    def _in_use(self, key: str) -> str:
        """Which value the shown result uses for `key`, for an error message."""
        current = self.current
        value = None if current is None else current.values.get(key)
        return "nothing computed yet" if current is None else f"the result shown uses {value if value not in (None, '') else 'none'}"

    @staticmethod
    def _checked(kind: str, value, handle):
        """The value a field may pass on to a recomputation; ValueError when out of bounds."""
        if kind in ("integer", "number"):
            try:
                number = float(value)
            except (TypeError, ValueError, OverflowError):
                raise ValueError(f"not a number: {str(value)[:MAX_TEXT_LENGTH]!r}") from None
            if not math.isfinite(number):
                raise ValueError(f"not a finite number: {value!r}")
            if kind == "number":
                return number
            if number > MAX_GUI_STEPS:
                raise ValueError(f"at most {MAX_GUI_STEPS} in the explorer, got {number:.6g}")
            return int(number) if number.is_integer() else number
        text = str(value)
        if len(text) > MAX_TEXT_LENGTH:
            raise ValueError(f"longer than {MAX_TEXT_LENGTH} characters")
        if kind == "choice" and text not in handle.options:
            raise ValueError(f"not one of the choices: {text!r}")
        return text

    def _reject(self, message: str) -> None:
        """Show why a value from the page was not used; like a computation's error, it counts as
        the newest request handled."""
        with self._lock:
            self._serial += 1
            self._error = (self._serial, message)

    def _effects_changed(self, event) -> None:
        if self._is_echo():
            return
        chosen = [name for name, handle in self.effects.items() if handle.value]
        with self._lock:
            if "elastic" in chosen and not self._has_stiffness():
                # no error for a missing [linkage]: the effect waits for a stiffness typed in
                self._held_effects = chosen
                label, _, unit = PARAMETERS["linkage.stiffness"]
                self._note = (f"elastic needs a linkage stiffness: type one into '{label} [{unit}]' "
                              f"(e.g. 3000 {unit}); until then the result shown is without it")
                return
            self._held_effects = None
            self._note = ""
            self._user["effects"] = override("effects", chosen or ["kinematics"])
        self._submit(edited=("effects",))

    def _has_stiffness(self) -> bool:
        """Whether the next computation has a linkage stiffness (lock held)."""
        if "linkage.stiffness" in self._user:
            return True
        current = self.current
        return current is not None and bool(current.values.get("linkage.stiffness"))

    def _held_elastic(self) -> bool:
        with self._lock:
            return self._held_effects is not None

    def _scene_changed(self, event) -> None:
        if self._is_echo():
            return
        if event.target.value not in self.scene_paths:
            return  # not one of the offered scenes: nothing a page may load
        with self._lock:
            self._scene_label = event.target.value
            self._base_overrides = ()
            self._user.clear()
            self._typed.clear()
            self._held_effects, self._note = None, ""
            self._speed_chosen = False
        self._submit(refresh=True)

    def _reset_clicked(self, event) -> None:
        with self._lock:
            self._user.clear()
            self._typed.clear()
            self._held_effects, self._note = None, ""
        self._submit(refresh=True)

    def _magnification_changed(self, event) -> None:
        if self._is_echo():
            return
        value = float(event.target.value)
        if not math.isfinite(value):
            return
        with self._lock:
            self._magnification = min(max(value, MAGNIFICATION_RANGE[0]), MAGNIFICATION_RANGE[1])
        self._submit()

    def _event_chosen(self, event) -> None:
        if self._is_echo():
            return
        with self._lock:
            angle = self._event_angles.get(event.target.value)
            if angle is None:
                return  # the "—" entry, or a list replaced meanwhile
            self._scrub = angle
            self._pause_requested = True

    def _play_changed(self, event) -> None:
        if self._is_echo():
            return
        with self._lock:
            self.playback.playing = bool(event.target.value)

    def _speed_changed(self, event) -> None:
        if self._is_echo():
            return
        speed = dict(SPEEDS).get(event.target.value)
        if speed is None:
            return
        with self._lock:
            self.playback.speed = speed
            self._speed_chosen = True

    def _angle_changed(self, event) -> None:
        if self._is_echo():
            return  # the loop moving the slider along with the animation
        angle = float(event.target.value)
        if not math.isfinite(angle):
            return
        with self._lock:
            self._scrub = angle
            self._pause_requested = True

    def _sweep_speed_chosen(self, event) -> None:
        """A speed chosen under the sweep plot: the same as typing it into Camshaft rpm."""
        if self._is_echo():
            return
        value = event.target.value
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)) \
                or float(value) <= 0.0:
            return
        self._apply_edit("drive.rpm", float(value))

    def _on_sweep(self, serial: int, sweep) -> None:
        with self._lock:
            self._sweep_incoming = (serial, sweep)

    def _submit(self, refresh: bool = False, edited: tuple[str, ...] = ()) -> None:
        with self._lock:
            self._serial += 1
            if refresh:
                self._refresh_serial = self._serial
                # every field shows what the new scene file holds
                self._edit_serial = {}
            for key in edited:
                self._edit_serial[key] = self._serial
            if edited:
                self._edited[self._serial] = edited
                for old in [s for s in self._edited if s < self._serial - 64]:
                    del self._edited[old]
            request = Request(
                path=self.scene_paths[self._scene_label],
                overrides=self._base_overrides + tuple(self._user[k] for k in sorted(self._user)),
                magnification=self._magnification,
                serial=self._serial,
            )
        self.worker.submit(request)

    def _client_connected(self, client) -> None:
        client.camera.on_update(self._camera_reported)
        with self._lock:
            self._aim_pending.add(client.client_id)

    def _camera_reported(self, camera) -> None:
        """A page reports its camera after every change. Its canvas often changes shape after
        the first report (the side panels dock) and whenever the window is resized: frame the
        gear again for the new shape, as long as the camera is still where it was put (a
        camera someone has moved is theirs)."""
        client_id = camera.client.client_id
        frame = self.client_cameras.get(client_id)
        if frame is None:
            return
        try:
            aspect = camera.aspect
            position, look_at = np.asarray(camera.position), np.asarray(camera.look_at)
        except (AssertionError, ZeroDivisionError):
            return
        # Untouched: the page shows a camera we put there, the last aim or one before it (the
        # initial camera, an earlier aim): on a loaded machine a page's report can cross our newest
        # aim on the wire, and such a late report is not the user moving the camera.
        untouched = any(_same_camera(position, look_at, placed) for placed in (frame, *self._placed_cameras(client_id)))
        if untouched and math.isfinite(aspect) and abs(aspect - frame.aspect) > 0.01 * frame.aspect:
            with self._lock:
                self._aim_pending.add(client_id)

    def _placed_cameras(self, client_id: int) -> tuple:
        earlier = self._earlier_aims.get(client_id, ())
        return (*earlier, self.camera) if self.camera is not None else tuple(earlier)

    def _client_disconnected(self, client) -> None:
        with self._lock:
            self._aim_pending.discard(client.client_id)
        self.client_cameras.pop(client.client_id, None)
        self._earlier_aims.pop(client.client_id, None)

    def _on_ready(self, prepared: Prepared) -> None:
        with self._lock:
            if self._incoming is None or prepared.request.serial > self._incoming.request.serial:
                self._incoming = prepared
            if self._error is not None and self._error[0] < prepared.request.serial:
                self._error = None

    def _on_error(self, request: Request, message: str) -> None:
        with self._lock:
            # the values this request changed are not used: later edits go on from the values
            # of the result shown, and the message says which value that is
            edited = self._edited.pop(request.serial, ())
            mine = _user_overrides(request.overrides)
            for key in edited:
                if self._user.get(key) == mine.get(key):
                    if key in self._good_user:
                        self._user[key] = self._good_user[key]
                    else:
                        self._user.pop(key, None)
            if edited and self.current is not None:
                names = [PARAMETERS[k][0] if k in PARAMETERS else k for k in edited]
                used = "; ".join(self._in_use(k) for k in edited if k in PARAMETERS)
                message = f"{message} — {', '.join(names)} not applied" + (f"; {used}" if used else "")
            # a value the callbacks rejected may be newer than the computation failing now
            if self._error is None or request.serial > self._error[0]:
                self._error = (request.serial, message)

    # ------------------------------------------------------------------ the loop

    def _loop(self) -> None:
        period = 1.0 / self.fps
        last = time.perf_counter()
        while not self._stop.is_set():
            now = time.perf_counter()
            try:
                self.tick(min(now - last, 0.1))
            except Exception:  # keep serving; the traceback helps whoever reads the console
                import traceback

                self.loop_errors += 1
                traceback.print_exc()
            last = now
            self._stop.wait(max(0.0, period - (time.perf_counter() - now)))

    def tick(self, dt: float) -> None:
        """Apply whatever was requested and advance the animation by dt seconds (one frame)."""
        self._apply_typed()
        with self._lock:
            incoming, self._incoming = self._incoming, None
            error, self._error = self._error, None
            scrub, self._scrub = self._scrub, None
            sweep, self._sweep_incoming = self._sweep_incoming, None
            pause, self._pause_requested = self._pause_requested, False
            if scrub is not None:
                self.playback.angle_deg = scrub % 360.0
                if pause:
                    self.playback.playing = False
            prepared = incoming or self.current
            if prepared is not None and scrub is None:
                self.playback.advance(dt, prepared.result.summary["revolution_time_s"])
            angle = self.playback.angle_deg
            playing = self.playback.playing
            refresh = incoming is not None and incoming.request.serial >= self._refresh_serial
            if refresh:
                self._refresh_serial = math.inf  # once per scene load or reset, not for every result
            if incoming is not None:
                self._good_user = _user_overrides(incoming.request.overrides)
                for serial in [s for s in self._edited if s <= incoming.request.serial]:
                    del self._edited[serial]
            choose_speed = incoming is not None and not self._speed_chosen
            if choose_speed:
                self._speed_chosen = True
            aim: set[int] = set()
            if prepared is not None:
                aim, self._aim_pending = self._aim_pending, set()
        with self.target.atomic():
            if incoming is not None:
                self._apply(incoming, refresh, choose_speed)
                self.handled_serial = max(self.handled_serial, incoming.request.serial)
            if error is not None:
                self.handled_serial = max(self.handled_serial, error[0])
            if error is not None and (incoming is None or error[0] > incoming.request.serial):
                self.error_text = error[1]
            elif incoming is not None and self.error_text:
                self.error_text = ""
            with self._lock:
                note = self._note
            if (self.error_text, note) != self._status_shown:
                self.status.content = self._status_html(self.error_text, note)
                self._status_shown = (self.error_text, note)
            self._mark_stale()
            if sweep is not None or incoming is not None:
                self._show_sweep(sweep)
            if self.current is not None:
                self._pose(angle, force=incoming is not None)
                self._sync_controls(angle, playing, scrub)
                clients = self._clients() if aim else {}
                for client_id in aim:
                    if client_id in clients:
                        self._aim_client(clients[client_id], self.current)
        self.target.flush()
        self.frames += 1

    def _mark_stale(self) -> None:
        """While the last change failed, the plots and read-outs say that they are the previous
        result's (the status box says why)."""
        stale = bool(self.error_text) and self.current is not None
        key = (stale, self.current.label if stale else "")
        if key == self._stale_shown:
            return
        text = (f"⚠ **Stale:** the last change failed (see the red box); shown is the previous result, "
                f"`{self.current.label}`") if stale else ""
        for handle in (self.stale_plots, self.stale_readout):
            handle.content = text
            handle.visible = stale
        self._stale_shown = key

    def _sync_controls(self, angle: float, playing: bool, scrub: float | None) -> None:
        """Keep the Play box and the cam-angle slider in step with the playback, without ever
        overwriting a person's input. viser stores a browser's new value in the handle first and
        runs the callback later (on its thread pool, late on a busy machine); a loop that set
        the control back to the playback state in between made the callback read its own value,
        and the click was lost. So the loop moves a control only while it still holds what the
        loop last put there; a value it did not put there is in flight, and is left alone until
        its callback has acted on it."""
        with self._programmatic():
            box = self.play.value
            if box == playing:
                self._play_shown = box
            elif box == self._play_shown:
                self.play.value = self._play_shown = playing
            shown = round(angle, 1) % 360.0
            for k, handle in enumerate((self.angle, self.plot_angle)):
                slider = handle.value
                if abs(slider - shown) < 1e-9 or (scrub is not None and abs(slider - scrub) < 1e-9):
                    self._slider_shown[k] = slider  # in step, or the scrub just applied came from it
                if abs(slider - self._slider_shown[k]) < 1e-9 and abs(slider - shown) > 1e-9:
                    handle.value = self._slider_shown[k] = shown

    def _apply(self, prepared: Prepared, refresh: bool, choose_speed: bool) -> None:
        """A new result (or a new magnification): meshes that changed, plots, read-outs, fields."""
        previous = self.current
        self.current = prepared
        self.applied_serial = prepared.request.serial
        n = len(prepared.result.columns["cam_angle_deg"])
        i = step_index(self.playback.angle_deg, n)
        # parts the new gear does not have (a rocking cam's eccentric after a swap to a
        # translating roller) leave the scene; re-adding a name replaces only that node
        for name in [name for name in self._shown_meshes if name not in prepared.meshes]:
            handle = self._handles.pop(name, None)
            if handle is not None:
                handle.remove()
            del self._shown_meshes[name]
        for name, (vertices, faces) in prepared.meshes.items():
            shown = self._shown_meshes.get(name)
            if shown is not None and shown[0] is vertices:
                continue
            if shown is not None and shown[0].shape == vertices.shape and np.array_equal(shown[0], vertices) \
                    and np.array_equal(shown[1], faces):
                self._shown_meshes[name] = (vertices, faces)
                continue
            pos, quat = prepared.poses[name]
            self._handles[name] = self.target.scene.add_mesh_simple(
                part_node(name), vertices, faces, color=_color(name),
                position=tuple(pos[i]), wxyz=tuple(quat[i]),
                flat_shading=False, side="double" if name == "spring" else "front",
            )
            self._shown_meshes[name] = (vertices, faces)
            if name == "spring":
                self._last_spring = prepared.layout.spring_rest_length
        self._last_index = -1
        # compared with what is shown, not with the worker's previous bundle (`new_result`): a
        # new result and a magnification change coming in the same frame arrive as one bundle
        # with new_result False, which must still redraw the plots
        if previous is None or prepared.result is not previous.result:
            self._update_plots(prepared)
            self.readout.content = prepared.readout
            self._show_events(prepared)
        law = self.fields["lift.law"]
        if prepared.laws and tuple(law.options) != prepared.laws:
            with self._programmatic():  # only the laws this scene can take
                if law.value not in prepared.laws and prepared.scene.lift.law in prepared.laws:
                    law.value = prepared.scene.lift.law
                law.options = prepared.laws
        if previous is None or Path(previous.request.path) != Path(prepared.request.path):
            self._aim_camera(prepared)
        self._show_values(prepared, refresh)
        if choose_speed:
            label = default_speed(prepared.result.summary["revolution_time_s"])
            with self._lock:
                self.playback.speed = dict(SPEEDS)[label]
            with self._programmatic():
                self.speed.value = label

    def _show_events(self, prepared: Prepared) -> None:
        self.events_table.content = prepared.events_html
        labels = tuple(label for label, _ in prepared.events)
        with self._lock:
            self._event_angles = dict(prepared.events)
        with self._programmatic():
            self.event_jump.options = (NO_EVENT, *labels)
            self.event_jump.value = NO_EVENT
            self.event_jump.disabled = not labels

    def _show_values(self, prepared: Prepared, refresh: bool) -> None:
        """Make every field show the value the result was computed with, except a field the user
        is editing: one with typed text not applied yet, one whose newest edit is in a request
        newer than this result, and one holding a value the loop did not put there and no
        request has carried (viser stores a page's value before its callback runs)."""
        values = prepared.values
        used = _user_overrides(prepared.request.overrides)
        with self._lock:
            typed = set(self._typed)
            edit_serial = dict(self._edit_serial)
        serial = prepared.request.serial
        with self._programmatic():
            if refresh:
                label = next((k for k, v in self.scene_paths.items() if Path(v) == Path(prepared.request.path)), None)
                if label is not None and self.scene.value != label:
                    self.scene.value = label
            for key, handle in self.fields.items():
                if key in typed or edit_serial.get(key, -1) > serial:
                    continue
                kind = PARAMETERS[key][1]
                value = values.get(key)
                shown = handle.value
                if key in used and used[key] == override(key, self._as_sent(kind, shown)):
                    continue  # the text the user gave is the value used (maybe in other units)
                if not (_same(shown, self._field_shown.get(key)) or _same(shown, self._field_sent.get(key))):
                    continue  # a page's new value whose callback has not run yet: in flight
                if kind == "quantity":
                    handle.value = value or ""
                elif kind == "choice":
                    if value in handle.options:
                        handle.value = value
                elif value is not None:
                    handle.value = value
                self._field_shown[key] = handle.value
            if "effects" not in typed and edit_serial.get("effects", -1) <= serial and not self._held_elastic():
                for name, handle in self.effects.items():
                    handle.value = name in prepared.scene.effects

    @staticmethod
    def _as_sent(kind: str, value):
        """A field's value as `_apply_edit` puts it into an override."""
        if kind in ("integer", "number"):
            try:
                number = float(value)
            except (TypeError, ValueError, OverflowError):
                return value
            if kind == "integer" and math.isfinite(number) and number.is_integer():
                return int(number)
            return number
        return str(value)

    def _aim_camera(self, prepared: Prepared) -> None:
        """Frame the new scene: the initial camera (new pages, "Reset View") and every page's
        own camera, each for its canvas' shape."""
        frame = camera_frame(prepared)
        if self.client is None:  # the initial camera is the server's: only a shared app sets it
            initial = self.server.initial_camera
            initial.fov = frame.fov
            initial.up = frame.up
            initial.position = frame.position
            initial.look_at = frame.look_at
        self.camera = frame
        for client in self._clients().values():
            self._aim_client(client, prepared)

    def _clients(self) -> dict:
        """The pages this app shows itself on."""
        if self.client is not None:
            return {self.client.client_id: self.client}
        return self.server.get_clients()

    def _aim_client(self, client, prepared: Prepared) -> None:
        camera = client.camera
        try:
            aspect = camera.aspect
        except (AssertionError, ZeroDivisionError):
            # no camera report yet (viser counts a page as connected only after one): it
            # starts from the initial camera, and connecting brings it here (`_client_connected`)
            return
        frame = camera_frame(prepared, aspect if math.isfinite(aspect) and aspect > 0.0 else ASSUMED_ASPECT)
        camera.fov = frame.fov
        camera.up_direction = frame.up
        camera.position = frame.position  # moves look_at along; set it after (viser's rule)
        camera.look_at = frame.look_at
        previous = self.client_cameras.get(client.client_id)
        if previous is not None:  # the last few aims: a late report may still show one of them
            self._earlier_aims[client.client_id] = (*self._earlier_aims.get(client.client_id, ())[-3:], previous)
        self.client_cameras[client.client_id] = frame

    def _pose(self, angle: float, force: bool = False) -> None:
        prepared = self.current
        n = len(prepared.result.columns["cam_angle_deg"])
        i = step_index(angle, n)
        if i != self._last_index or force:
            for name, (pos, quat) in prepared.poses.items():
                if name in meshes.STATIC_PARTS and not force:
                    continue
                handle = self._handles.get(name)
                if handle is None:
                    continue
                handle.position = pos[i]
                handle.wxyz = quat[i]
            length = float(prepared.spring_lengths[i])
            surge = None if prepared.spring_surge is None else prepared.spring_surge[i]
            if (abs(length - self._last_spring) > 1e-9 or surge is not None) and "spring" in self._handles:
                self._handles["spring"].vertices = meshes.spring_vertices(
                    prepared.layout, length, **SPRING_RESOLUTION, surge=surge).astype(np.float32)
                self._last_spring = length
            self._last_index = i
        now = time.perf_counter()
        if force or (i != self._cursor_index and now - self._last_cursor >= 1.0 / PLOT_CURSOR_HZ):
            self._move_cursor(angle)
            self._last_cursor = now
            self._cursor_index = i

    # ------------------------------------------------------------------ plots

    def _update_plots(self, prepared: Prepared) -> None:
        if self.plot_note.content != prepared.plot_note:
            self.plot_note.content = prepared.plot_note
            self.plot_note.visible = bool(prepared.plot_note)
        signature = [(p.title, tuple(label for label, _, _ in p.series)) for p in prepared.plots]
        if signature != self._plot_signature:
            for handle in self._plot_handles:
                handle.remove()
            self._plot_handles = []
            with self._plots_tab:
                for plot in prepared.plots:
                    self._plot_handles.append(self.target.gui.add_uplot(
                        data=self._plot_data(plot, self.playback.angle_deg), **plot_options(plot)))
            self._plot_signature = signature
        else:
            for handle, plot in zip(self._plot_handles, prepared.plots):
                handle.data = self._plot_data(plot, self.playback.angle_deg)

    def _show_sweep(self, arrived) -> None:
        """The speed sweep: a new or extended sweep (`arrived`: (serial, SpeedSweep or None)), or
        only the current-speed marker after a new result (loop thread)."""
        from .speedsweep import sweep_plots

        if arrived is not None:
            serial, sweep = arrived
            if sweep is None:
                self.sweep = None
            elif self.sweep is None or sweep.serial >= self.sweep.serial:
                self.sweep = sweep
        sweep = self.sweep
        if sweep is None or self.current is None:
            for handle in self._sweep_handles:
                handle.remove()
            self._sweep_handles, self._sweep_signature = [], ()
            self.sweep_rpm.disabled = True
            self.sweep_progress.content = ""
            if arrived is not None and arrived[1] is None:
                self.sweep_note.content = ("**Speed sweep:** none; it needs the rigid forces ([valve] mass and "
                                           "[spring]): tick 'forces' under Scene → Effects.")
            return
        rpm = float(self.current.scene.drive.rpm)
        plots = sweep_plots(sweep, rpm)
        signature = (sweep.span, tuple(tuple(label for label, _, _ in series) for _, _, _, series, _, _ in plots))
        data = [(x, *(values for _, values, _ in series), *markers) for _, _, x, series, markers, _ in plots]
        if signature != self._sweep_signature:
            for handle in self._sweep_handles:
                handle.remove()
            self._sweep_handles = []
            with self._plots_tab:
                for k, ((title, y_label, _, series, _, y_lim), values) in enumerate(zip(plots, data)):
                    self._sweep_handles.append(self.target.gui.add_uplot(
                        data=values, order=SWEEP_ORDER + 1 + 2 * k,
                        **sweep_plot_options(title, y_label, series, sweep.span, y_lim)))
            self._sweep_signature = signature
        else:
            for handle, values, (title, _, _, _, _, y_lim) in zip(self._sweep_handles, data, plots):
                handle.data = values
                if handle.title != title:
                    handle.title = title
                scales = sweep_scales(sweep.span, y_lim)
                if handle.scales != scales:
                    handle.scales = scales
        float_text = f"{sweep.float_rpm:.0f} rpm" if math.isfinite(sweep.float_rpm) else "none"
        self.sweep_note.content = (f"**Speed sweep** of this scene: {sweep.rpm.size} speeds up to "
                                   f"{sweep.span[1]:g} rpm; rigid float speed {float_text}.")
        self.sweep_progress.content = f"<small>{sweep.progress()}</small>"
        with self._programmatic():
            slider = self.sweep_rpm
            if (slider.min, slider.max) != (0.0, float(sweep.span[1])):
                slider.min, slider.max = 0.0, float(sweep.span[1])
                slider.step = float(sweep.span[0])
            slider.disabled = False
            if rpm != self._sweep_rpm_shown:
                slider.value = self._sweep_rpm_shown = rpm

    @staticmethod
    def _plot_data(plot, angle: float) -> tuple[np.ndarray, ...]:
        cursor = np.zeros(len(plot.x))
        cursor[int(np.argmin(np.abs(plot.x - angle % 360.0)))] = 1.0
        return (plot.x, *(values for _, values, _ in plot.series), cursor)

    def _move_cursor(self, angle: float) -> None:
        if self.current is None:
            return
        for handle, plot in zip(self._plot_handles, self.current.plots):
            handle.data = self._plot_data(plot, angle)

    # ------------------------------------------------------------------ control from Python

    def wait_applied(self, timeout: float = 30.0) -> bool:
        """Wait until the newest request has been computed and shown (or rejected)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.worker.wait_idle(max(0.0, deadline - time.monotonic())):
                with self._lock:
                    pending = self._incoming is not None or self._error is not None or self._scrub is not None \
                        or bool(self._typed)
                    serial = self._serial
                if not pending and self.handled_serial >= serial:
                    # one more frame so that pose updates after the last apply are out
                    frames = self.frames
                    while self.frames < frames + 2 and time.monotonic() < deadline:
                        time.sleep(0.002)
                    return True
            time.sleep(0.002)
        return False

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.worker.stop()  # ends the computing child process too
        if self.client is None:
            origin.forget(self._port)  # per client, the server's guard outlives this page
