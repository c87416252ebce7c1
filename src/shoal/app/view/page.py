"""What a tab's page does by itself for the arena, in one script the server sends it on connect.

viser passes no page events to Python, but it runs a script the server sends
(``RunJavascriptMessage``, as the keyboard shortcuts do). :func:`install_page` sends one that

- keeps the top view flat: the left mouse button and one finger pan instead of orbiting, and the
  orbit angles are held at the top view's (viser also orbits on the arrow keys, and → steps the
  run: it tips nothing now); :func:`set_flat` with False gives the orbit back (the 3-D view);
- renders the arena at half its pixels in the light drawing (:func:`set_light`);
- ticks the *light drawing* box once, when WebGL draws in software (a renderer named SwiftShader,
  llvmpipe, softpipe or "software": the test of viser's own warning), through the box itself, the
  path of a user's click (the view row's *Display* button shows the boxes a moment for it), in
  each tab once it is in view, and without pressing the button again while its answer is on its
  way (a second tab of a loaded server once hid the boxes it had asked for);
- closes viser's "Software WebGL rendering detected" toast whenever it shows (it covered the top
  left of the arena on every load): the status area names the light drawing instead;
- takes a time plot's new rows (``__shoalPage.plot``, sent by :mod:`shoal.app.panel.plot_stream`)
  into viser's GUI store, where a data push would put the whole window, once it has told the server
  it can (through the hidden control the server names); a chart that does not hold the rows an
  append was made for asks for its whole data again;
- lays a plotly figure out only once it has a size and purges one that left the page only a while
  later (plotly's work on a figure still under way as viser purged it was an error in the page);
- scales the page's text (:func:`set_text_scale`: Mantine's ``--mantine-scale``) for a projector.

:func:`install_page` sends three more with it, one concept each: the style sheet and the projector
mode's switch (:mod:`.projector`), the arena's labels as HTML (:mod:`.overlay`), and the names,
announcements and title a screen reader needs (:mod:`.access`).

The camera controls are reached through the page's React tree (the canvas' fiber up to viser's
viewer context, ``mutable.current.cameraControl``, a camera-controls instance): viser's client
internals, hence the upper bound on viser. Where they cannot be found the script leaves the
camera alone and the server straightens a tipped camera (:func:`shoal.app.view.camera.tipped`).
"""

from __future__ import annotations

import contextlib
import json
from typing import Any

from .access import access_script
from .overlay import overlay_script
from .projector import projector_script
from .script import run_script

LIGHT_LABEL = "light drawing"  # the Display box the script ticks …
SHOW_BOXES = "Display"  # … after showing the boxes with the view row's button
# Pixels of the arena per CSS pixel in the light drawing: a software rasteriser's frame costs about
# its pixel count (at 1000 robots: 3.6 frames/s at 1, 6.4 at 0.6, 7.7 at 0.5, on a loaded machine)
LIGHT_DPR = 0.5
SOFTWARE_TOAST = "Software WebGL rendering detected"  # viser's toast (BrowserWarning)
PANEL_WIDTH = 384  # px: the panel of viser's "large" control width (24 em)

PAGE_JS = """
(() => {
  const P = window.__shoalPage || (window.__shoalPage = {});
  if (P.installed) return;
  P.installed = true;
  P.flat = true;        // hold the top view
  P.held = null;        // [azimuth, polar] of the top view, while held
  P.reported = false;   // the light drawing box was looked at (once per page)
  const SOFTWARE = /swiftshader|llvmpipe|softpipe|software/i;
  const LIGHT = %(light)s, SHOW = %(show)s, TOAST = %(toast)s;

  const arena = () => [...document.querySelectorAll("canvas")]
    .reduce((a, c) => (!a || c.width * c.height > a.width * a.height) ? c : a, null);
  P.viewer = () => {
    const c = arena();
    const key = c && Object.keys(c).find((k) => k.startsWith("__reactFiber"));
    for (let f = key && c[key]; f; f = f.return) {
      const v = f.memoizedProps && f.memoizedProps.value;
      if (v && v.mutable && v.mutable.current && "cameraControl" in v.mutable.current) return v;
    }
    return null;
  };
  P.controls = () => { const v = P.viewer(); return v && v.mutable.current.cameraControl; };
  // Straight down on the ground (viser's world +z is three.js' +y), where the camera is going.
  const topDown = (c) => {
    const V = c.camera.position.constructor;
    const d = c.getTarget(new V(), true).sub(c.getPosition(new V(), true)).normalize();
    return -d.y > Math.cos(0.5 * Math.PI / 180);
  };
  // Set only what differs: each assignment wakes the controls, and viser then draws frames back
  // to back for a while (an idle page would never rest).
  const set = (o, key, value) => { if (o[key] !== value) o[key] = value; };
  P.apply = () => {
    const c = P.controls();
    if (!c) return false;
    const A = c.constructor.ACTION;
    if (P.flat) {
      set(c.mouseButtons, "left", A.TRUCK);
      set(c.touches, "one", A.TOUCH_TRUCK);
      if (!P.held && topDown(c)) {  // hold the angles the camera is going to (it may still be easing there)
        const S = c._spherical && c._spherical.constructor;
        const s = S && c.getSpherical ? c.getSpherical(new S(), true) : {theta: c.azimuthAngle, phi: c.polarAngle};
        P.held = [s.theta, s.phi];
      }
      if (P.held) {
        set(c, "minAzimuthAngle", P.held[0]); set(c, "maxAzimuthAngle", P.held[0]);
        set(c, "minPolarAngle", P.held[1]); set(c, "maxPolarAngle", P.held[1]);
      }
    } else {
      set(c.mouseButtons, "left", A.ROTATE);
      set(c.touches, "one", A.TOUCH_ROTATE);
      set(c, "minAzimuthAngle", -Infinity); set(c, "maxAzimuthAngle", Infinity);
      set(c, "minPolarAngle", 0); set(c, "maxPolarAngle", Math.PI);
      P.held = null;
    }
    return true;
  };
  P.setFlat = (flat) => { P.flat = flat; if (flat) P.held = null; P.apply(); };
  // The light drawing renders the arena at a fixed share of its pixels (viser's own fixedDpr
  // setting, which also stops its adaptive resolution); null gives viser's default back.
  P.dpr = null;
  P.setLight = (on) => { P.dpr = on ? %(light_dpr)s : null; P.applyDpr(); };
  P.applyDpr = () => {
    const v = P.viewer();
    if (!v || !v.useDevSettings || !v.useDevSettings.set) return;
    if (v.useDevSettings.get().fixedDpr !== P.dpr) v.useDevSettings.set({fixedDpr: P.dpr});
  };

  const renderer = () => {
    try {
      const c = arena();
      const gl = (c && (c.getContext("webgl2") || c.getContext("webgl")))
        || document.createElement("canvas").getContext("webgl");
      const ext = gl && gl.getExtension("WEBGL_debug_renderer_info");
      return ext ? String(gl.getParameter(ext.UNMASKED_RENDERER_WEBGL) || "") : "";
    } catch (e) { return ""; }
  };
  const box = (label) => {
    const l = [...document.querySelectorAll("label")].find((e) => e.textContent.trim() === label);
    return l && document.getElementById(l.getAttribute("for"));
  };
  const button = (name) => [...document.querySelectorAll("button")].find((b) => b.textContent.trim() === name);
  // Each tab decides for itself, once it is in view (a tab opened behind another draws nothing
  // yet): the boxes are shown with the view row's button, the light drawing ticked, the boxes
  // hidden again. A loaded server may take seconds to show them: the button is pressed again
  // only after SHOW_WAIT (pressing it sooner would hide the boxes it asked for).
  P.report = () => {
    if (P.reported || document.visibilityState === "hidden") return;
    if (P.renderer === undefined) P.renderer = renderer();
    if (!SOFTWARE.test(P.renderer)) { P.reported = true; return; }
    const b = box(LIGHT);
    if (!b) {  // the boxes hide behind the view row's button: show them a moment
      const d = button(SHOW);
      if (d && (!P.shownAt || Date.now() - P.shownAt > %(show_wait)s)) { d.click(); P.shownAt = Date.now(); }
      return;
    }
    if (!b.checked) {
      if (P.tickedAt && Date.now() - P.tickedAt < %(show_wait)s) return;  // (its tick on its way)
      b.click();
      P.tickedAt = Date.now();
      return;
    }
    P.reported = true;  // ticked: hide the boxes again if they were shown for it
    if (P.shownAt) { const d = button(SHOW); if (d) d.click(); }
  };
  document.addEventListener("visibilitychange", () => P.report());
  const dropToast = () => {
    for (const n of document.querySelectorAll(".mantine-Notification-root")) {
      if (!n.textContent.includes(TOAST)) continue;
      const x = n.querySelector(".mantine-Notification-closeButton") || n.querySelector("button");
      if (x) x.click(); else n.remove();
    }
  };
  // viser lays out every plotly figure it holds, also those of a hidden tab at width 0, and
  // purges a figure the moment it leaves the page; plotly's own work on it may still be under way
  // then (a swap of panels), and finding the figure purged it threw (an error in the page). So a
  // figure without a size is drawn once it has one, and a figure that left is purged a while later.
  const guard = (Pl) => {
    if (!Pl || Pl.__shoal) return Pl;
    const react = Pl.react, purge = Pl.purge;
    Pl.react = function (gd, data, layout) {
      if (layout && (!layout.width || !layout.height)) return Promise.resolve(gd);
      return react.apply(this, arguments);
    };
    Pl.purge = function (gd) { setTimeout(() => purge.call(Pl, gd), 10000); return gd; };
    Pl.__shoal = true;
    return Pl;
  };
  if (window.Plotly) guard(window.Plotly);
  else {  // (viser sends plotly's bundle after this script: it sets window.Plotly)
    let real;
    Object.defineProperty(window, "Plotly", {configurable: true, enumerable: true, get: () => real,
                                             set: (v) => { real = guard(v); }});
  }
  new MutationObserver(dropToast).observe(document.body, {childList: true, subtree: true});
  dropToast();
  P.text = (scale) => document.documentElement.style.setProperty("--mantine-scale", String(scale));

  // Plots: say once per panel (P.plotSync: its hidden control) that appended rows are taken here.
  P.plotTold = 0; P.plotAsked = 0;
  const tell = (v, word) => v.mutable.current.sendMessage(
    {type: "GuiUpdateMessage", uuid: P.plotSync, updates: {value: word + " " + (++P.plotTold)}});
  const store = (v) => v && v.useGuiConfig && v.useGuiConfig.get && v.useGuiConfig.set
    && v.mutable.current.sendMessage ? v.useGuiConfig : null;
  P.sayPlots = () => {
    if (!P.plotSync || P.plotSaid === P.plotSync) return;
    const v = P.viewer(), s = store(v);
    if (!s || !s.get(P.plotSync)) return;  // (no store, or its control has not arrived yet)
    tell(v, "appends");
    P.plotSaid = P.plotSync;
  };
  // A missed append: ask for the whole charts, at most once a second (a miss within that second
  // is asked for at its end, never dropped: a paused tab would keep the stale chart)
  P.plotAskTimer = null;
  const askResync = (v) => {
    if (P.plotAskTimer !== null) return;
    const wait = Math.max(0, P.plotAsked + 1000 - Date.now());
    P.plotAskTimer = setTimeout(() => { P.plotAskTimer = null; P.plotAsked = Date.now(); tell(v, "resync"); }, wait);
  };
  // Rows for chart `uuid`, which holds n0 x values from x0 to x1: drop that many from the front,
  // append cols[i] to series i, take `scales`; after the other messages of this batch.
  P.plot = (sync, uuid, n0, x0, x1, drop, cols, scales) => queueMicrotask(() => {
    const v = P.viewer(), s = store(v), conf = s && s.get(uuid);
    if (!conf) return;  // (the chart was removed meanwhile)
    const data = conf.props.data, xs = data && data[0];
    const held = xs && data.length === cols.length && xs.length === n0 && xs[0] === x0 && xs[n0 - 1] === x1;
    if (!held) {
      if (sync === P.plotSync) askResync(v);
      return;
    }
    const out = data.map((a, i) => {
      const c = cols[i], r = new Float64Array(a.length - drop + c.length);
      r.set(a.slice(drop)); r.set(c, a.length - drop);
      return r;
    });
    s.set({[uuid]: {...conf, props: {...conf.props, data: out, scales: scales}}});
  });
  // A veil over the arena while another scene is built: the old one is not taken for the new
  // (shown after a moment, so that a quick swap does not flicker; its seconds count)
  P.veil = (text) => {
    clearTimeout(P.veilTimer); clearInterval(P.veilClock);
    if (P.veilEl) { P.veilEl.remove(); P.veilEl = null; }
    if (text === null) return;
    const start = Date.now();
    P.veilTimer = setTimeout(() => {
      const c = arena(), r = c && c.getBoundingClientRect();
      if (!r) return;
      const v = document.createElement("div");
      v.id = "shoal-veil";
      v.setAttribute("role", "status");
      v.style.cssText = `position:fixed;left:${r.left}px;top:${r.top}px;width:${r.width}px;height:${r.height}px;` +
        "z-index:4;background:rgba(255,255,255,0.82);display:flex;align-items:center;justify-content:center;" +
        "font-size:calc(18px * var(--shoal-k, 1));color:#111;text-align:center;padding:1em";
      document.body.appendChild(v);
      P.veilEl = v;
      const say = () => { v.textContent = `${text} (${Math.round((Date.now() - start) / 1000)} s)`; };
      say();
      P.veilClock = setInterval(say, 500);
    }, 250);
  };
  setInterval(() => { P.apply(); P.applyDpr(); P.report(); P.sayPlots(); }, 400);
})();
"""


SHOW_WAIT_MS = 15000  # the page presses Display or ticks the box again only after this long without an answer


def page_script() -> str:
    return PAGE_JS % {"light": json.dumps(LIGHT_LABEL), "show": json.dumps(SHOW_BOXES),
                      "toast": json.dumps(SOFTWARE_TOAST), "light_dpr": json.dumps(LIGHT_DPR),
                      "show_wait": SHOW_WAIT_MS}


def install_page(gui: Any) -> None:
    """Send the page scripts to the page of ``gui`` (once per page; a second copy does nothing).
    Sent before the tab's panel, so that what the tab tells the page while it is built arrives."""
    run_script(gui, page_script())
    run_script(gui, projector_script())
    run_script(gui, overlay_script())
    run_script(gui, access_script())


def set_flat(gui: Any, flat: bool) -> None:
    """Hold the top view (True) or give the orbit back (False: the 3-D view)."""
    run_script(gui, f"window.__shoalPage && window.__shoalPage.setFlat({json.dumps(bool(flat))});")


def set_light(gui: Any, light: bool) -> None:
    """Render the arena at :data:`LIGHT_DPR` (True) or as viser chooses (False)."""
    run_script(gui, f"window.__shoalPage && window.__shoalPage.setLight({json.dumps(bool(light))});")


def set_veil(gui: Any, text: str | None) -> None:
    """Veil the arena with ``text`` (and the seconds it has waited) while another scene is built;
    None lifts it."""
    run_script(gui, f"window.__shoalPage && window.__shoalPage.veil && window.__shoalPage.veil({json.dumps(text)});")


def set_text_scale(gui: Any, scale: float) -> None:
    """Scale the page's text (and the panel's spacing with it) by ``scale``, and widen the panel as
    much (its controls keep their room)."""
    run_script(gui, f"window.__shoalPage && window.__shoalPage.text({float(scale)!r});")
    with contextlib.suppress(AttributeError):  # a viser without panel placement: the width stays
        gui.main_panel.set_width(round(PANEL_WIDTH * scale))
