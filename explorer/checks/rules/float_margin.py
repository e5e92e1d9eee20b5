"""Float margin: the lowest speed at which the valve leaves the cam (the elastic linkage's first
separation while the valve is open, from the rigid opening to its first seat impact: the sweep's
`separations`, effects/elastic_events.valve_periods -- one after the valve has landed is its
bounce; found on the speed grid and refined by bisection; without a linkage the rigid float speed)
less the highest operating speed.

A valve that separates already at the lowest speed of the range has its first separation at or
below it: the figure is then an upper bound (Measure.bound "at most", shown "<= "), as a margin
the search above the range did not reach is a lower one ("at least", ">= "). The rule
does not search below the range for the figure -- it fails there whatever lies below (the limit
is a margin above the highest speed), separation need not be monotone in the speed (a linkage
resonance separates in a band), so a search down would need a floor of its own and end in the
same bound when the floor separates; the bound costs no run, and `explorer sweep --vary drive.rpm`
or a lower --rpm locates it.

With tolerance draws each draw runs at the speeds its Case gives the rule (the nominal first
separation, if within reach, and the highest speed plus the margin; over the whole range for the
draws the checks verify): its first separation among them. A draw that separates at none of them
passes there, though it may separate at a speed it did not run: the measure says so
(speed_exact = False) and the checks bound that share (explorer.checks.run)."""

from __future__ import annotations

import math

import numpy as np

from ...mechanics.forces import TrainLoads, float_speed
from ...mechanics.gear_contact import NotApplicable
from ..case import RPM
from ..rule import Measure

BISECTIONS = 12  # ~(grid step) / 4096: well under an rpm on any range
MAX_BEYOND = 8  # speeds above the range, up to the highest speed + 1.5 margins


def measure(case, settings) -> Measure:
    if case.scene.valve is None or case.scene.spring is None:
        return Measure.not_applicable("needs [valve] and [spring]")
    margin = settings["fail"] if settings["fail"] is not None else 0.0
    high = float(case.speeds.max())
    reach = high + 1.5 * margin / RPM
    try:
        case.needs_linkage()
    except NotApplicable:
        return _rigid(case, settings, high)
    if case.sampling:
        speeds = case.rule_speeds("float_margin", extra=[high + margin / RPM])
        speeds = speeds[speeds <= reach]
        sep = case.elastic(speeds)["separations"] > 0
        first = np.where(sep, speeds[None, :], np.inf).min(axis=1)
        value = np.where(np.isfinite(first), (first - high) * RPM, np.inf)
        return Measure.of(value[:, None], np.full((case.n, 1), np.nan), None, settings, speed_exact=False,
                          note=f"draws run at {speeds.size} speed{'s' if speeds.size != 1 else ''} up to the highest "
                               "+ margin (elastic)")
    grid = np.asarray(case.speeds, dtype=float)
    step = float(np.median(np.diff(grid))) if grid.size > 1 else max(1.0, 0.02 * high)
    count = int(min(MAX_BEYOND, max(1, math.ceil((reach - high) / step)))) if reach > high else 0
    beyond = np.linspace(high, reach, count + 1)[1:]  # the speeds above the range up to the margin's reach
    speeds = np.unique(np.concatenate([grid, beyond, [reach]]))
    fig = case.elastic(speeds)
    sep = fig["separations"][0] > 0
    if not sep.any():
        return Measure.of([[(speeds[-1] - high) * RPM]], [[np.nan]], None, settings,
                          note=f"no separation up to {speeds[-1]:.6g} rpm (searched): the margin is at least this",
                          bound="at least")
    k = int(np.argmax(sep))
    lo, hi = (speeds[k - 1], speeds[k]) if k > 0 else (None, speeds[k])
    angle = fig["first_separation_deg"][0, k]
    if lo is not None:
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo + hi)
            f = case.elastic([mid])
            if f["separations"][0, 0] > 0:
                hi, angle = mid, f["first_separation_deg"][0, 0]
            else:
                lo = mid
    if k == 0:
        # the first separation is at or below the lowest speed checked, where nothing was run:
        # the margin is at most this (the module docstring says why no search below the range)
        note = (f"separates already at the lowest speed checked, {hi:.6g} rpm (cam angle {angle:.4g} deg, elastic): "
                "the first separation is at or below it, the margin at most this; widen --rpm downwards to find it")
        return Measure(np.array([[(hi - high) * RPM]]), np.array([[angle]]), np.array([hi]), settings["fail"],
                       settings["warn"], note=note, bound="at most")
    note = f"first separation at {hi:.6g} rpm, cam angle {angle:.4g} deg (elastic){_where_in_lift(case, angle)}"
    return Measure(np.array([[(hi - high) * RPM]]), np.array([[angle]]), np.array([hi]), settings["fail"],
                   settings["warn"], note=note)


def _rigid(case, settings, high) -> Measure:
    """The rigid float speed: exact for the nominal design (explorer.mechanics.forces.float_speed);
    for draws the grid's min of G/(-A) over the open, decelerating samples."""
    if not case.sampling:
        jump = float_speed(case.lift, TrainLoads.from_scene(case.scene), case.scene.follower.ratio,
                           case.scene.valve.lash)
        value = jump.omega - high * RPM
        angle = math.degrees(jump.theta) if math.isfinite(jump.theta) else math.nan
        return Measure(np.array([[value]]), np.array([[angle]]), np.array([jump.rpm]) if math.isfinite(jump.omega)
                       else None, settings["fail"], settings["warn"],
                       note=f"rigid float speed {jump.rpm:.6g} rpm (no [linkage])" if math.isfinite(jump.omega)
                       else "rigid: the valve never floats (no [linkage])")
    a_coef, g_part, is_open = case.force_parts(slice(None))
    with np.errstate(divide="ignore", invalid="ignore"):
        w2 = np.where(is_open & (a_coef < 0.0), g_part / -a_coef, np.inf)
    w2 = np.where(np.isnan(w2), np.inf, w2)
    omega = np.sqrt(np.maximum(w2.min(axis=1), 0.0))
    value = omega - high * RPM
    return Measure.of(np.broadcast_to(value[:, None], (case.n, 1)), np.full((case.n, 1), np.nan), None, settings,
                      note="rigid float speed on the grid (no [linkage])")


def _where_in_lift(case, angle_deg: float) -> str:
    """Where on the lift a separation is, against the rigid valve's opening and its peak lift (an
    early separation on the opening flank is the linkage's vibration after the take-up, not the
    inertia float over the nose that the rigid float speed predicts): '' when it does not open."""
    lift = case.valve_lift()[0]
    if not (lift > 0.0).any() or not math.isfinite(angle_deg):
        return ""
    peak = float(case.theta_deg[int(np.argmax(lift))])
    if angle_deg < peak:
        return f"; on the opening flank, {peak - angle_deg:.4g} deg before the rigid valve's peak lift ({peak:.4g} deg)"
    return f"; on the closing flank, {angle_deg - peak:.4g} deg after the rigid valve's peak lift ({peak:.4g} deg)"
