"""Helpers shared by the real-browser tests: Chromium flags, waiting, and finding viser's
inputs by their labels."""

from __future__ import annotations

import math
import re
import shutil
import time
from contextlib import contextmanager
from typing import Iterator

import numpy as np
import pytest

ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
VIEWPORT = {"width": 1280, "height": 800}


# viser's page renders the arena only while an IntersectionObserver says its canvas is in view
# (the client mounts a no-op render loop of top priority otherwise: the panel stays live, the
# scene tree fills, the canvas stays blank but for the axes gizmo). Headless Chromium on a busy
# machine sometimes leaves the observer's last report at "not in view" for a canvas that fills
# the window, which is the empty arena seen on load or after a click. This init script keeps
# the observer's reports and adds the one it failed to send: every 0.5 s an element last
# reported (or not yet reported) out of view that lies inside the window is reported in view.
ARENA_IN_VIEW = """
(() => {
  const Native = window.IntersectionObserver;
  if (!Native) return;
  window.IntersectionObserver = class extends Native {
    constructor(callback, options) {
      const shown = new Map();  // element -> last "in view" told to the page
      super((entries, observer) => {
        for (const e of entries) if (shown.has(e.target)) shown.set(e.target, e.isIntersecting);
        callback(entries, observer);
      }, options);
      this._shown = shown;
      this._timer = setInterval(() => {
        for (const [el, inView] of shown) {
          if (inView) continue;
          const r = el.getBoundingClientRect();
          const inside = r.bottom > 0 && r.right > 0 && r.top < innerHeight && r.left < innerWidth;
          if (r.width > 0 && r.height > 0 && inside) {
            shown.set(el, true);
            callback([{target: el, isIntersecting: true, intersectionRatio: 1, boundingClientRect: r,
                       intersectionRect: r, rootBounds: null, time: performance.now()}], this);
          }
        }
      }, 500);
    }
    observe(el) { if (!this._shown.has(el)) this._shown.set(el, false); super.observe(el); }
    unobserve(el) { this._shown.delete(el); super.unobserve(el); }
    disconnect() { clearInterval(this._timer); this._shown.clear(); super.disconnect(); }
  };
})();
"""


def arena_in_view(target):
    """Install :data:`ARENA_IN_VIEW` on a Playwright page or browser context (before it loads the app)."""
    target.add_init_script(ARENA_IN_VIEW)
    return target


def wait_until(cond, timeout: float = 45.0, what: str = "condition"):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = cond()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def root_for(page, label: str):
    """The visible input element viser labels exactly ``label`` (``<label for=id>``)."""
    exact = re.compile(rf"^\s*{re.escape(label)}\s*$")
    fid = page.locator("label").filter(has_text=exact).first.get_attribute("for")
    return page.locator(f'[id="{fid}"]')


def number_box(page, label: str):
    """The number box beside a slider."""
    return root_for(page, label).locator("xpath=..").locator(".mantine-NumberInput-input")


def choose(page, label: str, option: str) -> None:
    root_for(page, label).click()
    page.get_by_role("option", name=option, exact=True).click()


def upload_input(page, label: str):
    """The hidden file input of viser's upload button ``label`` (there may be several on a page)."""
    fid = page.get_by_role("button", name=label, exact=True).get_attribute("id")
    return page.locator(f'[id="file_upload_{fid}"]')


def dismiss_toasts(page) -> None:
    closes = page.locator(".mantine-Notification-root button")
    for i in range(closes.count()):
        try:
            closes.nth(i).click(timeout=1000)
        except Exception:
            pass


def canvas_box(page):
    """The page box of the 3-D canvas (the largest canvas)."""
    boxes = [b for b in (c.bounding_box() for c in page.locator("canvas").all()) if b]
    return max(boxes, key=lambda b: b["width"] * b["height"])


PAGE_CAMERA = """
(() => {
  const c = window.__shoalPage && window.__shoalPage.controls && window.__shoalPage.controls();
  if (!c) return null;
  const V = c.camera.position.constructor;
  const p = c.getPosition(new V()), t = c.getTarget(new V());
  return {position: [p.x, p.y, p.z], target: [t.x, t.y, t.z], fov: c.camera.fov};
})()
"""


def page_camera(page) -> dict | None:
    """The camera the page draws with, read from its camera controls (None where the page script
    cannot reach them): ``look_at`` and ``position`` in viser's world (+z up), ``fov`` in radians."""
    cam = page.evaluate(PAGE_CAMERA)
    if cam is None:
        return None

    def world(v: list[float]) -> np.ndarray:  # three.js → viser's world of a +z-up scene
        return np.array([-v[2], -v[0], v[1]])

    return {"position": world(cam["position"]), "look_at": world(cam["target"]), "fov": math.radians(cam["fov"])}


def server_camera(server, cid) -> dict:
    """The camera the page last reported to the server."""
    camera = server.viser.get_clients()[cid].camera
    return {"position": np.asarray(camera.position, float), "look_at": np.asarray(camera.look_at, float),
            "fov": float(camera.fov)}


def to_pixel(server, cid, page, xy: np.ndarray) -> np.ndarray:
    """World metres → page pixels (x right, y down) through the camera the page draws with (the one
    it last reported where the page script cannot reach it) and the tab's view. The camera looks
    straight down."""
    tab = server.tabs[cid]
    camera = page_camera(page) or server_camera(server, cid)
    box = canvas_box(page)
    distance = float(camera["position"][2] - camera["look_at"][2])
    px_per_unit = (box["height"] / 2) / (distance * math.tan(camera["fov"] / 2))
    s = tab.arena.to_scene(np.asarray(xy, dtype=float))[..., :2] - camera["look_at"][:2]
    return np.stack([box["x"] + box["width"] / 2 + s[..., 0] * px_per_unit,
                     box["y"] + box["height"] / 2 - s[..., 1] * px_per_unit], axis=-1)


def point_radius_px(server, cid, page, size: float) -> float:
    """The radius in pixels the picture checks give a viser point of ``point_size`` = ``size``
    scene units: ``size`` at the camera's scale."""
    metre = np.linalg.norm(to_pixel(server, cid, page, np.array([1.0, 0.0])) - to_pixel(server, cid, page, np.zeros(2)))
    return float(metre) * size / server.tabs[cid].arena.scale


def open_folder(page, title: str, probe: str) -> None:
    """Open the folder titled ``title`` (folders may start closed) unless the control labelled
    or named ``probe`` inside it already shows (a control: the legend beside the arena says
    "robot" too)."""
    exact = re.compile(rf"^\s*{re.escape(probe)}\s*$")
    inside = page.locator("label").filter(has_text=exact).or_(page.get_by_role("button", name=probe, exact=True)).first
    if not (inside.count() and inside.is_visible()):
        page.get_by_text(title, exact=True).first.click()
        inside.wait_for(state="visible", timeout=30000)


@contextmanager
def app_page(server, init_script: str | None = None) -> Iterator:
    """A Chromium page (1280×800) on ``server``'s app once its panel shows; ``init_script`` runs
    in the page before the app's own scripts."""
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
        pg = arena_in_view(browser.new_page(viewport=VIEWPORT))
        if init_script is not None:
            pg.add_init_script(init_script)
        pg.goto(f"http://127.0.0.1:{server.port}/")
        pg.wait_for_selector("label:has-text('robots')", timeout=90000)
        try:
            yield pg
        finally:
            browser.close()
