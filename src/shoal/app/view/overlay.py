"""The arena's text as HTML over the canvas, sharp whatever the canvas' resolution.

viser draws a scene label into the WebGL canvas, which the light drawing renders at half its
pixels: 8 px labels came out blurred. Here a label is an invisible node of the scene (a frame,
:meth:`shoal.app.view.canvas.Canvas.label`) that places it, and a ``<div>`` over the canvas that
shows it: :data:`OVERLAY_JS` finds each node's three.js object (viser's ``nodeRefFromName``),
projects its world position with the page's camera every animation frame, and moves the text
there, dark on white, in CSS pixels (``--shoal-k`` of the projector mode), never under the
page's smallest text (:data:`~.projector.MIN_PX`). :class:`Labels` is what a canvas tells its
page: a label's text, anchor and size, whether it shows, and when it goes.

A lecture's class sees the broadcast's arena, drawn once on the server-wide scene for every
watcher: :class:`ClassLabels` keeps the whole state of its labels in one element of the
broadcast's panel (:meth:`ClassLabels.holder_html`, ``[data-shoal-labels]``), which viser sends every
watcher once serialised and gives a watcher that joins late, and the page follows it.
"""

from __future__ import annotations

import html
import json
from typing import Any

from .projector import MIN_PX
from .script import run_script

LABEL_PX = 13.0  # a label of scale 1 (viser's screen labels are 12 px × their scale)
HOLDER = "data-shoal-labels"  # the attribute of the element that holds a class's labels
FOLLOW_MS = 200  # how often a page looks at that element


def label_px(scale: float) -> float:
    """The CSS size of a label of ``scale`` (before the projector's factor): never under the page's smallest text."""
    return round(max(float(MIN_PX), LABEL_PX * scale), 2)


OVERLAY_JS = """
(() => {
  const P = window.__shoalPage || (window.__shoalPage = {});
  if (P.overlayInstalled) return;
  P.overlayInstalled = true;
  const style = document.createElement("style");
  style.textContent = `
    #shoal-labels { position: fixed; left: 0; top: 0; width: 0; height: 0; pointer-events: none; z-index: 3; }
    #shoal-labels > div { position: absolute; left: 0; top: 0; white-space: nowrap; color: #111;
      background: #fff; border: 1px solid rgba(0,0,0,0.25); border-radius: 3px; padding: 0 0.25em;
      line-height: 1.25; font-family: system-ui, -apple-system, "Segoe UI", Roboto, sans-serif;
      will-change: transform; }`;
  document.head.appendChild(style);
  const layer = document.createElement("div");
  layer.id = "shoal-labels";
  layer.setAttribute("aria-hidden", "true");
  document.body.appendChild(layer);
  const labels = new Map();  // node name -> {el, anchor, shown, key}
  const SHIFT = {"top-left": [0, 0], "top-center": [-50, 0], "top-right": [-100, 0],
                 "center-left": [0, -50], "center-center": [-50, -50], "center-right": [-100, -50],
                 "bottom-left": [0, -100], "bottom-center": [-50, -100], "bottom-right": [-100, -100]};
  P.label = (name, text, anchor, px, shown) => {
    let l = labels.get(name);
    if (!l) {
      const el = document.createElement("div");
      el.className = "shoal-label";
      layer.appendChild(el);
      l = {el, anchor: "top-left", shown: true, key: ""};
      labels.set(name, l);
    }
    if (text !== null) l.el.textContent = text;
    if (anchor !== null) l.anchor = anchor;
    if (px !== null) l.el.style.fontSize = `calc(${px}px * var(--shoal-k, 1))`;
    if (shown !== null) l.shown = shown;
    l.key = "";
  };
  P.unlabel = (names) => {
    for (const n of names) { const l = labels.get(n); if (l) { l.el.remove(); labels.delete(n); } }
  };
  const shownInScene = (o) => { for (; o; o = o.parent) if (!o.visible) return false; return true; };
  // A class's labels: the whole state in the attribute __HOLDER__ of one element of the panel
  // ({name: [text, anchor, px, shown]}), followed here; only the labels it named are dropped with it.
  const followed = new Set();
  let held = null, lookedAt = 0;
  const follow = (now) => {
    if (now - lookedAt < __FOLLOW_MS__) return;
    lookedAt = now;
    const holder = document.querySelector("[__HOLDER__]");
    const text = holder ? holder.getAttribute("__HOLDER__") : null;
    if (text === held) return;
    held = text;
    let state = {};
    try { state = text ? JSON.parse(text) : {}; } catch (e) { state = {}; }
    if (!state || typeof state !== "object") state = {};
    const has = (name) => Object.prototype.hasOwnProperty.call(state, name);
    for (const name of [...followed]) if (!has(name)) { P.unlabel([name]); followed.delete(name); }
    for (const [name, v] of Object.entries(state)) {
      if (!Array.isArray(v) || v.length !== 4) continue;
      P.label(name, String(v[0]), String(v[1]), Number(v[2]), !!v[3]);
      followed.add(name);
    }
  };
  let V = null;
  const frame = (now) => {
    requestAnimationFrame(frame);
    follow(now || 0);
    if (!labels.size) return;
    const v = P.viewer && P.viewer();
    const m = v && v.mutable && v.mutable.current;
    const canvas = m && m.canvas;
    const c = m && m.cameraControl;
    if (!canvas || !c || !m.nodeRefFromName) return;
    const cam = c.camera;
    const r = canvas.getBoundingClientRect();
    if (!V) V = cam.position.constructor;
    const p = new V();
    for (const [name, l] of labels) {
      const o = m.nodeRefFromName[name];
      let show = l.shown && !!o && shownInScene(o);
      let key = "hidden";
      if (show) {
        o.getWorldPosition(p);
        p.project(cam);
        show = p.z > -1 && p.z < 1;
        const x = r.left + (p.x + 1) / 2 * r.width, y = r.top + (1 - p.y) / 2 * r.height;
        show = show && x >= r.left - 2 && x <= r.right + 2 && y >= r.top - 2 && y <= r.bottom + 2;
        const s = SHIFT[l.anchor] || SHIFT["top-left"];
        key = show ? `translate(${x.toFixed(1)}px, ${y.toFixed(1)}px) translate(${s[0]}%, ${s[1]}%)` : "hidden";
      }
      if (key === l.key) continue;  // unchanged: touch nothing
      l.key = key;
      if (key === "hidden") l.el.style.display = "none";
      else { l.el.style.display = ""; l.el.style.transform = key; }
    }
  };
  requestAnimationFrame(frame);
})();
"""


def overlay_script() -> str:
    return OVERLAY_JS.replace("__HOLDER__", HOLDER).replace("__FOLLOW_MS__", str(FOLLOW_MS))


class Labels:
    """What a canvas tells its page about the labels over the arena (``api``: anything with viser's
    ``_websock_interface``: a client's scene or GUI)."""

    def __init__(self, api: Any) -> None:
        self.api = api

    def _run(self, source: str) -> None:
        run_script(self.api, source)

    def put(self, name: str, text: str | None = None, anchor: str | None = None, scale: float | None = None,
            shown: bool | None = None) -> None:
        """Create or change the label of node ``name`` (None: leave that part as it is)."""
        px = None if scale is None else label_px(scale)
        args = ", ".join(json.dumps(v) for v in (name, text, anchor, px, shown))
        self._run(f"window.__shoalPage && window.__shoalPage.label && window.__shoalPage.label({args});")

    def drop(self, names: list[str]) -> None:
        if names:
            self._run(f"window.__shoalPage && window.__shoalPage.unlabel && "
                      f"window.__shoalPage.unlabel({json.dumps(names)});")


class ClassLabels:
    """The labels of the arena a lecture's class watches (a canvas' ``labels``, as :class:`Labels`):
    their whole state, which :meth:`holder_html` gives the broadcast's panel to show every watcher."""

    def __init__(self) -> None:
        self.state: dict[str, list[Any]] = {}  # node name -> [text, anchor, px, shown]
        self.revision = 0  # bumped by every change

    def put(self, name: str, text: str | None = None, anchor: str | None = None, scale: float | None = None,
            shown: bool | None = None) -> None:
        old = self.state.get(name)
        was = old if old is not None else ["", "top-left", label_px(1.0), True]
        now = [was[0] if text is None else str(text), was[1] if anchor is None else str(anchor),
               was[2] if scale is None else label_px(scale), was[3] if shown is None else bool(shown)]
        if now != old:
            self.state[name] = now
            self.revision += 1

    def drop(self, names: list[str]) -> None:
        for name in names:
            if self.state.pop(name, None) is not None:
                self.revision += 1

    def holder_html(self) -> str:
        """An element that shows nothing and holds every label (the page's overlay follows it)."""
        data = html.escape(json.dumps(self.state, separators=(",", ":")), quote=True)
        return f'<div hidden {HOLDER}="{data}"></div>'
