"""Progress on stderr for the commands' long work, one helper for all of them.

`Progress` draws one line that rewrites itself from the first second on: with a known total,
items done, rate and time left (sweep, check, residual, record --sweep); without one (a single long
computation: export of a million points, simulate at hundreds of thousands of steps), the seconds
elapsed, ticked by `ticking`. Work that ends within a second prints nothing.

It draws only on a terminal: a log file or a pipe gets no carriage-return noise. EXPLORER_PROGRESS=1
draws it anyway (to follow a job's log), EXPLORER_PROGRESS=0 never.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from typing import Iterator, TextIO

ENV = "EXPLORER_PROGRESS"
FIRST_SECONDS = 1.0  # work shorter than this shows nothing
EVERY_SECONDS = 0.2  # at most five redraws a second


def wanted(stream: TextIO) -> bool:
    """Draw on `stream`? A terminal yes, anything else no; EXPLORER_PROGRESS=1/0 decides instead."""
    forced = os.environ.get(ENV, "").strip()
    if forced in ("0", "1"):
        return forced == "1"
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # a closed or odd stream
        return False


class Progress:
    """A line on stderr, from the first second on: items done, rate, time left (or, with no
    total, the seconds elapsed). Call it with (done, total, seconds); `end()` closes the line."""

    def __init__(self, stream: TextIO, unit: str = "runs", label: str = ""):
        self.stream = stream
        self.unit = unit
        self.label = label
        self.active = wanted(stream)
        self.shown = False
        self.last = 0.0
        self._lock = threading.Lock()  # `ticking` draws from a thread

    def __call__(self, done: int, total: int | None, seconds: float) -> None:
        if not self.active or seconds < FIRST_SECONDS:
            return
        with self._lock:
            final = total is not None and done >= total
            if seconds - self.last < EVERY_SECONDS and not final:
                return
            self.last = seconds
            self.stream.write("\r" + self._line(done, total, seconds))
            self.stream.flush()
            self.shown = True

    def _line(self, done: int, total: int | None, seconds: float) -> str:
        head = f"{self.label}: " if self.label else ""
        if total is None:
            return f"{head}working, {seconds:5.0f} s"
        rate = done / seconds if seconds > 0 else 0.0
        left = (total - done) / rate if rate > 0 else float("inf")
        width = 30
        filled = int(width * done / max(total, 1))
        eta = f"{left:5.0f} s left" if left < 1e7 else "   ? s left"
        return f"{head}[{'#' * filled}{'.' * (width - filled)}] {done}/{total} {self.unit}  {rate:8.1f} {self.unit}/s  {eta}"

    def end(self) -> None:
        with self._lock:
            if self.shown:
                self.stream.write("\n")
                self.stream.flush()
                self.shown = False


@contextlib.contextmanager
def ticking(stream: TextIO, label: str) -> Iterator[None]:
    """The seconds elapsed on `stream` while the block runs (for one long computation that has no
    count of its own to report); nothing if it ends within a second or stream is no terminal."""
    progress = Progress(stream, label=label)
    if not progress.active:
        yield
        return
    stop = threading.Event()
    started = time.perf_counter()

    def tick() -> None:
        while not stop.wait(EVERY_SECONDS):
            progress(0, None, time.perf_counter() - started)

    thread = threading.Thread(target=tick, name="explorer-progress", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        progress.end()
