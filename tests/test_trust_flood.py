"""One client's flood and malformed messages (issue 20, case 7), over viser's raw websocket.

- A flood of refused values is read at the connection's budget (``message_guard.RATE`` a
  second after a burst), so it waits in the flooder's own socket while another tab's scene
  keeps updating; how much the other tab's update rate keeps is measured in
  ``benchmarks/bench_hostile.py``, not asserted here.
- A malformed message (not msgpack, a text frame, an unknown type, a field of the wrong type)
  is dropped with one line on stderr; the connection stays open (no 1011, no traceback) until
  ``MAX_MALFORMED`` of them close it with 1008.
"""

from __future__ import annotations

import time

import msgspec
import pytest
from viser import _messages

from shoal.app import message_guard
from shoal.app.server import start_server
from shoal.presets import io as presets_io

from browser.browser_helpers import wait_until
from viser_wire import WireClient


@pytest.fixture(scope="module")
def served():
    srv = start_server("default", port=0)
    yield srv
    srv.stop()


def _tab(srv) -> WireClient:
    before = set(srv.tabs)
    c = WireClient(srv.port, decode=True)
    wait_until(lambda: set(srv.tabs) - before and c.uuid_of("robots"), what="a tab")
    c.report_camera()  # (the page has drawn: the tab plays)
    (key,) = set(srv.tabs) - before
    wait_until(lambda: srv.tabs[key].session.playing, what="the tab playing")
    return c


def test_a_flood_is_read_at_the_connections_budget_and_the_other_tab_goes_on(served):
    other, flood = _tab(served), _tab(served)
    try:
        uuid = flood.uuid_of("robots")
        refusals = lambda: sum(1 for t, _, _ in flood.notifications() if t.startswith("Refused"))  # noqa: E731
        start = time.monotonic()
        for _ in range(5_000):  # values no control can hold: each one refused
            flood.send(_messages.GuiUpdateMessage(uuid, {"value": "lots"}))
        sent = time.monotonic() - start
        before = other.counts()[2]
        time.sleep(2.0)
        elapsed = time.monotonic() - start
        handled = refusals()
        allowed = message_guard.BURST + message_guard.RATE * elapsed + 50
        assert 0 < handled <= allowed, (handled, allowed, sent)
        assert other.counts()[2] > before  # the other tab's robots kept moving
        assert not flood.closed.is_set()  # paced, not cut off
    finally:
        flood.close()
        other.close()


BAD = [
    b"\x00\x01\x02 not msgpack",
    msgspec.msgpack.encode([1, 2, 3]),
    msgspec.msgpack.encode({"type": "NoSuchMessage", "x": 1}),
    msgspec.msgpack.encode({"type": "ViewerCameraMessage", "wxyz": "abc", "position": 1}),
    msgspec.msgpack.encode({"type": "GuiUpdateMessage", "uuid": 123, "updates": []}),
    msgspec.msgpack.encode({"type": "FileTransferPart", "source_component_uuid": None, "transfer_uuid": 5,
                            "part_index": "x", "content": "not bytes"}),
]


@pytest.mark.parametrize("payload", [*BAD, "a text frame"], ids=[*(f"bad{i}" for i in range(len(BAD))), "text"])
def test_a_malformed_message_is_dropped_with_one_line_and_the_tab_stays(served, capfd, payload):
    c = _tab(served)
    try:
        frames = c.counts()[0]
        c.ws.send(payload)
        wait_until(lambda: c.counts()[0] > frames + 3, what="updates after the malformed message")
        assert not c.closed.is_set()
        c.set_value("robots", 9)  # the tab still works
        wait_until(lambda: any(s.sim.robots == 9 for s in served.sessions.values()), what="9 robots")
    finally:
        c.close()
    err = capfd.readouterr().err
    assert "dropped a malformed message" in err and "Traceback" not in err and "1011" not in err, err[-2000:]
    assert err.count("dropped a malformed message") == 1


def test_many_malformed_messages_close_the_connection_with_1008(served, capfd):
    c = _tab(served)
    for _ in range(message_guard.MAX_MALFORMED + 5):
        try:
            c.ws.send(b"\xc1")  # (never used in msgpack)
        except Exception:
            break
    wait_until(lambda: c.closed.is_set(), what="the connection closed")
    assert c.ws.close_code == message_guard.POLICY_VIOLATION
    err = capfd.readouterr().err
    assert "closed the connection" in err and "Traceback" not in err
    assert err.count("dropped a malformed message") <= 3  # said once, then counted


def test_a_preset_uploaded_while_the_tab_is_built_is_loaded(served, capfd):
    """The upload button reaches the page before the rest of the tab; an upload sent at once
    used to be lost (``AttributeError: 'TabApp' object has no attribute 'panels'``)."""
    data = presets_io.to_toml(presets_io.load("course-dvc")).encode()  # another kind: the tab is swapped
    before = set(served.tabs)
    c = WireClient(served.port, decode=True)
    try:
        end = time.monotonic() + 60
        while not c.uuid_of("Upload preset") and time.monotonic() < end:  # sent the moment the button is there
            time.sleep(0.001)
        early = not (set(served.tabs) - before)  # the server has not finished the tab yet
        c.upload("Upload preset", "early.toml", data)
        wait_until(lambda: any(t.session.scenario.name == "course-dvc" for k, t in served.tabs.items()
                               if k not in before), timeout=60, what="the uploaded preset loaded")
        wait_until(lambda: c.saw("Preset uploaded"), what="the verdict in the page")
    finally:
        c.close()
    err = capfd.readouterr().err
    assert "AttributeError" not in err and "Traceback" not in err, err[-2000:]
    assert early, "the upload came after the tab was built: the test did not test the race"


@pytest.mark.parametrize("name, data, words", [
    ("dotted.toml", b"a" + b".a" * 49_000 + b" = 1\n", "a key of more than 16 dotted parts"),
    ("header.toml", b"[" + b"a." * 49_000 + b"a]\n", "a key of more than 16 dotted parts"),
    ("deep.toml", b"x = " + b"{a = " * 20_000 + b"1" + b"}" * 20_000, "nested deeper than 16"),
])
def test_a_99_kib_hostile_preset_on_the_wire_is_refused_at_once(served, name, data, words):
    """Issue 20, case 2: ``tomllib`` took minutes and gigabytes on these; the bounds refuse them
    before it parses (how fast is measured in ``benchmarks/bench_hostile.py``)."""
    assert len(data) > 90 * 1024
    c = _tab(served)
    try:
        c.upload("Upload preset", name, data)
        wait_until(lambda: c.saw(words), timeout=30, what="the refusal")
    finally:
        c.close()


@pytest.mark.parametrize("message", ["ShareUrlRequest", "ShareUrlDisconnect"])
def test_a_client_cannot_make_the_server_share_itself(served, capfd, monkeypatch, message):
    """viser answers a ShareUrlRequest from any client by opening a public tunnel to the server
    through its share service: the guard drops it, and viser's share calls are never made."""
    calls: list[str] = []
    monkeypatch.setattr(served.viser, "request_share_url", lambda *a, **k: calls.append("request"))
    monkeypatch.setattr(served.viser, "disconnect_share_url", lambda *a, **k: calls.append("disconnect"))
    c = _tab(served)
    try:
        frames = c.counts()[0]
        c.ws.send(msgspec.msgpack.encode({"type": message}))
        wait_until(lambda: c.counts()[0] > frames + 3, what="updates after the share request")
        time.sleep(0.3)
        assert not c.closed.is_set()
    finally:
        c.close()
    assert calls == []
    err = capfd.readouterr().err
    assert f"{message}: this server is not shared" in err, err[-2000:]
