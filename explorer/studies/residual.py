"""Residual vibration over a speed range: how far the elastic valve strays from the lift it should
have, speed by speed, with the scene's own solver (exact by default).

The reference lift is the one the cam was made for: a polydyne cam's wanted valve lift (then
the deviation vanishes at the design speed), else the rigid valve lift ratio * L - lash. For a
polydyne cam with a polynomial rise followed by a dwell, the vibration amplitude during the
dwell has a closed form while the valve stays in contact (explorer.lift.polydyne.residual_amplitude);
the table carries it beside the solver's value.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, replace

import numpy as np

from ..core.errors import InputError

TWO_PI = 2.0 * math.pi
MAX_SPEEDS = 2000


@dataclass(frozen=True)
class ResidualRow:
    rpm: float
    max_deviation_m: float  # largest |s - reference| over the revolution
    dwell_amplitude_m: float | None  # sqrt(e^2 + (e'/wn)^2) where the dwell after the rise starts
    closed_form_m: float | None  # the linear closed form of that amplitude (polydyne, polynomial rise)
    contact_kept: bool  # the linkage stayed loaded from lift-off to the end of the rise
    min_linkage_force_N: float  # smallest linkage force while the valve is open
    seat_velocity_m_s: float  # the fastest landing on the seat (<= 0)


def reference_lift(scene, lift, theta, order: int = 1) -> np.ndarray:
    """(order + 1, N) valve lift the cam is meant to give, per radian, at cam angles theta."""
    wanted = getattr(lift, "wanted_valve_lift", None)
    if wanted is not None:
        return wanted(theta, order)
    d = lift.derivatives(theta)[: order + 1] * scene.follower.ratio
    lash = scene.valve.lash
    is_open = d[0] - lash > 0.0
    d[0] -= lash
    return np.where(is_open, d, 0.0)


def _dwell_start(lift):
    """Cam angle where the dwell after the rise starts (None without a dwell)."""
    w = getattr(lift, "wanted", None)
    start = w.dwell_start() if w is not None else None
    return None if start is None else (lift.start + start) % TWO_PI


def residual_row(scene, lift, rpm: float) -> ResidualRow:
    from ..effects.elastic import linkage_model, solve_reporting, solver_options
    from ..dynamics.model import Drive

    omega = rpm * TWO_PI / 60.0
    model = linkage_model(scene, lift, omega)
    drive = Drive(lift, scene.follower.ratio, omega)
    n = scene.solver.steps_per_revolution
    period = TWO_PI / omega
    grid = np.arange(n + 1) * (period / n)
    d0 = drive(grid)[0]
    t0 = grid[int(np.argmin(d0))]  # the valve rests on its seat where the drive is lowest
    t = t0 + grid
    dwell = _dwell_start(lift)
    t_dwell = None
    if dwell is not None:
        t_dwell = t0 + ((dwell - omega * t0) % TWO_PI) / omega
        t = np.unique(np.append(t, t_dwell))
    sol, _ = solve_reporting(model, drive, t, scene.solver.method, solver_options(scene), scene.source)
    ref = reference_lift(scene, lift, omega * t, 1)
    e, e_dot = sol.s - ref[0], sol.v - omega * ref[1]
    is_open = (sol.s > 0.0) | (ref[0] > 0.0)
    amplitude = closed = None
    contact_kept = True
    if t_dwell is not None:
        i = int(np.searchsorted(t, t_dwell))
        wn = math.sqrt((model.stiffness + model.spring_rate) / model.oscillating_mass)
        amplitude = math.hypot(e[i], e_dot[i] / wn)
        rising = (t <= t_dwell) & (ref[0] > 0.0)
        contact_kept = bool(np.all(sol.contact[rising]))
        from ..lift.polydyne import RISE_POLYNOMIALS, residual_amplitude

        if lift.wanted.rise_law in RISE_POLYNOMIALS and contact_kept:
            closed = residual_amplitude(lift, rpm)
    seats = [ev.get("velocity_m_s", 0.0) for ev in sol.events if ev["kind"] == "seat"]
    force = sol.linkage_force[is_open] if np.any(is_open) else np.zeros(1)
    return ResidualRow(rpm, float(np.max(np.abs(e))), amplitude, closed, contact_kept,
                       float(force.min()), float(min(seats, default=0.0)))


def residual_sweep(scene, rpms, progress=None) -> list[ResidualRow]:
    """One row per speed (rev/min); the cam stays the scene's (a polydyne cam keeps its design)."""
    from ..effects.lift import build_lift

    rpms = np.asarray(rpms, dtype=float).ravel()
    if scene.valve is None or scene.spring is None or scene.linkage is None:
        missing = [s for s in ("valve", "spring", "linkage") if getattr(scene, s) is None]
        raise InputError(scene.source, missing[0], "missing section: the residual vibration needs the elastic linkage "
                         "([valve], [spring], [linkage])")
    if scene.follower.type != "translating-roller":
        raise InputError(scene.source, "follower.type", "residual vibration sweeps are for translating-roller cams")
    lift = build_lift(scene)
    rows = []
    for i, rpm in enumerate(rpms):
        rows.append(residual_row(replace(scene, drive=replace(scene.drive, rpm=float(rpm))), lift, float(rpm)))
        if progress is not None:
            progress(i + 1, rpms.size, f"{rpm:g} rpm")
    return rows


def table_text(scene, rows) -> str:
    out = io.StringIO()
    out.write(f"# {scene.name}: the elastic valve against the lift the cam is made for, one revolution per speed\n")
    out.write("rpm,max_deviation_m,dwell_amplitude_m,closed_form_m,contact_kept,min_linkage_force_N,seat_velocity_m_s\n")
    for r in rows:
        cells = [f"{r.rpm:.10g}", f"{r.max_deviation_m:.6e}",
                 "" if r.dwell_amplitude_m is None else f"{r.dwell_amplitude_m:.6e}",
                 "" if r.closed_form_m is None else f"{r.closed_form_m:.6e}",
                 str(int(r.contact_kept)), f"{r.min_linkage_force_N:.6g}", f"{r.seat_velocity_m_s:.6g}"]
        out.write(",".join(cells) + "\n")
    return out.getvalue()


def chart_png(scene, rows) -> bytes:
    """Deviation (and the dwell amplitude with its closed form) against speed, log scale."""
    from .charts import figure, png

    rpm = np.array([r.rpm for r in rows])
    floor = 1e-16
    with figure(figsize=(8.0, 4.8), dpi=110) as (fig, ax):
        ax.semilogy(rpm, np.maximum([r.max_deviation_m for r in rows], floor), "o-", label="largest deviation over the revolution")
        if any(r.dwell_amplitude_m is not None for r in rows):
            amp = [np.nan if r.dwell_amplitude_m is None else max(r.dwell_amplitude_m, floor) for r in rows]
            ax.semilogy(rpm, amp, "s--", label="vibration amplitude in the dwell (solver)")
        if any(r.closed_form_m is not None for r in rows):
            cf = [np.nan if r.closed_form_m is None else max(r.closed_form_m, floor) for r in rows]
            ax.semilogy(rpm, cf, "k:", label="closed form (linear, in contact)")
        design = getattr(getattr(scene, "lift", None), "options", None)
        if design is not None and hasattr(design, "design_rpm"):
            ax.axvline(design.design_rpm, color="grey", lw=0.8)
            ax.text(design.design_rpm, ax.get_ylim()[1], " design", va="top", color="grey")
        ax.set_xlabel("camshaft speed [rpm]")
        ax.set_ylabel("valve deviation [m]")
        ax.set_title(f"{scene.name}: residual vibration")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        return png(fig)


def parse_speeds(text: str) -> np.ndarray:
    """'A:B:N' (N speeds from A to B rpm) or 'A,B,C'."""
    key = "--rpm"
    try:
        if ":" in text:
            a, b, n = text.split(":")
            lo, hi, count = float(a), float(b), int(n)
            if not 1 <= count <= MAX_SPEEDS:
                raise InputError("<command line>", key, f"between 1 and {MAX_SPEEDS} speeds, got {count}")
            speeds = np.linspace(lo, hi, count)
        else:
            speeds = np.array([float(x) for x in text.split(",")])
    except ValueError:
        raise InputError("<command line>", key, f"expected A:B:N or A,B,C in rpm, got {text[:40]!r}") from None
    if speeds.size > MAX_SPEEDS:
        raise InputError("<command line>", key, f"at most {MAX_SPEEDS} speeds, got {speeds.size}")
    if not np.all(np.isfinite(speeds)) or np.any(speeds <= 0.0) or np.any(speeds > 100_000.0):
        raise InputError("<command line>", key, "speeds must lie in (0, 100000] rpm")
    return speeds
