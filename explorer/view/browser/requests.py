"""What the page and the compute thread ask of the explorer, recorded for the frame loop.

The pattern of viser's examples and of mjlab's viewer: callbacks (viser's event loop and thread
pool, the compute thread) only record a request here; one loop (explorer.view.browser.loop)
takes them all once a frame and applies them, in the order they came, under `server.atomic()`.
So every piece of state is the loop's alone, and nothing a callback does can interleave with a
frame half applied.

A page's value is recorded by an `async` callback, which viser runs on its event loop right after
storing the value the page sent: in arrival order, at arrival time, and with the value sent (a
thread-pool callback ran late on a busy machine and could read a value the loop had written
meanwhile: a click on a slider was lost, issue #28.7).

The loop writes a control (a field showing the result's value, a slider following the animation)
only when the page is not changing it (`Inbox.write`). It knows each control's last value and
viser's update time as it last heard them: from its own write, or from a page's request it has
taken. A control whose value or update time differs from that holds a page's value on its way to
the loop, and is left alone. (A comparison of viser's update time with the time a frame began
lost values twice under load: viser stores a page's value before its time, and records the
request after both, and a frame could run in either gap; two clock readings can also be equal.)
What the loop hears is ordered by when it was read (`Heard.seq`): a page's request made from a
state older than the loop's own write since (viser's thread stored the page's value between the
loop's check and its write, or the loop set a dropdown itself while the request waited) does not
replace what the loop knows; else the control would stay "in flight" for ever.
"""

from __future__ import annotations

import itertools
import math
import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable


@dataclass(frozen=True)
class Edited:
    """A field's new value. `page`: sent by a page as typed (applied once the typing pauses or
    Enter is pressed), else set from Python or a dropdown (applied at once)."""

    key: str
    value: Any
    page: bool = False
    at: float = 0.0  # time.monotonic() when it came


@dataclass(frozen=True)
class Submitted:
    """Enter pressed in a field: apply what was typed now."""


@dataclass(frozen=True)
class EffectsTicked:
    names: tuple[str, ...]


@dataclass(frozen=True)
class SceneChosen:
    label: str


@dataclass(frozen=True)
class ResetClicked:
    pass


@dataclass(frozen=True)
class Magnified:
    value: float


@dataclass(frozen=True)
class Played:
    on: bool


@dataclass(frozen=True)
class SpeedChosen:
    label: str


@dataclass(frozen=True)
class Scrubbed:
    """Show this cam angle, animation paused (a slider, an event chosen)."""

    angle: float


@dataclass(frozen=True)
class EventChosen:
    label: str


@dataclass(frozen=True)
class SweepSpeedChosen:
    rpm: float


@dataclass(frozen=True)
class Computed:
    prepared: Any  # model.Prepared


@dataclass(frozen=True)
class Failed:
    request: Any  # model.Request, or None for a value refused before any computation
    message: str
    serial: int


@dataclass(frozen=True)
class SweepArrived:
    serial: int
    sweep: Any  # speedsweep.SpeedSweep or NoSweep


@dataclass(frozen=True)
class AdviceArrived:
    serial: int
    readout: str


@dataclass(frozen=True)
class ClientConnected:
    client: Any


@dataclass(frozen=True)
class ClientLeft:
    client_id: int


@dataclass(frozen=True)
class CameraMoved:
    camera: Any  # viser's camera handle of a page


@dataclass(frozen=True)
class Heard:
    """A control's value and viser's update time as the frame loop knows them."""

    handle: Any
    value: Any
    stamp: float
    seq: int  # when it was read (Inbox.hear): of two, the loop knows the later


class Inbox:
    """The requests recorded and not yet applied, in arrival order (any thread may `put`), and
    what the frame loop has heard of each control (module docstring; the loop's thread alone
    calls `take`, `know`, `in_flight` and `write`)."""

    def __init__(self):
        self._cond = threading.Condition()
        self._items: deque = deque()
        self._recorded = 0
        self._applied = 0
        self._known: dict[int, Heard] = {}  # id(handle) ->
        self._reads = itertools.count()  # Heard.seq (next() is atomic: any thread may `hear`)
        self.arrived = threading.Event()  # set by `put`: the frame loop waits on it (loop.FrameLoop)

    def put(self, item, heard: Heard | None = None) -> None:
        """Record `item`; `heard`: the control's value and update time it was made from."""
        with self._cond:
            self._items.append((item, heard))
            self._recorded += 1
        self.arrived.set()

    def take(self) -> list:
        """Every request recorded so far, oldest first (the loop calls `done` once applied); the
        loop now knows the values they were made from."""
        with self._cond:
            out = list(self._items)
            self._items.clear()
        for _, heard in out:
            if heard is not None:
                self.know(heard)
        return [item for item, _ in out]

    def hear(self, handle) -> Heard:
        """The control's value and update time now (any thread). The number is drawn before
        they are read: a write read after it has the higher number."""
        seq = next(self._reads)
        return Heard(handle, handle.value, handle.update_timestamp, seq)

    def know(self, heard: Heard) -> None:
        """The loop has heard `heard`, unless it heard the control later (its own write read
        after the page's request was made)."""
        known = self._known.get(id(heard.handle))
        if known is None or heard.seq > known.seq:
            self._known[id(heard.handle)] = heard

    def in_flight(self, handle) -> bool:
        """Whether the page changed `handle` since the loop last heard from it or wrote it."""
        known = self._known[id(handle)]  # KeyError: a control never wired (`wire`)
        return handle.update_timestamp != known.stamp or not same_value(handle.value, known.value)

    def write(self, handle, value) -> bool:
        """The loop's write of a control, unless a page's value is on its way (then False: the
        request that carries it comes to a later frame)."""
        if self.in_flight(handle):
            return False
        if not same_value(handle.value, value):
            handle.value = value  # the loop's own write: `wire`'s callback makes it known
        return True

    def done(self, count: int) -> None:
        with self._cond:
            self._applied += count
            self._cond.notify_all()

    def settled(self) -> bool:
        """Whether every request recorded so far has been applied."""
        with self._cond:
            return self._applied == self._recorded


def wire(handle, inbox, make: Callable[[Any, bool, float], Any], echo: Callable[[], bool]) -> None:
    """Record a handle's changes as requests: a page's with an async callback (viser runs it on
    its event loop as the value arrives: order, time and value as sent), one made from Python
    with a plain one (run at once in the assigning thread), except the loop's own writes."""

    async def from_page(event) -> None:
        if event.client is not None:
            heard = inbox.hear(handle)
            inbox.put(make(heard.value, True, time.monotonic()), heard)

    def from_python(event) -> None:
        if event.client is None:
            heard = inbox.hear(handle)
            if echo():  # the loop's own write, in its thread, right after viser stored it
                inbox.know(heard)
            else:
                inbox.put(make(heard.value, False, time.monotonic()), heard)

    inbox.know(inbox.hear(handle))
    # the plain one first: viser calls a handle's callbacks in order, and scheduling the async
    # one on the event loop lets other threads run; the value set from Python is read before
    handle.on_update(from_python)
    handle.on_update(from_page)


def same_value(a, b) -> bool:
    """Equal control values (numbers by value, NaN equal to NaN)."""
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return float(a) == float(b) or (math.isnan(float(a)) and math.isnan(float(b)))
    return a == b
