"""Refuse cross-site connections to the explorer's viser server.

Browsers let any page open a websocket to 127.0.0.1 (the same-origin policy does not cover
websockets); the server's only defence is the `Origin` header the browser adds. viser (1.1) gives
no hook for it, so `install()` wraps `websockets.asyncio.server.serve`, which viser's server
thread looks up at start, and puts an Origin check in front of viser's own `process_request`.
Servers started before `install()` are not guarded; `guarded(port)` tells, and `ExplorerApp`
refuses a server that is not.

Allowed: no Origin header (non-browser clients such as websockets' own client; a browser always
sends one with a websocket handshake), or an http(s) Origin on the server's port whose host is
127.0.0.1, localhost, [::1], the address the connection arrived on (`--host` given as an address,
or the interface address when listening on all of them) or a host registered with `allow()`
(`--host` given as a name). Anything else gets 403 before viser sees the request.
"""

from __future__ import annotations

import http
import ipaddress
import threading
import weakref
from urllib.parse import urlsplit

LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "::1"})
DEFAULT_PORTS = {"http": 80, "https": 443}

_lock = threading.Lock()
_installed = False
_serves: "weakref.WeakSet" = weakref.WeakSet()  # the serve() objects created while installed
_extra: dict[int, set[str]] = {}  # port -> further host names allowed in Origin
refused = 0  # handshakes refused so far (for tests and a curious reader)


def _address(text: str):
    try:
        address = ipaddress.ip_address(text.split("%", 1)[0])
    except ValueError:
        return None
    mapped = getattr(address, "ipv4_mapped", None)  # dual-stack sockets report ::ffff:a.b.c.d
    return mapped or address


def origin_allowed(origin: str | None, local_address, extra_hosts=()) -> bool:
    """Whether a handshake carrying `origin` may reach the server listening at `local_address`
    ((host, port, ...) of the accepted socket)."""
    if origin is None:
        return True
    try:
        parts = urlsplit(origin.strip())
        host, port = parts.hostname, parts.port
    except ValueError:  # a malformed port
        return False
    if parts.scheme not in DEFAULT_PORTS or not host or parts.path not in ("", "/"):
        return False
    if port is None:
        port = DEFAULT_PORTS[parts.scheme]
    local_host, local_port = str(local_address[0]), int(local_address[1])
    if port != local_port:
        return False
    if host in LOOPBACK_NAMES or host in {h.lower() for h in extra_hosts}:
        return True
    address = _address(host)
    return address is not None and address == _address(local_host)


def _guard(inner):
    def process_request(connection, request):
        global refused
        origin = request.headers.get("Origin")
        local = connection.local_address
        with _lock:
            extra = tuple(_extra.get(int(local[1]), ()))
        # every request with an Origin is checked, not only those viser treats as websocket
        # upgrades: viser tests the Upgrade header case-sensitively and websockets does not
        if not origin_allowed(origin, local, extra):
            with _lock:
                refused += 1
            return connection.respond(http.HTTPStatus.FORBIDDEN, "Cross-origin request refused.\n")
        return None if inner is None else inner(connection, request)

    return process_request


def install() -> None:
    """Guard every websockets server started from now on in this process (idempotent)."""
    global _installed
    import websockets.asyncio.server as ws_server

    with _lock:
        if _installed:
            return
        original = ws_server.serve

        class GuardedServe(original):
            def __init__(self, *args, process_request=None, **kwargs):
                super().__init__(*args, process_request=_guard(process_request), **kwargs)
                _serves.add(self)

        GuardedServe.__name__ = GuardedServe.__qualname__ = "serve"
        GuardedServe.__doc__ = original.__doc__
        ws_server.serve = GuardedServe
        _installed = True


def guarded(port: int) -> bool:
    """Whether the server listening on `port` was started with the Origin check."""
    with _lock:
        serves = list(_serves)
    for serve in serves:
        try:
            sockets = serve.server.sockets
        except AttributeError:
            continue
        if any(s.getsockname()[1] == port for s in sockets):
            return True
    return False


def allow(port: int, host: str) -> None:
    """Also accept Origins naming `host` for the server on `port` (a `--host` given by name)."""
    with _lock:
        _extra.setdefault(int(port), set()).add(host.lower().strip("[]"))


def forget(port: int) -> None:
    with _lock:
        _extra.pop(int(port), None)
