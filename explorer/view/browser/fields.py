"""The Scene folder: the scene list, "Reset to scene file", the parameter fields and the effects;
what the user typed, when it applies, and what each field shows.

A field is in one of four states (the loop's alone, explorer.view.browser.loop):
- shown:   it holds the value of the result on screen, in its label's unit; after each result
           the loop writes that value into it (so field and result agree, issue #28.3);
- typed:   a page sent text not applied yet. It applies once it is a complete quantity of the
           field's dimension (parameters.field_value) and the typing has paused for
           TYPING_PAUSE_S, or at once when Enter is pressed (the fields sit in a viser form,
           which reports Enter). "7 " (a number waiting for its unit) waits without an error; a
           text that cannot be a value ("7 kg" for a length) is refused once the typing pauses;
- sent:    applied in request `serial`, whose result is not on screen yet;
- refused: its text was not used (refused, or its computation failed): the field keeps it while
           the status box says why and which value the result shown uses, until the user edits
           it, a newer result replaces that message, or the scene is loaded or reset.
The loop writes a field only in the first state, and only when no page's value of it is on its
way (requests.Inbox.write): a value sent from a page is never overwritten. A field a page typed
in shows the value used (with its unit, in its display form) only once the typing has paused for
FIELD_SETTLE_S, or at once after Enter: a pause long enough to apply a value ("3" of "3000") is
not long enough to rewrite the text under the cursor ("3 N/mm" and then "3 N/mm000").
"""

from __future__ import annotations

import math
from typing import Any, Callable

from ...effects import registry as effect_table
from ...lift import registry as law_table
from .parameters import MAX_GUI_STEPS, PARAMETERS, NotYet, field_value, override, user_overrides
from .requests import EffectsTicked, Edited, ResetClicked, SceneChosen, Submitted, wire

# A value typed into a field on the page applies once the typing pauses this long (newest wins),
# never per keystroke: viser sends every change of a text or number input. Enter applies at once.
TYPING_PAUSE_S = 0.6
# A field typed in keeps its text this long after the last key before the value used is written
# into it (module docstring): longer than a pause in the middle of typing a number.
FIELD_SETTLE_S = 2.0


class Fields:
    """The Scene folder's controls and the state of every field (see the module docstring)."""

    def __init__(self, gui, inbox, echo, scene_labels: list[str], scene_label: str):
        self.scene = gui.add_dropdown("Scene", scene_labels, initial_value=scene_label)
        # right under the scene: an 800 px page shows it even with an error above
        self.reset = gui.add_button("Reset to scene file", hint="every field back to the scene file's values")
        laws = list(law_table.names())  # every law of the tables; offered_laws narrows it per scene
        self.handles: dict[str, Any] = {}
        # a form: Enter in any of its fields reports itself (viser's GuiFormSubmitMessage)
        self.form = gui.add_form(None)
        with self.form:
            for key, p in PARAMETERS.items():
                if p.kind == "choice":
                    handle = gui.add_dropdown(p.title, laws, initial_value=laws[0])
                elif p.kind == "number":
                    handle = gui.add_number(p.title, 1.0, step=1.0, hint="press Enter to apply at once")
                elif p.kind == "integer":
                    handle = gui.add_number(p.title, 3600, min=1, max=MAX_GUI_STEPS, step=1,
                                            hint="press Enter to apply at once")
                else:
                    handle = gui.add_text(p.title, "", hint=f"a quantity, e.g. '1.5 {p.unit}' (a bare number is "
                                                             f"{p.unit}); Enter applies at once")
                wire(handle, inbox, lambda v, page, at, key=key: Edited(key, v, page, at), echo)
                self.handles[key] = handle
        self.effects: dict[str, Any] = {}
        with gui.add_folder("Effects"):
            for name in effect_table.names():
                handle = gui.add_checkbox(name, initial_value=name == "kinematics")
                wire(handle, inbox, lambda v, page, at: EffectsTicked(self._ticked()), echo)
                self.effects[name] = handle

        async def submitted(event) -> None:
            if event.client is not None:
                inbox.put(Submitted())

        self.form.on_submit(submitted)
        wire(self.scene, inbox, lambda v, page, at: SceneChosen(str(v)), echo)
        self.reset.on_click(lambda event: inbox.put(ResetClicked()))

        self.inbox = inbox  # the loop writes a field only when no page's value is on its way
        self.typed: dict[str, tuple[Any, float]] = {}  # key -> (text from a page, when): not applied yet
        self.parked: set[str] = set()  # typed keys whose text waits for its unit (nothing happens without the user)
        self.sent: dict[str, int] = {}  # key -> serial of the request that applied its value
        self.refused: dict[str, int] = {}  # key -> serial of the message saying why its text was not used
        self.keyed: dict[str, float] = {}  # key -> when a page last typed in it (until Enter or shown)
        self.unsettled: set[str] = set()  # keys whose value used is written once their typing settles
        self.settle_s = FIELD_SETTLE_S
        self.user: dict[str, str] = {}  # key -> override of the next request
        self.held_effects: tuple[str, ...] | None = None  # ticked effects waiting for a linkage stiffness
        self.note = ""  # a remark for the status box that is no error

    # the fields by their keys, as a mapping (the scene keys' handles)
    def __getitem__(self, key: str):
        return self.handles[key]

    def __iter__(self):
        return iter(self.handles)

    def __len__(self) -> int:
        return len(self.handles)

    def items(self):
        return self.handles.items()

    # ---------------------------------------------------------------- requests (loop thread)

    def _ticked(self) -> tuple[str, ...]:
        return tuple(name for name, handle in self.effects.items() if handle.value)

    def edited(self, request: Edited, submit, refuse, current) -> None:
        """A field changed: a page's text waits for a pause or Enter, anything else applies now."""
        p = PARAMETERS[request.key]
        if request.page and p.kind != "choice":
            self.typed[request.key] = (request.value, request.at)
            self.keyed[request.key] = request.at
            self.parked.discard(request.key)
            self.refused.pop(request.key, None)
            return
        self.typed.pop(request.key, None)
        self.parked.discard(request.key)
        self.apply(request.key, request.value, submit, refuse, current, forced=True)

    def submitted(self, submit, refuse, current) -> None:
        """Enter: every typed text applies now (or is refused, saying why), and its field shows
        the value used as soon as it comes."""
        self.keyed.clear()
        for key, (value, _) in list(self.typed.items()):
            self.apply(key, value, submit, refuse, current, forced=True)

    def apply_due(self, now: float, submit, refuse, current) -> None:
        """Apply the typed texts whose typing has paused; a text that waits for its unit waits."""
        for key, (value, at) in list(self.typed.items()):
            if now - at >= TYPING_PAUSE_S and key not in self.parked:
                self.apply(key, value, submit, refuse, current, forced=False)

    def waiting(self) -> bool:
        """Whether a typed text may still apply by itself, or a field still show its value used
        once the typing settles (any thread)."""
        return bool(set(self.typed) - set(self.parked)) or bool(self.unsettled)

    def apply(self, key: str, value, submit, refuse, current, forced: bool) -> None:
        p = PARAMETERS[key]
        try:
            value = field_value(p, value, tuple(self.handles[key].options) if p.kind == "choice" else (), final=forced)
        except NotYet as why:
            if why.typing and not forced:
                self.parked.add(key)  # "7 ": the unit is still to come; it stays typed, and nothing is said
                return
            self.typed.pop(key, None)
            self.parked.discard(key)
            self.refused[key] = refuse(f"error: {p.title} ({key}): {why} — {p.label} not applied; {in_use(current, key)}")
            return
        self.typed.pop(key, None)
        self.parked.discard(key)
        self.refused.pop(key, None)
        self.user[key] = override(key, value)
        edited = [key]
        if key == "linkage.stiffness" and self.held_effects is not None:
            # the stiffness the elastic effect waited for: apply both together
            self.user["effects"] = override("effects", self.held_effects)
            self.held_effects, self.note = None, ""
            edited.append("effects")
        serial = submit()
        for k in edited:
            self.sent[k] = serial

    def effects_ticked(self, names: tuple[str, ...], submit, current) -> None:
        if "elastic" in names and not self._has_stiffness(current):
            # no error for a missing [linkage]: the effect waits for a stiffness typed in
            self.held_effects = names
            p = PARAMETERS["linkage.stiffness"]
            self.note = (f"elastic needs a linkage stiffness: type one into '{p.title}' (e.g. 3000 {p.unit}); "
                         "until then the result shown is without it")
            return
        self.held_effects, self.note = None, ""
        self.user["effects"] = override("effects", list(names) or ["kinematics"])
        self.sent["effects"] = submit()

    def _has_stiffness(self, current) -> bool:
        """Whether the next computation has a linkage stiffness."""
        return "linkage.stiffness" in self.user or (current is not None and bool(current.values.get("linkage.stiffness")))

    def cleared(self) -> None:
        """A scene loaded or reset: every field shows the scene file's values again."""
        self.user.clear()
        self.typed.clear()
        self.parked.clear()
        self.sent.clear()
        self.refused.clear()
        self.keyed.clear()
        self.unsettled.clear()
        self.held_effects, self.note = None, ""

    def failed(self, request, current, message: str) -> str:
        """A computation failed: the values it changed are not used (later edits go on from the
        result shown), their fields keep their text; the message names them and the values in use."""
        mine = user_overrides(request.overrides)
        shown = user_overrides(current.request.overrides) if current is not None else {}
        edited = [k for k, text in mine.items() if shown.get(k) != text]
        for key in edited:
            if self.user.get(key) == mine[key]:
                if key in shown:
                    self.user[key] = shown[key]
                else:
                    self.user.pop(key, None)
            if self.sent.get(key) == request.serial:
                del self.sent[key]
                self.refused[key] = request.serial
        if edited and current is not None:
            names = [PARAMETERS[k].label if k in PARAMETERS else k for k in edited]
            used = "; ".join(in_use(current, k) for k in edited if k in PARAMETERS)
            message = f"{message} — {', '.join(names)} not applied" + (f"; {used}" if used else "")
        return message

    # ---------------------------------------------------------------- what the fields show

    def show(self, prepared, now: float) -> None:
        """After a result: each field in the `shown` state (module docstring) shows the value
        the result used, unless a page's value of it is on its way (requests.Inbox.write) or a
        page typed in it less than FIELD_SETTLE_S before `now` (time.monotonic; then `settle`
        writes it later)."""
        serial = prepared.request.serial
        for key in [k for k, s in self.sent.items() if s <= serial]:
            del self.sent[key]
        for key in [k for k, s in self.refused.items() if s < serial]:
            del self.refused[key]  # a newer result replaced the message: the field shows the value used
        if prepared.laws and tuple(self.handles["lift.law"].options) != prepared.laws:
            law = self.handles["lift.law"]  # only the laws this scene can take
            if law.value not in prepared.laws and prepared.scene.lift.law in prepared.laws:
                law.value = prepared.scene.lift.law
            law.options = prepared.laws
        for key in self.handles:
            if key in self.typed or key in self.sent or key in self.refused:
                continue
            if now - self.keyed.get(key, -math.inf) < self.settle_s:
                self.unsettled.add(key)
                continue
            self.keyed.pop(key, None)
            self._show_value(key, prepared)
        if "effects" not in self.sent and self.held_effects is None:
            for name, handle in self.effects.items():
                self.inbox.write(handle, name in prepared.scene.effects)

    def settle(self, now: float, current) -> None:
        """Each frame: the fields whose typing has settled since a result came show its value."""
        for key in list(self.unsettled):
            if key in self.typed or key in self.sent or key in self.refused or current is None:
                self.unsettled.discard(key)  # typing again, or another state's: a result writes it
            elif now - self.keyed.get(key, -math.inf) >= self.settle_s:
                self.unsettled.discard(key)
                self.keyed.pop(key, None)
                self._show_value(key, current)

    def _show_value(self, key: str, prepared) -> None:
        handle = self.handles[key]
        value = prepared.values.get(key)
        kind = PARAMETERS[key].kind
        if kind == "quantity":
            value = value or ""
        elif kind == "choice" and value not in handle.options:
            return
        elif value is None:
            return
        self.inbox.write(handle, value)


def in_use(current, key: str) -> str:
    """Which value the result shown uses for `key`, for a message."""
    if current is None:
        return "nothing computed yet"
    value = current.values.get(key)
    return f"the result shown uses {value if value not in (None, '') else 'none'}"

