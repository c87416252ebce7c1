"""The class's screen: the lecture's run drawn once, on the server-wide scene and GUI, for every watcher.

A :class:`Broadcast` draws the lecture session (``lecture.session``: the lecturer's tab's
session, whatever kind it shows now) into a :class:`~shoal.app.view.view.View` on the viser
server's own scene, and keeps a read-only panel on the server's own GUI: the run's name and
status line, the legend of the arena, and the lecturer's time plots. Viser sends both to every
connection of the server, and :mod:`.fanout` sends them only to watchers, serialised once.

Nothing here takes input: no control, no click callback, no drag. The panel holds markdown,
HTML and plots only, so no message a watcher sends reaches a handler of the broadcast (a
server-wide control would take a watcher's value and show it to everyone). What a watcher may
do (take over, answer a round) is on its own ``client.gui``: :mod:`.watcher`.

The status line and the plots are the lecturer's: the status line's text as the lecturer's panel
shows it, and each of the lecturer's time plots as that panel frames it (``Panel._frame``), so
the class sees what the lecturer sees, at the same step. A plot's frame goes to the class whole
(a page that joins late needs the whole of it), at most :data:`MAX_ROWS` rows of it (every
k-th row and the last: the curve as a plot a few hundred pixels wide draws it) and at most
:data:`PLOT_HZ` times a second, so what a watcher receives does not grow with the run's age.
Without a lecturer's tab the run does not advance, and the class is told.
"""

from __future__ import annotations

import contextlib
import dataclasses
from typing import Any, Protocol

import numpy as np

from ..kinds.registry import app_kind
from ..markdown import escape
from ..panel.plots import Chart, Frame, PlotSpec
from ..panel.view_row import LIGHT_NOTE, legend_html
from ..session.session import Session
from ..tab import TabApp
from ..view.overlay import ClassLabels
from ..view.view import View
from .round_view import class_html
from .rounds import Rounds


class Shown(Protocol):
    """What a broadcast shows (:class:`~.lecture.Lecture`): the run, and the lecturer's tab if connected."""

    @property
    def session(self) -> Session: ...

    @property
    def lecturer(self) -> TabApp | None: ...


# Where the broadcast's parts sit in a watcher's panel; a watcher's own controls go between them
# (viser orders the elements of a panel by ``order``, across the server's GUI and the client's).
ORDER_TITLE, ORDER_STATUS, ORDER_OWN, ORDER_ROUND, ORDER_ANSWER, ORDER_LEGEND, ORDER_PLOTS, ORDER_LABELS = (
    1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0)
AWAY = "the lecturer's tab is not connected: the run waits for it"
MAX_ROWS = 400  # of a plot sent to the class
PLOT_HZ = 2.0  # the class's status line, round and plots
TITLE = "### Watching the lecture"


def bounded(f: Frame, rows: int = MAX_ROWS) -> Frame:
    """``f`` with at most ``rows`` rows: every k-th one, and the last."""
    n = len(f.data[0]) if f.data else 0
    if n <= rows:
        return f
    keep = np.unique(np.append(np.arange(0, n, int(np.ceil(n / (rows - 1)))), n - 1))
    return dataclasses.replace(f, data=tuple(np.asarray(column)[keep] for column in f.data))


def status_text(tab: TabApp) -> str:
    """The lecturer's status line as the class should read it (without the note on the lecturer's
    own light drawing)."""
    text = str(tab.panels.status.content)
    return text.removesuffix(f"<br>{LIGHT_NOTE}")


class Broadcast:
    """The lecture drawn on ``server.scene`` and ``server.gui`` (a ``viser.ViserServer``), ticked by
    the server's thread with the tabs (:meth:`tick`)."""

    SCENE_HZ = TabApp.SCENE_HZ
    PLOT_HZ = PLOT_HZ

    def __init__(self, server: Any, lecture: Shown, rounds: Rounds | None = None) -> None:
        self.server, self.lecture, self.rounds = server, lecture, rounds
        gui = server.gui
        self.title = gui.add_markdown(TITLE, order=ORDER_TITLE)
        self.status = gui.add_markdown("", order=ORDER_STATUS)
        self.round = gui.add_html("", order=ORDER_ROUND, visible=False)
        self._round_shown = -1  # the rounds' revision on screen
        self.legend = gui.add_markdown("", order=ORDER_LEGEND)
        self.plots_folder = gui.add_folder("Plots", order=ORDER_PLOTS)
        # the arena's labels, HTML over each watcher's canvas as over a tab's (sharp, dark on white)
        self.labels = ClassLabels()
        self.label_holder = gui.add_html(self.labels.holder_html(), order=ORDER_LABELS)
        self._labels_sent = self.labels.revision
        self._session: Session | None = None
        self.arena: View | None = None
        self._panel: Any = None  # the lecturer's Panel whose plots are mirrored
        self._plots: list[tuple[Any, Any]] = []  # (spec, the broadcast's uplot handle)
        self._sent: dict[int, tuple[Any, Any, Any]] = {}  # (series, axes, padding) last sent, by handle
        self._next_scene = self._next_plot = 0.0
        self._plot_key: tuple | None = None
        self._legend: str | None = None
        self.plots_due = False  # the last tick refreshed status and plots
        self.draws = 0  # arena draws so far (tests, benchmarks)
        self.step_drawn = -1  # the engine step of the last snapshot drawn

    # ------------------------------------------------------------------ ticking
    def tick(self, now: float, plots: bool = True) -> None:
        """Draw what is due: the arena at most ``SCENE_HZ`` times a second (when the run changed),
        status and plots at most ``PLOT_HZ`` times."""
        s = self.lecture.session
        if s is not self._session:
            self._show(s)
        arena = self.arena
        assert arena is not None
        if s.scene_revision != arena.built_revision:
            with self.server.atomic():
                arena.rebuild(s.scene_revision)
                self._send_labels()
        if now >= self._next_scene and s.revision != arena.drawn_revision:
            snap = s.shown_snapshot()
            with self.server.atomic():  # one window for every watcher
                arena.draw(snap)
                self._send_labels()
                legend = legend_html(arena.legend())
                if legend != self._legend:
                    self.legend.content = self._legend = legend
            self.draws += 1
            self.step_drawn = int(snap.k)
            self._next_scene = now + 1.0 / self.SCENE_HZ
        self.plots_due = plots and now >= self._next_plot
        if self.plots_due:
            self._refresh(s)
            self._show_round()
            self._next_plot = now + 1.0 / self.PLOT_HZ

    def _send_labels(self) -> None:
        """The labels' state to the class, when it changed (with the nodes that place them)."""
        if self.labels.revision != self._labels_sent:
            self.label_holder.content = self.labels.holder_html()
            self._labels_sent = self.labels.revision

    def _show_round(self) -> None:
        """The round's block: the question while it is open, the results once revealed."""
        rounds = self.rounds
        if rounds is None or rounds.revision == self._round_shown:
            return
        self._round_shown = rounds.revision
        r = rounds.current
        with self.server.atomic():
            self.round.content = class_html(r)
            self.round.visible = r is not None

    def _show(self, session: Session) -> None:
        """The lecture now shows ``session`` (at first, or another kind's): a new arena for it."""
        if self.arena is not None:
            with self.server.atomic():
                self.arena.clear()
        self._session = session
        self.arena = app_kind(session).view(self.server.scene, None, labels=self.labels)
        self._next_scene = 0.0
        self._plot_key = None

    # ------------------------------------------------------------------ status and plots
    def _refresh(self, s: Session) -> None:
        tab = self.lecture.lecturer
        panel = tab.panels if tab is not None else None
        if panel is not self._panel:
            self._mirror(panel)
        key = (s.revision, s.playing, id(panel), panel.status.content if panel is not None else None)
        if key == self._plot_key:
            return
        self._plot_key = key
        with self.server.atomic():
            if tab is None or panel is None:
                self.status.content = f"**{escape(s.scenario.name)}** · {s.progress()} · {AWAY}"
                return
            self.status.content = status_text(tab)
            for spec, handle in self._plots:
                shown = spec.visible is None or bool(spec.visible(s))
                if handle.visible != shown:
                    handle.visible = shown
                if not shown:
                    continue
                with contextlib.suppress(Exception):  # a panel swapped out meanwhile: the next refresh mirrors the new
                    self._push(handle, bounded(panel._frame(spec)))

    def _push(self, handle: Any, f: Frame) -> None:
        """One plot's frame to the class: series, axes and padding only when they change (the page
        rebuilds the chart for those), data and scales every time."""
        sent = self._sent.get(id(handle))
        if sent is None or sent[0] != f.series:
            handle.series = f.series
        if sent is None or sent[1] != f.axes:
            handle.axes = f.axes
        if sent is None or sent[2] != f.padding:
            handle.padding = f.padding
        self._sent[id(handle)] = (f.series, f.axes, f.padding)
        handle.data = f.data
        handle.scales = f.scales

    def _mirror(self, panel: Any) -> None:
        """Plots for the time plots of the lecturer's ``panel`` (None: keep the last ones shown)."""
        self._panel = panel
        if panel is None:
            return
        with self.server.atomic():
            for _, handle in self._plots:
                handle.remove()
            self._plots = []
            with self.plots_folder:
                for spec, _ in panel._controls:
                    if not isinstance(spec, (PlotSpec, Chart)):
                        continue
                    f = bounded(panel._frame(spec))
                    handle = self.server.gui.add_uplot(
                        data=f.data, series=f.series, scales=f.scales, axes=f.axes, title=spec.title,
                        aspect=spec.aspect, legend=spec.legend, padding=f.padding)
                    self._plots.append((spec, handle))
                    self._sent[id(handle)] = (f.series, f.axes, f.padding)
        self._plot_key = None

    def clear(self) -> None:
        """Take the broadcast off the server's scene and GUI."""
        with self.server.atomic():
            if self.arena is not None:
                self.arena.clear()
            for h in (self.title, self.status, self.round, self.legend, self.plots_folder, self.label_holder):
                h.remove()
