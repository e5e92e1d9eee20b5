"""The speed sweep under the plots: its plots (rigid forces, camshaft torque, the elastic
figures), the line saying what it is or why there is none, its progress, and the speed slider
right under the rigid plot (explorer.view.browser.speedsweep computes it, in the compute child)."""

from __future__ import annotations

import math

from .speedsweep import SpeedSweep, sweep_plots

SWEEP_ORDER = 2e6  # the speed sweep below the plots and their slider
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


def _labels(series) -> tuple[str, ...]:
    return tuple(s["label"] for s in series)


class SweepView:
    """The speed sweep of the result shown: `sweep` is the newest SpeedSweep (or NoSweep)."""

    def __init__(self, gui, tab):
        self.gui, self.tab = gui, tab
        self.sweep = None  # the SpeedSweep shown, or a NoSweep
        self.serial = -1  # the request whose result it is of
        self.handles: list = []
        # its plots are added as sweeps arrive (at SWEEP_ORDER + 1, + 3, + 5, ...); this slider
        # sits right under the rigid one, on its speed scale (viser's uPlot reports no clicks)
        with tab:
            self.note = gui.add_markdown("**Speed sweep:** computing…", order=SWEEP_ORDER)
            self.rpm = gui.add_slider("Speed [rpm]", min=0.0, max=1.0, step=1.0, initial_value=0.0,
                                      order=SWEEP_ORDER + 2, disabled=True,
                                      hint="choose a camshaft speed: the gear, plots and read-outs move to it")
            self.progress = gui.add_markdown("", order=SWEEP_ORDER + 10)

    def arrived(self, serial: int, sweep) -> None:
        """A new or extended sweep of request `serial`'s result (the newest result's is kept)."""
        if serial >= self.serial:
            self.sweep, self.serial = sweep, serial

    def show(self, current, write, compiling: str = "", speed_pending: bool = False) -> None:
        """Draw the sweep for the result shown (its speed marked), or say why there is none;
        `write`: the loop's write of a control (requests.Inbox.write); `compiling`: a line while
        the compiled solver is prepared (explorer.view.browser.kernels);
        `speed_pending`: a new speed is being computed (the slider keeps it meanwhile)."""
        sweep = self.sweep
        if not isinstance(sweep, SpeedSweep) or current is None:
            for handle in self.handles:
                handle.remove()
            self.handles = []
            self.rpm.disabled = True
            if sweep is not None and not isinstance(sweep, SpeedSweep):
                self.note.content = sweep.reason
            self.progress.content = f"<small>{compiling}</small>" if compiling else ""
            return
        rpm = float(current.scene.drive.rpm)
        plots = sweep_plots(sweep, rpm)
        wanted = [sweep_plot_options(title, y_label, series, sweep.span, y_lim)
                  for title, y_label, _, series, _, y_lim in plots]
        data = [(x, *(values for _, values, _ in series), *markers) for _, _, x, series, markers, _ in plots]
        same = len(wanted) == len(self.handles) and all(
            _labels(h.series) == _labels(o["series"]) for h, o in zip(self.handles, wanted))
        if not same:
            for handle in self.handles:
                handle.remove()
            with self.tab:
                self.handles = [self.gui.add_uplot(data=values, order=SWEEP_ORDER + 1 + 2 * k, **options)
                                for k, (options, values) in enumerate(zip(wanted, data))]
        else:
            for handle, values, options in zip(self.handles, data, wanted):
                handle.data = values
                if handle.title != options["title"]:
                    handle.title = options["title"]
                if handle.scales != options["scales"]:
                    handle.scales = options["scales"]
        float_text = f"{sweep.float_rpm:.0f} rpm" if math.isfinite(sweep.float_rpm) else "none"
        self.note.content = (f"**Speed sweep** of this scene: {sweep.rpm.size} speeds up to "
                             f"{sweep.span[1]:g} rpm; rigid float speed {float_text}.")
        progress = sweep.progress() + (f"; {compiling}" if compiling and not sweep.batched else "")
        self.progress.content = f"<small>{progress}</small>"
        slider = self.rpm
        if (slider.min, slider.max) != (0.0, float(sweep.span[1])):
            slider.min, slider.max = 0.0, float(sweep.span[1])
            slider.step = float(sweep.span[0])
        slider.disabled = False
        if slider.value != rpm and not speed_pending:
            write(slider, rpm)
