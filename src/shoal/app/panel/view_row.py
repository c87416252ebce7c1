"""The arena's row of every panel: *Fit all* (the home view widened to everything that matters
now: the robots wherever they went, a source; the camera back straight above), *Follow
swarm* (the swarm's middle stays in the middle of the screen until *Fit all*), *Display*
(shows or hides its boxes below the row: light drawing, 3-D view, large text; hidden at first,
so that the kind's first controls fit at 1280×800) and the legend of the glyphs on screen (the
view's layers name them)."""

from __future__ import annotations

import html
from dataclasses import dataclass
from typing import Any, Callable, Protocol, Sequence

from .spec import Host

VIEW_BUTTONS = {"Fit all": "fit", "Follow swarm": "follow"}
DISPLAY = "display"  # the action that says a Display box changed
DISPLAY_BUTTON = "Display"  # shows or hides the Display boxes
TEXT_SCALE = 1.3  # of the large text
LIGHT_NOTE = '<span style="font-size:0.8em">◐ <b>Light drawing</b> for software WebGL (no GPU) · view ▸ Display</span>'


@dataclass
class Display:
    """How a tab's arena and page are drawn; the tab keeps it across a swap of panels. The page
    ticks ``light`` itself when it draws in software (:mod:`shoal.app.view.page`)."""

    light: bool = False  # dots for robots' trails, no heading strokes
    orbit: bool = False  # the 3-D view: the mouse orbits (else the top view holds: pan and zoom)
    large_text: bool = False  # for a projector

    @property
    def text_scale(self) -> float:
        return TEXT_SCALE if self.large_text else 1.0


# (label, Display field, hint): the boxes of the Display folder; the page script finds the first by its label
BOXES = (
    ("light drawing", "light", "for a page drawn without a GPU (ticked by itself there): the arena at half "
                               "resolution, trails as dots, no heading strokes, a plainer grid, so that the page "
                               "keeps up with the run"),
    ("3-D view", "orbit", "the left mouse button orbits the camera; unticked, the top view holds (pan and zoom only)"),
    ("large text", "large_text", "larger text in the panel and the arena, for a projector"),
)


class Glyph(Protocol):
    """A legend entry (the view's ``LegendEntry``): a glyph in a colour and what it stands for."""

    @property
    def glyph(self) -> str: ...

    @property
    def colour(self) -> tuple[int, int, int]: ...

    @property
    def label(self) -> str: ...


def legend_html(entries: Sequence[Glyph]) -> str:
    """One compact paragraph: each glyph in its colour, then what it stands for."""
    def rgb(c: tuple[int, int, int]) -> str:
        return ",".join(str(int(v)) for v in c)

    items = (f'<span style="color:rgb({rgb(e.colour)});font-weight:700">{html.escape(e.glyph)}</span>&nbsp;'
             f"{html.escape(e.label)}" for e in entries)
    return '<span style="font-size:0.74em;line-height:1.3">' + " &nbsp; ".join(items) + "</span>"


class ViewRow:
    """The view buttons and the Display boxes, sent to ``panel.services.view`` (absent where nothing
    shows a view); the boxes show and set ``panel.services.display``."""

    def __init__(self, panel: Host) -> None:
        self.panel = panel
        act = panel.services.view
        display: Display | None = panel.services.display
        names = tuple(VIEW_BUTTONS) + ((DISPLAY_BUTTON,) if display is not None else ())
        self.buttons = panel.gui.add_button_group("view", names, visible=act is not None,
                                                  hint="Fit all: everything on screen · Follow swarm: keep the swarm "
                                                       "in the middle · Display: light drawing, 3-D view, large text")
        self.boxes: dict[str, Any] = {}
        if display is not None:
            for label, field, hint in BOXES:
                box = panel.gui.add_checkbox(label, bool(getattr(display, field)), hint=hint, visible=False)
                panel.on_user_change(box, self._changed(field, box))
                self.boxes[field] = box
        self.legend = panel.gui.add_markdown("")
        self._entries: tuple[Glyph, ...] = ()
        panel.top += [self.buttons, *self.boxes.values(), self.legend]

        @self.buttons.on_click
        def _(event: Any) -> None:
            if event.target.value == DISPLAY_BUTTON:
                self.show_boxes(not self.showing_boxes)
                return
            action = VIEW_BUTTONS.get(event.target.value)
            if action is not None and act is not None:
                act(action)

    @property
    def showing_boxes(self) -> bool:
        return any(box.visible for box in self.boxes.values())

    def show_boxes(self, shown: bool) -> None:
        """Show or hide the Display boxes (the *Display* button)."""
        for box in self.boxes.values():
            box.visible = shown

    def _changed(self, field: str, box: Any) -> Callable[[], None]:
        def changed() -> None:
            display, act = self.panel.services.display, self.panel.services.view
            if display is None or getattr(display, field) == bool(box.value):
                return
            setattr(display, field, bool(box.value))
            if act is not None:
                act(DISPLAY)
        return changed

    def sync(self, display: Display) -> None:
        """Show ``display`` in the boxes (a change made elsewhere), except on a box whose user's
        tick has arrived and waits for its callback (the page's own tick of the light drawing, say)."""
        for field, box in self.boxes.items():
            self.panel.set_quietly(box, bool(getattr(display, field)))

    def show_legend(self, entries: Sequence[Glyph]) -> None:
        """Show ``entries`` (sent only when they changed)."""
        entries = tuple(dict.fromkeys(entries))
        if entries != self._entries:
            self._entries = entries
            self.legend.content = legend_html(entries)
