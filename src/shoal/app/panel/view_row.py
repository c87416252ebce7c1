"""The arena's row of every panel: *Fit all* (the home view widened to everything that matters
now: the robots wherever they went, a source; the camera back straight above), *Follow
swarm* (the swarm's middle stays in the middle of the screen until *Fit all*) and the legend
of the glyphs on screen (the view's layers name them)."""

from __future__ import annotations

import html
from typing import Any, Protocol, Sequence

from .spec import Host

VIEW_BUTTONS = {"Fit all": "fit", "Follow swarm": "follow"}


class Glyph(Protocol):
    """A legend entry (the view's ``LegendEntry``): a glyph in a colour and what it stands for."""

    glyph: str
    colour: tuple[int, int, int]
    label: str


def legend_html(entries: Sequence[Glyph]) -> str:
    """One compact paragraph: each glyph in its colour, then what it stands for."""
    def rgb(c: tuple[int, int, int]) -> str:
        return ",".join(str(int(v)) for v in c)

    items = (f'<span style="color:rgb({rgb(e.colour)});font-weight:700">{html.escape(e.glyph)}</span>&nbsp;'
             f"{html.escape(e.label)}" for e in entries)
    return '<span style="font-size:0.74em;line-height:1.3">' + " &nbsp; ".join(items) + "</span>"


class ViewRow:
    """The view buttons, sent to ``panel.services.view`` (absent where nothing shows a view)."""

    def __init__(self, panel: Host) -> None:
        self.panel = panel
        act = panel.services.view
        self.buttons = panel.gui.add_button_group("view", tuple(VIEW_BUTTONS), visible=act is not None,
                                                  hint="Fit all: everything on screen · Follow swarm: "
                                                       "keep the swarm in the middle")
        self.legend = panel.gui.add_markdown("")
        self._entries: tuple[Glyph, ...] = ()
        panel.top += [self.buttons, self.legend]

        @self.buttons.on_click
        def _(event: Any) -> None:
            action = VIEW_BUTTONS.get(event.target.value)
            if action is not None and act is not None:
                act(action)

    def show_legend(self, entries: Sequence[Glyph]) -> None:
        """Show ``entries`` (sent only when they changed)."""
        entries = tuple(dict.fromkeys(entries))
        if entries != self._entries:
            self._entries = entries
            self.legend.content = legend_html(entries)

