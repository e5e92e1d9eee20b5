"""The frame loop: one thread calling `tick(dt)` `fps` times a second, which applies the requests
recorded since the last frame and advances the animation (explorer.view.browser.app)."""

from __future__ import annotations

import threading
import time
import traceback
from typing import Callable


class FrameLoop:
    """A daemon thread calling `tick(dt)` at `fps`; an exception in a frame is printed and
    counted (`errors`), and the loop goes on serving."""

    def __init__(self, tick: Callable[[float], None], fps: float = 60.0, wake: threading.Event | None = None):
        self.tick, self.fps = tick, fps
        self.errors = 0
        self._stop = threading.Event()
        # set: a frame now, not at the next period (a request came: a result is shown, a change
        # goes to the compute thread, at once)
        self._wake = wake if wake is not None else threading.Event()
        self._thread = threading.Thread(target=self._run, name="explorer-loop", daemon=True)

    def start(self) -> "FrameLoop":
        self._thread.start()
        return self

    def alive(self) -> bool:
        return self._thread.is_alive()

    def wake(self) -> None:
        """Apply the next frame now (any thread): a result waits for no frame period."""
        self._wake.set()

    def stop(self, timeout: float = 30.0) -> None:
        """End the loop (a test then calls `tick` itself)."""
        self._stop.set()
        self._wake.set()
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(timeout=timeout)

    def _run(self) -> None:
        period = 1.0 / self.fps
        last = time.perf_counter()
        while not self._stop.is_set():
            now = time.perf_counter()
            self._wake.clear()  # before the frame: a request that comes during it wakes the next one
            try:
                self.tick(min(now - last, 0.1))
            except Exception:  # keep serving; the traceback helps whoever reads the console
                self.errors += 1
                traceback.print_exc()
            last = now
            self._wake.wait(max(0.0, period - (time.perf_counter() - now)))
