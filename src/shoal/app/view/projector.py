"""How the page's text looks, in both modes, and the projector mode's switch.

Every tab gets one style sheet (:data:`STYLE_CSS`): nothing under 12 px (viser draws slider
marks at 9 px and buttons at 11 px), labels and hints dark enough for WCAG AA on white (viser's
"dimmed" grey is 3.3:1), and the page's own text (the legend, the labels over the arena) sized in
``--shoal-k`` units. **Projector mode** (``html.shoal-projector``) doubles every text: Mantine's
``--mantine-scale`` (the panel, :func:`shoal.app.view.page.set_text_scale`), ``--shoal-k``
(the rest of the page), the plots' axes and figures (the panel's ``text_scale``).

The mode is one box in the panel's header (:data:`SWITCH`). The page keeps a user's choice for the
browser (``localStorage``) and in the address (``?projector=1``, which a lecturer can bookmark):
:data:`PROJECTOR_JS` reads them when the page loads and ticks the box if they differ from what
the server chose (``shoal serve --projector`` starts every tab in it); :func:`set_projector`
applies a change and, for a user's change, remembers it.
"""

from __future__ import annotations

import json
from typing import Any

from .script import run_script

SWITCH = "projector mode"  # the header's box; the page script finds it by this label
PROJECTOR_SCALE = 2.0  # of every text of the page
PARAM = "projector"  # ?projector=1 / ?projector=0
STORE = "shoal-projector"  # localStorage key: "1" or "0"
MIN_PX = 12  # nothing smaller outside projector mode (16 px at least in it, 24 in practice)
DIMMED = "#495057"  # labels and hints: 8.2:1 on white (viser's #868e96 is 3.3:1)
BRAND = (28, 74, 168)  # buttons' and tabs' text: 8.0:1 on white (40, 90, 200 gave 4.2:1)

STYLE_CSS = """
:root { --shoal-k: 1; }
html.shoal-projector { --shoal-k: %(scale)s; }
:root, :root[data-mantine-color-scheme="light"] {
  --mantine-color-dimmed: %(dimmed)s !important;
  --mantine-font-size-xs: calc(%(min)spx * var(--mantine-scale)) !important;
}
.mantine-Slider-markLabel {
  font-size: calc(%(min)spx * var(--mantine-scale)) !important; color: %(dimmed)s !important;
}
.mantine-Slider-markLabel { transform: translate(-50%%, 0.1rem) !important; }
.mantine-Tooltip-tooltip { font-size: calc(%(min)spx * var(--mantine-scale)) !important; }
.shoal-legend { font-size: calc(%(min)spx * var(--shoal-k)); line-height: 1.45; }
.mantine-Notification-description { color: %(dimmed)s !important; }
.u-legend { font-size: calc(%(min)spx * var(--shoal-k)) !important; }
.u-title { font-size: calc(14px * var(--shoal-k)) !important; }
.shoal-note { font-size: calc(%(min)spx * var(--shoal-k)); }
/* a stray click on the strip above a docked panel no longer folds it away: only its chevron does */
[data-dock-region-handle], [data-dock-column-handle] { pointer-events: none; }
[data-dock-region-handle] button, [data-dock-column-handle] button,
[data-dock-region-handle] [role="button"], [data-dock-column-handle] [role="button"] { pointer-events: auto; }
"""

PROJECTOR_JS = """
(() => {
  const P = window.__shoalPage || (window.__shoalPage = {});
  if (P.projectorInstalled) return;
  P.projectorInstalled = true;
  const SWITCH = %(switch)s, PARAM = %(param)s, STORE = %(store)s;
  const style = document.createElement("style");
  style.id = "shoal-style";
  style.textContent = %(css)s;
  document.head.appendChild(style);
  const truthy = (v) => v === "1" || v === "true" || v === "on";
  // The browser's choice: the address first (a bookmark), then what it chose before (null: none)
  P.projectorChoice = () => {
    const q = new URLSearchParams(location.search).get(PARAM);
    if (q !== null) return truthy(q);
    try { const v = localStorage.getItem(STORE); return v === null ? null : truthy(v); } catch (e) { return null; }
  };
  P.projectorWanted = P.projectorChoice();
  P.projector = false;
  P.setProjector = (on, remember) => {
    P.projector = on;
    document.documentElement.classList.toggle("shoal-projector", on);
    if (!remember) return;
    P.projectorWanted = on;
    try { localStorage.setItem(STORE, on ? "1" : "0"); } catch (e) {}
    const u = new URL(location.href);
    if (on) u.searchParams.set(PARAM, "1"); else u.searchParams.delete(PARAM);
    history.replaceState(history.state, "", u);
  };
  const box = (label) => {
    const l = [...document.querySelectorAll("label")].find((e) => e.textContent.trim() === label);
    return l && document.getElementById(l.getAttribute("for"));
  };
  // Once the switch shows, tick it (the path of a user's click) if the browser's choice differs
  const timer = setInterval(() => {
    if (P.projectorWanted === null) { clearInterval(timer); return; }
    const b = box(SWITCH);
    if (!b) return;
    clearInterval(timer);
    if (b.checked !== P.projectorWanted) b.click();
  }, 250);
})();
"""


def style_css() -> str:
    return STYLE_CSS % {"scale": PROJECTOR_SCALE, "dimmed": DIMMED, "min": MIN_PX}


def projector_script() -> str:
    return PROJECTOR_JS % {"switch": json.dumps(SWITCH), "param": json.dumps(PARAM), "store": json.dumps(STORE),
                           "css": json.dumps(style_css())}


def set_projector(gui: Any, on: bool, remember: bool) -> None:
    """Tell the page that projector mode is ``on`` (``remember``: a user's choice, kept for the
    browser and written into the address)."""
    run_script(gui, f"window.__shoalPage && window.__shoalPage.setProjector && "
                    f"window.__shoalPage.setProjector({json.dumps(bool(on))}, {json.dumps(bool(remember))});")
