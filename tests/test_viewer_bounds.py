"""The browser explorer's server against crowds and malformed requests (issue #22, item 15):
threads a crowd of pages made busy are freed after it leaves; every refused handshake gets a
status (403 for two Origins or unreadable headers, 503 beyond the page limit, counted at the
handshake); a frame viser cannot decode is one line in the log, no traceback. Server side, in this
process, with raw sockets and websockets' client for pages."""

from __future__ import annotations

import concurrent.futures
import socket
import threading
import time

import pytest

from conftest import SCENES, process_timeout

DEMO = SCENES / "cycloidal_demo.toml"
WAIT_S = process_timeout()
CLIENT_THREADS = ("recv_events", "keepalive", "page-")  # websockets' sync client's, and ours: not the server's


def _handshake(port: int, *headers: str) -> int:
    """Status code of a raw websocket upgrade request (0: closed without an answer)."""
    lines = ["GET / HTTP/1.1", f"Host: 127.0.0.1:{port}", "Upgrade: websocket", "Connection: Upgrade",
             "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==", "Sec-WebSocket-Version: 13", *headers]
    with socket.create_connection(("127.0.0.1", port), timeout=WAIT_S) as sock:
        sock.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        status_line = sock.makefile("rb").readline().decode()
    return int(status_line.split()[1]) if status_line else 0


def _server_threads() -> list[str]:
    return sorted(t.name for t in threading.enumerate() if not any(c in t.name for c in CLIENT_THREADS))


def _wait_for(condition, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


class _Page:
    """A page as far as the server can tell: viser's protocol, its camera sent, messages read."""

    def __init__(self, port: int, number: int):
        import msgspec
        import viser
        from websockets.sync.client import connect

        self.ws = connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"],
                          open_timeout=WAIT_S, max_size=None)
        self.ws.send(msgspec.msgpack.encode({
            "type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [0.0, -1.0, 0.0],
            "fov": 1.2, "near": 0.01, "far": 1000.0, "image_height": 720, "image_width": 1280,
            "look_at": [0.0, 0.0, 0.0], "up_direction": [0.0, 0.0, 1.0]}))
        self.reader = threading.Thread(target=self._drain, name=f"page-{number}", daemon=True)
        self.reader.start()

    def _drain(self) -> None:
        try:
            while True:
                self.ws.recv()
        except Exception:  # noqa: BLE001 - the page closed
            pass

    def close(self) -> None:
        self.ws.close()
        self.reader.join(WAIT_S)


@pytest.fixture
def serving():
    import viser

    from explorer.view.browser.sessions import PerClientExplorer

    made = []

    def start(**kwargs):
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
        explorer = PerClientExplorer(server, str(DEMO), playing=False, **kwargs)
        made.append((server, explorer))
        return server, explorer

    yield start
    for server, explorer in made:
        explorer.stop()
        server.stop()


def test_the_threads_a_crowd_of_pages_made_busy_are_freed_when_it_leaves(serving):
    server, explorer = serving()
    port = server.get_port()
    time.sleep(0.5)
    before = _server_threads()
    pages = []
    try:
        with concurrent.futures.ThreadPoolExecutor(6, thread_name_prefix="page-open") as pool:  # at once
            pages = list(pool.map(lambda i: _Page(port, i), range(6)))
        assert _wait_for(lambda: len(explorer.sessions()) == 6, WAIT_S)
        for app in explorer.sessions().values():
            assert app.wait_applied(WAIT_S)
        assert len(_server_threads()) > len(before)  # the pages' loops and compute readers, callbacks
    finally:
        for page in pages:
            page.close()
    assert _wait_for(lambda: not explorer.sessions(), WAIT_S)
    # every thread of the sessions ends with them; the callback pool's idle threads shortly after
    assert _wait_for(lambda: _server_threads() == before, WAIT_S), (before, _server_threads())


def test_handshakes_beyond_the_page_limit_are_refused_at_the_handshake(serving):
    """Six simultaneous upgrades against a limit of three: three are answered 101, the others
    503 -- at the handshake, not by a page the server builds and then tells it is full."""
    server, explorer = serving(max_sessions=3)
    port = server.get_port()
    barrier = threading.Barrier(6)

    def knock(_):
        barrier.wait(WAIT_S)
        lines = ["GET / HTTP/1.1", f"Host: 127.0.0.1:{port}", "Upgrade: websocket", "Connection: Upgrade",
                 "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==", "Sec-WebSocket-Version: 13"]
        sock = socket.create_connection(("127.0.0.1", port), timeout=WAIT_S)
        sock.sendall(("\r\n".join(lines) + "\r\n\r\n").encode())
        return sock, int(sock.makefile("rb").readline().decode().split()[1])

    with concurrent.futures.ThreadPoolExecutor(6, thread_name_prefix="page-knock") as pool:
        answers = list(pool.map(knock, range(6)))
    try:
        codes = sorted(code for _, code in answers)
        assert codes == [101, 101, 101, 503, 503, 503], codes
        assert explorer.refused == 0  # nobody was let in only to be told the server is full
    finally:
        for sock, _ in answers:
            sock.close()
    # closed pages free their places
    from explorer.view.browser import origin

    assert _wait_for(lambda: origin.open_connections(port) == 0, WAIT_S)
    assert _wait_for(lambda: not explorer.sessions(), WAIT_S)
    assert _handshake(port) == 101


def test_malformed_handshakes_are_answered_403_not_500_or_silence(serving):
    server, _ = serving()
    port = server.get_port()
    own = f"http://127.0.0.1:{port}"
    assert _handshake(port, f"Origin: {own}", "Origin: http://evil.example") == 403
    assert _handshake(port, f"Origin: {own}", f"Origin: {own}") == 403
    assert _handshake(port, "Origin: http://" + "a" * 60_000) == 403
    assert _handshake(port, *[f"X-Filler-{i}: x" for i in range(200)]) == 403
    assert _handshake(port, f"Origin: {own}") == 101  # still serving


def test_a_frame_viser_cannot_decode_is_one_line_in_the_log(serving, capfd):
    import viser
    from websockets.sync.client import connect

    server, _ = serving(max_sessions=4)
    port = server.get_port()
    capfd.readouterr()
    for payload in (b"\x00" * 20, b"garbage", "a text frame", b"\xff" * 64):
        with connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], open_timeout=WAIT_S) as ws:
            ws.send(payload)
            with pytest.raises(Exception):  # the server ends the connection
                while True:
                    ws.recv(timeout=WAIT_S)
    from explorer.view.browser import origin

    assert _wait_for(lambda: origin.open_connections(port) == 0, WAIT_S)
    err = ""
    deadline = time.monotonic() + WAIT_S
    while err.count("websocket: ") < 4 and time.monotonic() < deadline:  # the log comes after the close
        time.sleep(0.05)
        err += capfd.readouterr().err
    assert "Traceback" not in err, err[:2000]
    logged = [line for line in err.splitlines() if line.startswith("websocket: ")]
    assert len(logged) == 4, err[:2000]  # one line per bad frame
    assert all(len(line) < 400 for line in logged)


def test_idle_callback_threads_end_and_a_busy_pool_keeps_its_bound():
    from explorer.view.browser.callbacks import IdleEndingExecutor

    pool = IdleEndingExecutor(max_workers=4, idle_s=0.2)
    gate = threading.Event()
    futures = [pool.submit(gate.wait, WAIT_S) for _ in range(10)]
    assert _wait_for(lambda: pool.threads() == 4, WAIT_S)  # never more than max_workers
    gate.set()
    assert all(f.result(WAIT_S) for f in futures)
    assert pool.submit(lambda x: x * 2, 21).result(WAIT_S) == 42
    failing = pool.submit(lambda: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        failing.result(WAIT_S)
    assert _wait_for(lambda: pool.threads() == 0, WAIT_S)  # all idle: all ended
    assert pool.submit(lambda: "again").result(WAIT_S) == "again"  # and started again on demand
    pool.shutdown(wait=True)
    assert pool.threads() == 0
    with pytest.raises(RuntimeError):
        pool.submit(print)
