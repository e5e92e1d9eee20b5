"""What the page says about the result: the status box (an error, a note or "ready"), the "Stale"
lines while the last change failed, and the Read-outs tab (figures, warnings, every event in a
table with "Go to event")."""

from __future__ import annotations

import html

from .requests import EventChosen, wire

# The error box shows at most this many lines' height and scrolls beyond: a long message must not
# push the controls below it off an 800 px page.
ERROR_BOX_MAX_EM = 7.5
NO_EVENT = "—"


def status_html(message: str, note: str = "") -> str:
    if not message and note:
        return ('<div role="status" style="color:#7a4f01;background:#fff4e0;border:1px solid #f0d19a;'
                'border-radius:4px;padding:4px 6px;font-size:0.85em">' f"{html.escape(note)}</div>")
    if not message:
        return '<div style="color:#2e7d32;font-size:0.85em">ready</div>'
    # a long message scrolls inside its box: the controls below stay where they are
    return (
        '<div role="alert" class="explorer-error" style="color:#b71c1c;background:#fdecea;'
        'border:1px solid #f5c6cb;border-radius:4px;padding:4px 6px;font-size:0.85em;white-space:pre-wrap;'
        f'max-height:{ERROR_BOX_MAX_EM}em;overflow-y:auto;overflow-wrap:anywhere">'
        f"{html.escape(message)}</div>"
    )


def stale_text(label: str) -> str:
    return f"⚠ **Stale:** the last change failed (see the red box); shown is the previous result, `{label}`"


class Readouts:
    """The status box (in the right-hand panel) and the Read-outs tab."""

    def __init__(self, status, gui, tab, inbox, echo):
        self.status = status  # the status box, near the top of the right-hand panel
        with tab:
            self.stale = gui.add_markdown("", visible=False)
            self.readout = gui.add_markdown("computing…")
            self.event_jump = gui.add_dropdown("Go to event", (NO_EVENT,), initial_value=NO_EVENT,
                                               hint="shows the gear at the event's cam angle (pauses the animation)")
            self.events_table = gui.add_html("")
        wire(self.event_jump, inbox, lambda v, page, at: EventChosen(str(v)), echo)

    def say(self, error: str, note: str) -> None:
        content = status_html(error, note)
        if self.status.content != content:
            self.status.content = content

    def mark_stale(self, handles, label: str | None) -> None:
        """The "Stale" lines (`handles`: this tab's and the Plots tab's) while the last change failed."""
        text = stale_text(label) if label is not None else ""
        for handle in handles:
            if handle.content != text:
                handle.content = text
                handle.visible = label is not None

    def show(self, prepared) -> None:
        """The read-outs and events of a new result."""
        self.readout.content = prepared.readout
        self.events_table.content = prepared.events_html
        labels = tuple(label for label, _ in prepared.events)
        self.event_jump.options = (NO_EVENT, *labels)
        self.event_jump.value = NO_EVENT
        self.event_jump.disabled = not labels
