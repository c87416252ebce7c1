"""The board: what a hall reads beside the arena, in a viser panel of its own.

It holds the plot the scene is about (the kind's ``KindPanel.main``: the (ω, ĉ) plane of a
Chapter 3 swarm, the speed plot of a Fig. 3-4/3-5 scene, a fleet's progress, a sonar's distance
to the source, Mai's localisation error or best fitness) and the legend of the glyphs on screen.
The plot moves here from its tab (it is drawn once), so that it is in view without scrolling.
The tab keeps one board for its life (a swap of scene kinds builds the new plot into it and
retires the old one): a board docked again at every swap re-laid the old plot out as it was
being taken off the page, which plotly reported as an error.

Normal mode docks it left of the arena (:data:`WIDTH` pixels); projector mode docks it under the
controls, where the arena keeps its width when every text is twice its size. The user may fold
it away with its chevron; the tab fits the arena to the space it then has.
"""

from __future__ import annotations

import contextlib
from typing import Any

WIDTH = 340  # px, docked left of the arena
TITLE = "beside the arena"  # the board's tab (the plot carries its own title)
NORMAL_HEIGHT = 0.87  # a plot's height / width on the board left of the arena
# px of the projector board's height that are not its plot's drawing: its strip and tab, and a
# time plot's title and legend (at twice their size; a plotly figure holds its own)
CHROME = {"time": 300.0, "figure": 170.0}


def plot_height(projector: bool, window_height: float | None, width: float, kind: str = "time") -> float:
    """A board plot's height / width (``kind``: a time plot or a figure): in projector mode the
    board has the lower half of the window (``window_height``, px; 768 when not known yet)
    under the controls, ``width`` wide."""
    if not projector:
        return NORMAL_HEIGHT
    room = (window_height or 768.0) / 2 - CHROME[kind]
    return min(0.5, max(0.15, room / max(width, 1.0)))


class Board:
    """A panel of ``gui`` with one tab (``title``) to build into (``with board:``)."""

    def __init__(self, gui: Any, title: str = TITLE) -> None:
        self.gui, self.title = gui, title
        self.handle = gui.add_panel()
        self.tab = self.handle.add_tab(title)
        self.placed: bool | None = None  # the mode it was last placed for

    def __enter__(self) -> "Board":
        self.tab.__enter__()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.tab.__exit__(*exc)

    def place(self, projector: bool) -> None:
        """Dock it for the mode: left of the arena, or (projector) under the controls."""
        if self.placed == projector:
            return
        self.placed = projector
        with contextlib.suppress(Exception):  # a tab closing meanwhile
            if projector:
                self.handle.dock_below(self.gui.main_panel)
            else:
                self.handle.dock_left()
                self.handle.set_width(WIDTH)

    @property
    def visible(self) -> bool:
        return bool(self.handle.visible)

    @visible.setter
    def visible(self, shown: bool) -> None:
        self.handle.visible = shown

    def remove(self) -> None:
        with contextlib.suppress(Exception):  # removed already
            self.handle.remove()
