"""A tab closed mid-update raises no warning: the writes to a client that has just gone (from the
ticker, from the tab's build, from a callback) are dropped by viser, and Shoal tells viser they are
expected for the connection's whole life (``server.expect_late_writes``)."""

from __future__ import annotations

import time
import warnings

from viser import _messages

from browser.browser_helpers import wait_until
from viser_wire import WireClient

APP_PRESET = "default"


def _closed_warnings(caught) -> list[str]:
    return [str(w.message) for w in caught if "closed connection" in str(w.message)]


def test_closing_tabs_mid_update_raises_no_warning(server):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # (the ticker's thread warns into the same, process-wide list)
        for i in range(8):
            before = set(server.tabs)
            client = WireClient(server.port, decode=True)
            wait_until(lambda before=before: set(server.tabs) - before, what="a tab")
            time.sleep(0.2 + 0.13 * i)  # closed at another point of the ticker's round each time
            client.ws.close()
            wait_until(lambda before=before: not set(server.tabs) - before, what="the closed tab to go")
        time.sleep(0.5)
    closed = _closed_warnings(caught)
    assert not closed, closed[:3]


def test_tabs_that_close_while_built_or_answered_raise_no_warning(server):
    """A tab gone while its panels are still being sent, and one gone while the server answers a
    change it sent (a preset switch rebuilds the arena, the panels and the plots)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for i in range(6):
            client = WireClient(server.port, decode=True)
            time.sleep(0.05 * i)  # at another point of its build each time
            client.ws.close()
        for preset in ("rastrigin", "course-dvc"):
            before = set(server.tabs)
            client = WireClient(server.port, decode=True)
            wait_until(lambda before=before: set(server.tabs) - before, what="a tab")
            client.send(_messages.GuiUpdateMessage(client.wait_uuid("preset"), {"value": preset}))
            time.sleep(0.1)
            client.ws.close()
        wait_until(lambda: not server.tabs and not server._opening, timeout=60, what="every tab to go")
        time.sleep(1.0)
    closed = _closed_warnings(caught)
    assert not closed, closed[:3]
