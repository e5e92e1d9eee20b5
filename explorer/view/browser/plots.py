"""The Plots tab's cam-angle plots: s, v, p and forces over the revolution with a cursor at the
angle shown, the line saying which plot is missing, and the slider under them.

viser passes uPlot options to the page as they are (JSON only, no JavaScript). Each plot's y
range is set from Python, like the speed sweep's: uPlot's autorange takes NaN (a column that does
not apply somewhere, such as the required spring force while the valve is not carried) for a
number, and a plot whose range is NaN draws neither tick labels nor grid (issue #28.4).
"""

from __future__ import annotations

import time

import numpy as np

PLOT_X_LABEL = "cam angle θ [°]"
PLOT_CURSOR_HZ = 8.0  # the plots' angle cursor is redrawn at most this often
# A plot that gets new data while a page lays it out for the first time keeps the axes it
# computed at width 0: no tick labels, no grid, for good (#28.4: viser's uPlot is created at width
# 0 and resized once its panel is measured; uPlot's redraw() after a data update clears the
# pending recalculation of the axes that the resize asked for, so its axes' increments stay
# [0, 0]). The cursor was the data that changed all the time, 8 times a second while the
# animation played. So the cursor is drawn while the animation is paused (or scrubbed: one update
# per change, throttled while a slider is dragged) and hidden while it plays, when the sliders and
# the 3D gear show the angle; it also holds still for CURSOR_SETTLE_S after the plots are made,
# and a page that connects gets its plots made anew REPLOT_AFTER_S later, once laid out.
CURSOR_SETTLE_S = 2.0
REPLOT_AFTER_S = 3.0
PLOT_SLIDER_ORDER = 1e6  # after every plot: the plots are added and removed as results change


def y_range(values) -> tuple[float, float]:
    """The y range a plot shows: its finite values with 5 % margin (0..1 when it has none; uPlot's
    own autorange fails on NaN, which marks an elastic speed not computed yet or a figure that
    does not apply). The revolution's plots and the speed sweep's use it."""
    finite = np.concatenate([np.asarray(v, dtype=float)[np.isfinite(v)] for v in values] or [np.empty(0)])
    if finite.size == 0:
        return (0.0, 1.0)
    lo, hi = float(finite.min()), float(finite.max())
    pad = 0.05 * (hi - lo) if hi > lo else max(abs(hi), 1.0) * 0.05
    return (lo - pad, hi + pad)


def plot_scales(plot) -> dict:
    lo, hi = y_range([values for _, values, _ in plot.series])
    return {"x": {"time": False, "auto": False, "range": [0, 360]},
            "y": {"auto": False, "range": [lo, hi]},
            "cursor": {"auto": False, "range": [0.02, 1.0]}}


def plot_options(plot) -> dict:
    """uPlot options of one plot. Both axes are named with their unit; the series carry their
    dashes (explorer.view.browser.model.DASHES); the legend follows the pointer and shows the
    values under it (a click on a legend entry hides or shows that curve); a curve near the
    pointer is highlighted; the top padding keeps the highest tick label ("1,000") inside."""
    series = [{"label": PLOT_X_LABEL}]
    for k, (label, _, colour) in enumerate(plot.series):
        style = plot.styles[k] if k < len(plot.styles) else {"width": 1.5}
        series.append({"label": label, "stroke": colour, **style})
    # the cursor: a one-sample spike on its own 0..1 scale whose base lies below the visible
    # range, so only a vertical line at the current angle shows
    series.append({"label": "now", "stroke": "#111111", "width": 1.5, "scale": "cursor"})
    return dict(
        series=tuple(series), title=plot.title,
        scales=plot_scales(plot),
        axes=({"label": PLOT_X_LABEL, "size": 30, "labelSize": 16, "labelGap": 0},
              {"label": plot.y_label, "size": 58, "labelSize": 16, "labelGap": 0}),
        padding=(14, 18, 0, 0), aspect=2.0,
        legend={"show": True, "live": True},
        cursor={"focus": {"prox": 12}},
        focus={"alpha": 0.35},
    )


def plot_data(plot, angle: float | None) -> tuple[np.ndarray, ...]:
    """The plot's data with the cursor at `angle` (None: no cursor)."""
    cursor = np.zeros(len(plot.x))
    if angle is not None:
        cursor[int(np.argmin(np.abs(plot.x - angle % 360.0)))] = 1.0
    return (plot.x, *(values for _, values, _ in plot.series), cursor)


def _labels(series) -> tuple[str, ...]:
    return tuple(s["label"] for s in series)


class Plots:
    """The cam-angle plots of the result shown, in the Plots tab (`tab`)."""

    def __init__(self, gui, tab, angle_slider_hint: str):
        self.gui, self.tab = gui, tab
        self.handles: list = []
        self._settle_until = 0.0  # no cursor data before this (time.perf_counter())
        self._cursor_at = 0.0  # when the cursor was last redrawn (it is throttled to PLOT_CURSOR_HZ)
        self._cursor_step = -1
        self.replots = 0  # how often the plots were made anew for pages that connected
        # prepared -> the plots drawn: the result's, with the Checks panel's limits as more series
        # and plots (checks_panel.with_limits)
        self.limits = lambda prepared: list(prepared.plots)
        self.drawn: list = []  # the plots as drawn (the result's, with the limits)
        with tab:
            self.stale = gui.add_markdown("", visible=False, order=-2.0)
            self.note = gui.add_markdown("", visible=False, order=-1.0)
            # viser's uPlot sends no clicks or pointer positions back to Python: the nearest thing
            # to clicking a plot is this slider right under the plots, on their angle scale
            self.angle = gui.add_slider(PLOT_X_LABEL, min=0.0, max=360.0, step=0.1, initial_value=0.0,
                                        order=PLOT_SLIDER_ORDER, hint=angle_slider_hint)

    def replot(self, prepared, angle: float | None) -> None:
        """Make the plots anew (a page that connected is laid out by now)."""
        for handle in self.handles:
            handle.remove()
        self.handles = []
        self.show(prepared, angle)
        self.replots += 1

    def show(self, prepared, angle: float | None) -> None:
        """The plots of a new result: replaced where their titles or curves differ, else new data."""
        if self.note.content != prepared.plot_note:
            self.note.content = prepared.plot_note
            self.note.visible = bool(prepared.plot_note)
        self.drawn = plots = self.limits(prepared)
        wanted = [plot_options(plot) for plot in plots]
        same = len(wanted) == len(self.handles) and all(
            h.title == o["title"] and _labels(h.series) == _labels(o["series"]) for h, o in zip(self.handles, wanted))
        if not same:
            for handle in self.handles:
                handle.remove()
            with self.tab:
                self.handles = [self.gui.add_uplot(data=plot_data(plot, angle), **options)
                                for plot, options in zip(plots, wanted)]
            self.settle()
        else:
            for handle, plot, options in zip(self.handles, plots, wanted):
                handle.data = plot_data(plot, angle)
                if handle.scales != options["scales"]:
                    handle.scales = options["scales"]

    def settle(self) -> None:
        """A page is laying the plots out: no cursor data for CURSOR_SETTLE_S."""
        self._settle_until = time.perf_counter() + CURSOR_SETTLE_S

    def cursor(self, prepared, angle: float | None, step: int, force: bool = False) -> None:
        """The cursor at `angle` (step `step` of the revolution; None: hidden, the animation
        plays), at most PLOT_CURSOR_HZ a second, none while the plots settle unless forced."""
        now = time.perf_counter()
        if not force and now < self._settle_until:
            return
        step = -2 if angle is None else step
        if force or (step != self._cursor_step and now - self._cursor_at >= 1.0 / PLOT_CURSOR_HZ):
            for handle, plot in zip(self.handles, self.drawn or prepared.plots):
                handle.data = plot_data(plot, angle)
            self._cursor_at, self._cursor_step = now, step
