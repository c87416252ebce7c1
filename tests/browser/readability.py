"""What a page shows as text, measured in the page: the browser tests of issue 32 and
``benchmarks/bench_readability.py`` share it.

:data:`TEXT_JS` lists every visible text node of the page (in the window, not hidden, not
covered: the element found at the middle of its box is its own element or inside it; for a text
that lets pointer events through, as the labels over the arena do, the arena's canvas) with its
computed font size and its WCAG 2.1 contrast against the background it is drawn on (the
backgrounds of its element and its ancestors composited over white; a text over the arena's
canvas without a background of its own is measured against the canvas pixels under it, read by
the caller from a screenshot). :func:`unnamed_controls` counts the controls that the page's
accessibility tree gives no name (Playwright's ARIA snapshot).
"""

from __future__ import annotations

import re
import statistics
from dataclasses import dataclass
from typing import Any

TEXT_JS = r"""
(() => {
  const parse = (c) => {
    const m = c && c.match(/rgba?\(([^)]+)\)/);
    if (!m) return null;
    const v = m[1].split(/[ ,\/]+/).filter(Boolean).map(Number);
    return [v[0], v[1], v[2], v.length > 3 ? v[3] : 1];
  };
  const over = (top, under) => {  // top (with alpha) composited over an opaque colour
    const a = top[3];
    return [0, 1, 2].map((i) => top[i] * a + under[i] * (1 - a));
  };
  const lum = (c) => {
    const f = (v) => { v /= 255; return v <= 0.04045 ? v / 12.92 : Math.pow((v + 0.055) / 1.055, 2.4); };
    return 0.2126 * f(c[0]) + 0.7152 * f(c[1]) + 0.0722 * f(c[2]);
  };
  const ratio = (a, b) => { const x = lum(a), y = lum(b); return (Math.max(x, y) + 0.05) / (Math.min(x, y) + 0.05); };
  // The background an element is drawn on: its own and its ancestors' colours, nearest on top.
  // null: nothing opaque below it but the arena's canvas (the caller samples the pixels).
  const canvases = [...document.querySelectorAll("canvas")];
  const arena = canvases.reduce((a, c) => (!a || c.width * c.height > a.width * a.height) ? c : a, null);
  const onArena = (r) => {
    if (!arena) return false;
    const b = arena.getBoundingClientRect();
    return r.left >= b.left - 1 && r.right <= b.right + 1 && r.top >= b.top - 1 && r.bottom <= b.bottom + 1;
  };
  const background = (el, rect) => {
    const layers = [];
    let opacity = 1;
    for (let e = el; e && e.nodeType === 1; e = e.parentElement) {
      const s = getComputedStyle(e);
      opacity *= Number(s.opacity);
      const c = parse(s.backgroundColor);
      if (c && c[3] > 0) { layers.push(c); if (c[3] >= 0.999) break; }
    }
    const opaque = layers.length && layers[layers.length - 1][3] >= 0.999;
    if (!opaque && onArena(rect)) return {layers, base: null, opacity};
    let bg = [255, 255, 255];
    for (let i = layers.length - 1; i >= 0; i--) bg = over(layers[i], bg);
    return {layers, base: bg, opacity};
  };
  const out = [];
  const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  const range = document.createRange();
  for (let n = walker.nextNode(); n; n = walker.nextNode()) {
    const text = n.textContent.replace(/\s+/g, " ").trim();
    if (!text) continue;
    const el = n.parentElement;
    if (!el || el.closest("script,style,noscript,svg title")) continue;
    range.selectNodeContents(n);
    const rects = [...range.getClientRects()].filter((r) => r.width > 0.5 && r.height > 0.5);
    if (!rects.length) continue;
    const r = rects.reduce((a, b) => (a.width * a.height >= b.width * b.height ? a : b));
    const x = r.left + r.width / 2, y = r.top + r.height / 2;
    if (x < 0 || y < 0 || x >= innerWidth || y >= innerHeight) continue;
    const s = getComputedStyle(el);
    if (s.visibility !== "visible") continue;
    const hit = document.elementsFromPoint(x, y);
    if (s.pointerEvents === "none") {
      // a text that lets pointer events through (a label over the arena) is never among the elements
      // found at a point: it shows where the first element found is the arena's canvas
      if (!hit.length || hit[0] !== arena) continue;
    } else if (!hit.length || !(hit[0] === el || el.contains(hit[0]) || hit[0].contains(el))) {
      // covered or clipped, unless what lies on top lets pointer events through and el is below it
      if (!hit.includes(el) || !hit.slice(0, hit.indexOf(el)).every(
          (h) => getComputedStyle(h).pointerEvents === "none" || h.contains(el))) continue;
    }
    const bg = background(el, r);
    if (bg.opacity < 0.05) continue;
    const fg = parse(s.color) || [0, 0, 0, 1];
    const item = {text: text.slice(0, 60), size: parseFloat(s.fontSize), weight: Number(s.fontWeight) || 400,
                  x: r.left, y: r.top, w: r.width, h: r.height, color: fg, opacity: bg.opacity,
                  layers: bg.layers, onCanvas: bg.base === null,
                  tag: el.tagName.toLowerCase(), cls: String(el.className || "").slice(0, 80)};
    if (bg.base !== null) item.contrast = ratio(over([fg[0], fg[1], fg[2], fg[3] * bg.opacity], bg.base), bg.base);
    out.push(item);
  }
  return out;
})()
"""

# Fonts the page's plots draw with (uPlot draws its axes on a canvas of its own): every
# fillText on a canvas in the document, the fonts since the canvas was last cleared whole.
CANVAS_FONTS = """
(() => {
  const fonts = new WeakMap();
  const clear = CanvasRenderingContext2D.prototype.clearRect;
  CanvasRenderingContext2D.prototype.clearRect = function (x, y, w, h) {
    if (x <= 0 && y <= 0 && w >= this.canvas.width && h >= this.canvas.height) fonts.set(this.canvas, new Map());
    return clear.apply(this, arguments);
  };
  const fill = CanvasRenderingContext2D.prototype.fillText;
  CanvasRenderingContext2D.prototype.fillText = function (text) {
    let m = fonts.get(this.canvas);
    if (!m) { m = new Map(); fonts.set(this.canvas, m); }
    if (String(text).trim()) m.set(this.font + "|" + String(text).slice(0, 20), this.font);
    return fill.apply(this, arguments);
  };
  window.__shoalCanvasFonts = () => {
    const out = [];
    for (const c of document.querySelectorAll("canvas")) {
      const m = fonts.get(c);
      const r = c.getBoundingClientRect();
      if (!m || r.width < 2 || r.bottom < 0 || r.top > innerHeight || r.right < 0 || r.left > innerWidth) continue;
      const s = getComputedStyle(c);
      if (s.visibility !== "visible" || !c.offsetParent) continue;
      const scale = r.width / c.width;  // canvas pixels → CSS pixels
      for (const [key, font] of m) {
        const px = font.match(/([\\d.]+)px/);
        if (px) out.push({text: key.split("|")[1], size: parseFloat(px[1]) * scale});
      }
    }
    return out;
  };
})();
"""


def canvas_texts(page: Any) -> list[dict]:
    """Text the page drew into its canvases since each was last cleared whole (:data:`CANVAS_FONTS`,
    installed before the page loaded): text and size in CSS pixels."""
    return page.evaluate("window.__shoalCanvasFonts ? window.__shoalCanvasFonts() : []")


CONTROL_ROLES = ("button", "checkbox", "combobox", "slider", "spinbutton", "textbox", "switch", "radio", "tab",
                 "listbox", "searchbox", "menuitem")
_LINE = re.compile(r"^\s*-\s+(?P<role>[a-z]+)(?P<rest>.*)$")


def relative_luminance(rgb: tuple[float, float, float]) -> float:
    def f(v: float) -> float:
        v /= 255.0
        return v / 12.92 if v <= 0.04045 else ((v + 0.055) / 1.055) ** 2.4
    return 0.2126 * f(rgb[0]) + 0.7152 * f(rgb[1]) + 0.0722 * f(rgb[2])


def contrast(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    """WCAG 2.1 contrast ratio of two opaque sRGB colours (0–255)."""
    x, y = relative_luminance(a), relative_luminance(b)
    return (max(x, y) + 0.05) / (min(x, y) + 0.05)


def _over(top: list[float], under: tuple[float, float, float]) -> tuple[float, float, float]:
    a = top[3] if len(top) > 3 else 1.0
    return tuple(top[i] * a + under[i] * (1 - a) for i in range(3))  # type: ignore[return-value]


def texts(page: Any, screenshot: Any = None) -> list[dict]:
    """Every visible text node of ``page`` (see :data:`TEXT_JS`), each with its ``contrast``. A text
    over the arena's canvas with no background of its own is measured against the pixels under
    its box in ``screenshot`` (a PIL image of the page; taken here when not given): the lowest
    contrast over the box's pixels, its own background layers composited over them."""
    items = page.evaluate(TEXT_JS)
    need = [t for t in items if t["onCanvas"]]
    if need:
        img = screenshot if screenshot is not None else _screenshot(page)
        for t in need:
            t["contrast"] = _canvas_contrast(img, t)
    return items


def _screenshot(page: Any) -> Any:
    import io

    from PIL import Image

    return Image.open(io.BytesIO(page.screenshot())).convert("RGB")


def _canvas_contrast(img: Any, t: dict) -> float:
    """The text's contrast against the pixels around its glyphs: the 10th percentile of the
    contrast between its colour and the box's pixels that are not its colour (the glyphs)."""
    import numpy as np

    scale = img.width / max(1.0, float(t.get("vw", 0)) or img.width)
    x0, y0 = int(max(0, t["x"] * scale)), int(max(0, t["y"] * scale))
    x1, y1 = int(min(img.width, (t["x"] + t["w"]) * scale)), int(min(img.height, (t["y"] + t["h"]) * scale))
    if x1 <= x0 or y1 <= y0:
        return float("nan")
    box = np.asarray(img.crop((x0, y0, x1, y1)), dtype=float).reshape(-1, 3)
    fg = np.array(t["color"][:3], dtype=float)
    far = box[np.linalg.norm(box - fg, axis=1) > 60]  # not the glyphs' own pixels
    if not len(far):
        return float("nan")
    ratios = sorted(contrast(tuple(fg), tuple(p)) for p in far[:: max(1, len(far) // 400)])
    return float(ratios[len(ratios) // 10])


@dataclass(frozen=True)
class Summary:
    """The numbers of one page: how many text nodes, their median and smallest font size, the
    lowest contrast, and those below ``small`` px or ``low`` contrast."""

    count: int
    median_px: float
    min_px: float
    min_contrast: float
    smallest: tuple[str, ...]
    palest: tuple[str, ...]

    def row(self) -> dict[str, Any]:
        return {"texts": self.count, "median_px": round(self.median_px, 1), "min_px": round(self.min_px, 1),
                "min_contrast": round(self.min_contrast, 2)}


def summary(items: list[dict], small: float = 12.0, low: float = 4.5) -> Summary:
    sizes = [t["size"] for t in items]
    ratios = [t["contrast"] for t in items if t.get("contrast") == t.get("contrast") and "contrast" in t]
    smallest = tuple(f"{t['text']!r} {t['size']:.1f}px" for t in sorted(items, key=lambda t: t["size"])
                     if t["size"] < small)
    palest = tuple(f"{t['text']!r} {t['contrast']:.2f}:1" for t in sorted(items, key=lambda t: t.get("contrast", 99))
                   if t.get("contrast", 99) < low)
    return Summary(len(items), statistics.median(sizes) if sizes else float("nan"), min(sizes, default=float("nan")),
                   min(ratios, default=float("nan")), smallest, palest)


def aria_controls(snapshot: str) -> list[tuple[str, str]]:
    """(role, name) of every control in a Playwright ARIA snapshot (YAML); name "" when it has none."""
    out = []
    for line in snapshot.splitlines():
        m = _LINE.match(line)
        if not m or m["role"] not in CONTROL_ROLES:
            continue
        rest = m["rest"].strip()
        name = ""
        if rest.startswith('"'):
            name = rest[1:].split('"', 1)[0]
        elif rest.startswith("/"):
            name = rest[1:].split("/", 1)[0]
        out.append((m["role"], name.strip()))
    return out


def unnamed_controls(page: Any) -> list[str]:
    """The controls of the page that have no accessible name (their roles)."""
    return [role for role, name in aria_controls(page.locator("body").aria_snapshot()) if not name]
