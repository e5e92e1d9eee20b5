"""What the browser explorer shows, computed without any viewer: a request (scene file, GUI
overrides, magnification) becomes a `Prepared` bundle of meshes, per-step poses, plot data and
read-outs. `ComputeWorker` (explorer.view.browser.compute) does this off the GUI threads, newest
request wins, in a child process with a time and memory budget (explorer.view.browser.worker).

Nothing here imports viser, so it is testable and reusable (the benchmark drives it directly).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...core.errors import InputError
from ...core.units import printable
from ...effects.lift import build_lift
from ...effects.pipeline import simulate
from ...lift import registry as laws
from ...scene.scene import load_scene
from .parameters import PARAMETERS, override, scene_values  # noqa: F401 - the fields' table, re-exported


@dataclass(frozen=True)
class Request:
    """One thing to show: a scene file, overrides ("section.key=value"), a magnification (None:
    the scene's default, explorer.view.parts.default_magnification; the Prepared bundle's request
    holds the one used)."""

    path: str
    overrides: tuple[str, ...] = ()
    magnification: float | None = 1.0
    serial: int = 0  # increases with every request, so the newest is known


# The spring is resent every frame while the valve moves: a coarser tube than the default keeps
# that message small (1.5k vertices, 18 kB) while the coils still look round.
SPRING_RESOLUTION = {"segments_per_turn": 24, "wire_segments": 8}

# ---------------------------------------------------------------------------------------------
# Plots


@dataclass(frozen=True)
class Plot:
    title: str
    x: np.ndarray  # cam angle, deg (decimated)
    series: tuple[tuple[str, np.ndarray, str], ...]  # (label, values, colour), drawn in this order
    y_label: str = ""  # the y axis' name with its unit
    styles: tuple[dict, ...] = ()  # per series: uPlot line options (width, dash)


SERIES_COLORS = ("#c0392b", "#2471a3", "#7d8a96", "#27ae60", "#8e44ad", "#d68910", "#17a589")
DISPLAY_POINTS = 720
X_LABEL = "cam angle θ [°]"
# Curves that lie on each other stay apart: the first of a plot is drawn solid and widest, the
# later ones on top of it thinner and dashed, each with its own dash, so where two coincide both
# colours show in turn.
DASHES = ((), (7, 4), (2, 3), (10, 3, 2, 3), (4, 4), (1, 5), (12, 6))
WIDTHS = (3.0, 1.8, 1.8, 1.6, 1.6, 1.6, 1.6)


def decimate(x: np.ndarray, ys: list[np.ndarray], points: int = DISPLAY_POINTS) -> tuple[np.ndarray, list[np.ndarray]]:
    """Thin columns to about `points` samples for the plots, keeping each bucket's extremes
    (min and max of every series, in their order) so impacts and spikes stay visible."""
    n = len(x)
    if n <= points:
        return x.copy(), [y.copy() for y in ys]
    buckets = points // 2
    edges = np.linspace(0, n, buckets + 1).astype(int)
    starts, ends = edges[:-1], edges[1:]
    xs = np.empty(2 * buckets)
    xs[0::2], xs[1::2] = x[starts], x[ends - 1]
    out = []
    for y in ys:
        # NaN marks where a column does not apply (e.g. the trip gear's spring requirement while
        # the valve closes freely): a bucket's extremes ignore it, an all-NaN bucket stays NaN
        gaps = np.isnan(y)
        lo = np.fmin.reduceat(y, starts)
        hi = np.fmax.reduceat(y, starts)
        i_lo = _argreduce(np.where(gaps, np.inf, y) if gaps.any() else y, starts, ends, np.argmin)
        i_hi = _argreduce(np.where(gaps, -np.inf, y) if gaps.any() else y, starts, ends, np.argmax)
        first_is_lo = i_lo <= i_hi
        z = np.empty(2 * buckets)
        z[0::2] = np.where(first_is_lo, lo, hi)
        z[1::2] = np.where(first_is_lo, hi, lo)
        out.append(z)
    return xs, out


def _argreduce(y, starts, ends, fn):
    width = int((ends - starts).max())
    idx = np.minimum(starts[:, None] + np.arange(width)[None, :], ends[:, None] - 1)
    return np.take_along_axis(idx, fn(y[idx], axis=1)[:, None], axis=1)[:, 0]


def _same_curve(a: np.ndarray, b: np.ndarray) -> bool:
    scale = max(float(np.nanmax(np.abs(a))) if np.isfinite(a).any() else 0.0, 1e-30)
    return a.shape == b.shape and bool(np.all((np.isnan(a) & np.isnan(b)) | (np.abs(a - b) <= 1e-9 * scale)))


def build_plots(result) -> list[Plot]:
    """s, v, p and the forces over one revolution, from whatever columns the effects made. A
    plot without data (no force effect) is left out; `plots_note` says why in one line."""
    cols = result.columns
    x = np.asarray(cols["cam_angle_deg"], dtype=float)
    plots = []

    def add(title, y_label, entries):
        entries = [(label, np.asarray(values, dtype=float) * k) for label, values, k in entries if values is not None]
        if not entries:
            return
        xs, ys = decimate(x, [v for _, v in entries])
        labels = [label for label, _ in entries]
        for i, (label, values) in enumerate(entries):  # a curve equal to an earlier one says so
            twin = next((labels[j] for j in range(i) if _same_curve(entries[j][1], values)), None)
            if twin is not None:
                labels[i] = f"{label} (= {twin})"
        series = tuple((label, y, SERIES_COLORS[i % len(SERIES_COLORS)]) for i, (label, y) in enumerate(zip(labels, ys)))
        styles = tuple({"width": WIDTHS[i % len(WIDTHS)], "dash": list(DASHES[i % len(DASHES)])} for i in range(len(series)))
        plots.append(Plot(title, xs, series, y_label, styles))

    def maybe_rigid(name):
        rigid = cols.get(f"rigid_{name}")
        return rigid if rigid is not None and not np.array_equal(rigid, cols[name]) else None

    scene = result.scene
    lash = scene.valve.lash if scene.valve is not None else 0.0
    linkage = scene.follower.ratio * np.asarray(cols["follower_lift_m"]) - lash
    # the valve's own curve first (solid, under), the rigid and linkage curves dashed on top
    add("Valve lift s", "s [mm]", [
        ("valve s", cols["valve_lift_m"], 1e3),
        ("rigid", maybe_rigid("valve_lift_m"), 1e3),
        ("linkage S − lash", linkage if maybe_rigid("valve_lift_m") is not None else None, 1e3),
    ])
    add("Velocity v", "v [m/s]", [("valve v", cols["valve_velocity_m_s"], 1.0), ("rigid", maybe_rigid("valve_velocity_m_s"), 1.0)])
    add("Acceleration p", "p [m/s²]", [("valve p", cols["valve_accel_m_s2"], 1.0), ("rigid", maybe_rigid("valve_accel_m_s2"), 1.0)])
    add("Forces", "F [N]", [(label, values, 1.0) for label, values in _force_columns(cols)])
    # a train of parts (issue #25): the force at each joint from the cam to the valve, one curve each
    add("Contact forces", "F [N]", [(name[len("contact_"):-len("_force_N")], cols[name], 1.0)
                                    for name in _joint_force_columns(cols)])
    return plots


def _joint_force_columns(cols) -> list[str]:
    # a train's joints report contact_<joint>_force_N with contact_<joint>_closed beside it
    # (effects/train_elastic.py); in the train's order, cam first
    return [name for name in cols if name.startswith("contact_") and name.endswith("_force_N")
            and f"{name[:-len('_force_N')]}_closed" in cols]


def _force_columns(cols) -> list[tuple[str, Any]]:
    # the linkage force first (Schenker's back-pressure on the camshaft), then the cam contact and
    # the spring; any further force columns after those, up to five curves
    preferred = ("linkage_force_N", "contact_force_N", "spring_force_N", "required_spring_force_N",
                 "camshaft_back_pressure_N")
    joints = set(_joint_force_columns(cols))  # a train's joints have a plot of their own
    names = [n for n in preferred if n in cols] + sorted(
        n for n in cols if n.endswith("_N") and n not in preferred and n not in joints)
    return [(name[:-2].replace("_", " "), cols[name]) for name in names[:5]]


def plots_note(result) -> str:
    """One line for the plots the result has no data for ("" when every plot is drawn)."""
    if _force_columns(result.columns):
        return ""
    return ("No forces plot: this run computes no forces. Tick 'forces' (needs [valve] mass and "
            "[spring]) or 'elastic' (also a linkage stiffness) under Scene → Effects.")


# ---------------------------------------------------------------------------------------------
# Read-outs


UNIT_SUFFIXES = (
    ("_m_s2", "m/s²", 1.0), ("_m_s3", "m/s³", 1.0), ("_m_s", "m/s", 1.0), ("_rpm", "rpm", 1.0),
    ("_deg", "°", 1.0), ("_mm", "mm", 1.0), ("_m", "mm", 1e3), ("_N_m", "N·m", 1.0), ("_Nm", "N·m", 1.0),
    ("_N", "N", 1.0), ("_Pa", "MPa", 1e-6), ("_s", "ms", 1e3), ("_kg", "kg", 1.0), ("_J", "J", 1.0),
)
SKIP_SUMMARY = {"scene", "rpm", "steps_per_revolution", "effects", "events", "warnings", "lash_m"}


def _fmt_value(key: str, value) -> tuple[str, str]:
    value = printable(float(value), key)  # round-off (4.97e-14, -0) shows as 0
    for suffix, unit, k in UNIT_SUFFIXES:
        if key.endswith(suffix):
            return key[: -len(suffix)].replace("_", " "), f"{printable(value * k):.4g} {unit}"
    return key.replace("_", " "), f"{value:.4g}"


def _event_speed(event) -> str:
    v = event.get("velocity_m_s", event.get("relative_velocity_m_s"))
    return f"{printable(float(v)):+.3f} m/s" if isinstance(v, (int, float)) and not isinstance(v, bool) else ""


def event_choices(result) -> list[tuple[str, float]]:
    """Every event of the result as (label, cam angle in degrees), in the order of the summary:
    the entries of the explorer's "Go to event" list. Labels are numbered, so equal kinds at
    different angles stay distinct."""
    out = []
    for k, e in enumerate(result.events, start=1):
        angle = e.get("cam_angle_deg")
        if not isinstance(angle, (int, float)) or not math.isfinite(float(angle)):
            continue
        speed = _event_speed(e)
        out.append((f"{k}. {e.get('kind', '?')} at {float(angle):.2f}°" + (f", {speed}" if speed else ""),
                    float(angle)))
    return out


EVENTS_HEIGHT_PX = 220  # the events table scrolls inside this height: every event is there


def events_html(result) -> str:
    """All events as a table that scrolls within EVENTS_HEIGHT_PX (no "… 11 more")."""
    import html

    events = list(result.events)
    if not events:
        return "<div style='font-size:0.85em'>no events</div>"
    rows = []
    for k, e in enumerate(events, start=1):
        angle = e.get("cam_angle_deg")
        shown = f"{float(angle):.2f}°" if isinstance(angle, (int, float)) else ""
        rows.append(f"<tr><td>{k}</td><td>{html.escape(str(e.get('kind', '?')))}</td>"
                    f"<td style='text-align:right'>{shown}</td>"
                    f"<td style='text-align:right'>{html.escape(_event_speed(e))}</td></tr>")
    return (f"<div class='explorer-events' style='max-height:{EVENTS_HEIGHT_PX}px;overflow-y:auto;font-size:0.85em'>"
            "<table style='width:100%;border-collapse:collapse'><thead><tr><th>#</th><th>event</th>"
            "<th style='text-align:right'>angle</th><th style='text-align:right'>speed</th></tr></thead><tbody>"
            + "".join(rows) + "</tbody></table></div>")


ADVICE_PENDING = "pending"  # readout_markdown's `advice` while the advisor is still to run


def spring_advice_lines(design) -> list[str]:
    """The spring advisor's advice (the [spring_design] block of the forces summary) as
    read-out lines; ADVICE_PENDING: a line saying it is being computed."""
    if design == ADVICE_PENDING:
        return ["", "**Spring advice:** computing… (after the plots, once the page is idle)"]
    advice = design.get("advice") if isinstance(design, dict) else None
    if not isinstance(advice, dict):
        return []

    def n(key, k=1.0, unit="N"):
        v = advice.get(key)
        return f"{v * k:.4g} {unit}" if isinstance(v, (int, float)) and math.isfinite(v) else "?"

    lines = ["", f"**Spring advice** for {advice.get('rpm', 0):g} rpm with a margin of {n('safety_margin_N')}", ""]
    lines.append(f"- preload {n('preload_N')}, rate {n('rate_N_m', 1e-3, 'N/mm')} "
                 f"(largest spring force {n('max_spring_force_N')})")
    lines.append(f"- with the scene's rate: preload {n('preload_for_current_rate_N')}")
    lines.append(f"- force needed {n('needed_spring_force_N')} (opening {n('opening_required_spring_force_N')}, "
                 f"closing {n('closing_required_spring_force_N')})")
    return lines


def float_warning(result, float_rpm: float) -> str | None:
    """The float warning of a result whose effects did not judge float themselves (no 'forces'
    ticked), by the same definition: the rigid float (jump) speed of the scene's forces effect
    (rigid_float_rpm). None when the forces effect ran (its own warning says it) or no float."""
    if "jump_speed_rpm" in result.summary or not math.isfinite(float_rpm):
        return None
    rpm = float(result.summary.get("rpm", 0.0))
    if rpm < float_rpm:
        return None
    return (f"valve float: {rpm:.6g} rpm is at or above the rigid float (jump) speed {float_rpm:.6g} rpm "
            "(of the rigid forces; tick 'forces' under Scene → Effects for the contact forces)")


def readout_markdown(result, label: str = "", float_rpm: float = math.nan, advice=None) -> str:
    """Compute times, events, key figures (peaks, jump speed, impact speeds...) and warnings;
    `float_rpm` the page's float speed (rigid_float_rpm), `advice` the [spring_design] block
    (ADVICE_PENDING while it is computed; None: the result's own)."""
    s = result.summary
    lines = [f"**{s.get('scene', '')}** at {s.get('rpm', 0):g} rpm, {s.get('steps_per_revolution', 0)} steps"]
    if label:
        lines.append(f"<small>{label}</small>")
    # warnings first: undercut, self-locking, float... are what a designer must not miss
    warnings = list(result.warnings)
    extra = float_warning(result, float_rpm)
    if extra is not None:
        warnings.append(extra)
    lines += ["", f"**Warnings** ({len(warnings)})", ""]
    lines += [f"- ⚠ {w}" for w in warnings] or ["none"]
    if math.isfinite(float_rpm) and "jump_speed_rpm" not in s:
        lines += ["", f"Rigid float (jump) speed: {float_rpm:.6g} rpm"]
    lines += ["", "| effect | compute |", "|---|---:|"]
    for name, timing in result.timings.items():
        lines.append(f"| {name} | {1e3 * timing.compute_time_s:.2f} ms |")
    # the events are a table of their own beside this text (events_html) with "Go to event"
    lines += spring_advice_lines(s.get("spring_design") if advice is None else advice)
    figures = []
    for key, value in s.items():
        if key in SKIP_SUMMARY or isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if not math.isfinite(float(value)):
            continue
        figures.append(_fmt_value(key, float(value)))
    if figures:
        lines += ["", "**Key figures**", "", "| quantity | value |", "|---|---:|"]
        lines += [f"| {name} | {text} |" for name, text in figures]
    return "\n".join(lines)


def rigid_float_rpm(scene, lift, result=None) -> float:
    """The page's one float speed (#28.5), whichever effects are ticked: the rigid train's float
    (jump) speed as the scene's 'forces' effect defines it (the gear's own variant where it has
    one: the trip gear's latch), from the result when that effect ran, else from a run of that
    effect alone. NaN when the scene has none (no [valve] mass or [spring]: InputError) or never
    floats; 0 when it floats at any speed."""
    summary = result.summary if result is not None else {}
    if "jump_speed_rpm" not in summary:
        rigid = dataclasses.replace(scene, effects=("forces",), spring_design=None)
        try:
            summary = simulate(rigid, lift=lift).summary
        except InputError:
            return math.nan
    value = summary.get("jump_speed_rpm")
    return float(value) if isinstance(value, (int, float)) else math.nan


def float_key(scene):
    """What the rigid float speed depends on: the scene without its speed, effects and advice
    (a speed change reuses the previous float speed)."""
    return dataclasses.replace(scene, drive=None, effects=(), spring_design=None, name="", description="")


def advice_key(scene):
    """What the spring advice depends on: everything, except the speed when [spring_design]
    names a target_rpm of its own."""
    design = scene.spring_design
    if design is not None and design.target_rpm is not None:
        return dataclasses.replace(scene, drive=None, name="", description="")
    return dataclasses.replace(scene, name="", description="")


def equal_scenes(a, b) -> bool:
    """a == b for scenes that may hold arrays (point contours), whose == is ambiguous: False."""
    try:
        return bool(a == b)
    except (ValueError, TypeError):
        return False


# ---------------------------------------------------------------------------------------------
# The prepared bundle


@dataclass(frozen=True)
class Prepared:
    request: Request
    scene: Any
    result: Any
    layout: Any
    lift: Any  # the lift curve (reused when only the magnification changes)
    meshes: dict  # part -> (vertices float32 (V, 3), faces uint32 (F, 3))
    poses: dict  # part -> (positions (N, 3), wxyz (N, 4))
    spring_lengths: np.ndarray  # (N,)
    plots: list
    readout: str
    label: str
    values: dict  # scene_values(scene): what the GUI fields show
    new_result: bool  # False when only the magnification changed since the worker's previous bundle
    seconds: float = 0.0  # wall time of the preparation
    plot_note: str = ""  # why a plot is missing (plots_note)
    laws: tuple[str, ...] = ()  # the lift laws this scene file can take (offered_laws)
    events: tuple[tuple[str, float], ...] = ()  # event_choices(result)
    events_html: str = ""
    spring_surge: np.ndarray | None = None  # (N, coils): the coils' surge as drawn (spring as masses)
    float_rpm: float = math.nan  # the page's one float speed (rigid_float_rpm)
    advice_pending: bool = False  # the spring advice ([spring_design]) is computed after, off the path to the plots

    @functools.cached_property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World box (lo, hi) of every part over the whole revolution, where the camera looks
        (explorer.view.parts.motion_bounds; tens of milliseconds, so computed once, when asked)."""
        from .. import parts as meshes  # heavy (PIL, scipy, trimesh): imported on use

        return meshes.motion_bounds(self.meshes, self.poses)


def _request_label(request: Request) -> str:
    name = Path(request.path).name
    return name + ("".join(f"  {o}" for o in request.overrides) if request.overrides else "")


def _same_cam(a, b) -> bool:
    """True when two scenes have the same cam: lift spec, cam section and follower geometry.
    Sections may hold arrays (point contours) whose == is ambiguous: then they count as different."""
    try:
        return bool(a.lift == b.lift and a.cam == b.cam and a.follower == b.follower and a.directory == b.directory)
    except (ValueError, TypeError):
        return False


def offered_laws(path: str, overrides=(), current: str | None = None) -> tuple[str, ...]:
    """The lift laws the scene file can take: each law of the dropdown that the scene loads and
    builds a lift with (a table law needs its table, a contour its [cam], "gear" a gear...).
    Any failure, not only bad input, leaves the law out: the dropdown must not offer what cannot
    be computed. The current law is always offered. Tens of milliseconds, once per scene file."""
    others = [o for o in overrides if not o.startswith("lift.law=")]
    offered = []
    for law in laws.names():
        if law == current:
            offered.append(law)
            continue
        try:
            build_lift(load_scene(path, [*others, override("lift.law", law)]))
        except Exception:  # noqa: BLE001 - whatever fails, the law is not offered
            continue
        offered.append(law)
    return tuple(offered)


def prepare(request: Request, previous: Prepared | None = None) -> Prepared:
    """Load, simulate and build everything the viewer needs. Raises InputError on bad input.
    Reuses the previous simulation when only the magnification changed."""
    from .. import parts as meshes  # heavy (PIL, scipy, trimesh): imported on use
    started = time.perf_counter()
    same = previous is not None and (previous.request.path, previous.request.overrides) == (request.path, request.overrides)
    if same:
        scene, result, lay, parts = previous.scene, previous.result, previous.layout, previous.meshes
        plots, readout, values = previous.plots, previous.readout, previous.values
        plot_note = previous.plot_note
        lift = previous.lift
        events, table = previous.events, previous.events_html
        float_rpm, advice_pending = previous.float_rpm, previous.advice_pending
    else:
        scene = load_scene(request.path, list(request.overrides))
        lift = build_lift(scene)
        # the spring advisor (73 % of simulate on the float demo) is not on the path to the
        # plots: the compute thread asks for it once the page is idle (advice_readout)
        advice_pending = scene.spring_design is not None and "forces" in scene.effects
        run = dataclasses.replace(scene, spring_design=None) if advice_pending else scene
        result = simulate(run, lift=lift)
        if "jump_speed_rpm" in result.summary:
            float_rpm = rigid_float_rpm(scene, lift, result)
        elif previous is not None and equal_scenes(float_key(previous.scene), float_key(scene)):
            float_rpm = previous.float_rpm  # it does not depend on the speed
        else:
            float_rpm = rigid_float_rpm(scene, lift, result)
        lay = meshes.layout(scene, result)
        # only the cam depends on more than the layout: keep the other meshes when it is unchanged,
        # and the cam too when its lift and geometry are (an edit of speed, lash, springs...).
        # Another kind of gear has other parts; a gear whose levers and links are drawn from its
        # own geometry (its view's parts_follow_cam) keeps parts only with the same cam.
        keep = previous is not None and previous.scene.follower.type == scene.follower.type \
            and previous.layout == lay and meshes.train_shape(previous.scene) == meshes.train_shape(scene)
        keep_cam = keep and _same_cam(previous.scene, scene)
        if keep and not keep_cam and meshes.parts_follow_cam(scene):
            keep = False
        built = meshes.build_parts(scene, result, lay=lay, lift=lift, only=() if keep_cam else ("cam",) if keep else None)
        parts = dict(previous.meshes) if keep else {}
        parts.update({
            name: (np.ascontiguousarray(m.vertices, dtype=np.float32), np.ascontiguousarray(m.faces, dtype=np.uint32))
            for name, m in built.items() if name != "spring"
        })
        if "spring" in built:
            parts["spring"] = (
                meshes.spring_vertices(lay, lay.spring_rest_length, **SPRING_RESOLUTION).astype(np.float32),
                meshes.spring_faces(lay, **SPRING_RESOLUTION).astype(np.uint32),
            )
        plots = build_plots(result)
        plot_note = plots_note(result)
        readout = readout_markdown(result, _request_label(request), float_rpm,
                                   ADVICE_PENDING if advice_pending else None)
        values = scene_values(scene)
        events, table = tuple(event_choices(result)), events_html(result)
    if previous is not None and previous.request.path == request.path and previous.laws:
        laws = previous.laws if scene.lift.law in previous.laws else (*previous.laws, scene.lift.law)
    else:
        laws = offered_laws(request.path, request.overrides, scene.lift.law)
    if request.magnification is None:  # the scene's default: x20 for a train of masses
        request = dataclasses.replace(request, magnification=meshes.default_magnification(scene))
    poses = meshes.part_poses(scene, result, magnification=request.magnification, lay=lay, lift=lift)
    lengths = meshes.spring_length(lay, meshes.displayed_valve_lift(result, request.magnification))
    prepared = Prepared(
        request=request, scene=scene, result=result, layout=lay, lift=lift, meshes=parts, poses=poses,
        spring_lengths=np.asarray(lengths, dtype=float), plots=plots, readout=readout,
        spring_surge=meshes.spring_surge(result, request.magnification),
        label=_request_label(request), values=values, new_result=not same, seconds=time.perf_counter() - started,
        plot_note=plot_note, laws=laws, events=events, events_html=table, float_rpm=float_rpm,
        advice_pending=advice_pending,
    )
    if previous is None or Path(previous.request.path) != Path(request.path):
        prepared.bounds  # another scene file: the viewer aims its camera at it, here off the GUI's loop
    return prepared


@dataclass(frozen=True)
class AdviceTask:
    """A message to the compute child: the read-out of request `serial`'s result with the spring
    advice in it (advice_readout)."""

    serial: int


def advice_readout(prepared: Prepared, cache: dict) -> str:
    """The read-out of `prepared` with the spring advice in it (the [spring_design] block,
    explorer.effects.spring_design), reusing `cache` {"key": advice_key, "block": block} when
    the advice depends on nothing that changed (the speed, when it has a target_rpm of its own)."""
    key = advice_key(prepared.scene)
    if "key" in cache and equal_scenes(cache["key"], key):
        block = cache["block"]
    else:
        from ...effects import spring_design  # local: looked up on use (tests count its calls)
        block, _ = spring_design.spring_design_summary(prepared.scene, prepared.lift)
        cache.clear()
        cache.update(key=key, block=block)
    return readout_markdown(prepared.result, prepared.label, prepared.float_rpm, block)


# ---------------------------------------------------------------------------------------------
# Worker


# Every recomputation has a budget: it runs in a child process (explorer.view.browser.worker) that is
# killed when it takes longer than this, or needs more memory than MEMORY_LIMIT_BYTES. Seconds
# rather than minutes: the explorer is for trying changes, and the slowest built-in scene takes
# about 1 s on a loaded 2-core machine.
COMPUTE_TIME_LIMIT_S = 10.0
# A computation running longer than this is abandoned as soon as a newer request waits (newest
# wins): starting a fresh child costs about half a second, less than waiting out a slow one.
SUPERSEDE_AFTER_S = 1.0
MEMORY_LIMIT_BYTES = 4 << 30  # address space of the child (its libraries alone reserve ~1.5 GB)


# ---------------------------------------------------------------------------------------------
# Playback clock


SPEEDS: tuple[tuple[str, float], ...] = (
    ("real time", 1.0), ("1/2", 0.5), ("1/5", 0.2), ("1/10", 0.1), ("1/20", 0.05), ("1/50", 0.02),
    ("1/100", 0.01), ("1/200", 0.005), ("1/500", 0.002), ("1/1000", 0.001), ("1/2000", 5e-4),
    ("1/5000", 2e-4), ("1/10000", 1e-4),
)


def default_speed(revolution_time: float, target_seconds: float = 4.0) -> str:
    """The listed speed whose slowed revolution lasts closest to `target_seconds` (log scale)."""
    return min(SPEEDS, key=lambda kv: abs(math.log(revolution_time / kv[1] / target_seconds)))[0]


@dataclass
class Playback:
    angle_deg: float = 0.0
    playing: bool = True
    speed: float = 0.01

    def advance(self, dt: float, revolution_time: float) -> float:
        if self.playing and revolution_time > 0.0:
            self.angle_deg = (self.angle_deg + 360.0 * dt * self.speed / revolution_time) % 360.0
        return self.angle_deg


def step_index(angle_deg: float, n: int) -> int:
    """Step of a revolution sampled at theta_i = 360 i / n that is nearest to `angle_deg`."""
    return int(round((angle_deg % 360.0) * n / 360.0)) % n
