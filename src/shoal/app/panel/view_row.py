"""The arena's row of every panel: *Fit all* (the home view widened to everything that matters
now: the robots wherever they went, a source; the camera back straight above), *Follow
swarm* (the swarm's middle stays in the middle of the screen until *Fit all*), *Display*
(shows or hides its boxes below the row: light drawing, 3-D view; hidden at first, so that the
kind's first controls fit at 1280×800), the *projector mode* box (every text twice its size,
:mod:`shoal.app.view.projector`) and the legend of the glyphs on screen (the view's layers
name them; each glyph drawn in its shape, colour and dash: the second cue of a colour)."""

from __future__ import annotations

import html
from dataclasses import dataclass
from typing import Any, Callable, Protocol, Sequence

from .spec import Host

VIEW_BUTTONS = {"Fit all": "fit", "Follow swarm": "follow"}
DISPLAY = "display"  # the action that says a Display box changed
DISPLAY_BUTTON = "Display"  # shows or hides the Display boxes
TEXT_SCALE = 2.0  # of every text in projector mode (the page's own: view.projector.PROJECTOR_SCALE)
SWITCH = "projector mode"  # the header's box (the page script finds it by this label: view.projector.SWITCH)
LIGHT_NOTE = '<span class="shoal-note">◐ <b>Light drawing</b> for software WebGL (no GPU) · view ▸ Display</span>'


@dataclass
class Display:
    """How a tab's arena and page are drawn; the tab keeps it across a swap of panels. The page
    ticks ``light`` itself when it draws in software (:mod:`shoal.app.view.page`)."""

    light: bool = False  # dots for robots' trails, no heading strokes
    orbit: bool = False  # the 3-D view: the mouse orbits (else the top view holds: pan and zoom)
    projector: bool = False  # every text twice its size, the main plot beside the controls

    @property
    def text_scale(self) -> float:
        return TEXT_SCALE if self.projector else 1.0


# (label, Display field, hint): the boxes of the Display folder; the page script finds the first by its label
BOXES = (
    ("light drawing", "light", "for a page drawn without a GPU (ticked by itself there): the arena at half "
                               "resolution, trails as dots, no heading strokes, a plainer grid, so that the page "
                               "keeps up with the run"),
    ("3-D view", "orbit", "the left mouse button orbits the camera; unticked, the top view holds (pan and zoom only)"),
)
PROJECTOR_HINT = ("every text twice its size, for a hall: panel, status, legend, plots and the arena's labels; "
                  "kept for this browser (and in the address: ?projector=1)")


class Glyph(Protocol):
    """A legend entry (the view's ``LegendEntry``): a glyph in a colour and what it stands for."""

    @property
    def glyph(self) -> str: ...

    @property
    def colour(self) -> tuple[int, int, int]: ...

    @property
    def label(self) -> str: ...


OUTLINE = "#222"  # a glyph's edge: every glyph reads on white whatever its colour
# glyph → its SVG shape on a 16 × 12 box ({c}: the colour); a line's dash and width are its second cue
SHAPES = {
    "●": '<circle cx="8" cy="6" r="4.6" fill="{c}" stroke="{o}" stroke-width="1"/>',
    "○": '<circle cx="8" cy="6" r="4.2" fill="none" stroke="{c}" stroke-width="2.4"/>'
         '<circle cx="8" cy="6" r="5.6" fill="none" stroke="{o}" stroke-width="0.6"/>',
    "■": '<rect x="3.5" y="1.5" width="9" height="9" fill="{c}" stroke="{o}" stroke-width="1"/>',
    "◆": '<path d="M8 0.5 L13.5 6 L8 11.5 L2.5 6 Z" fill="{c}" stroke="{o}" stroke-width="1"/>',
    "▲": '<path d="M8 1 L13.5 11 L2.5 11 Z" fill="{c}" stroke="{o}" stroke-width="1"/>',
    "✕": '<path d="M3 1.5 L13 10.5 M13 1.5 L3 10.5" stroke="{c}" stroke-width="2.6"/>',
    "—": '<path d="M1 6 H15" stroke="{c}" stroke-width="2"/>',
    "━": '<path d="M1 6 H15" stroke="{c}" stroke-width="4"/>',
    "╌": '<path d="M1 6 H15" stroke="{c}" stroke-width="2" stroke-dasharray="3 2"/>',
    "┅": '<path d="M1 6 H15" stroke="{c}" stroke-width="4" stroke-dasharray="3 2"/>',
}


def glyph_svg(glyph: str, colour: tuple[int, int, int]) -> str:
    """A legend glyph as a small inline SVG in ``colour`` (a shape, not a letter: it keeps its form
    at any size); a glyph without a shape here stays a letter."""
    c = "rgb(" + ",".join(str(int(v)) for v in colour) + ")"
    shape = SHAPES.get(glyph)
    if shape is None:
        return f'<span style="color:{c};font-weight:700">{html.escape(glyph)}</span>'
    return ('<svg width="1.35em" height="1em" viewBox="0 0 16 12" aria-hidden="true" '
            f'style="vertical-align:-0.12em">{shape.format(c=c, o=OUTLINE)}</svg>')


def legend_html(entries: Sequence[Glyph]) -> str:
    """One compact paragraph: each glyph in its shape and colour, then what it stands for."""
    items = (f'<span style="white-space:nowrap">{glyph_svg(e.glyph, e.colour)}&nbsp;{html.escape(e.label)}</span>'
             for e in entries)
    return '<span class="shoal-legend">' + " &nbsp; ".join(items) + "</span>"


class ViewRow:
    """The view buttons and the Display boxes, sent to ``panel.services.view`` (absent where nothing
    shows a view); the boxes show and set ``panel.services.display``."""

    def __init__(self, panel: Host, legend: Any = None) -> None:
        """``legend``: the markdown handle the legend goes into (the board beside the arena), else
        one is added under the row."""
        self.panel = panel
        act = panel.services.view
        display: Display | None = panel.services.display
        names = tuple(VIEW_BUTTONS) + ((DISPLAY_BUTTON,) if display is not None else ())
        self.buttons = panel.gui.add_button_group("view", names, visible=act is not None,
                                                  hint="Fit all: everything on screen · Follow swarm: keep the swarm "
                                                       "in the middle · Display: light drawing, 3-D view")
        self.boxes: dict[str, Any] = {}
        if display is not None:
            for label, field, hint in BOXES:
                box = panel.gui.add_checkbox(label, bool(getattr(display, field)), hint=hint, visible=False)
                panel.on_user_change(box, self._changed(field, box))
                self.boxes[field] = box
            box = panel.gui.add_checkbox(SWITCH, display.projector, hint=PROJECTOR_HINT)
            panel.on_user_change(box, self._changed("projector", box))
            self.boxes["projector"] = box
        self.legend = legend if legend is not None else panel.gui.add_markdown("")
        self._entries: tuple[Glyph, ...] = ()
        panel.top += [self.buttons, *self.boxes.values()] + ([self.legend] if legend is None else [])

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
        return any(box.visible for field, box in self.boxes.items() if field != "projector")

    def show_boxes(self, shown: bool) -> None:
        """Show or hide the Display boxes (the *Display* button)."""
        for field, box in self.boxes.items():
            if field != "projector":
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
