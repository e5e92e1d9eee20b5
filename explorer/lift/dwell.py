"""Dwells of a lift curve: the stretches of cam angle where the lift is constant.

A lift curve (explorer.lift.curves.LiftCurve) is smooth between its breakpoints, so a stretch of
constant lift is a union of whole pieces between consecutive breakpoints: a piece is constant
when L', L'' and L''' vanish (within DERIVATIVE_TOLERANCE times the lift's range, per radian to
that power) at PROBES points spread over its inside. No closed-form law, polynomial or arc that is
not constant vanishes in all three at seven points of one piece; a constant piece gives exactly 0
(the laws' own dwells and base circles) or rounding (an arc concentric with the cam). A lift with
no breakpoints (a table's periodic spline) is one piece, constant only if the whole cam is.

`dwell_after_rise` is the dwell in which the residual vibration of the valve is read
(explorer.effects.residual, docs/theory/residual.md): the first constant stretch after the base
circle (the lowest constant stretch; the longest if several are as low), following the cam's
rotation -- the dwell at the top of a rise-dwell-return cam, or, for a cam without one, the base
circle itself, reached again after the event.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

TWO_PI = 2.0 * math.pi
PROBES = 7  # points inside each piece at which L', L'', L''' must vanish
DERIVATIVE_TOLERANCE = 1e-9  # relative to the lift's range (1e-9 h of drift per radian of cam angle)


@dataclass(frozen=True)
class Dwell:
    """A stretch of constant lift: from cam angle `start` (rad, in [0, 2 pi)) over `length` (rad)."""

    start: float
    length: float
    lift: float  # m, the follower lift L there

    def first_sample(self, theta) -> int | None:
        """Index of the first angle of theta (cam angles of one revolution) inside the dwell, by
        cam angle since its start, or None (no angle of theta falls inside)."""
        x = np.mod(np.asarray(theta, dtype=float) - self.start, TWO_PI)  # angle since the dwell began
        inside = np.nonzero(x < self.length)[0]
        if inside.size == 0:
            return None
        return int(inside[np.argmin(x[inside])])


def _pieces(lift) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends) of the pieces between consecutive breakpoints, in angle order; the last one
    wraps through 2 pi (its end is the first start + 2 pi)."""
    marks = np.unique(np.mod(np.asarray(lift.breakpoints(), dtype=float).ravel(), TWO_PI))
    if marks.size == 0:
        return np.zeros(1), np.full(1, TWO_PI)
    return marks, np.append(marks[1:], marks[0] + TWO_PI)


def constant_stretches(lift) -> list[Dwell]:
    """The maximal stretches of constant lift (adjacent constant pieces at the same lift merged,
    also across 2 pi), in angle order of their starts; [] when the lift is nowhere constant. A cam
    that is constant everywhere is one stretch of length 2 pi."""
    starts, ends = _pieces(lift)
    widths = ends - starts
    fractions = np.arange(1, PROBES + 1) / (PROBES + 1)
    probes = (starts[:, None] + widths[:, None] * fractions[None, :]).ravel()
    d = np.asarray(lift.derivatives(probes), dtype=float)[:4].reshape(4, starts.size, PROBES)
    scale = float(np.max(d[0]) - np.min(d[0]))
    scale = scale if scale > 0.0 else float(np.max(np.abs(d[0])))
    tol = DERIVATIVE_TOLERANCE * scale
    flat = np.all(np.abs(d[1:]) <= tol, axis=(0, 2)) & (widths > 0.0)
    values = d[0, :, PROBES // 2]
    n = starts.size
    if flat.all() and np.ptp(values) <= tol:
        return [Dwell(float(starts[0]), TWO_PI, float(values[0]))]

    def joins(i: int) -> bool:  # piece i continues the constant stretch of piece i - 1
        return bool(flat[i] and flat[i - 1] and abs(values[i] - values[i - 1]) <= tol)

    # begin at a piece that starts a stretch (one exists: not every piece joins its predecessor)
    first = next((i for i in range(n) if not joins(i)), 0)
    out: list[Dwell] = []
    for step in range(n):
        i = (first + step) % n
        if not flat[i]:
            continue
        if joins(i) and out:
            last = out[-1]
            out[-1] = Dwell(last.start, last.length + float(widths[i]), last.lift)
        else:
            out.append(Dwell(float(starts[i]), float(widths[i]), float(values[i])))
    return sorted(out, key=lambda s: s.start)


def dwell_after_rise(lift) -> Dwell | None:
    """The dwell whose residual vibration is read (module doc), or None: the lift has no constant
    stretch, or is constant everywhere (no event)."""
    stretches = constant_stretches(lift)
    if not stretches or stretches[0].length >= TWO_PI:
        return None
    lifts = [s.lift for s in stretches]
    low = min(lifts)
    tol = DERIVATIVE_TOLERANCE * max(max(lifts) - low, abs(low))
    base = max((s for s in stretches if s.lift - low <= tol), key=lambda s: s.length)
    end = base.start + base.length  # the rise begins here
    return min(stretches, key=lambda s: (s.start - end) % TWO_PI if s is not base else TWO_PI)
