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

The same guard answers every handshake it refuses, before the connection closes (issue #22):
- more than one Origin header: 403 (a browser sends one; two are a forgery, not a server error);
- a request whose headers websockets cannot read within its limits (a line over 8 KiB, such as a
  60 KB Origin; more than 128 headers): 403, where websockets would drop the connection silently;
- a websocket upgrade beyond the server's page limit (`limit(port, n)`, set by the per-page
  sessions): 503 at the handshake, before viser builds anything for the page. The count is of
  the upgrades admitted and still open, so simultaneous handshakes cannot all slip past it.
And websockets' log of a failed handshake or a connection that ends in an exception (a bad frame
that viser cannot decode) is one line with the exception's type and first line, no traceback.
"""

from __future__ import annotations

import asyncio
import http
import ipaddress
import logging
import threading
import weakref
from urllib.parse import urlsplit

LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "::1"})
DEFAULT_PORTS = {"http": 80, "https": 443}

_lock = threading.Lock()
_installed = False
_serves: "weakref.WeakSet" = weakref.WeakSet()  # the serve() objects created while installed
_extra: dict[int, set[str]] = {}  # port -> further host names allowed in Origin
_limits: dict[int, int] = {}  # port -> most websocket connections at once (the page limit)
_open: dict[int, int] = {}  # port -> websocket upgrades admitted and not yet closed
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


def _is_upgrade(request) -> bool:
    return any("websocket" in v.lower() for v in request.headers.get_all("Upgrade"))


def _guard(inner):
    def process_request(connection, request):
        global refused
        origins = request.headers.get_all("Origin")
        local = connection.local_address
        port = int(local[1])
        with _lock:
            extra = tuple(_extra.get(port, ()))
        # every request with an Origin is checked, not only those viser treats as websocket
        # upgrades: viser tests the Upgrade header case-sensitively and websockets does not
        if len(origins) > 1 or not origin_allowed(origins[0] if origins else None, local, extra):
            with _lock:
                refused += 1
            why = "More than one Origin: refused." if len(origins) > 1 else "Cross-origin request refused."
            return connection.respond(http.HTTPStatus.FORBIDDEN, why + "\n")
        if _is_upgrade(request):
            with _lock:
                limit = _limits.get(port)
                full = limit is not None and _open.get(port, 0) >= limit
                if full:
                    refused += 1
                else:
                    _open[port] = _open.get(port, 0) + 1
            if full:
                return connection.respond(http.HTTPStatus.SERVICE_UNAVAILABLE,
                                          f"The explorer is full: {limit} pages are open on this server. Close one, "
                                          "then reload this page.\n")
            asyncio.get_running_loop().create_task(_release_when_closed(connection, port))
        return None if inner is None else inner(connection, request)

    return process_request


async def _release_when_closed(connection, port: int) -> None:
    try:
        await connection.wait_closed()
    finally:
        with _lock:
            if _open.get(port, 0) > 0:
                _open[port] -= 1


def limit(port: int, pages: int | None) -> None:
    """At most `pages` websocket connections at once on the server at `port` (None: no limit);
    more handshakes are answered 503."""
    with _lock:
        if pages is None:
            _limits.pop(int(port), None)
        else:
            _limits[int(port)] = int(pages)


def open_connections(port: int) -> int:
    """Websocket upgrades admitted on `port` and not yet closed."""
    with _lock:
        return _open.get(int(port), 0)


class _OneLineHandler(logging.Handler):
    """websockets' log on stderr, each record one line: an exception as its type and first line,
    no traceback (a page that sends a frame viser cannot decode is the page's problem, not a
    crash of the server). Written to the sys.stderr of the moment (tests capture it)."""

    def emit(self, record: logging.LogRecord) -> None:
        import sys

        try:
            text = record.getMessage()
            exc = record.exc_info[1] if record.exc_info else None
            if exc is not None:
                first = (str(exc).splitlines() or [""])[0][:200]
                text = f"{text}: {type(exc).__name__}" + (f": {first}" if first else "")
            sys.stderr.write(f"websocket: {' '.join(text.split())}\n")
        except Exception:  # noqa: BLE001 - logging must never fail the server
            self.handleError(record)


def _one_line_logger() -> logging.Logger:
    log = logging.getLogger("explorer.view.browser.websockets")
    if not any(isinstance(h, _OneLineHandler) for h in log.handlers):
        log.addHandler(_OneLineHandler())
        log.setLevel(logging.WARNING)
        log.propagate = False
    return log


def _guarded_connection_class():
    """websockets' ServerConnection whose protocol answers an unreadable request with 403 instead
    of closing the connection without a word."""
    from websockets.asyncio.server import ServerConnection
    from websockets.exceptions import InvalidMessage
    from websockets.http11 import Request
    from websockets.protocol import CONNECTING, Protocol
    from websockets.server import ServerProtocol

    class GuardedProtocol(ServerProtocol):
        def parse(self):
            if self.state is CONNECTING:
                try:
                    request = yield from Request.parse(self.reader.read_line)
                except Exception as exc:
                    self.handshake_exc = InvalidMessage("did not receive a valid HTTP request")
                    self.handshake_exc.__cause__ = exc
                    self.send_response(self.reject(http.HTTPStatus.FORBIDDEN,
                                                   "Request refused: its headers could not be read.\n"))
                    yield  # the parser is discard() from here on (send_response set it)
                    return
                self.events.append(request)
            yield from Protocol.parse(self)

    class GuardedConnection(ServerConnection):
        def __init__(self, protocol, *args, **kwargs):
            protocol.__class__ = GuardedProtocol  # same state; only parse() differs
            protocol.parser = protocol.parse()  # nothing received yet: restart with ours
            next(protocol.parser)
            super().__init__(protocol, *args, **kwargs)

    return GuardedConnection


def install() -> None:
    """Guard every websockets server started from now on in this process (idempotent)."""
    global _installed
    import websockets.asyncio.server as ws_server

    with _lock:
        if _installed:
            return
        original = ws_server.serve

        connection_class = _guarded_connection_class()

        class GuardedServe(original):
            def __init__(self, *args, process_request=None, **kwargs):
                kwargs.setdefault("create_connection", connection_class)
                kwargs.setdefault("logger", _one_line_logger())
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
        _limits.pop(int(port), None)
