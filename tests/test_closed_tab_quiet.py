"""A tab closed mid-update raises no warning: the ticker's writes to a client that has just gone
are dropped by viser, and Shoal tells viser they are expected (``server.closed_tab_quiet``)."""

from __future__ import annotations

import time
import warnings

from browser.browser_helpers import wait_until
from viser_wire import WireClient

APP_PRESET = "default"


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
    closed = [str(w.message) for w in caught if "closed connection" in str(w.message)]
    assert not closed, closed[:3]
