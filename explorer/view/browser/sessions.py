"""One explorer per page (`explorer serve`, the default): a teaching room shares one server, and
one person's edit must not change another's view.

Every page that connects gets its own ExplorerApp on its own GUI and scene (viser's per-client
handles), with its own requests, playback and compute worker (a child process of its own); when
the page goes (closed, reloaded, network lost) its app is stopped and dropped: its loop thread
ends, its worker's child process is ended, and nothing of it stays referenced here.

Bounds (issue #22): at most MAX_SESSIONS pages, refused at the websocket handshake (503, by the
Origin guard's count of open connections: simultaneous handshakes cannot all slip past it, and
viser builds nothing for a refused page); the callbacks run on a pool whose idle threads end
(explorer.view.browser.callbacks), so the threads a crowd of pages made busy are freed after it
leaves.
"""

from __future__ import annotations

import threading
from typing import Any, Callable

from . import callbacks, origin
from .app import ExplorerApp

# Each page costs a compute child process (about 100 MB) and a loop thread; past this many pages
# a new one is told the server is full instead of starving the others.
MAX_SESSIONS = 32


class PerClientExplorer:
    """Makes an ExplorerApp for each page that connects to `server`, stops it when the page
    disconnects. `app_options` go to every ExplorerApp (playing, fps, on_result, scenes,
    time_limit)."""

    def __init__(self, server, scene_path: str, overrides=(), *, max_sessions: int = MAX_SESSIONS,
                 on_session: Callable[[int, ExplorerApp | None], None] | None = None, **app_options: Any):
        self.server = server
        self.scene_path = scene_path
        self.overrides = tuple(overrides)
        self.max_sessions = max_sessions
        self.app_options = app_options
        self._on_session = on_session  # for tests: (client id, app or None when it ended)
        self._lock = threading.Condition()
        self._sessions: dict[int, ExplorerApp] = {}
        self._starting: set[int] = set()
        self._gone: set[int] = set()  # pages that left while their app was being built
        self._stopped = False
        self.refused = 0  # pages turned away because MAX_SESSIONS were open
        callbacks.use_for(server)
        origin.limit(server.get_port(), max_sessions)  # refused at the handshake beyond this
        server.on_client_connect(self._connected)
        server.on_client_disconnect(self._disconnected)

    def sessions(self) -> dict[int, ExplorerApp]:
        with self._lock:
            return dict(self._sessions)

    def _connected(self, client) -> None:
        cid = client.client_id
        with self._lock:
            if self._stopped:
                return
            if len(self._sessions) + len(self._starting) >= self.max_sessions:
                self.refused += 1
                full = True
            else:
                full = False
                self._starting.add(cid)
        if full:
            client.gui.add_markdown(f"**The explorer is full:** {self.max_sessions} pages are open on this "
                                    "server. Close one, then reload this page.")
            return
        app = None
        try:
            app = ExplorerApp(self.server, self.scene_path, self.overrides, client=client, **self.app_options)
        finally:
            with self._lock:
                self._starting.discard(cid)
                self._lock.notify_all()
                keep = app is not None and not self._stopped and cid not in self._gone
                self._gone.discard(cid)
                if keep:
                    self._sessions[cid] = app
        if app is not None and not keep:
            app.stop()  # the page left (or the server stopped) while its app was being built
            return
        if keep and self._on_session is not None:
            self._on_session(cid, app)

    def _disconnected(self, client) -> None:
        cid = client.client_id
        with self._lock:
            app = self._sessions.pop(cid, None)
            if app is None and cid in self._starting:
                self._gone.add(cid)
        if app is not None:
            app.stop()
            if self._on_session is not None:
                self._on_session(cid, None)

    def stop(self, timeout: float = 30.0) -> None:
        with self._lock:
            self._stopped = True
            # an app being built is stopped by its builder: wait for that, so that no compute
            # child outlives the server
            self._lock.wait_for(lambda: not self._starting, timeout)
            apps = list(self._sessions.values())
            self._sessions.clear()
        for app in apps:
            app.stop()
        origin.forget(self.server.get_port())
