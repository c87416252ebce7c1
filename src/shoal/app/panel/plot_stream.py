"""A uPlot's data sent as what is new: the rows a refresh appends, never the whole window again.

viser's uPlot takes its data whole (``GuiUplotHandle.data``: every x and y value of every
series, on every push), and a time plot's window is up to ``PlotSpec.history`` rows. A
:class:`PlotStream` keeps what the page holds of each chart and sends the difference instead:

- it compares the frame a refresh renders with the data last sent; when the new data is the
  old with ``drop`` rows gone from the front and rows added at the end (a plot that plays on:
  the same x values, the same scaled y values), only those rows travel, in a call of the page
  script (``window.__shoalPage.plot``, :mod:`shoal.app.view.page`) that puts them into viser's
  GUI store as a push would, after the other messages of the same batch. Anything else (a
  scrubbed cut, a reset, a new exponent on the y axis, a non-time :class:`~.plots.Chart`) is a
  keyframe: the whole data through viser's own update, as before;
- the handle's props are kept equal to what the page holds, without a message
  (``handle._impl.props``: viser's internals, under the bound on viser), so ``handle.data`` is
  what the page draws and a later keyframe is compared against it;
- appends start only once the page said it applies them: the page script finds viser's store,
  then writes ``"appends …"`` into a hidden text control of this panel (:data:`SYNC_LABEL`).
  A page that cannot (another viser, a client without the script) never says so and keeps
  getting keyframes. An append whose base the page does not hold (a message it missed) makes
  it write ``"resync …"``: every chart is sent whole at once, as the server holds it (so a
  tab paused just after a miss still ends with the page drawing what the server rendered), and
  the appends that follow build on that;
- viser never drops a script message on its way to a page, while a data update replaces the one
  still waiting for the same chart: so while more than :data:`MAX_BACKLOG` messages wait for a
  page (a slow or stalled client), refreshes are keyframes again, and what waits stays bounded.

A refresh of a playing plot then costs the page a few hundred bytes, whatever the window.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any, Callable

import numpy as np

SYNC_LABEL = "plot sync"  # the hidden control the page answers through
RESYNC_SECONDS = 0.5  # a page asks at most once a second: the server answers at most once in this
MAX_BACKLOG = 256  # messages waiting for the page beyond which a refresh is a keyframe (it coalesces)
Script = Callable[[str], None]  # runs JavaScript in the tab's page
Backlog = Callable[[], int]  # messages still waiting to reach the tab's page


def delta(old: tuple[np.ndarray, ...], new: tuple[np.ndarray, ...]) -> tuple[int, tuple[np.ndarray, ...]] | None:
    """(rows to drop from the front, rows to add at the end) that turn ``old`` into ``new`` (every
    series of the same length, ``[0]`` the x values), or None when ``new`` is not ``old`` slid on."""
    if len(old) != len(new) or not new or not len(old[0]) or not len(new[0]):
        return None
    drop = int(np.searchsorted(old[0], new[0][0]))  # (x increases: where the new window starts)
    keep = len(old[0]) - drop
    if drop >= len(old[0]) or keep > len(new[0]):
        return None
    for o, n in zip(old, new):
        if len(o) != len(old[0]) or len(n) != len(new[0]) or not np.array_equal(o[drop:], n[:keep], equal_nan=True):
            return None
    return drop, tuple(np.asarray(n[keep:], dtype=np.float64) for n in new)


def js_number(v: float) -> str:
    """``v`` as a JavaScript literal that reads back as the same double."""
    if math.isnan(v):
        return "NaN"
    if math.isinf(v):
        return "Infinity" if v > 0 else "-Infinity"
    return repr(v)


def js_value(v: Any) -> str:
    """A JSON-like value (scales: dicts, tuples, numbers, strings, booleans, None) as JavaScript."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if v is None:
        return "null"
    if isinstance(v, (int, float, np.floating, np.integer)):
        return js_number(float(v))
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, dict):
        return "{" + ",".join(f"{js_value(str(k))}:{js_value(x)}" for k, x in v.items()) + "}"
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ",".join(js_value(x) for x in v) + "]"
    raise TypeError(f"not a plot value: {v!r}")


def append_call(sync: str, uuid: str, base: np.ndarray, drop: int, rows: tuple[np.ndarray, ...],
                scales: dict[str, Any]) -> str:
    """The page-script call that appends ``rows`` to chart ``uuid`` holding x values ``base``."""
    n = len(base)
    x0, x1 = (js_number(float(base[0])), js_number(float(base[-1]))) if n else ("0", "0")
    cols = "[" + ",".join("[" + ",".join(js_number(v) for v in col.tolist()) + "]" for col in rows) + "]"
    return (f"window.__shoalPage&&window.__shoalPage.plot({js_value(sync)},{js_value(uuid)},{n},{x0},{x1},"
            f"{int(drop)},{cols},{js_value(scales)});")


def sync_call(uuid: str) -> str:
    """The call that tells the page which control to answer through (kept until its script runs)."""
    return (f"(window.__shoalPage=window.__shoalPage||{{}}).plotSync={js_value(uuid)};"
            "window.__shoalPage.plotSaid=null;")


class PlotStream:
    """One panel's uPlots as the page holds them. Without a ``script`` (a tab with no page, tests
    driving the panels) every refresh is a keyframe, as viser sends it."""

    def __init__(self, gui: Any, script: Script | None, backlog: Backlog | None = None) -> None:
        self.script, self.backlog = script, backlog
        self.appends = False  # the page said it applies appended rows
        self._charts: dict[str, Any] = {}  # the charts pushed so far, by uuid
        self._lock = threading.Lock()  # a push and a resync's keyframes, one at a time (ticker, viser's thread)
        self._resent = -math.inf  # when every chart was last sent whole on the page's asking
        self.appended = self.keyframes = 0  # refreshes sent each way (for the benchmarks and tests)
        self.sync: Any = None
        if script is not None:
            self.sync = gui.add_text(SYNC_LABEL, initial_value="", visible=False)
            self.sync.on_update(lambda _event: self.heard(str(self.sync.value)))
            script(sync_call(self.sync._impl.uuid))

    def heard(self, said: str) -> None:
        """The page's answer (viser's thread): ``appends N`` (it applies them), ``resync N`` (it
        missed one: every chart is sent whole now). Anything else is ignored."""
        word = said.split(" ", 1)[0]
        if word == "appends":
            self.appends = True
        elif word == "resync":
            now = time.monotonic()
            if now - self._resent < RESYNC_SECONDS:
                return  # (faster than a page asks: a client flooding the server gets one answer)
            self._resent = now
            with self._lock:
                for handle in list(self._charts.values()):
                    self._keyframe(handle, tuple(handle._impl.props.data), handle._impl.props.scales)

    def push(self, handle: Any, data: tuple[np.ndarray, ...], scales: dict[str, Any]) -> None:
        """Bring the page's chart ``handle`` to ``data`` and ``scales``, as cheaply as it can."""
        with self._lock:
            self._push(handle, data, scales)

    def _push(self, handle: Any, data: tuple[np.ndarray, ...], scales: dict[str, Any]) -> None:
        uuid = handle._impl.uuid
        self._charts[uuid] = handle
        props = handle._impl.props
        if (self.appends and self.script is not None
                and (self.backlog is None or self.backlog() <= MAX_BACKLOG)):
            found = delta(tuple(props.data), data)
            if found is not None:
                drop, rows = found
                if drop or len(rows[0]) or props.scales != scales:
                    self.script(append_call(self.sync._impl.uuid, uuid, props.data[0], drop, rows, scales))
                    props.data = tuple(np.asarray(a, dtype=np.float64).copy() for a in data)
                    props.scales = scales
                    self.appended += 1
                return
        self._keyframe(handle, data, scales)

    def _keyframe(self, handle: Any, data: tuple[np.ndarray, ...], scales: dict[str, Any]) -> None:
        """The whole of ``data`` and ``scales`` through viser's own update (a removed chart: nothing)."""
        uuid = handle._impl.uuid
        if handle._impl.removed:
            self._charts.pop(uuid, None)
            return
        handle.data = data
        handle.scales = scales
        self.keyframes += 1

    def remove(self) -> None:
        if self.sync is not None:
            self.sync.remove()
            self.sync = None
