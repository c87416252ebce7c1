"""An exported page opened without Shoal, in Debian's Chromium.

The page of a seeded run is served by a plain static file server (``http.server``, no Shoal,
no websocket) and also opened from ``file://``. viser's own player plays it: while it plays
the robots move through the recorded frames; scrubbed to two times, the robots in the
client's scene are the run's robots at a step near each time, the later time at a later
step, and they are on screen where those positions project.
"""

from __future__ import annotations

import functools
import http.server
import io
import math
import shutil
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

sync_api = pytest.importorskip("playwright.sync_api")

from browser_helpers import ARGS, VIEWPORT, arena_in_view, canvas_box, dismiss_toasts, wait_until  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from share_pages import data_block  # noqa: E402

from shoal.app.share import preset_html  # noqa: E402
from shoal.app.share.draw import new_session  # noqa: E402
from shoal.app.view.camera import CAMERA_FOV, CAMERA_HEIGHT, VIEW_HALF  # noqa: E402
from shoal.presets import io as presets_io  # noqa: E402

STEPS = 200
ROBOTS_JS = """() => {
  const m = window.__viserMutable;
  const name = m && Object.keys(m.nodeRefFromName).find(n => n.endsWith('/robots'));
  const o = name && m.nodeRefFromName[name];
  if (!o) return null;
  let pts = null;
  o.traverse(c => {
    const p = c.geometry && c.geometry.attributes && c.geometry.attributes.position;
    if (p && pts === null) pts = Array.from(p.array.slice(0, 3 * p.count));
  });
  return pts;
}"""


class Run:
    """The exported page and the run it came from (robots at every step, in metres)."""

    def __init__(self, folder: Path) -> None:
        self.scenario = presets_io.load("default", [f"sim.steps={STEPS}", "sim.seed=2", "view.trail_seconds=1"])
        self.page = preset_html(self.scenario)
        self.path = folder / "run.html"
        self.path.write_text(self.page, encoding="utf-8")
        session = new_session(self.scenario)
        session.step(STEPS)
        self.positions = {f.k: f.x.copy() for f in session.frames}
        self.kept = data_block(self.page)["run"]
        self.scale = VIEW_HALF / float(self.scenario.arena.half_size)  # metres → scene units (the Chapter 3 view)

    def step_of(self, pts: list[float]) -> int:
        """The recorded step whose robots the client shows (asserts an exact match, float32)."""
        xy = np.asarray(pts, dtype=float).reshape(-1, 3)[:, :2] / self.scale
        gaps = {k: float(np.abs(x - xy).max()) for k, x in self.positions.items() if x.shape == xy.shape}
        k = min(gaps, key=gaps.get)
        assert gaps[k] < 1e-4, f"the robots drawn are no recorded frame (closest: step {k}, {gaps[k]:.3g} m off)"
        return k


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Run:
    return Run(tmp_path_factory.mktemp("course-page"))


class QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args) -> None:
        pass


@pytest.fixture(scope="module")
def static_url(run):
    """The page's folder on a plain static file server (Python's http.server in a thread)."""
    httpd = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(QuietHandler, directory=str(run.path.parent)))
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}/{run.path.name}"
    httpd.shutdown()
    httpd.server_close()
    thread.join(timeout=10)


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


def open_page(browser, url: str):
    pg = arena_in_view(browser.new_page(viewport=VIEWPORT))
    sockets: list[str] = []
    requests: list[str] = []
    pg.on("websocket", lambda ws: sockets.append(ws.url))
    pg.on("request", lambda r: requests.append(r.url))
    pg.goto(url)
    wait_until(lambda: pg.evaluate(ROBOTS_JS), timeout=90, what="the robots in viser's scene")
    return pg, sockets, requests


def scrub(pg, fraction: float) -> None:
    """Click viser's playback bar at ``fraction`` of its length (this also pauses)."""
    box = pg.locator(".mantine-Slider-root").first.bounding_box()
    pg.mouse.click(box["x"] + fraction * box["width"], box["y"] + box["height"] / 2)


def pause(pg, run: Run) -> None:
    """Stop the player (a click on its bar pauses it; the clock of a busy page may still add the
    time it lost before the pause lands, so later clicks are the ones that go exactly where told)."""
    def paused() -> bool:  # (a click the page took while it was still laying out is clicked again)
        scrub(pg, 0.05)
        try:
            return shown_step(pg, run, timeout=5.0) >= 0
        except AssertionError:
            return False
    wait_until(paused, timeout=60.0, what="the player paused")


def shown_step(pg, run: Run, timeout: float = 20.0) -> int:
    """The step drawn now, once two reads a moment apart agree (the player applies a frame at once)."""
    def settled():
        a = run.step_of(pg.evaluate(ROBOTS_JS))
        time.sleep(0.3)
        return (a,) if run.step_of(pg.evaluate(ROBOTS_JS)) == a else None
    return wait_until(settled, timeout=timeout, what="a still frame")[0]


def to_pixels(pg, run: Run, x: np.ndarray) -> np.ndarray:
    box = canvas_box(pg)
    px_per_unit = (box["height"] / 2) / (CAMERA_HEIGHT * math.tan(CAMERA_FOV / 2))
    s = x * run.scale
    return np.stack([box["x"] + box["width"] / 2 + s[:, 0] * px_per_unit,
                     box["y"] + box["height"] / 2 - s[:, 1] * px_per_unit], axis=-1)


def red_share(pg, pixels: np.ndarray) -> float:
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(pg.screenshot())).convert("RGB")).astype(int)
    hits = 0
    for x, y in np.round(pixels).astype(int):
        patch = img[y - 1: y + 2, x - 1: x + 2]
        hits += bool(((patch[..., 0] > 170) & (patch[..., 1] < 110) & (patch[..., 2] < 110)).any())
    return hits / len(pixels)


def test_a_page_on_a_static_server_plays_the_run_as_recorded(browser, run, static_url):
    pg, sockets, requests = open_page(browser, static_url)
    try:
        assert pg.title() == "default, seed 2 · Shoal"
        panel = pg.locator("#shoal-run")
        assert "Shoal · default, seed 2" in panel.inner_text() and "free-space swarm" in panel.inner_text()
        # it plays: the robots go through recorded frames on their own
        first = run.step_of(pg.evaluate(ROBOTS_JS))
        wait_until(lambda: run.step_of(pg.evaluate(ROBOTS_JS)) != first, timeout=30, what="the player to move on")
        # scrubbed to two times: the recorded robots of an early and of a later step
        dismiss_toasts(pg)
        pause(pg, run)
        scrub(pg, 0.25)
        k1 = shown_step(pg, run)
        scrub(pg, 0.75)
        k2 = shown_step(pg, run)
        assert abs(k1 - 0.25 * STEPS) <= 0.05 * STEPS and abs(k2 - 0.75 * STEPS) <= 0.05 * STEPS, (k1, k2)
        assert np.abs(run.positions[k2] - run.positions[k1]).max() > 0.5  # the robots moved in between
        time.sleep(1.0)
        assert run.step_of(pg.evaluate(ROBOTS_JS)) == k2  # scrubbing paused the player
        # ...and they are on screen where those positions project (red discs)
        assert red_share(pg, to_pixels(pg, run, run.positions[k2])) >= 0.8
        # nothing but the page itself was fetched, and no server was called
        assert sockets == [] and {u for u in requests if not u.startswith(("data:", "blob:"))} == {static_url}
    finally:
        pg.close()


def test_a_page_opened_from_a_file_plays_too(browser, run):
    pg, sockets, _ = open_page(browser, run.path.as_uri())
    try:
        dismiss_toasts(pg)
        pause(pg, run)
        scrub(pg, 0.5)
        k = shown_step(pg, run)
        assert abs(k - 0.5 * STEPS) <= 0.05 * STEPS and sockets == []
    finally:
        pg.close()


def clock(pg) -> float:
    """The player's clock, the number beside its ▶ (seconds of the page)."""
    return float(pg.locator("input").first.input_value())


def test_the_panel_leaves_the_arena_clear_and_the_clock_runs_as_the_about_text_says(browser, run):
    """At 1280×800 the panel sits left of the arena (its colour bar is to the right), viser's
    software-WebGL toast is closed and named in one line of the panel; the About text's frames,
    frames a second and clock end are what the player shows."""
    pg, _, _ = open_page(browser, run.path.as_uri())
    try:
        half = float(run.scenario.arena.half_size)
        card = pg.locator("#shoal-run").bounding_box()
        left_edge = to_pixels(pg, run, np.array([[-half, half]]))[0, 0]
        assert card["x"] + card["width"] < left_edge, (card, left_edge)
        wait_until(lambda: not pg.get_by_text("Software WebGL rendering detected").count(), timeout=20,
                   what="viser's software-WebGL toast closed")
        assert pg.locator("#shoal-software").is_visible()  # (headless Chromium draws without a GPU)
        kept = run.kept
        fps, stride = 1.0 / kept["seconds_per_frame"], kept["stride"]
        pg.get_by_text("About this page").click()
        about = " ".join(pg.locator("#shoal-run").inner_text().split())
        assert (f"{kept['frames']} frames of a seeded run" in about and f"plays {fps:.3g} frames a second" in about
                and f"runs from 0 to {kept['seconds']:.4g} s" in about), about
        pause(pg, run)
        scrub(pg, 0.999)  # the end: the clock the About text names, the last step
        assert shown_step(pg, run) == STEPS and clock(pg) == pytest.approx(kept["seconds"], abs=0.11)
        for fraction in (0.3, 0.6):
            scrub(pg, fraction)
            k = shown_step(pg, run)
            assert abs(k - clock(pg) * fps * stride) <= 2 * stride + 0.1 * fps * stride, (fraction, k, clock(pg))
    finally:
        pg.close()
