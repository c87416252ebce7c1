"""The guard on every viser server Shoal starts (issue 20, cases 5 and 7):

- the private server that records a Share page or ``shoal export-replay``'s scene refuses every
  request while it lives (it used to hand the recorded scene to any page: ``Origin:
  http://evil.example`` got 101), however long the run it records;
- a request that names ``Host`` or ``Origin`` twice is refused with 403, on the app's server
  and on the private one (it used to be a 500).
"""

from __future__ import annotations

import socket
import threading

import psutil
import pytest
from websockets.exceptions import InvalidStatus

from shoal.app.share import page
from shoal.presets.io import load

from browser.browser_helpers import wait_until
from viser_wire import WireClient


def _listening() -> set[int]:
    return {c.laddr.port for c in psutil.Process().net_connections(kind="tcp") if c.status == psutil.CONN_LISTEN}


def _raw(port: int, headers: list[str]) -> str:
    """The status line of a raw HTTP request with ``headers`` (as written, duplicates kept)."""
    with socket.create_connection(("127.0.0.1", port), timeout=10) as s:
        s.sendall(("GET / HTTP/1.1\r\n" + "".join(h + "\r\n" for h in headers) + "\r\n").encode())
        return s.recv(4096).split(b"\r\n", 1)[0].decode()


UPGRADE = ["Upgrade: websocket", "Connection: Upgrade", "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
           "Sec-WebSocket-Version: 13"]


def test_the_private_recording_server_refuses_every_request():
    before = _listening()
    with page.recording_scene():
        (port,) = _listening() - before
        for origin in ("http://evil.example", f"http://127.0.0.1:{port}", None):
            with pytest.raises(InvalidStatus) as err:
                WireClient(port, origin=origin)
            assert err.value.response.status_code == 403
        with pytest.raises(InvalidStatus):
            WireClient(port, host="rebound.example")
        assert _raw(port, [f"Host: 127.0.0.1:{port}"]).endswith("403 Forbidden")


def test_the_private_server_of_a_long_export_refuses_every_request():
    """``shoal export-replay``'s run goes on inside the recording: a foreign page knocks meanwhile."""
    before, found, statuses = _listening(), [], []
    scenario = load("default", ["sim.steps=3000"])

    def knock() -> None:
        port = wait_until(lambda: next(iter(_listening() - before), None), timeout=60, what="the private server")
        found.append(port)
        statuses.append(_raw(port, [f"Host: 127.0.0.1:{port}", "Origin: http://evil.example", *UPGRADE]))

    t = threading.Thread(target=knock)
    t.start()
    page_html = __import__("shoal.app.share", fromlist=["preset_html"]).preset_html(scenario)
    t.join(timeout=60)
    assert found and statuses == ["HTTP/1.1 403 Forbidden"] and "shoal-run-data" in page_html


@pytest.mark.parametrize("headers", [
    ["Host: 127.0.0.1", "Host: evil.example"],
    ["Host: 127.0.0.1", "Origin: http://127.0.0.1", "Origin: http://evil.example", *UPGRADE],
    ["Host: 127.0.0.1", "Host: 127.0.0.1"],
])
def test_duplicate_host_or_origin_headers_get_403_not_500(server, headers):
    status = _raw(server.port, [h.replace("127.0.0.1", f"127.0.0.1:{server.port}") if h.startswith("Host") else h
                                for h in headers])
    assert status == "HTTP/1.1 403 Forbidden", status
