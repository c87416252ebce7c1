"""A hand-ticked app tab on a real viser server, shared by the app-level tests."""

from __future__ import annotations

import html
import re
from contextlib import contextmanager
from typing import Any, Iterator

HAND_TAB = -3  # client id of the tab a test drives (no browser behind it)


@contextmanager
def hand_tab(server: Any, cid: int = HAND_TAB) -> Iterator[Any]:
    """A tab whose panels live on ``server.viser.gui``, ticked only by the test; closed (and
    the server's GUI and scene cleared) afterwards."""
    t = server.open_tab(cid, server.viser.gui, server.viser.scene, auto_tick=False)
    t.control_hold = 0.0  # a test ticks by hand, at the times it picks: the scene follows each change at once
    t.tick(0.0)
    try:
        yield t
    finally:
        server.close_tab(cid)
        server.viser.gui.reset()
        server.viser.scene.reset()


def wire_tab(server: Any, *labels: str) -> tuple[Any, int]:
    """A new tab of ``server`` opened over the raw websocket (:class:`viser_wire.WireClient`), once
    its page shows a control of each of ``labels``: the client and the tab's key in ``server.tabs``."""
    from browser.browser_helpers import wait_until
    from viser_wire import WireClient

    before = set(server.tabs)
    c = WireClient(server.port, decode=True)
    wait_until(lambda: set(server.tabs) - before and all(c.uuid_of(label) for label in labels), what="a tab")
    (key,) = set(server.tabs) - before
    return c, key


_ESCAPED = re.compile(r"\\([!-/:-@\[-`{-~])")


def shown(markdown: str) -> str:
    """Markdown as the page reads it: the app's escapes (``markdown.escape``) undone, and the
    word joiners that keep addresses from becoming links (invisible) left out."""
    return html.unescape(_ESCAPED.sub(r"\1", markdown)).replace("\u2060", "")
