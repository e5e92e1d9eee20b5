"""The masses of an elastic valve train as the drawings show them (issue #25, item 3).

A result of the train of parts (explorer.effects.train_elastic: [[linkage.elements]], [hla]) holds
each part's own motion, `part_<name>_displacement_m` along the part's own travel (valve travel per
part travel: the element's ratio), and the lash adjuster's plunger travel `hla_plunger_travel_m`
(into its body, from its rest on the base circle). The drawings pose the linkage by the rigid
kinematics; for such a result each mass is drawn where it is computed to be, its deviation from
the rigid motion magnified:

    displayed travel of a part (valve-referred) = S + m (r x - S)

with S = follower.ratio * follower_lift_m the cam's drive referred to the valve (where every part
of a rigid train would be), r x the part's travel referred to the valve, m the magnification
(the valve's own displayed lift, explorer.view.drawing.displayed_valve_lift, takes the same m);
the plunger, which a rigid adjuster would not move at all, is drawn at m times its travel.

A gear's drawing says which of its parts each mass carries (explorer/view/base.py, items 7 and
8): its stations, ordered from the cam to the valve, each a tuple of part names. The train's
elements are laid on the stations by `carriers`: the first element on the first station, the last
on the last, the ones between in order; a station with no element of its own moves with the
element before it (a one-part train -- a finger -- moves every station as one).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

# The magnification a train's scene opens with: its parts' deviations from the rigid motion are
# tens of micrometres against millimetres of lift, invisible at x1.
TRAIN_MAGNIFICATION = 20.0


@dataclass(frozen=True)
class TrainMotion:
    """The displayed motion of a train's masses, one array per station of the drawing (N steps)."""

    carriers: tuple[str, ...]  # the element (part name) whose motion each station shows
    travel: tuple[np.ndarray, ...]  # per station: the carrier's travel referred to the valve, m (computed)
    displayed: tuple[np.ndarray, ...]  # per station: S + m (travel - S), m
    drive: np.ndarray  # S: the cam's drive referred to the valve, m
    plunger: np.ndarray | None  # displayed plunger travel into its body (m times the column), m; None: no adjuster
    magnification: float


def train_shape(scene) -> tuple[tuple[str, ...], bool]:
    """The train's part names (cam first) and whether it has an adjuster: what the drawing's
    parts depend on (a scene without a train: ((), False))."""
    linkage = getattr(scene, "linkage", None)
    elements = tuple(e.name for e in (linkage.elements if linkage is not None else ()))
    return elements, getattr(scene, "hla", None) is not None


def default_magnification(scene) -> float:
    """The magnification a scene opens with: TRAIN_MAGNIFICATION for a train of parts or an
    adjuster, 1 otherwise (the rigid gears and the one-mass model look as before)."""
    names, hla = train_shape(scene)
    return TRAIN_MAGNIFICATION if names or hla else 1.0


def carriers(elements: int, stations: int) -> tuple[int, ...]:
    """The element (index, cam first) each station (index, cam first) moves with: the first on the
    first, the last on the last, those between in order; a station beyond the elements between
    the ends takes the last element before the valve's."""
    if elements <= 0 or stations <= 0:
        return ()
    if elements == 1:
        return (0,) * stations
    return tuple(elements - 1 if k == stations - 1 else min(k, elements - 2) for k in range(stations))


def train_motion(scene, result, stations: int, magnification: float) -> TrainMotion | None:
    """The displayed motion of the scene's train over `stations` stations, or None when the
    result has no train columns (a rigid or one-mass result: the drawing's own poses stand)."""
    linkage = getattr(scene, "linkage", None)
    elements = linkage.elements if linkage is not None else ()
    cols = result.columns
    if not elements or stations <= 0 or "follower_lift_m" not in cols \
            or any(f"part_{e.name}_displacement_m" not in cols for e in elements):
        return None
    m = float(magnification)
    drive = scene.follower.ratio * np.asarray(cols["follower_lift_m"], dtype=float)
    which = carriers(len(elements), stations)
    travel = tuple(elements[i].ratio * np.asarray(cols[f"part_{elements[i].name}_displacement_m"], dtype=float)
                   for i in which)
    plunger = cols.get("hla_plunger_travel_m")
    return TrainMotion(
        carriers=tuple(elements[i].name for i in which), travel=travel,
        displayed=tuple(drive + m * (x - drive) for x in travel), drive=drive,
        plunger=None if plunger is None else m * np.asarray(plunger, dtype=float), magnification=m)
