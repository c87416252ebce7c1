"""Tabs of a lecture over viser's raw websocket, shared by the lecture-hall tests."""

from __future__ import annotations

import re

import numpy as np
from viser import _messages

from shoal.app.hall import routes
from shoal.app.hall.watcher import TAKE_OVER

from browser.browser_helpers import wait_until
from viser_wire import WireClient


def lecturer(srv) -> WireClient:
    """The lecturer's tab of ``srv`` (the key in its cookie), once its panel arrived."""
    c = WireClient(srv.port, decode=True, path=routes.LECTURER_PATH,
                   headers={"Cookie": f"{routes.KEY_COOKIE}={srv.key}"})
    wait_until(lambda: srv.lecture.lecturer is not None and c.uuid_of("playback"), what="the lecturer's tab")
    return c


def watcher(srv) -> WireClient:
    """A class tab of ``srv``, once its own controls arrived."""
    before = set(srv.watchers)
    c = WireClient(srv.port, decode=True)
    wait_until(lambda: set(srv.watchers) - before and c.uuid_of(TAKE_OVER), what="a watcher")
    return c


def press(c: WireClient, button: str) -> None:
    """A playback button (Play, Pause, Step, Reset) of a tab with the full panel."""
    c.send(_messages.GuiUpdateMessage(newest(c, "playback"), {"value": button}))


def status_of(c: WireClient) -> str:
    """The last status line a tab was sent (the markdown that names the step)."""
    return next((m for m in reversed(c.markdown()) if re.search(r"step \d+/\d+", m)), "")


def robots_of(c: WireClient) -> np.ndarray | None:
    """The robots' points (scene units) a tab was last sent."""
    return next((p for name, p in c.points.items() if name.endswith("/robots")), None)


def newest(c: WireClient, label: str) -> str:
    """The id of the newest element labelled ``label`` (a panel rebuilt for another kind of scene has new ones)."""
    ids = [m["uuid"] for m in c.gui if (m.get("props") or {}).get("label") == label]
    assert ids, f"no element labelled {label!r} arrived"
    return ids[-1]
