"""The Checks tab (issue #26.3): one line per design rule in traffic-light colours, each a button
that moves the gear and the plots to the speed and cam angle of the rule's worst value, and the
rules' limits drawn as horizontal lines on the plots of the columns they concern.

The checks are the design's (explorer.checks, through the CheckRunner `explorer serve` hands the
app: explorer.view.verdicts); they run in the compute child after the result is shown, like the
spring advice (explorer.view.browser.compute), so they never delay the first result. What a click
asks is recorded (CheckChosen) and applied by the frame loop like any other request: the speed as
if typed into Camshaft rpm, the angle as if scrubbed.

Nothing here imports viser: the panel is given the GUI and its tab.
"""

from __future__ import annotations

import dataclasses
import html
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..verdicts import RGB, CheckLine, CheckRunner, CheckSummary

# The browser's cam-angle plots (explorer.view.browser.model.build_plots) by title: the result
# column each draws and its display factor (a limit in the column's unit times this is the line's
# height). tests/test_checks_view.py holds this to build_plots.
PLOT_COLUMNS: dict[str, tuple[tuple[str, float], ...]] = {
    "Valve lift s": (("valve_lift_m", 1e3),),
    "Velocity v": (("valve_velocity_m_s", 1.0),),
    "Acceleration p": (("valve_accel_m_s2", 1.0),),
}
LIMIT_DASH = [3, 3]
# Plots the page draws only to carry a rule's limits (build_plots has none of these quantities):
# (title, y label, [(column, label)], display factor), added after the others when the result has
# one of the columns and the checks put a limit on it.
LIMIT_PLOTS: tuple[tuple[str, str, tuple[tuple[str, str], ...], float], ...] = (
    ("Pressure angle α", "α [°]", (("pressure_angle_deg", "pressure angle"),), 1.0),
    ("Contact stress σ (Hertz)", "σ [MPa]", (("hertz_stress_Pa", "Hertz"), ("face_hertz_stress_Pa", "face (crown)"),
                                            ("tip_hertz_stress_Pa", "lifter tip"),
                                            # the same under the elastic train's cam force (the contact effect's dynamic_*)
                                            ("dynamic_hertz_stress_Pa", "Hertz, elastic train"),
                                            ("dynamic_face_hertz_stress_Pa", "face, elastic train"),
                                            ("dynamic_tip_hertz_stress_Pa", "lifter tip, elastic train")), 1e-6),
)


@dataclass(frozen=True)
class ChecksTask:
    """A message to the compute child: check the scene of request `serial`'s result with `runner`
    (a module-level function: it pickles by reference, and the child imports its module)."""

    serial: int
    runner: CheckRunner


@dataclass(frozen=True)
class ChecksArrived:
    serial: int  # the request whose result was checked
    summary: Any  # CheckSummary, or a str: why there are none (time limit, bad [checks])


@dataclass(frozen=True)
class CheckChosen:
    """A line of the Checks panel clicked: go to its rule's worst."""

    rule: str


def run_checks(task: ChecksTask, scene) -> tuple[str, Any]:
    """The child's side: ("checks", CheckSummary) or ("checks", message) for a scene whose checks
    cannot run (bad [checks]: the scene file's own error line)."""
    from ...core.errors import InputError

    try:
        return ("checks", task.runner(scene))
    except InputError as exc:
        return ("checks", f"error: {exc}")


def hex_colour(rgb) -> str:
    return "#" + "".join(f"{int(c):02x}" for c in rgb)


def limit_plots(result, summary: CheckSummary) -> list:
    """The plots of LIMIT_PLOTS whose columns the result has and the checks limit."""
    from .model import DASHES, SERIES_COLORS, WIDTHS, Plot, decimate

    cols = result.columns
    x = np.asarray(cols["cam_angle_deg"], dtype=float)
    out = []
    for title, y_label, entries, factor in LIMIT_PLOTS:
        present = [(column, label) for column, label in entries if column in cols]
        if not any(summary.thresholds(column) for column, _ in present):
            continue
        xs, ys = decimate(x, [np.asarray(cols[column], dtype=float) * factor for column, _ in present])
        series = tuple((label, y, SERIES_COLORS[i % len(SERIES_COLORS)]) for i, ((_, label), y) in enumerate(zip(present, ys)))
        styles = tuple({"width": WIDTHS[i % len(WIDTHS)], "dash": list(DASHES[i % len(DASHES)])} for i in range(len(series)))
        out.append(Plot(title, xs, series, y_label, styles))
    return out


def plot_columns(title: str) -> tuple[tuple[str, float], ...]:
    """The result columns a plot draws and their display factor (PLOT_COLUMNS, LIMIT_PLOTS)."""
    for name, _, entries, factor in LIMIT_PLOTS:
        if name == title:
            return tuple((column, factor) for column, _ in entries)
    return PLOT_COLUMNS.get(title, ())


def with_limits(plots, summary: CheckSummary | None, result=None) -> list:
    """The plots with each limit of `summary` on a column a plot draws as one more series: a
    dashed horizontal line in the colour of the limit (red fail, amber warn), labelled with the
    rule, the limit and its value. With the `result`, the plots of LIMIT_PLOTS that carry a limit
    are added after the others."""
    if summary is None or isinstance(summary, str):
        return list(plots)
    if result is not None:
        plots = list(plots) + limit_plots(result, summary)
    out = []
    for plot in plots:
        extra, styles, drawn = [], [], set()
        for column, factor in plot_columns(plot.title):
            for line, threshold in summary.thresholds(column):
                for value in threshold.values:
                    height = value * factor
                    # a rule's limit once per plot (hertz_stress names the line contact's, the
                    # crown's and the tip's columns: one allowable)
                    if (line.rule, threshold.limit, height) in drawn:
                        continue
                    drawn.add((line.rule, threshold.limit, height))
                    extra.append((f"{line.title} {threshold.limit} {height:.4g}",
                                  np.full(len(plot.x), height), hex_colour(RGB[threshold.limit])))
                    styles.append({"width": 1.2, "dash": LIMIT_DASH})
        if extra:
            base = tuple(plot.styles) + ({"width": 1.5},) * (len(plot.series) - len(plot.styles))
            plot = dataclasses.replace(plot, series=tuple(plot.series) + tuple(extra), styles=base + tuple(styles))
        out.append(plot)
    return out


def header_html(summary, label: str = "", checking: bool = False) -> str:
    if summary is None:
        return "<div style='font-size:0.85em'>checking the design…</div>"
    if isinstance(summary, str):
        return f"<div style='font-size:0.85em;color:#c0392b'>{html.escape(summary)}</div>"
    counts = summary.counts()
    state = " · checking the new result…" if checking else ""
    return (f"<div style='font-size:0.85em'><b>{html.escape(summary.scene)}</b>: "
            f"<b style='color:{hex_colour(RGB.get(summary.verdict, (90, 90, 90)))}'>{summary.verdict.upper()}</b> "
            f"({counts['fail']} fail, {counts['warn']} warn, {counts['pass']} pass, {counts['n/a']} n/a) over "
            f"{html.escape(summary.range_text)}; {1e3 * summary.seconds:.0f} ms{state}<br>"
            "A line moves the gear and the plots to its worst value (speed and cam angle); the limits are "
            "dashed lines on the plots of the quantities they concern.</div>")


# A rule's line is two rows: a button with its verdict and title, and under it a small text with
# the rest (the worst, where, the limits; why a rule cannot judge). viser 1.1.1's button neither
# wraps nor shows its `hint` (client/src/components/Button.tsx: one row 2em high, the label clipped
# at the panel's edge), so a line in one button lost its end ("... 0.06071 mm/de" in the 440 px
# panel). A title too long for the button row (BUTTON_CHARS: the 422 px button at size sm holds
# about 64 characters of Mantine's sans-serif, with room for wide glyphs) is cut with an ellipsis
# and given whole in the text row; the limit's source is the text row's tooltip (its title).
BUTTON_CHARS = 56
DETAIL_CLASS = "explorer-check-detail"


def button_text(line: CheckLine, limit: int = BUTTON_CHARS) -> str:
    """The button row: verdict and title ("FAIL · Seating velocity"), cut to `limit` characters
    at a word with an ellipsis."""
    text = f"{line.verdict.upper() if line.judged else line.verdict} · {line.title}"
    if len(text) <= limit:
        return text
    head = text[: limit - 1]
    cut = head.rsplit(" ", 1)[0] if " " in head[len(line.verdict) + 3:] else head
    return cut.rstrip(" ·:,;") + "…"


def worst_text(line: CheckLine) -> str:
    """The worst and where it is ("8.007 m/s at 3472.36 rpm, 176.17°"); "" for a rule that
    cannot judge or shows no value."""
    if not line.judged or not line.shown:
        return ""
    return line.shown + (f" at {line.where()}" if line.where() else "")


def _detail_parts(line: CheckLine) -> list[tuple[str, bool]]:
    """The text row's pieces, each with whether it is the worst (drawn in the verdict's colour)."""
    parts = [(line.title, False)] if button_text(line).endswith("…") else []
    if not line.judged:
        return parts + [(line.reason or line.verdict, False)]
    worst = worst_text(line)
    return parts + ([(worst, True)] if worst else []) + ([(f"limits {line.limit}", False)] if line.limit else [])


def detail_text(line: CheckLine) -> str:
    """The text row under the button: the whole title when the button cut it, then the worst with
    where, and the limits; for a rule that cannot judge, why."""
    return " · ".join(text for text, _ in _detail_parts(line))


def detail_html(line: CheckLine) -> str:
    """detail_text as the panel shows it: small, wrapped within the panel, the worst in the
    verdict's colour, the source of the limits as the row's tooltip."""
    colour = hex_colour(RGB.get(line.verdict, (90, 90, 90)))
    text = " · ".join(f"<b style='color:{colour}'>{html.escape(t)}</b>" if worst else html.escape(t)
                      for t, worst in _detail_parts(line))
    grey = "#555" if line.judged else "#8a8a8a"  # a rule that cannot judge: as faint as its greyed button
    tip = f" title='{html.escape('source: ' + line.source, quote=True)}'" if line.judged and line.source else ""
    return (f"<div class='{DETAIL_CLASS}' data-rule='{html.escape(line.rule, quote=True)}'{tip} "
            f"style='font-size:0.8em;line-height:1.3;margin:-0.35em 0.75em 0.5em;color:{grey};"
            f"overflow-wrap:anywhere'>{text}</div>")


class ChecksPanel:
    """The Checks tab: a header and, per rule, a button and a text row under it (`buttons`,
    `details`: rule -> handle)."""

    def __init__(self, gui, tab, inbox):
        self.gui, self.tab, self.inbox = gui, tab, inbox
        self.summary: CheckSummary | str | None = None
        self.serial = -1  # the request whose result `summary` checked
        self.buttons: dict[str, Any] = {}
        self.details: dict[str, Any] = {}
        with tab:
            self.header = gui.add_html(header_html(None))

    def line(self, rule: str) -> CheckLine | None:
        return self.summary.line(rule) if isinstance(self.summary, CheckSummary) else None

    def checking(self, label: str) -> None:
        """A new result is shown: its checks are on their way."""
        self.header.content = header_html(self.summary, label, checking=self.summary is not None)

    def show(self, serial: int, summary) -> None:
        """The checks of request `serial`'s result (the loop's; `summary` and `serial` are set
        last: another thread that sees them sees the buttons too)."""
        self.header.content = header_html(summary)
        lines = summary.lines if isinstance(summary, CheckSummary) else ()
        for handle in [*self.buttons.values(), *self.details.values()]:
            handle.remove()
        buttons, details = {}, {}
        with self.tab:
            for line in lines:
                # a judged rule keeps its colour even where it locates nothing (a click then does
                # nothing); a rule that cannot judge is greyed out
                button = self.gui.add_button(button_text(line), color=line.colour, disabled=not line.judged)
                button.on_click(_recorder(self.inbox, line.rule))
                buttons[line.rule] = button
                details[line.rule] = self.gui.add_html(detail_html(line))
        self.buttons, self.details = buttons, details
        self.serial, self.summary = serial, summary


def _recorder(inbox, rule: str) -> Callable:
    # async: viser runs it on its event loop as the click arrives (explorer.view.browser.requests)
    async def clicked(event) -> None:
        inbox.put(CheckChosen(rule))

    return clicked
