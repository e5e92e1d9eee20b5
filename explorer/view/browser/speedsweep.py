"""The browser's speed sweep: figures of the current scene against camshaft speed, without viser.

Rigid figures at every speed, vectorised: on the scene's own sampling grid the rigid contact
force is F_i(w) = w^2 A_i + G_i (explorer.mechanics.forces.load_parts), so the smallest contact
force and the largest linkage force (the rigid linkage carries the contact force) at RIGID_SPEEDS
speeds are one broadcast min/max over (speeds x open samples). These are grid values, the same
as `simulate`'s contact_force_N column at that speed (tests/test_speedsweep.py); the float speed
marked is the exact one (explorer.mechanics.forces.float_speed).

The vectorised rigid figures hold where the scene's rigid contact force is F = w^2 A + G over the
revolution: `rigid_model_holds` checks it against the forces effect's own column at the scene's
speed. A gear whose forces are its own (the trip gear's latch carries the valve only from its
pick-up to the trip) gets no sweep and a note that says why (#28.6). The float speed marked is the
page's one float speed (explorer.view.browser.model.rigid_float_rpm, #28.5).

Elastic figures (first separation, seating velocity, largest deviation from the rigid lift) need
the elastic solver at each speed. Where the compiled exact solver takes the scene
(explorer.effects.elastic_batch: the translating roller with the `exact` solver, the sweep's
compiled path) and is compiled (explorer.view.browser.kernels), `elastic_batch` computes
ELASTIC_BATCH_SPEEDS speeds in one call (tens of ms); otherwise `elastic_figures` runs `simulate`
of the effects the elastic figures need at one speed, and the compute thread asks the compute
child for them one speed at a time while it has nothing newer to do
(explorer.view.browser.compute), so a parameter change waits at most one such run. Those speeds
come coarse to fine (`coarse_to_fine`): the first few already span the whole range (#28.8).

This lives in view/ rather than reusing explorer.studies.sweeps: view/ and studies/ must not
import each other (issue #12 layers), and both build on explorer.mechanics.forces.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ...core.errors import InputError
from ...effects.contact import peak_torques, torque_factors
from ...effects.elastic_batch import BatchCache, ELASTIC, accepts, elastic_chunk
from ...effects.pipeline import Context, simulate
from ...effects.registry import order
from ...mechanics.forces import RPM_PER_RAD_S, TrainLoads, grid_load_parts
from .model import rigid_float_rpm
from .plots import y_range

RIGID_SPEEDS = 500
ELASTIC_SPEEDS = 24  # one simulate per speed (the scenes the compiled solver does not take)
ELASTIC_BATCH_SPEEDS = 500  # in one compiled call, as many as the rigid figures
_BLOCK_CELLS = 2_000_000  # speeds x samples per block (16 MB of float64)


@dataclass(frozen=True)
class NoSweep:
    """Why a scene has no speed sweep (a line under the plots)."""

    reason: str


def coarse_to_fine(count: int) -> np.ndarray:
    """Indices 0..count-1 in the order that covers their range soonest: the top speed, the
    lowest, then each next one as far as possible from those already taken (ties: the lower)."""
    order = [count - 1] if count else []
    taken = np.zeros(count, dtype=bool)
    if count:
        taken[-1] = True
    index = np.arange(count)
    while len(order) < count:
        chosen = np.asarray(order)
        distance = np.min(np.abs(index[:, None] - chosen[None, :]), axis=1)
        distance[taken] = -1
        k = int(np.argmax(distance))
        order.append(k)
        taken[k] = True
    return np.asarray(order, dtype=int)


@dataclass(frozen=True)
class SpeedSweep:
    """The sweep of one result (`serial`: its request). Elastic entries are NaN until computed."""

    serial: int
    rpm: np.ndarray  # rev/min, RIGID_SPEEDS speeds over `span`
    min_contact_force: np.ndarray  # N, smallest rigid contact force over the open samples
    peak_linkage_force: np.ndarray  # N, largest rigid linkage (= contact) force
    float_rpm: float  # rev/min, exact rigid float speed (nan: never floats)
    span: tuple[float, float]  # rev/min, the plotted range
    elastic_rpm: np.ndarray  # rev/min, the coarser elastic speeds (empty: no elastic effect)
    first_separation_deg: np.ndarray  # cam angle of the first separation while the valve is open (nan: none)
    seating_velocity: np.ndarray  # m/s, hardest seat impact, < 0 (nan: none)
    max_deviation: np.ndarray  # m, largest deviation of the valve from the rigid lift
    peak_torque: np.ndarray | None = None  # N m, rigid camshaft torque peak (None: no contact effect)
    elastic_done: int = 0  # how many elastic speeds are computed (in elastic_order)
    note: str = ""  # why a part is missing
    batched: bool = False  # the elastic speeds come all at once (elastic_batch), not one by one
    elastic_order: np.ndarray | None = None  # the order the elastic speeds are computed in (coarse_to_fine)

    @property
    def elastic_total(self) -> int:
        return int(self.elastic_rpm.size)

    def _order(self) -> np.ndarray:
        return self.elastic_order if self.elastic_order is not None else np.arange(self.elastic_total)

    def next_elastic(self) -> float | None:
        """The next elastic speed to compute (None: all done)."""
        if self.elastic_done >= self.elastic_total:
            return None
        return float(self.elastic_rpm[self._order()[self.elastic_done]])

    def elastic_computed(self) -> np.ndarray:
        """Which elastic speeds are computed (a figure may still be NaN: none at that speed)."""
        done = np.zeros(self.elastic_total, dtype=bool)
        done[self._order()[:self.elastic_done]] = True
        return done

    def progress(self) -> str:
        if self.elastic_total == 0:
            return self.note or "rigid figures at every speed"
        text = f"elastic figures: {self.elastic_done} of {self.elastic_total} speeds done"
        return f"{text}; {self.note}" if self.note else text


def sweep_span(rpm: float, float_rpm: float, previous: tuple[float, float] | None = None) -> tuple[float, float]:
    """The speed range plotted: kept from the previous sweep while the current speed lies well
    inside it (choosing a speed on the plot must not rescale the plot under the pointer), else
    0 to twice the current speed or 1.25 times the float speed, whichever is larger."""
    if previous is not None and previous[0] <= rpm <= 0.98 * previous[1]:
        return previous
    hi = max(2.0 * rpm, 1.25 * float_rpm if math.isfinite(float_rpm) else 0.0)
    hi = _round_up(hi)
    return (hi / RIGID_SPEEDS, hi)


def _round_up(x: float) -> float:
    """x rounded up to two significant digits (a plot range with round tick labels)."""
    p = 10.0 ** math.floor(math.log10(x))
    return math.ceil(x / p * 10.0) * p / 10.0


def speed_parts(scene, lift, open_mask: bool = False):
    """(A, G) on the open samples of the scene's grid: F = w^2 A + G (mechanics.forces.grid_load_parts); with
    `open_mask` also which samples of the grid those are."""
    _, a_coef, g_part, is_open = grid_load_parts(scene, lift)
    if open_mask:
        return a_coef[is_open], g_part[is_open], is_open
    return a_coef[is_open], g_part[is_open]


def torque_sweep(scene, lift, result, rpms) -> np.ndarray:
    """Peak rigid camshaft torque [N m] at each speed of `rpms` (the contact effect's
    max_camshaft_torque_Nm, explorer.effects.contact.peak_torques), its geometry from `result`'s
    kinematics columns (a simulate result of this scene at any speed)."""
    from types import MappingProxyType

    theta, a_coef, g_part, is_open = grid_load_parts(scene, lift)
    cols = result.columns
    ctx = Context(scene, theta, np.asarray(cols["time_s"]), lift, MappingProxyType(dict(cols)),
                  MappingProxyType(dict(result.summary)))
    push, pull = torque_factors(ctx)
    return peak_torques(a_coef, g_part, is_open, push, pull, np.asarray(rpms, dtype=float) / RPM_PER_RAD_S)


def rigid_model_holds(scene, lift, result=None) -> bool:
    """Whether the sweep's F = w^2 A + G on the grid is this scene's rigid contact force: checked
    against the 'forces' effect's own contact_force_N at the scene's speed (from `result` when it
    has the column, else from a run of that effect), to 1e-9 of the largest force. It is for the
    translating roller and the lever gears (1e-16 measured); the trip gear's latch force is not."""
    if result is None or "contact_force_N" not in result.columns:
        result = simulate(dataclasses.replace(scene, effects=("forces",), spring_design=None), lift=lift)
    _, a_coef, g_part, is_open = grid_load_parts(scene, lift)
    force = np.asarray(result.columns["contact_force_N"], dtype=float)
    if force.shape != a_coef.shape:
        return False
    if not is_open.any():
        return True
    w = float(scene.drive.rpm) / RPM_PER_RAD_S
    model = w * w * a_coef[is_open] + g_part[is_open]
    scale = max(float(np.max(np.abs(force[is_open]))), 1.0)
    return bool(np.all(np.abs(model - force[is_open]) <= 1e-9 * scale))


def has_contact(scene) -> bool:
    return "contact" in order(scene.effects)


def rigid_sweep(scene, lift, rpms) -> tuple[np.ndarray, np.ndarray]:
    """(smallest contact force, largest linkage force) in N at each speed of `rpms`, on the
    scene's grid (+inf, 0 when the valve never opens)."""
    rpm = np.asarray(rpms, dtype=float).ravel()
    a_coef, g_part = speed_parts(scene, lift)
    if a_coef.size == 0:
        return np.full(rpm.shape, np.inf), np.zeros(rpm.shape)
    w2 = (rpm / RPM_PER_RAD_S) ** 2
    lo, hi = np.empty(rpm.size), np.empty(rpm.size)
    block = max(1, _BLOCK_CELLS // a_coef.size)
    for start in range(0, rpm.size, block):
        end = min(rpm.size, start + block)
        forces = w2[start:end, None] * a_coef[None, :]
        forces += g_part[None, :]
        lo[start:end] = forces.min(axis=1)
        hi[start:end] = forces.max(axis=1)
    return lo, hi


def has_elastic(scene) -> bool:
    return "elastic" in order(scene.effects)


NO_FORCES = ("**Speed sweep:** none; it needs the rigid forces: a [valve] mass and a [spring] in the scene "
             "(whichever effects are ticked)")
OWN_FORCES = ("**Speed sweep:** none for this gear: its rigid forces are not F = ω²A + G over the revolution, which "
              "the sweep computes at every speed (checked against its own forces at this speed: the trip gear's "
              "latch carries the valve only from the pick-up to the trip); its float speed is in the Read-outs")


def start_sweep(scene, lift, serial: int, previous: tuple[float, float] | None = None, result=None,
                float_rpm: float | None = None, compiled: bool = True) -> SpeedSweep | NoSweep:
    """The rigid part of the sweep of this scene (elastic entries NaN), or NoSweep saying why
    there is none. `float_rpm`: the page's float speed (model.rigid_float_rpm; computed here when
    None); `compiled`: whether the compiled solver may be called (kernels.KernelWarmup.ready)."""
    try:
        TrainLoads.from_scene(scene)
    except (InputError, AttributeError):
        return NoSweep(NO_FORCES)
    try:
        if not rigid_model_holds(scene, lift, result):
            return NoSweep(OWN_FORCES)
        if float_rpm is None:
            float_rpm = rigid_float_rpm(scene, lift, result)
        span = sweep_span(float(scene.drive.rpm), float_rpm, previous)
        rpm = np.linspace(span[0], span[1], RIGID_SPEEDS)
        low, high = rigid_sweep(scene, lift, rpm)
        torque = torque_sweep(scene, lift, result, rpm) if result is not None and has_contact(scene) else None
    except (InputError, ValueError):
        return NoSweep(NO_FORCES)
    elastic = has_elastic(scene)
    takes = elastic and batch_accepts(scene, lift)
    batched = takes and compiled
    count = ELASTIC_BATCH_SPEEDS if batched else ELASTIC_SPEEDS
    speeds = np.linspace(span[1] / count, span[1], count) if elastic else np.empty(0)
    nan = np.full(speeds.shape, np.nan)
    note = "" if elastic else "no elastic effect: rigid figures only"
    if takes and not compiled:
        note = (f"{ELASTIC_SPEEDS} speeds one at a time while the compiled solver is being prepared "
                f"(first start; then {ELASTIC_BATCH_SPEEDS} at once)")
    return SpeedSweep(serial, rpm, low, high, float_rpm, span, speeds, nan, nan.copy(), nan.copy(), peak_torque=torque,
                      note=note, batched=batched, elastic_order=None if batched else coarse_to_fine(speeds.size))


def batch_accepts(scene, lift) -> bool:
    """Whether the compiled exact solver takes this scene's elastic runs."""
    try:
        return accepts(scene, BatchCache(lift))
    except (AttributeError, ValueError):
        return False


def elastic_batch(scene, lift, rpms) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """elastic_figures at every speed of `rpms` in one compiled call (effects.elastic_batch, the
    sweep's compiled path: each equal to simulate's within rounding, tests/test_sweep_kernel.py);
    NaN where there is none or the run fails."""
    figures, _ = elastic_chunk([at_speed(scene, r) for r in rpms], BatchCache(lift))
    column = {name: figures[:, i] for i, name in enumerate(ELASTIC)}
    return column["first_separation_deg"], column["seating_velocity_m_s"], column["max_deviation_m"]


def at_speed(scene, rpm: float):
    """The scene driven at `rpm` rev/min, everything else unchanged."""
    return dataclasses.replace(scene, drive=dataclasses.replace(scene.drive, rpm=float(rpm)))


def elastic_figures(scene, lift, rpm: float) -> tuple[float, float, float]:
    """(first separation [deg], seating velocity [m/s], largest deviation [m]) of `simulate` at
    `rpm`: NaN where there is none, all NaN when the run fails (too slow for the step budget).
    Only the effects the elastic figures need run (elastic and what it depends on): the rocking
    cam's forces and gear figures took 7 of every 8 parts of a speed's time (0.63 s -> 0.09 s),
    and the figures are the same (no effect reads another's figures but its dependencies')."""
    try:
        result = simulate(at_speed(dataclasses.replace(scene, effects=("elastic",), spring_design=None), rpm), lift=lift)
    except (InputError, RuntimeError, ValueError, ArithmeticError):
        return (math.nan, math.nan, math.nan)
    events = [e for e in result.events if e.effect == "elastic"]
    seps = [float(e["cam_angle_deg"]) for e in events if e.get("kind") == "separation"]
    seats = [float(e["velocity_m_s"]) for e in events if e.get("kind") == "seat"]
    deviation = result.summary.get("max_deviation_m")
    return (seps[0] if seps else math.nan, min(seats) if seats else math.nan,
            math.nan if deviation is None else float(deviation))


def with_elastic(sweep: SpeedSweep, figures: tuple) -> SpeedSweep:
    """The sweep with the next elastic speed's figures filled in (a batched sweep: every speed's,
    three arrays)."""
    if sweep.batched:
        sep, seat, dev = (np.asarray(f, dtype=float).copy() for f in figures)
        return dataclasses.replace(sweep, first_separation_deg=sep, seating_velocity=seat, max_deviation=dev,
                                   elastic_done=sweep.elastic_total)
    k = int(sweep._order()[sweep.elastic_done])
    sep, seat, dev = sweep.first_separation_deg.copy(), sweep.seating_velocity.copy(), sweep.max_deviation.copy()
    sep[k], seat[k], dev[k] = figures
    return dataclasses.replace(sweep, first_separation_deg=sep, seating_velocity=seat, max_deviation=dev,
                               elastic_done=sweep.elastic_done + 1)


def with_markers(x: np.ndarray, values: list[np.ndarray], at: list[float]):
    """(x, values, markers) for a uPlot: each marker a vertical line at its exact speed. uPlot
    draws a series against one shared x, so every finite marker speed m in range gets the samples
    m - d, m, m + d (d a thousandth of a grid step) inserted, where the curves take their linear
    interpolation (what the plot draws between the samples anyway) and the marker series is 1 at m
    and 0 elsewhere: drawn on a scale whose visible range starts above 0 it shows as a vertical
    line (as the cam-angle cursor)."""
    x = np.asarray(x, dtype=float)
    d = 1e-3 * float(np.min(np.diff(x))) if x.size > 1 else 1e-3
    inserted = sorted({float(v) + k * d for v in at if math.isfinite(v) and x[0] <= v <= x[-1] for k in (-1, 0, 1)})
    xs = np.union1d(x, np.asarray(inserted, dtype=float))
    out = []
    for y in values:
        y = np.asarray(y, dtype=float)
        ok = np.isfinite(y)
        yi = np.interp(xs, x[ok], y[ok]) if ok.sum() >= 2 else np.full(xs.shape, np.nan)
        # keep gaps: an inserted sample between two samples one of which is NaN is NaN
        left = np.clip(np.searchsorted(x, xs, side="right") - 1, 0, x.size - 1)
        right = np.clip(left + 1, 0, x.size - 1)
        exact = np.isin(xs, x)
        yi = np.where(exact, np.interp(xs, x, np.where(ok, y, 0.0)), yi)
        yi = np.where(exact, np.where(np.isin(xs, x[ok]), yi, np.nan), np.where(ok[left] & ok[right], yi, np.nan))
        out.append(yi)
    markers = []
    for v in at:
        m = np.zeros(xs.size)
        if math.isfinite(v) and x[0] <= v <= x[-1]:
            m[int(np.argmin(np.abs(xs - v)))] = 1.0
        markers.append(m)
    return xs, out, markers


def sweep_plots(sweep: SpeedSweep, current_rpm: float) -> list[tuple]:
    """(title, y label, x, [(label, values, colour)], [current-speed marker, float-speed marker],
    y range) for the rigid forces and, where the scene has them, the camshaft torque and the
    elastic figures; markers at the exact speeds (with_markers)."""
    specs = [("Speed sweep (rigid)", "F [N]", sweep.rpm,
              [("min contact force", sweep.min_contact_force, "#c0392b"),
               ("peak linkage force", sweep.peak_linkage_force, "#2471a3")])]
    if sweep.peak_torque is not None:
        specs.append(("Speed sweep (rigid camshaft torque)", "T [N·m]", sweep.rpm,
                      [("peak camshaft torque", sweep.peak_torque, "#17a589")]))
    if sweep.elastic_total:
        # one plot per figure: three units on one axis would need a scaled series ([°/100]) that
        # reads wrong under the pointer. Only the speeds computed so far are drawn (they come
        # coarse to fine): the curve through them, a NaN a gap where a figure does not apply
        done = f"{sweep.elastic_done}/{sweep.elastic_total} speeds"
        computed = sweep.elastic_computed()
        if computed.sum() < 2:
            computed = np.ones(sweep.elastic_total, dtype=bool)  # nothing to draw yet: NaN everywhere
        x = sweep.elastic_rpm[computed]
        specs += [(f"Speed sweep (elastic first separation, {done})", "θ [°]", x,
                   [("first separation [°]", sweep.first_separation_deg[computed], "#d68910")]),
                  (f"Speed sweep (elastic seating velocity, {done})", "v [m/s]", x,
                   [("seating velocity, signed (< 0 = downward) [m/s]", sweep.seating_velocity[computed], "#8e44ad")]),
                  (f"Speed sweep (elastic deviation, {done})", "Δs [mm]", x,
                   [("largest deviation from the rigid lift [mm]", sweep.max_deviation[computed] * 1e3, "#27ae60")])]
    out = []
    for title, y_label, x, series in specs:
        xs, ys, markers = with_markers(x, [v for _, v, _ in series], [current_rpm, sweep.float_rpm])
        shown = tuple((label, y, colour) for (label, _, colour), y in zip(series, ys))
        out.append((title, y_label, xs, list(shown), markers, y_range(ys)))
    return out


@dataclass(frozen=True)
class SweepTask:
    """A message to the compute child: for the result of request `serial`, the rigid sweep
    (`rpm` None, `span` the previous range or None) or the elastic figures at `rpm`."""

    serial: int
    rpm: float | None = None
    span: tuple[float, float] | None = None
    rpms: tuple[float, ...] | None = None  # every elastic speed at once (a batched sweep)
    compiled: bool = True  # the compiled solver may be called (explorer.view.browser.kernels)


def run_task(task: SweepTask, prepared):
    """What the child answers a SweepTask with, for that result (a model.Prepared)."""
    scene, lift = prepared.scene, prepared.lift
    if task.rpms is not None:
        return elastic_batch(scene, lift, task.rpms)
    if task.rpm is None:
        return start_sweep(scene, lift, task.serial, task.span, prepared.result, prepared.float_rpm, task.compiled)
    return elastic_figures(scene, lift, task.rpm)
