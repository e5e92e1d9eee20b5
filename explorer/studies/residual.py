"""Residual vibration over a speed range: a sweep of drive.rpm (explorer.studies.sweep_run, the
same engine, table and conventions as `explorer sweep`) whose rows carry the elastic effect's
residual columns (explorer.effects.residual):

  residual_deviation_m   largest |s - s_ref| over the revolution, s_ref the lift the cam is made
                         for (a polydyne cam's wanted valve lift: then ~0 at the design speed;
                         else the rigid valve lift)
  residual_amplitude_m   the vibration amplitude in the dwell after the rise (NaN: no dwell)

and one column the study adds after the sweep, since it is a formula of the speed alone:

  residual_closed_form_m the linear closed form of that amplitude for a polydyne cam with a
                         polynomial rise and a dwell (explorer.lift.polydyne.residual_amplitude),
                         in the runs where the valve stayed on the cam from lift-off to the
                         dwell (no separation, or the first one after the dwell began); NaN
                         elsewhere.

The cam is the scene's in every run (a polydyne cam keeps its design speed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..core import grids
from ..core.errors import InputError
from ..effects.lift import build_lift
from ..gears.registry import GEARS
from ..lift.polydyne import RISE_POLYNOMIALS, residual_amplitude
from .charts import figure, png
from .sweep_run import run_plan
from .sweep_spec import SWEEP_KEYS, check_scene, check_values, make_plan, parse_axis, quantity
from .sweep_table import SweepTable

TWO_PI = 2.0 * math.pi
MAX_SPEEDS = 2000
CLOSED_FORM = "residual_closed_form_m"


@dataclass(frozen=True)
class ResidualRow:
    """One speed of the table, by name (the tests' and the chart's view of it)."""

    rpm: float
    max_deviation_m: float  # residual_deviation_m
    dwell_amplitude_m: float | None  # residual_amplitude_m (None: no dwell)
    closed_form_m: float | None  # residual_closed_form_m (None: no closed form here)
    contact_kept: bool  # the valve stayed on the cam through the rise (the closed form applies)
    seating_velocity_m_s: float  # the hardest seat impact (< 0; NaN: none)


def residual_scene(scene):
    """The scene checked for a residual sweep, with the elastic effect on."""
    if scene.valve is None or scene.spring is None or scene.linkage is None:
        missing = [s for s in ("valve", "spring", "linkage") if getattr(scene, s) is None]
        raise InputError(scene.source, missing[0], "missing section: the residual vibration needs the elastic linkage "
                         "([valve], [spring], [linkage])")
    if not scene.gear_plugin.batch_sweeps:  # the cam must be the same at every speed
        makers = [name for name, gear in GEARS.items() if gear.batch_sweeps]
        raise InputError(scene.source, "follower.type", f"residual vibration sweeps are for {', '.join(makers)} cams")
    if scene.spring.elements > 0:
        raise InputError(scene.source, "spring.elements", "residual vibration sweeps are for the massless spring "
                         "(the spring chain's effect computes no residual columns)")
    if "elastic" not in scene.effects:
        scene = replace(scene, effects=(*scene.effects, "elastic"))
    return scene


def contact_through_rise(lift, separations: float, first_separation_deg: float) -> bool:
    """True when the valve stayed on the cam from lift-off to the dwell: no separation, or the
    first one (by cam angle from 0, as the table has it) at or after the dwell's start. An event
    that straddles 0 deg has its return before its rise in that order: only no separation counts."""
    if separations == 0:
        return True
    begin = (lift.start - lift.ramp) % TWO_PI  # the opening ramp starts here
    if begin + lift.wanted.end + 2.0 * lift.ramp >= TWO_PI or not math.isfinite(first_separation_deg):
        return False
    return math.radians(first_separation_deg) - begin >= lift.ramp + lift.wanted.dwell_start()


def closed_forms(scene, rpm: np.ndarray, separations: np.ndarray, first_separation_deg: np.ndarray) -> np.ndarray:
    """residual_closed_form_m per run (module doc)."""
    out = np.full(rpm.shape, math.nan)
    lift = build_lift(scene)
    wanted = getattr(lift, "wanted", None)
    if wanted is None or wanted.dwell_start() is None or getattr(wanted, "rise_law", None) not in RISE_POLYNOMIALS:
        return out
    for i, (r, n_sep, first) in enumerate(zip(rpm, separations, first_separation_deg)):
        if contact_through_rise(lift, float(n_sep), float(first)):
            out[i] = residual_amplitude(lift, float(r))
    return out


def residual_table(scene, rpms, *, workers: int | None = None, progress=None):
    """The sweep table over the speeds `rpms` (rev/min) with the closed-form column added."""
    scene = residual_scene(scene)
    plan = make_plan([parse_axis("drive.rpm", [float(r) for r in np.asarray(rpms, dtype=float).ravel()], file="--rpm")],
                     file="--rpm")
    check_scene(scene, plan)
    table = run_plan(scene, plan, workers=workers, progress=progress)
    rpm = np.asarray(table.columns["drive_rpm"], dtype=float)
    separations = np.asarray(table.columns["separations"], dtype=float)
    columns = dict(table.columns)
    columns[CLOSED_FORM] = closed_forms(scene, rpm, separations, np.asarray(table.columns["first_separation_deg"], float))
    design = getattr(scene.lift.options, "design_rpm", None)
    metadata = {**table.metadata, "study": "residual", "design_rpm": design}
    return SweepTable.build(columns, metadata)


def rows_of(table) -> list[ResidualRow]:
    c = table.columns

    def maybe(x) -> float | None:
        return None if not math.isfinite(x) else float(x)

    return [ResidualRow(float(c["drive_rpm"][i]), float(c["residual_deviation_m"][i]),
                        maybe(float(c["residual_amplitude_m"][i])), maybe(float(c[CLOSED_FORM][i])),
                        bool(c["separations"][i] == 0 or math.isfinite(float(c[CLOSED_FORM][i]))),
                        float(c["seating_velocity_m_s"][i]))
            for i in range(len(table))]


def residual_sweep(scene, rpms, progress=None, workers: int | None = 1) -> list[ResidualRow]:
    """One row per speed (rev/min), from residual_table."""
    return rows_of(residual_table(scene, rpms, workers=workers, progress=progress))


def chart_png(scene, table) -> bytes:
    """Deviation (and the dwell amplitude with its closed form) against speed, log scale."""
    c = table.columns
    rpm = np.asarray(c["drive_rpm"], float)
    floor = 1e-16
    with figure(figsize=(8.0, 4.8), dpi=110) as (fig, ax):
        ax.semilogy(rpm, np.maximum(np.asarray(c["residual_deviation_m"], float), floor), "o-",
                    label="residual_deviation_m (largest over the revolution)")
        amp = np.asarray(c["residual_amplitude_m"], float)
        if np.isfinite(amp).any():
            ax.semilogy(rpm, np.maximum(amp, floor), "s--", label="residual_amplitude_m (in the dwell, solver)")
        closed = np.asarray(c[CLOSED_FORM], float)
        if np.isfinite(closed).any():
            ax.semilogy(rpm, np.maximum(closed, floor), "k:", label=f"{CLOSED_FORM} (linear, in contact)")
        design = table.metadata.get("design_rpm")
        if design is not None:
            ax.axvline(design, color="grey", lw=0.8)
            ax.text(design, ax.get_ylim()[1], " design", va="top", color="grey")
        ax.set_xlabel("drive_rpm")
        ax.set_ylabel("valve deviation [m]")
        ax.set_title(f"{scene.name}: residual vibration")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        return png(fig)


def parse_speeds(text: str) -> np.ndarray:
    """--rpm in the range grammar of every command (explorer.core.grids, as `explorer sweep
    --vary drive.rpm=...`): 'A:B:N' (N speeds from A to B, upwards), 'A:B:N:log' or 'A,B,C';
    bare numbers in rev/min, or with a unit; each speed in drive.rpm's valid range."""
    info, key = SWEEP_KEYS["drive.rpm"], "--rpm"
    shape = grids.read(text, file=key, key=info.key, max_points=MAX_SPEEDS)
    speeds = grids.values(shape, lambda value: quantity(value, info, key), file=key, key=info.key)
    check_values(info, speeds, key)
    return speeds
