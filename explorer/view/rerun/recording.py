"""Rerun recordings of simulations: per-step series, the animated 3D parts, events, a layout.

One simulation (a Result) becomes one rerun *recording*, named by a label (the scene name, plus
the sweep value when there is one). All recordings share the application id `valve-gear-explorer`,
so the viewer shows them side by side and can compare them.

Timelines (every per-step row carries all three):
- `time`            duration, t = θ/ω in seconds from the start of the revolution (the CSV's time_s)
- `step`            sequence, the step index 0 … N−1 of the revolution
- `cam_angle_0.01deg` sequence, the cam angle in hundredths of a degree, round(100·θ/°): 12 345
                    is 123.45° — comparable between runs at different speeds or step counts; the
                    default timeline. Its plots span one revolution (0 to 36 000), and at 1× a
                    revolution plays in ANGLE_PLAYBACK_S seconds (a sequence timeline plays `fps`
                    values a second: fps = 36 000 / ANGLE_PLAYBACK_S). Every sample has its own
                    position up to 36 000 steps per revolution (the default is 3 600): a series
                    plotted against the cam angle is the curve, not a staircase of samples sharing
                    a whole degree (#28.11); finer runs share hundredths, `step` has every step.

Entity paths of the series (one scalar per step; the values of `explorer simulate`'s CSV in the
browser explorer's display units: lengths in mm (the CSV's metres times 1000), everything else
SI as in the CSV; the series name in the viewer carries the unit). A column `<stem>_<unit>` maps by these
rules, first match wins:
- unit N   (forces)       -> /forces/<stem without "_force">   linkage_force_N  -> /forces/linkage
                                                               spring_force_N   -> /forces/spring
                                                               contact_force_N  -> /forces/contact
- unit Nm  (torques)      -> /torque/<stem without "_torque">  camshaft_torque_Nm -> /torque/camshaft
- unit Pa  (stresses)     -> /stress/<stem without "_stress">  hertz_stress_Pa -> /stress/hertz
- unit deg, rad (angles)  -> /angles/<stem without "_angle">   pressure_angle_deg -> /angles/pressure
- rigid_valve_<q>         -> /valve_rigid/<q>   rigid_valve_lift_m -> /valve_rigid/lift (the rigid-train
                                                motion, kept beside an elastic one)
- valve_<q>               -> /valve/<q>         valve_lift_m -> /valve/lift, valve_velocity_m_s ->
                                                /valve/velocity, valve_accel_m_s2 ->
                                                /valve/acceleration, valve_jerk_m_s3 -> /valve/jerk
- follower_<q>            -> /follower/<q>      follower_lift_m -> /follower/lift (the gear's lift
                                                curve, lash included: a translating roller's centre,
                                                a lever gear's drive referred to the valve)
- other lengths, unit m   -> /lengths/<stem>    contour_radius_m -> /lengths/contour_radius
- anything else           -> /other/<column>
("accel" is spelled out as "acceleration".) The columns `cam_angle_deg` and `time_s` are not
series: they become the timelines `cam_angle_0.01deg` (hundredths of a degree) and `time` (s). Should two columns land on one path, the later one goes to /other/<column>.

Other entities:
- /parts/<name>   Mesh3D (static, the part in its own frame, z up, metres) and a Transform3D per step
                  (translation, rotation) from explorer.view.parts: the recording replays the motion.
                  A part that never moves gets one static Transform3D instead; the spring gets a
                  per-step axial scale of its rest mesh (meshes.spring_axial_scale).
                  /parts carries the z-up view coordinates.
- /__properties/scene   label, scene name, source file, rpm, steps per revolution.
- /events         TextLog entries at the events' exact instants (lift-off, separation, re-contact,
                  seat, lash-take-up, … from result.events) at level INFO, and the
                  result's warnings at level WARN at t = 0.
- /summary        TextDocument (static, markdown): scene, label, peaks, effect timings, warnings.
- /events/checks and <series>/limit_*   with design checks (`explorer record --checks`; the live
                  stream's once the browser has computed them, log_checks): each
                  rule that warns or fails as a marker at the cam angle of its worst, each limit a
                  line beside its series (explorer.view.rerun.check_marks).

The default blueprint puts the 3D view (over the event log) beside time-series views of lift s,
velocity v, acceleration p and the forces (with tabs for jerk, torque, stress, angles, follower).
Each plot's legend sits in the corner its curves leave empty (legend_corner).

Several runs in one file (a --sweep, several scenes) also get one recording more, named
"overlay: …", that holds the lift, velocity, acceleration and forces of every run, each run a
child entity (/valve/lift/run01, … named by its label) on the cam-angle and step timelines: the
same layout, opened on that recording, draws the runs over each other. Sweep recordings are named
by their varied value first ("drive.rpm=600 · Cycloidal demo"), so the viewer's list, which cuts
long names, still tells them apart.

Files are written by the rules of explorer.core.outputs: to a hidden temporary name beside the
target, renamed when complete (and only if rerun's footer is there), so an interrupted run never
leaves a truncated file under the target name (a killed run may leave its hidden `.NAME.*.part(s)`
temporaries behind); a device or pipe (`-o /dev/stdout`) gets the finished file's bytes. Several
recordings are each written to their own temporary file, one after the other (a sweep holds one
run in memory at a time), and merged into one with `rerun rrd merge` (the CLI that ships in the
rerun-sdk wheel) together with the layout for all of them: the Python SDK writes one recording per
file sink. The logging itself runs in a helper process (explorer.view.rerun.worker): rerun keeps
every stream made in a process, with its threads, until that process exits.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping, Sequence

import numpy as np

from ...core.outputs import as_output, check_output, output_path
from ...core.processes import run_child
from . import worker as helper  # its functions looked up when called (tests replace them)
from .check_marks import CHECKS_PATH, check_paths, limit_series, markers

APP_ID = "valve-gear-explorer"
MERGE_TIMEOUT_S = 600.0  # `rerun rrd merge` of a long live session; it is killed past this
TIMELINE_TIME = "time"
TIMELINE_STEP = "step"
TIMELINE_ANGLE = "cam_angle_0.01deg"
ANGLE_UNITS_PER_DEG = 100  # the cam-angle timeline counts hundredths of a degree
ANGLE_UNITS_PER_REV = 360 * ANGLE_UNITS_PER_DEG
ANGLE_PLAYBACK_S = 6.0  # one revolution at 1x on the cam-angle timeline
OVERLAY_PATH_PREFIX = "run"
# lengths in the browser explorer's unit (mm); unit suffix -> (factor, shown unit)
DISPLAY_UNITS = {"m": (1e3, "mm")}
INDEX_COLUMNS = ("cam_angle_deg", "time_s")
EVENTS_PATH = "/events"
SUMMARY_PATH = "/summary"
PARTS_PATH = "/parts"

# Unit suffixes of column names, longest first so that "_m_s2" is not read as "_s2" or "_m".
UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("m_s3", "m/s³"), ("m_s2", "m/s²"), ("m_s", "m/s"),
    ("rad_s2", "rad/s²"), ("rad_s", "rad/s"),
    ("N_m", "N/m"), ("Nm", "N·m"), ("Pa", "Pa"), ("deg", "°"), ("rad", "rad"),
    ("kg", "kg"), ("J", "J"), ("W", "W"), ("N", "N"), ("m", "m"), ("s", "s"),
)
# unit -> (group path, word dropped from the end of the stem)
UNIT_GROUPS = {"N": ("/forces", "_force"), "Nm": ("/torque", "_torque"), "Pa": ("/stress", "_stress"),
               "deg": ("/angles", "_angle"), "rad": ("/angles", "_angle")}
PREFIX_GROUPS = (("rigid_valve_", "/valve_rigid"), ("valve_", "/valve"), ("follower_", "/follower"))


@dataclass(frozen=True)
class Series:
    """Where one result column goes: entity path, the name shown in the viewer, its unit."""

    column: str
    path: str
    name: str
    unit: str  # the unit shown (mm for lengths)
    scale: float = 1.0  # shown value = SI column value * scale

    def values(self, columns: Mapping) -> np.ndarray:
        """The logged values: the SI column in the shown unit."""
        values = np.asarray(columns[self.column], dtype=np.float64)
        return values * self.scale if self.scale != 1.0 else values


def split_unit(column: str) -> tuple[str, str, str]:
    """'valve_velocity_m_s' -> ('valve_velocity', 'm_s', 'm/s'); no known suffix -> (column, '', '')."""
    for suffix, label in UNIT_SUFFIXES:
        if column.endswith("_" + suffix) and len(column) > len(suffix) + 1:
            return column[: -len(suffix) - 1], suffix, label
    return column, "", ""


def _quantity(word: str) -> str:
    return "acceleration" if word == "accel" else word


def entity_path(column: str) -> str:
    """The entity path of a result column, by the rules in the module docstring."""
    stem, unit, _ = split_unit(column)
    if unit in UNIT_GROUPS:
        group, drop = UNIT_GROUPS[unit]
        leaf = stem[: -len(drop)] if stem.endswith(drop) and len(stem) > len(drop) else stem
        return f"{group}/{leaf}"
    for prefix, group in PREFIX_GROUPS:
        if stem.startswith(prefix) and len(stem) > len(prefix):
            return f"{group}/{_quantity(stem[len(prefix):])}"
    if unit == "m":
        return f"/lengths/{stem}"
    return f"/other/{column}"


def series_layout(columns: Iterable[str]) -> list[Series]:
    """Series for every column except the timelines, with collision-free paths."""
    out: list[Series] = []
    used: set[str] = set()
    for column in columns:
        if column in INDEX_COLUMNS:
            continue
        path = entity_path(column)
        if path in used:
            path = f"/other/{column}"
        used.add(path)
        stem, suffix, unit = split_unit(column)
        scale, unit = DISPLAY_UNITS.get(suffix, (1.0, unit))
        name = " ".join(_quantity(w) for w in stem.split("_")) + (f" [{unit}]" if unit else "")
        out.append(Series(column=column, path=path, name=name, unit=unit, scale=scale))
    return out


def step_indexes(result) -> dict[str, np.ndarray]:
    """The three timelines of the per-step rows: time in s, step index, cam angle in hundredths of a degree."""
    angle = np.asarray(result.columns["cam_angle_deg"], dtype=float)
    return {
        TIMELINE_TIME: np.asarray(result.columns["time_s"], dtype=float),
        TIMELINE_STEP: np.arange(angle.size, dtype=np.int64),
        TIMELINE_ANGLE: angle_sequence(angle),
    }


def angle_sequence(angle_deg) -> np.ndarray:
    """Cam angles in degrees as the cam-angle timeline's integers (nearest hundredth of a degree)."""
    return np.rint(np.asarray(angle_deg, dtype=float) * ANGLE_UNITS_PER_DEG).astype(np.int64)


def duration_ns(seconds) -> np.ndarray:
    """Seconds as numpy nanosecond durations, rounded to nearest (rerun truncates floats)."""
    return np.rint(np.asarray(seconds, dtype=np.float64) * 1e9).astype(np.int64).astype("timedelta64[ns]")


def _time_columns(rr, index: Mapping[str, np.ndarray]) -> list:
    return [
        rr.TimeColumn(TIMELINE_TIME, duration=duration_ns(index[TIMELINE_TIME])),
        rr.TimeColumn(TIMELINE_STEP, sequence=index[TIMELINE_STEP]),
        rr.TimeColumn(TIMELINE_ANGLE, sequence=index[TIMELINE_ANGLE]),
    ]


# ---------------------------------------------------------------------------------------------
# what goes into one recording


def recording_paths(result, part_names: Iterable[str] = (), checks=None) -> list[str]:
    """Entity paths a recording of `result` holds (used to build the blueprint before logging);
    `checks` (explorer.view.verdicts.CheckSummary): the design checks' limits and markers too."""
    series = series_layout(result.columns)
    paths = [s.path for s in series]
    paths += [f"{PARTS_PATH}/{name}" for name in part_names]
    return paths + [EVENTS_PATH, SUMMARY_PATH] + check_paths(series, checks)


def log_result(rec, result, label: str, parts: Mapping | None = None, poses: Mapping | None = None,
               scales: Mapping | None = None, colors: Mapping | None = None, points: Mapping | None = None,
               magnification: float = 1.0, checks=None) -> None:
    """Log one simulation into the recording stream `rec` (series, parts, events, summary; the
    parts' magnification in the summary and as the recording's property "parts"; the design
    checks' markers and limits when `checks`, a CheckSummary, is given)."""
    import rerun as rr

    rec.send_recording_name(label)
    scene = result.scene
    rec.send_property("scene", rr.AnyValues(
        label=label, name=str(getattr(scene, "name", "")), source=str(getattr(scene, "source", "")),
        rpm=float(result.summary.get("rpm", float("nan"))),
        steps_per_revolution=int(result.summary.get("steps_per_revolution", len(result.columns["time_s"]))),
    ))
    index = step_indexes(result)
    times = _time_columns(rr, index)
    for series in series_layout(result.columns):
        rec.log(series.path, rr.SeriesLines(names=series.name), static=True)
        values = series.values(result.columns)
        rec.send_columns(series.path, indexes=times, columns=rr.Scalars.columns(scalars=values))
    if parts:
        rec.send_property("parts", rr.AnyValues(magnification=float(magnification)))
        _log_parts(rec, rr, parts, poses or {}, scales or {}, colors or {}, times)
        for name, pts in (points or {}).items():  # child of the part: its pose and scale apply
            pts = np.asarray(pts, dtype=np.float64)
            rec.send_columns(f"{PARTS_PATH}/{name}/coils", indexes=times,
                             columns=rr.Points3D.columns(positions=pts.reshape(-1, 3)).partition(
                                 lengths=[pts.shape[1]] * pts.shape[0]))
    _log_events(rec, rr, result, index)
    _log_checks(rec, rr, result, checks, index)
    rec.log(SUMMARY_PATH, rr.TextDocument(summary_markdown(result, label, magnification if parts else None),
                                          media_type="text/markdown"), static=True)


def _log_parts(rec, rr, parts: Mapping, poses: Mapping, scales: Mapping, colors: Mapping, times) -> None:
    """Static meshes in their own frames plus one Transform3D per step (send_columns); a part
    that changes shape (the spring) gets a per-step scale of its rest mesh."""
    rec.log(PARTS_PATH, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for name, mesh in parts.items():
        path = f"{PARTS_PATH}/{name}"
        rec.log(path, mesh_archetype(rr, mesh, colors.get(name)), static=True)
        if name in poses:
            positions, wxyz = poses[name]
            positions = np.asarray(positions, dtype=np.float64)
            xyzw = np.asarray(wxyz, dtype=np.float64)[:, [1, 2, 3, 0]]  # rerun stores x, y, z, w
            if name not in scales and np.all(positions == positions[:1]) and np.all(xyzw == xyzw[:1]):
                # a part that never moves: one static pose instead of thousands of equal rows
                rec.log(path, rr.Transform3D(translation=positions[0], quaternion=xyzw[0]), static=True)
                continue
            extra = {"scale": np.asarray(scales[name], dtype=np.float64)} if name in scales else {}
            rec.send_columns(path, indexes=times,
                             columns=rr.Transform3D.columns(translation=positions, quaternion=xyzw, **extra))


def mesh_archetype(rr, mesh, color=None):
    """rr.Mesh3D from a trimesh.Trimesh, with vertex normals and the part's colour."""
    kwargs = {}
    visual = getattr(mesh, "visual", None)
    if color is not None:
        kwargs["albedo_factor"] = tuple(int(c) for c in color)
    elif visual is not None and getattr(visual, "kind", None) in ("vertex", "face"):
        kwargs["vertex_colors"] = np.asarray(visual.vertex_colors, dtype=np.uint8)
    return rr.Mesh3D(
        vertex_positions=np.asarray(mesh.vertices, dtype=np.float32),
        triangle_indices=np.asarray(mesh.faces, dtype=np.uint32),
        vertex_normals=np.asarray(mesh.vertex_normals, dtype=np.float32),
        **kwargs,
    )


def event_text(event: Mapping) -> str:
    """One line for an event: kind, angle, time, then its further numbers."""
    skip = {"kind", "time_s", "cam_angle_deg", "effect"}
    extras = []
    for key, value in event.items():
        if key in skip:
            continue
        if isinstance(value, (float, np.floating)):
            extras.append(f"{key} = {float(value):.6g}")
        else:
            extras.append(f"{key} = {value}")
    head = f"{event['kind']} at {float(event['cam_angle_deg']):.4f}° (t = {1e3 * float(event['time_s']):.6f} ms)"
    if event.get("effect"):
        head += f" [{event['effect']}]"
    return head + ("; " + ", ".join(extras) if extras else "")


def _log_events(rec, rr, result, index: Mapping[str, np.ndarray]) -> None:
    events = list(result.events)
    warnings = list(result.warnings)
    n = index[TIMELINE_STEP].size
    texts, levels, t, step, degrees = [], [], [], [], []
    for message in warnings:  # a warning belongs to the whole run: show it at the start
        texts.append(f"warning: {message}")
        levels.append("WARN")
        t.append(0.0)
        step.append(0)
        degrees.append(0)
    for event in events:
        angle = float(event["cam_angle_deg"])
        texts.append(event_text(event))
        levels.append("INFO")
        t.append(float(event["time_s"]))
        # the step at or before the instant; the exact instant is on the `time` timeline
        step.append(min(n - 1, max(0, int(math.floor(angle / 360.0 * n + 1e-9)))))
        degrees.append(int(angle_sequence(angle)))
    if not texts:
        return
    rec.send_columns(
        EVENTS_PATH,
        indexes=[rr.TimeColumn(TIMELINE_TIME, duration=duration_ns(t)),
                 rr.TimeColumn(TIMELINE_STEP, sequence=np.asarray(step, dtype=np.int64)),
                 rr.TimeColumn(TIMELINE_ANGLE, sequence=np.asarray(degrees, dtype=np.int64))],
        columns=rr.TextLog.columns(text=texts, level=levels),
    )


def log_checks(rec, result, checks) -> None:
    """Only the design checks of `result` (a CheckSummary: markers and limits) into `rec`, as
    log_result logs them: the live stream adds them to a result's recording when they come,
    after the recording itself (explorer.view.rerun.live)."""
    import rerun as rr

    _log_checks(rec, rr, result, checks, step_indexes(result))


def _log_checks(rec, rr, result, checks, index: Mapping[str, np.ndarray]) -> None:
    """The design checks' limit lines (two rows each: the revolution's first and last step) and
    their markers at the cam angle of each worst (explorer.view.rerun.check_marks)."""
    if checks is None:
        return
    steps = index[TIMELINE_STEP]
    ends = np.array([0, steps.size - 1])
    ends_index = [rr.TimeColumn(TIMELINE_TIME, duration=duration_ns(index[TIMELINE_TIME][ends])),
                  rr.TimeColumn(TIMELINE_STEP, sequence=steps[ends]),
                  rr.TimeColumn(TIMELINE_ANGLE, sequence=index[TIMELINE_ANGLE][ends])]
    for line in limit_series(series_layout(result.columns), checks):
        rec.log(line.path, rr.SeriesLines(names=line.name, colors=[line.rgb], widths=1.0), static=True)
        rec.send_columns(line.path, indexes=ends_index,
                         columns=rr.Scalars.columns(scalars=np.full(2, line.value, dtype=np.float64)))
    marks = markers(checks)
    if not marks:
        return
    n = steps.size
    at = np.array([m.angle_deg for m in marks])
    # the step at or before the angle, as the events; on `time` the instant of that angle in this run
    step = np.array([min(n - 1, max(0, int(math.floor(a / 360.0 * n + 1e-9)))) for a in at], dtype=np.int64)
    instant = np.interp(at, np.asarray(result.columns["cam_angle_deg"], dtype=float),
                        np.asarray(result.columns["time_s"], dtype=float))
    rec.send_columns(
        CHECKS_PATH,
        indexes=[rr.TimeColumn(TIMELINE_TIME, duration=duration_ns(instant)),
                 rr.TimeColumn(TIMELINE_STEP, sequence=step),
                 rr.TimeColumn(TIMELINE_ANGLE, sequence=angle_sequence(at))],
        columns=rr.TextLog.columns(text=[m.text for m in marks], level=[m.level for m in marks]),
    )


def summary_markdown(result, label: str, magnification: float | None = None) -> str:
    """The summary as a short markdown page: scalar entries, effect timings, warnings (and the
    3D parts' magnification when they are drawn)."""
    s = result.summary
    lines = [f"# {label}", ""]
    source = getattr(result.scene, "source", "")
    if source:
        lines += [f"scene file: `{source}`", ""]
    if magnification is not None:
        lines += [f"3D parts: each mass's deviation from rigid motion (and the lash) drawn ×{magnification:g}", ""]
    lines += ["| quantity | value |", "|---|---|"]
    for key, value in s.items():
        if isinstance(value, (dict, list, tuple)):
            continue
        if value is None or isinstance(value, (bool, np.bool_)):
            value = json.dumps(None if value is None else bool(value))  # the JSON summary's null, true, false
        elif isinstance(value, (float, np.floating)):
            value = f"{float(value):.6g}"
        lines.append(f"| {key} | {value} |")
    if result.timings:
        lines += ["", "| effect | compute time |", "|---|---|"]
        lines += [f"| {name} | {1e3 * t.compute_time_s:.3f} ms |" for name, t in result.timings.items()]
    warnings = list(result.warnings)
    if warnings:
        lines += ["", "**warnings**", ""] + [f"- {w}" for w in warnings]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# layout


def parts_bounds(parts: Mapping, poses: Mapping, step: int | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """World bounding box (lo, hi) of the parts over the whole revolution (explorer.view.parts.
    motion_bounds: the moving parts' sweep, which the 3D camera must see), or posed at `step`."""
    if step is None:
        from ..parts import motion_bounds  # heavy (PIL, scipy, trimesh): imported on use

        try:
            return motion_bounds(parts, poses)
        except ValueError:  # no vertices at all
            return None
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for name, mesh in parts.items():
        v = np.asarray(mesh.vertices, dtype=float)
        if name in poses:
            position, wxyz = np.asarray(poses[name][0][step]), np.asarray(poses[name][1][step])
            v = v @ quaternion_matrix(wxyz).T + position
        if v.size:
            lo, hi = np.minimum(lo, v.min(axis=0)), np.maximum(hi, v.max(axis=0))
    return (lo, hi) if np.all(np.isfinite(lo)) else None


def quaternion_matrix(wxyz) -> np.ndarray:
    """3x3 rotation matrix of a unit quaternion (w, x, y, z)."""
    w, x, y, z = np.asarray(wxyz, dtype=float) / np.linalg.norm(wxyz)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


# rerun's 3D eye has a fixed vertical field of view (Eye::DEFAULT_FOV_Y in re_view_spatial,
# 55 degrees) that a blueprint cannot set; the 3D view of the default layout is about as wide as
# tall or wider, so framing for a square view keeps the gear whole.
RERUN_FOV_Y = math.radians(55.0)
RERUN_VIEW_ASPECT = 1.0


def eye_for(bounds) -> dict:
    """The camera the browser explorer uses (explorer.view.parts.frame_bounds: in front of the gear,
    which works in the x-z plane, a little from above and the side), as near as it can be while
    seeing the whole box at rerun's field of view."""
    from ..parts import frame_bounds  # heavy (PIL, scipy, trimesh): imported on use

    lo, hi = (np.asarray(b, dtype=float) for b in bounds)
    frame = frame_bounds(lo, hi, fov=RERUN_FOV_Y, aspect=RERUN_VIEW_ASPECT)
    return {"position": list(frame.position), "look_target": list(frame.look_at), "eye_up": list(frame.up)}


# the main plots of the layout: name -> the series paths it draws (those a recording has)
MAIN_VIEWS = (
    ("valve lift s", ("/valve/lift", "/valve_rigid/lift", "/follower/lift")),
    ("velocity v", ("/valve/velocity", "/valve_rigid/velocity")),
    ("acceleration p", ("/valve/acceleration", "/valve_rigid/acceleration")),
)
FORCES_VIEW = "forces"
OVERLAID = tuple(p for _, paths in MAIN_VIEWS for p in paths[:1]) + ("/forces",)  # what the overlay holds
CORNERS = ("RightTop", "LeftTop", "RightBottom", "LeftBottom")  # in this order of preference
# the legend's box as fractions of the plot: about what rerun's legend takes in a view of the
# default layout (a few lines of text in one corner)
LEGEND_BOX = (0.35, 0.3)


def view_paths(name: str, paths: Iterable[str]) -> list[str]:
    """The series of one main view (or "forces") among `paths`."""
    paths = list(paths)
    if name == FORCES_VIEW:
        return [p for p in paths if p.startswith("/forces/")]
    wanted = dict(MAIN_VIEWS)[name]
    return [p for p in paths if p in wanted or any(p.startswith(w + "/") for w in wanted)]


def legend_corner(curves: Iterable[tuple[np.ndarray, np.ndarray]], box=LEGEND_BOX) -> str:
    """The corner of a plot over 0..360° where a legend box (fractions of width and height)
    covers the fewest samples of the curves [(angle in degrees, values)]; the y range is the
    curves' own (what the viewer shows by default). Ties go by CORNERS' order."""
    xs, ys = [], []
    for x, y in curves:
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        keep = np.isfinite(x) & np.isfinite(y)
        xs.append(x[keep])
        ys.append(y[keep])
    x = np.concatenate(xs) if xs else np.zeros(0)
    y = np.concatenate(ys) if ys else np.zeros(0)
    if y.size == 0:
        return CORNERS[0]
    lo, hi = float(y.min()), float(y.max())
    span = hi - lo if hi > lo else 1.0
    u, v = x / 360.0, (y - lo) / span  # 0..1 across, 0 (bottom) .. 1 (top)
    w, h = box
    inside = {
        "RightTop": (u >= 1 - w) & (v >= 1 - h), "LeftTop": (u <= w) & (v >= 1 - h),
        "RightBottom": (u >= 1 - w) & (v <= h), "LeftBottom": (u <= w) & (v <= h),
    }
    return min(CORNERS, key=lambda c: (int(np.count_nonzero(inside[c])), CORNERS.index(c)))


def legend_corners(runs_curves: Iterable[Mapping[str, tuple[np.ndarray, np.ndarray]]]) -> dict[str, str]:
    """view name -> legend corner, over the curves of one or more runs ({path: (angle, values)})."""
    per_view: dict[str, list] = {}
    for curves in runs_curves:
        for name in [n for n, _ in MAIN_VIEWS] + [FORCES_VIEW]:
            for path in view_paths(name, curves):
                per_view.setdefault(name, []).append(curves[path])
    return {name: legend_corner(curves) for name, curves in per_view.items()}


def plotted_curves(result, points: int = 720) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{path: (angle, shown values)} of the series the main views draw, thinned to about
    `points` samples (enough to place a legend; a sweep keeps these for every run)."""
    angle = np.asarray(result.columns["cam_angle_deg"], dtype=float)
    stride = max(1, angle.size // points)
    out = {}
    for series in series_layout(result.columns):
        if any(view_paths(name, [series.path]) for name in [n for n, _ in MAIN_VIEWS] + [FORCES_VIEW]):
            out[series.path] = (angle[::stride], series.values(result.columns)[::stride])
    return out


def log_overlay(rec, runs: Sequence[tuple[str, np.ndarray, np.ndarray, Mapping[str, np.ndarray]]],
                label: str) -> None:
    """The overlay recording of several runs: each run's curves (plotted_curves) under
    <path>/runNN, named by the run's label, on the cam-angle and time timelines."""
    import rerun as rr

    rec.send_recording_name(label)
    lines = [f"# {label}", "", "| curve | run |", "|---|---|"]
    for k, (run_label, angle, time_s, curves) in enumerate(runs, start=1):
        child = f"{OVERLAY_PATH_PREFIX}{k:02d}"
        lines.append(f"| {child} | {run_label} |")
        indexes = [rr.TimeColumn(TIMELINE_ANGLE, sequence=angle_sequence(angle)),
                   rr.TimeColumn(TIMELINE_TIME, duration=duration_ns(time_s))]
        for path, values in curves.items():
            rec.log(f"{path}/{child}", rr.SeriesLines(names=run_label), static=True)
            rec.send_columns(f"{path}/{child}", indexes=indexes,
                             columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=np.float64)))
    rec.log(SUMMARY_PATH, rr.TextDocument("\n".join(lines) + "\n", media_type="text/markdown"), static=True)


def overlay_entry(label: str, result, points: int = 720):
    """What the overlay recording keeps of one run: (label, angle, time, {path: shown values}),
    thinned to about `points` samples, so a long sweep holds little of each run."""
    curves = plotted_curves(result, points)
    angle = np.asarray(result.columns["cam_angle_deg"], dtype=float)
    stride = max(1, angle.size // points)
    kept = {p: v for p, (_, v) in curves.items() if any(p == o or p.startswith(o + "/") for o in OVERLAID)}
    return label, angle[::stride], np.asarray(result.columns["time_s"], dtype=float)[::stride], kept


def blueprint(paths: Iterable[str], bounds=None, corners: Mapping[str, str] | None = None):
    """The default layout: 3D view and event log beside time series of s, v, p and forces;
    `bounds` (lo, hi) of the parts places the 3D camera; `corners` (legend_corners) puts each
    plot's legend where its curves are not. The plots span the whole revolution on the cam-angle
    timeline; a view's paths include their children, so that the overlay recording of a sweep
    (/valve/lift/run01, ...) draws every run in the same views."""
    import rerun.blueprint as rrb

    paths = list(dict.fromkeys(paths))
    corners = dict(corners or {})

    def group(prefix: str) -> list[str]:
        return [p for p in paths if p.startswith(prefix + "/")]

    revolution = [rrb.VisibleTimeRange(TIMELINE_ANGLE, start=rrb.TimeRangeBoundary.absolute(seq=0),
                                       end=rrb.TimeRangeBoundary.absolute(seq=ANGLE_UNITS_PER_REV))]
    for timeline in (TIMELINE_STEP, TIMELINE_TIME):
        revolution.append(rrb.VisibleTimeRange(timeline, start=rrb.TimeRangeBoundary.infinite(),
                                               end=rrb.TimeRangeBoundary.infinite()))

    def view(name: str, contents: list[str]):
        legend = rrb.PlotLegend(corner=corners[name], visible=True) if name in corners else None
        return rrb.TimeSeriesView(origin="/", contents=contents, name=name, plot_legend=legend,
                                  time_ranges=revolution)

    main = []
    for name, candidates in MAIN_VIEWS:
        present = [p for p in candidates if p in paths or any(q.startswith(p + "/") for q in paths)]
        main.append(view(name, [f"{p}/**" for p in present] or [f"{candidates[0]}/**"]))
    tabs = [view(FORCES_VIEW, ["/forces/**"])]
    extra = [("jerk", [p for p in ("/valve/jerk", "/valve_rigid/jerk") if p in paths]), ("torque", group("/torque")),
             ("stress", group("/stress")), ("angles", group("/angles")), ("follower", group("/follower")),
             ("lengths", group("/lengths")), ("other", group("/other"))]
    tabs += [view(name, contents) for name, contents in extra if contents]
    left = rrb.Vertical(
        rrb.Spatial3DView(origin=PARTS_PATH, name="valve gear",
                          eye_controls=rrb.EyeControls3D(**eye_for(bounds)) if bounds is not None else None),
        rrb.Tabs(rrb.TextLogView(origin=EVENTS_PATH, name="events"),
                 rrb.TextDocumentView(origin=SUMMARY_PATH, name="summary")),
        row_shares=[3, 1],
    )
    right = rrb.Vertical(*main, rrb.Tabs(*tabs), row_shares=[1, 1, 1, 1])
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[1, 1]),
        rrb.TimePanel(timeline=TIMELINE_ANGLE, fps=ANGLE_UNITS_PER_REV / ANGLE_PLAYBACK_S, playback_speed=1.0),
        collapse_panels=False,
    )


# ---------------------------------------------------------------------------------------------
# files


@dataclass(frozen=True)
class Run:
    """One recording to write: its label, the result, and optionally the 3D parts and poses."""

    label: str
    result: object
    parts: Mapping | None = None  # name -> trimesh.Trimesh in the part's own frame
    poses: Mapping | None = None  # name -> (positions (N, 3), wxyz (N, 4))
    scales: Mapping | None = None  # name -> (N, 3) per-step scale of the part's mesh
    colors: Mapping | None = None  # name -> RGB(A) 0-255
    points: Mapping | None = None  # name -> (N, K, 3) per-step points in the part's frame (the coils)
    magnification: float = 1.0  # the parts' deviations from rigid motion drawn this many times
    checks: object = None  # explorer.view.verdicts.CheckSummary of the run's scene: markers and limits


def with_parts(label: str, result, magnification: float | None = None) -> Run:
    """A Run with the 3D parts, poses and colours of explorer.view.parts (the builders `serve`
    uses), drawn at `magnification` (None: the scene's default, as the browser opens it:
    meshes.default_magnification, x20 for a train of masses whose parts move each with its own
    motion). The spring's rest mesh is scaled along its axis per step (meshes.spring_axial_scale):
    per-step vertices would cost 3600 x thousands of vertices per recording."""
    from .. import parts as meshes  # heavy (PIL, scipy, trimesh): imported on use

    scene = result.scene
    m = meshes.default_magnification(scene) if magnification is None else float(magnification)
    lay = meshes.layout(scene, result)
    parts = meshes.build_parts(scene, result, lay=lay)
    poses = meshes.part_poses(scene, result, magnification=m, lay=lay)
    scales = {}
    if "spring" in parts and hasattr(meshes, "spring_axial_scale"):
        sz = np.asarray(meshes.spring_axial_scale(scene, result, magnification=m, lay=lay), dtype=np.float64)
        scales["spring"] = np.column_stack([np.ones_like(sz), np.ones_like(sz), sz])
    colors = dict(getattr(meshes, "PART_COLORS", {}))
    for name in parts:  # a part of another gear's table (a train's pushrod, an adjuster's plunger)
        if name not in colors:
            try:
                colors[name] = meshes.PART_COLORS[name]
            except KeyError:
                pass
    points = {}
    if "spring" in parts and hasattr(meshes, "coil_points"):
        coils = meshes.coil_points(lay, result, magnification=m)  # the spring as masses: its surge, visible
        if coils is not None:
            points["spring"] = coils
    return Run(label=label, result=result, parts=parts, poses=poses, scales=scales, colors=colors, points=points,
               magnification=m)


def recording_id(label: str) -> str:
    """A fresh random id: two files opened together must never merge into one recording."""
    return f"{label}-{uuid.uuid4().hex[:12]}"


def new_recording(label: str, rid: str | None = None, send_properties: bool = True):
    """A stream of a new recording (`rid` None: a fresh id), or with `rid` of an existing one: what
    it logs joins that recording (the viewer and `rerun rrd merge` put a recording's pieces
    together); such a stream sends no properties of its own (send_properties=False), so it keeps
    the recording's name and start."""
    import rerun as rr

    return rr.RecordingStream(APP_ID, recording_id=rid or recording_id(label), send_properties=send_properties)


def union_bounds(boxes):
    boxes = [b for b in boxes if b is not None]
    if not boxes:
        return None
    return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


def write_recordings(path, runs: Iterable[Run], on_run=None) -> None:
    """Write the runs as separate recordings into one .rrd file that appears only when complete
    (explorer.core.outputs: temporary file and rename; written through for a device or pipe).

    `runs` may be a generator: each run is logged (in the helper process of
    explorer.view.rerun.worker) and dropped before the next is made, so a long sweep needs the
    memory of one run. `on_run(run)` is called after each is written. A single run is one file
    with its layout as default blueprint; several are one file each, without, merged with
    `rerun rrd merge` together with the layout for all of them, written last."""
    out = as_output(path, "output")
    it = iter(runs)
    first = next(it, None)
    if first is None:
        raise ValueError("no runs to record")
    second = next(it, None)
    with output_path(out) as tmp, helper.RecordingWorker() as worker:
        if second is None:
            paths = recording_paths(first.result, (first.parts or {}).keys(), first.checks)
            bounds = parts_bounds(first.parts, first.poses or {}) if first.parts else None
            corners = legend_corners([plotted_curves(first.result)])
            helper.write_file(worker, tmp, first, (paths, bounds, corners))
            if on_run is not None:
                on_run(first)
        else:
            _write_merged(worker, out, tmp, itertools.chain([first, second], it), on_run)
        check_complete(tmp)


def _write_merged(worker, out, tmp: Path, runs: Iterable[Run], on_run) -> None:
    parent = None if out.direct else out.target.parent  # a device's temporaries go to the system's
    work_dir = Path(tempfile.mkdtemp(prefix=f".{Path(out.name).name}.", suffix=".parts", dir=parent))
    try:
        pieces: list[Path] = []
        paths: list[str] = []
        boxes = []
        overlay = []  # each run's thinned main curves: the overlay recording and the legends
        for run in runs:
            paths += recording_paths(run.result, (run.parts or {}).keys(), run.checks)
            if run.parts:
                boxes.append(parts_bounds(run.parts, run.poses or {}))
            overlay.append(overlay_entry(run.label, run.result))
            piece = work_dir / f"{len(pieces):05d}.rrd"
            helper.write_file(worker, piece, run, None)
            pieces.append(piece)
            if on_run is not None:
                on_run(run)
            del run  # the next run is made only now: one in memory at a time
        piece = work_dir / "overlay.rrd"
        helper.write_overlay(worker, piece, overlay, f"overlay: all {len(overlay)} runs")
        pieces.append(piece)
        corners = legend_corners({path: (angle, values) for path, values in curves.items()}
                                 for _, angle, _, curves in overlay)
        layout = work_dir / "layout.rbl"
        helper.write_blueprint(worker, layout, (list(dict.fromkeys(paths)), union_bounds(boxes), corners))
        merge_rrd([*pieces, layout], tmp)
    finally:
        shutil.rmtree(work_dir, ignore_errors=True)


def check_rrd_path(path: str, option: str):
    """An output .rrd path the user named (`option` names the flag in the error), checked before
    any work by the rules of explorer.core.outputs (a .rrd name, a directory that takes a new file;
    /dev/stdout or a FIFO need no suffix): an explorer.core.outputs.Output."""
    return check_output(path, option, suffix=".rrd")


def check_complete(path: Path) -> None:
    """Refuse to publish a file without its footer: rerun's file sink reports write errors
    (a full disk) only in its log, so check the result before renaming it into place."""
    from rerun_bindings import check_for_rrd_footer

    if not Path(path).is_file() or not check_for_rrd_footer(str(path)):
        raise RuntimeError(f"writing the recording failed: {path} is incomplete (no rrd footer)")


def rerun_executable() -> list[str]:
    """The rerun CLI that ships in the rerun-sdk wheel (as rerun_cli does it), as an argv prefix."""
    override = os.environ.get("RERUN_CLI_PATH")
    if override:
        return [override]
    try:
        import rerun_cli

        base = Path(rerun_cli.__file__).parent
        suffix = ".exe" if sys.platform.startswith("win") else ""
        for candidate in (base / "Rerun.app" / "Contents" / "MacOS" / "Rerun", base / f"rerun{suffix}"):
            if candidate.is_file():
                return [str(candidate)]
    except ImportError:
        pass
    found = shutil.which("rerun")
    if found:
        return [found]
    raise RuntimeError("the rerun command-line tool was not found (it ships with the rerun-sdk package)")


def merge_rrd(pieces: Sequence[Path], out: Path) -> None:
    """Merge several .rrd files (one recording each) into one file holding all of them."""
    cmd = [*rerun_executable(), "rrd", "merge", "-o", str(out), *map(str, pieces)]
    # its own group, dying with us, ended as a group on a stop signal or a timeout
    proc = run_child(cmd, timeout=MERGE_TIMEOUT_S, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                     stderr=subprocess.PIPE, text=True, env={**os.environ, "RUST_LOG": "warn"})
    if proc.returncode != 0:
        tail = "\n".join(proc.stderr.strip().splitlines()[-5:])
        raise RuntimeError(f"rerun rrd merge failed (exit {proc.returncode}): {tail}")
