"""Many tabs on one server: the session cap, tabs that vanish, and tabs that stay independent.

The tabs here are real websocket clients of a real app server (``viser_wire.WireClient``
speaks viser's protocol without a browser), so the server runs its ordinary connect,
disconnect and ticking paths; the real-Chromium versions live in
``tests/browser/test_browser_trust.py``.
"""

from __future__ import annotations

import gc
import subprocess
import sys
import weakref

import numpy as np
import pytest

from shoal.app.cli import build_parser
from shoal.app.kinds.registry import session_for
from shoal.app.server import DEFAULT_MAX_SESSIONS, FULL_TITLE, start_server
from shoal.app.tab import TabApp
from shoal.presets.io import load

from browser.browser_helpers import wait_until  # noqa: E402  (tests/ is on sys.path)
from viser_wire import WireClient


@pytest.fixture
def server():
    srv = start_server("default", port=0, max_sessions=2)
    yield srv
    srv.stop()


def _close_all(clients):
    for c in clients:
        c.close()


def test_a_tab_beyond_the_cap_is_told_so_and_gets_no_simulation(server):
    clients = [WireClient(server.port, decode=True) for _ in range(2)]
    try:
        wait_until(lambda: len(server.tabs) == 2, what="two sessions")
        third = WireClient(server.port, decode=True)
        clients.append(third)
        wait_until(lambda: server.turned_away, what="the third tab to be turned away")
        wait_until(lambda: third.saw("its maximum") and third.saw(FULL_TITLE), what="the message in the third tab")
        assert "2 sessions" in next(t for t in third.texts if "its maximum" in t)
        assert len(server.sessions) == 2 and not set(server.turned_away) & set(server.tabs)
        assert not any(c.saw("its maximum") for c in clients[:2])
    finally:
        _close_all(clients)
    wait_until(lambda: not server.tabs and not server.turned_away, what="every tab to be forgotten")


def test_a_closed_tab_frees_its_session_for_a_new_one(server):
    clients = [WireClient(server.port) for _ in range(2)]
    try:
        wait_until(lambda: len(server.tabs) == 2, what="two sessions")
        first = min(server.tabs)
        gone = weakref.ref(server.tabs[first].session)
        clients.pop(0).close()
        wait_until(lambda: first not in server.tabs, what="the closed tab's session to go")
        wait_until(lambda: (gc.collect(), gone() is None)[1], what="its simulation to be freed")
        clients.append(WireClient(server.port))
        wait_until(lambda: len(server.tabs) == 2, what="a session for the new tab")
        assert not server.turned_away
    finally:
        _close_all(clients)


def test_tabs_that_close_while_connecting_leave_nothing_behind(server):
    """Connect and disconnect race on viser's thread pool: no session may outlive its tab."""
    for _ in range(6):
        WireClient(server.port).close()
    wait_until(lambda: not server.tabs and not server._opening and not server.turned_away, what="an empty server")
    clients = [WireClient(server.port) for _ in range(2)]  # the cap is all free again
    try:
        wait_until(lambda: len(server.tabs) == 2 and not server._opening, what="two live sessions")
        wait_until(lambda: not server.turned_away, what="no tab left turned away")
    finally:
        _close_all(clients)
    wait_until(lambda: not server.tabs and not server._opening and not server.turned_away, what="an empty server")


def test_a_tab_dropped_mid_run_leaves_the_others_running(capfd):
    srv = start_server("default", port=0, max_sessions=4)
    clients = [WireClient(srv.port) for _ in range(3)]
    try:
        wait_until(lambda: len(srv.tabs) == 3, what="three sessions")
        wait_until(lambda: all(s.sim.state.k > 5 for s in srv.sessions.values()), what="all three playing")
        clients[0].ws.socket.close()  # the network goes: no closing handshake
        wait_until(lambda: len(srv.tabs) == 2, what="the dropped tab's session to go")
        before = {cid: s.sim.state.k for cid, s in srv.sessions.items()}
        wait_until(lambda: all(s.sim.state.k > before[cid] + 10 for cid, s in srv.sessions.items()),
                   what="the other two to keep advancing")
    finally:
        _close_all(clients[1:])
        srv.stop()
    err = capfd.readouterr().err
    assert "Traceback" not in err and "tab update failed" not in err, err[-2000:]
    assert err.count("closed connection") <= 3, err[-2000:]  # a warning or so, not a storm


def test_sessions_of_concurrent_tabs_are_independent():
    srv = start_server("default", port=0, max_sessions=5)
    clients = [WireClient(srv.port) for _ in range(5)]
    try:
        wait_until(lambda: len(srv.tabs) == 5, what="five sessions")
        sessions = srv.sessions
        assert len({id(s.sim) for s in sessions.values()}) == 5
        one, *rest = sorted(sessions)
        # (a tab plays at its page's first drawn frame, or FIRST_FRAME_SECONDS later: a raw client draws none)
        wait_until(lambda: all(s.sim.state.k > 0 for s in sessions.values()), what="all five playing")
        sessions[one].apply({"sim.robots": 7, "controller.U": 9.0})
        before = {cid: sessions[cid].sim.state.k for cid in sessions}
        wait_until(lambda: all(sessions[c].sim.state.k > before[c] + 5 for c in sessions), what="all five advancing")
        assert sessions[one].sim.robots == 7
        assert all(sessions[c].sim.robots == 20 and sessions[c].scenario.controller.U == 6.0 for c in rest)
    finally:
        _close_all(clients)
        srv.stop()


def test_a_heavy_tab_steps_within_its_budget_and_drops_the_rest(server):
    """Ticked by the server, a tab does at most ``STEP_BUDGET`` of steps per tick (here none
    beyond the first); the steps it could not do are dropped, not owed to the next tick."""
    tab = TabApp(session_for(load("default")), server.viser.gui, server.viser.scene)
    try:
        assert tab.auto_tick
        tab.STEP_BUDGET = 0.0
        tab.session.play()
        tab.tick(0.0)
        tab.tick(1.0)  # one second at 20 steps/s: 20 steps asked
        assert tab.session.sim.state.k == 1
        tab.tick(1.05)  # one more step is due, not the 19 skipped
        assert tab.session.sim.state.k == 2
    finally:
        tab.close()
        server.viser.gui.reset()
        server.viser.scene.reset()


def test_a_busy_round_lets_plots_wait_but_not_the_scene(server):
    """The server ticks a tab with ``plots=False`` once its round has spent its plot share: the
    arena still moves; status and plots stay due and refresh on a later tick."""
    tab = TabApp(session_for(load("default")), server.viser.gui, server.viser.scene)
    try:
        tab.tick(0.0)
        status, drawn = tab.panels.status.content, tab.arena.drawn_revision
        tab.session.step(5)
        tab.tick(1.0, plots=False)
        assert tab.arena.drawn_revision != drawn and tab.panels.status.content == status
        tab.tick(1.01)
        assert tab.panels.status.content != status
    finally:
        tab.close()
        server.viser.gui.reset()
        server.viser.scene.reset()


def test_a_tab_that_keeps_failing_is_reported_once_and_the_others_go_on(server, capfd):
    broken = server.open_tab(-5, server.viser.gui, server.viser.scene)
    try:
        def fail(snap):
            raise RuntimeError("broken arena")

        broken.arena.draw = fail
        broken.session.play()
        client = WireClient(server.port)
        try:
            wait_until(lambda: len(server.tabs) == 2, what="a healthy tab beside the broken one")
            healthy = next(s for cid, s in server.sessions.items() if cid != -5)
            k = healthy.sim.state.k
            wait_until(lambda: healthy.sim.state.k > k + 10 and broken.session.sim.state.k > 10,
                       what="both to advance")
        finally:
            client.close()
    finally:
        server.close_tab(-5)
        server.viser.gui.reset()
        server.viser.scene.reset()
    assert capfd.readouterr().err.count("tab update failed: RuntimeError('broken arena')") == 1


def test_an_oversized_upload_is_dropped_while_it_arrives(server):
    """A client that declares, or just sends, more than any upload may have: viser's buffer for
    it is dropped at once and the tab is told; an ordinary upload still works."""
    import uuid

    from viser import _messages as m

    from shoal.app.server import MAX_TRANSFER_BYTES
    from shoal.presets.io import to_toml

    before = set(server.tabs)  # a tab of an earlier test may still be leaving
    c = WireClient(server.port, decode=True)
    try:
        wait_until(lambda: c.uuid_of("Upload preset") and set(server.tabs) - before, what="the upload button")
        button = c.uuid_of("Upload preset")
        (cid,) = set(server.tabs) - before
        states = server.viser.get_clients()[cid].gui._current_file_upload_states

        def start(name: str, size: int, parts: int) -> str:
            tid = str(uuid.uuid4())
            c.send(m.FileTransferStartUpload(source_component_uuid=button, transfer_uuid=tid, filename=name,
                                             mime_type="application/toml", part_count=parts, size_bytes=size))
            return tid

        start("declared.toml", 10 * MAX_TRANSFER_BYTES, 1000)
        wait_until(lambda: c.saw("Refused: uploaded declared.toml"), what="the refusal of a declared giant")
        liar = start("liar.toml", 1000, 1000)
        part = b"#" * (MAX_TRANSFER_BYTES // 8)
        for i in range(12):
            c.send(m.FileTransferPart(source_component_uuid=button, transfer_uuid=liar, part_index=i, content=part))
        wait_until(lambda: c.saw("Refused: uploaded liar.toml"), what="the refusal of a growing upload")
        assert not states
        data = to_toml(load("rastrigin")).encode()
        good = start("mine.toml", len(data), 1)
        c.send(m.FileTransferPart(source_component_uuid=button, transfer_uuid=good, part_index=0, content=data))
        wait_until(lambda: server.sessions[cid].scenario.name == "rastrigin", what="the good upload loaded")
    finally:
        c.close()


def test_max_sessions_is_a_serve_option_with_a_checked_value():
    assert build_parser().parse_args(["serve"]).max_sessions == DEFAULT_MAX_SESSIONS
    assert build_parser().parse_args(["serve", "--max-sessions", "3"]).max_sessions == 3
    with pytest.raises(ValueError, match="max_sessions"):
        start_server("default", port=0, max_sessions=0)
    out = subprocess.run([sys.executable, "-m", "shoal",
                          "serve", "--port", "0", "--max-sessions", "0"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "argument --max-sessions: must be at least 1, got 0" in out.stderr


def test_robots_of_distinct_tabs_differ_only_where_their_settings_do():
    """Two sessions of one preset and seed are the same run; changing one leaves the other alone."""
    a, b = session_for(load("default")), session_for(load("default"))
    a.step(10), b.step(10)
    np.testing.assert_array_equal(a.sim.state.x, b.sim.state.x)
    a.apply({"controller.U": 9.0})
    a.step(10), b.step(10)
    assert not np.array_equal(a.sim.state.x, b.sim.state.x)
    c = session_for(load("default"))
    c.step(20)
    np.testing.assert_array_equal(b.sim.state.x, c.sim.state.x)
