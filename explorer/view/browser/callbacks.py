"""The thread pool that runs viser's callbacks, with threads that end when idle.

viser runs every plain `def` callback (a page connecting, a slider moved) on a
ThreadPoolExecutor of up to 32 threads. Python's executor starts a thread for each callback that
finds none idle and keeps it for the life of the server: twenty pages that connect at once leave
fourteen idle threads behind after they close (issue #22: 11 threads grew to 25 and stayed). The
pool here starts threads on the same rule, at most `max_workers`, and a thread that has had no
work for `idle_s` seconds ends: what a session made busy is freed shortly after it goes.

`use_for(server)` puts it in the place of viser's own pool (the server's, its GUI's and its
scene's; pages that connect later take it from the server), before any page connects.
"""

from __future__ import annotations

import queue
import threading
from concurrent.futures import Executor, Future

MAX_WORKERS = 32  # viser's own bound
IDLE_S = 2.0  # a thread with no work for this long ends


class IdleEndingExecutor(Executor):
    """An Executor whose threads start on demand (at most max_workers) and end after idle_s
    seconds without work."""

    def __init__(self, max_workers: int = MAX_WORKERS, idle_s: float = IDLE_S, name: str = "explorer-callback"):
        self._max, self._idle_s, self._name = int(max_workers), float(idle_s), name
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._threads: set[threading.Thread] = set()
        self._idle = 0  # threads waiting for work
        # work put and not yet taken. A thread that has just taken an item still counts as idle
        # until it takes the lock, but then the item still counts as pending too: a submit starts
        # a thread when pending work outnumbers the waiting threads, which stays right in that
        # window (comparing the idle count with zero did not: under load a burst of submits saw
        # the first thread 'idle' after it had taken its item and started too few threads)
        self._pending = 0
        self._shutdown = False
        self._started = 0

    # -- Executor -----------------------------------------------------------------------------
    def submit(self, fn, /, *args, **kwargs) -> Future:
        future: Future = Future()
        with self._lock:
            if self._shutdown:
                raise RuntimeError("cannot schedule new futures after shutdown")
            self._queue.put((future, fn, args, kwargs))
            self._pending += 1
            if self._pending > self._idle and len(self._threads) < self._max:
                self._started += 1
                thread = threading.Thread(target=self._work, name=f"{self._name}-{self._started}", daemon=True)
                self._threads.add(thread)
                thread.start()
        return future

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        with self._lock:
            self._shutdown = True
            threads = list(self._threads)
        if cancel_futures:
            while True:
                try:
                    item = self._queue.get_nowait()
                except queue.Empty:
                    break
                if item is not None:
                    with self._lock:
                        self._pending -= 1
                    item[0].cancel()
        for _ in threads:
            self._queue.put(None)  # one wake-up each: a thread that takes it ends
        if wait:
            for thread in threads:
                if thread is not threading.current_thread():
                    thread.join()

    # -- workers ------------------------------------------------------------------------------
    def threads(self) -> int:
        with self._lock:
            return len(self._threads)

    def _work(self) -> None:
        me = threading.current_thread()
        while True:
            with self._lock:
                self._idle += 1
            try:
                item = self._queue.get(timeout=self._idle_s)
            except queue.Empty:
                item = False
            with self._lock:
                self._idle -= 1
                if item:
                    self._pending -= 1
                # idle for idle_s and nothing came in since (a submit under the lock sees us gone
                # and starts a thread): end
                if item is False and (self._shutdown or self._pending == 0):
                    self._threads.discard(me)
                    return
                if item is None:
                    self._threads.discard(me)
                    return
            if item is False:
                continue
            future, fn, args, kwargs = item
            del item
            result = None
            if not future.set_running_or_notify_cancel():
                continue
            try:
                result = fn(*args, **kwargs)
            except BaseException as exc:  # noqa: BLE001 - handed to the future, as Python's pool does
                future.set_exception(exc)
            else:
                future.set_result(result)
            del future, fn, args, kwargs, result  # nothing of a finished callback stays referenced


def use_for(server) -> IdleEndingExecutor:
    """Make `server` (a viser.ViserServer no page has connected to yet) run its callbacks on an
    IdleEndingExecutor; idempotent."""
    current = getattr(server, "_thread_executor", None)
    if isinstance(current, IdleEndingExecutor):
        return current
    pool = IdleEndingExecutor()
    for holder in (server, getattr(server, "gui", None), getattr(server, "scene", None)):
        if holder is not None and hasattr(holder, "_thread_executor"):
            holder._thread_executor = pool
    if current is not None:
        current.shutdown(wait=False)
    return pool
