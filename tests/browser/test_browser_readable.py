"""Readable from the back row (issue 32), in a real headless Chromium: one page walks every
shipped preset, in the normal mode at 1280×800 and in projector mode at 1920×1080, and measures
every visible text node (tests/browser/readability.py: computed size, WCAG contrast against the
background it is drawn on, text drawn into canvases by its font), the controls without an
accessible name (Playwright's ARIA snapshot), where the scene's main plot sits, the colours and
shapes of the legend's pairs, and the page's console. Then the live region, the title, the
projector switch kept by the browser and the address, ``serve --projector``, and the panel's
strip. One server and one page for the module, the tests in file order."""

from __future__ import annotations

import shutil

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

pytest.importorskip("playwright.sync_api")

import readability  # noqa: E402

from shoal.app.panel.view_row import SWITCH  # noqa: E402
from shoal.app.view.palette import MIN_DELTA_E, cvd_delta_e  # noqa: E402
from shoal.app.view.projector import MIN_PX, PROJECTOR_SCALE, STORE  # noqa: E402
from shoal.presets.io import list_presets, load  # noqa: E402

from browser_helpers import ARGS, arena_in_view, dismiss_toasts, root_for, wait_until  # noqa: E402

PRESETS = list_presets()
NORMAL, PROJECTOR, SMALL_PROJECTOR = (1280, 800), (1920, 1080), (1366, 768)
SETTLE_MS = 1200  # after a preset's scene is drawn (the board's plot laid out, the legend sent)
PROJECTOR_MIN = 16.0  # px at 1920×1080: nothing readable smaller
AA = 4.5

BOARD_PLOT = """
(title) => {
  const tab = [...document.querySelectorAll('[role=tab]')].find((t) => t.textContent.trim() === title);
  let n = tab;
  while (n && !n.querySelector('.uplot, .js-plotly-plot')) n = n.parentElement;
  const plot = n && n.querySelector('.uplot, .js-plotly-plot');
  if (!plot) return null;
  const r = plot.getBoundingClientRect();
  return {top: r.top, bottom: r.bottom, left: r.left, right: r.right, width: r.width, height: r.height,
          w: innerWidth, h: innerHeight};
}
"""

LEGEND = """
(() => [...document.querySelectorAll('.shoal-legend > span')].map((item) => {
  const svg = item.querySelector('svg');
  const shape = svg && svg.querySelector('circle, rect, path');
  const get = (name) => (shape && shape.getAttribute(name)) || '';
  const fill = get('fill');
  return {label: item.textContent.replace(/\\s+/g, ' ').trim(), tag: shape ? shape.tagName : '', d: get('d'),
          dash: get('stroke-dasharray'), width: get('stroke-width'),
          colour: fill && fill !== 'none' ? fill : get('stroke')};  // a filled shape's fill, a line's stroke
}))()
"""


@pytest.fixture(scope="module")
def app():
    from shoal.app.server import start_server

    srv = start_server("default", port=0)
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def browser():
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


def _open(browser, port: int, size=NORMAL, query: str = ""):
    """A new page (its own browser context: its own localStorage) on the app, its panel shown;
    (page, console errors)."""
    ctx = arena_in_view(browser.new_context(viewport={"width": size[0], "height": size[1]}))
    ctx.add_init_script(readability.CANVAS_FONTS)
    page = ctx.new_page()
    errors: list[str] = []
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
    page.goto(f"http://127.0.0.1:{port}/{query}")
    page.wait_for_selector("label:has-text('preset')", timeout=90000)
    return page, errors


@pytest.fixture(scope="module")
def page(app, browser):
    page, errors = _open(browser, app.port)
    page.console_errors = errors  # type: ignore[attr-defined]
    yield page
    page.context.close()


def _tab(app):
    wait_until(lambda: len(app.tabs) >= 1, what="the tab")
    return next(iter(app.tabs.values()))


def _show(app, page, preset: str):
    """Load ``preset`` in the tab and wait until its scene is drawn and has settled on the page."""
    tab = _tab(app)
    assert tab.panels.load_preset(preset)
    tab = _tab(app)

    def drawn():
        s = tab.session
        return tab.arena.built_revision == s.scene_revision and tab.arena.drawn_revision >= 0 and \
            s.scenario.name == load(preset).name
    wait_until(drawn, timeout=120, what=f"{preset} drawn")
    page.wait_for_timeout(SETTLE_MS)
    dismiss_toasts(page)
    page.wait_for_timeout(400)  # (a toast fades out)
    return tab


def _measure(page) -> tuple[list[dict], list[dict]]:
    return readability.texts(page), readability.canvas_texts(page)


def _plot_in_view(page, tab) -> dict:
    title = tab.panels.board.title
    box = wait_until(lambda: page.evaluate(BOARD_PLOT, title), timeout=30, what=f"the board's plot '{title}'")
    return box


def _in_view(box: dict) -> bool:
    return box["top"] >= 0 and box["left"] >= 0 and box["bottom"] <= box["h"] + 0.5 and \
        box["right"] <= box["w"] + 0.5 and box["height"] > 100 and box["width"] > 200


def _check_pairs(page, tab, where: str) -> None:
    """Each pair the kind names is on the legend (when its layer is on screen) in two colours a
    colour-blind student tells apart, as two different shapes, dashes or widths."""
    legend = page.evaluate(LEGEND)
    by_label = {item["label"]: item for item in legend}
    entries = {(e.glyph, tuple(e.colour)): e.label for layer in tab.arena.layers for e in layer.legend}
    for pair in tab.session.kind.pairs:
        a, b = (by_label.get(entries.get((c.glyph, tuple(c.colour)), "")) for c in (pair.a, pair.b))
        if a is None or b is None:
            continue  # (not on screen in this scene: B without Compare, rays of another kind)
        ca, cb = (tuple(int(v) for v in x["colour"][4:-1].split(",")) for x in (a, b))
        assert cvd_delta_e(ca, cb) >= MIN_DELTA_E, f"{where}: {pair.what}: {ca} / {cb}"
        assert (a["tag"], a["d"], a["dash"], a["width"]) != (b["tag"], b["d"], b["dash"], b["width"]), \
            f"{where}: {pair.what}: the same glyph in the legend"


def test_every_preset_in_the_normal_mode_is_readable_named_and_shows_its_plot(app, page):
    seen_pairs = 0
    for preset in PRESETS:
        tab = _show(app, page, preset)
        texts, drawn = _measure(page)
        where = f"{preset} at 1280×800"
        small = [f"{t['text']!r} {t['size']:.1f}px" for t in texts + drawn if t["size"] < MIN_PX - 0.05]
        assert small == [], f"{where}: text under {MIN_PX} px: {small[:8]}"
        pale = [f"{t['text']!r} {t['contrast']:.2f}:1" for t in texts if t["contrast"] < AA]
        assert pale == [], f"{where}: text under {AA}:1: {pale[:8]}"
        assert readability.unnamed_controls(page) == [], where
        assert _in_view(_plot_in_view(page, tab)), f"{where}: the main plot is not in view"
        _check_pairs(page, tab, where)
        seen_pairs += len(tab.session.kind.pairs)
        assert page.console_errors == [], f"{where}: {page.console_errors}"
        assert page.title() == f"Shoal · {load(preset).name}"
    assert seen_pairs > 0


def test_every_preset_in_projector_mode_doubles_its_text_and_keeps_its_plot_in_view(app, page):
    tab = _tab(app)
    root_for(page, SWITCH).click()  # one box on the first screen
    wait_until(lambda: _tab(app).display.projector, what="projector mode")
    page.set_viewport_size({"width": PROJECTOR[0], "height": PROJECTOR[1]})
    page.wait_for_timeout(1500)
    for preset in PRESETS:
        tab = _show(app, page, preset)
        texts, drawn = _measure(page)
        where = f"{preset} in projector mode at 1920×1080"
        least = PROJECTOR_SCALE * MIN_PX - 0.5  # twice the normal mode's smallest (which is past today's 8.9 px)
        small = [f"{t['text']!r} {t['size']:.1f}px" for t in texts + drawn if t["size"] < max(least, PROJECTOR_MIN)]
        assert small == [], f"{where}: {small[:8]}"
        pale = [f"{t['text']!r} {t['contrast']:.2f}:1" for t in texts if t["contrast"] < AA]
        assert pale == [], f"{where}: {pale[:8]}"
        box = _plot_in_view(page, tab)
        assert _in_view(box), f"{where}: the main plot is not in view: {box}"
        assert page.console_errors == [], f"{where}: {page.console_errors}"
    page.set_viewport_size({"width": SMALL_PROJECTOR[0], "height": SMALL_PROJECTOR[1]})
    for preset in ("default", "fig3-4a", "course-dvc", "escort-moving", "slo-walk"):  # a plot of every kind
        tab = _show(app, page, preset)
        box = _plot_in_view(page, tab)
        assert _in_view(box), f"{preset} in projector mode at 1366×768: the plot is not in view: {box}"
    root_for(page, SWITCH).click()
    wait_until(lambda: not _tab(app).display.projector, what="projector mode off")
    page.set_viewport_size({"width": NORMAL[0], "height": NORMAL[1]})


def test_the_status_is_announced_politely_and_not_four_times_a_second(app, page):
    tab = _show(app, page, "default")
    live = page.locator("#shoal-live")
    assert live.get_attribute("aria-live") == "polite" and live.get_attribute("role") == "status"
    tab.session.play()
    page.wait_for_timeout(1500)
    said = [live.text_content()]
    for _ in range(10):  # 5 s of a playing run: the status line changes 20 times, the region at most once
        page.wait_for_timeout(500)
        said.append(live.text_content())
    assert len(set(said)) <= 2, said
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: "paused" in (live.text_content() or ""), timeout=10, what="'paused' announced")
    assert (live.text_content() or "").startswith("default ·")
    snapshot = page.locator("body").aria_snapshot()
    assert 'slider "omega ω"' in snapshot and 'textbox "omega ω, number"' in snapshot  # a slider's two inputs
    assert 'textbox "seed"' in snapshot and f'checkbox "{SWITCH}"' in snapshot


def test_projector_mode_is_kept_by_the_browser_and_the_address_and_by_serve_projector(app, browser):
    page, _ = _open(browser, app.port, query="?projector=1")
    try:
        tab = wait_until(lambda: next((t for t in app.tabs.values() if t.display.projector), None), timeout=60,
                         what="a tab the address put in projector mode")
        wait_until(lambda: page.evaluate("document.documentElement.classList.contains('shoal-projector')"),
                   what="the page's projector class")
        assert page.evaluate(f"localStorage.getItem({STORE!r})") == "1"
        page.goto(f"http://127.0.0.1:{app.port}/")  # no parameter: the browser remembers
        page.wait_for_selector("label:has-text('preset')", timeout=90000)
        wait_until(lambda: page.evaluate("document.documentElement.classList.contains('shoal-projector')"),
                   timeout=60, what="projector mode again from localStorage")
        assert "projector=1" in page.url  # (written back into the address: a lecturer can bookmark it)
        tab = wait_until(lambda: next((t for t in app.tabs.values() if t.display.projector), None), what="the tab")
        root_for(page, SWITCH).click()
        wait_until(lambda: page.evaluate(f"localStorage.getItem({STORE!r})") == "0", what="the choice kept: off")
        assert "projector" not in page.url and not tab.display.projector
    finally:
        page.context.close()
    from shoal.app.server import start_server

    projecting = start_server("default", port=0, projector=True)
    try:
        page, _ = _open(browser, projecting.port)
        wait_until(lambda: page.evaluate("document.documentElement.classList.contains('shoal-projector')"),
                   timeout=60, what="serve --projector: every tab in projector mode")
        size = page.evaluate("getComputedStyle(document.querySelector('label[for]')).fontSize")
        assert float(size.rstrip("px")) >= PROJECTOR_SCALE * MIN_PX
        page.context.close()
    finally:
        projecting.stop()


def test_a_stray_click_on_the_panels_strip_does_not_fold_it_and_a_fold_refits_the_arena(app, page):
    from shoal.app.view.camera import camera_height

    _show(app, page, "default")
    width = page.evaluate("Math.max(...[...document.querySelectorAll('canvas')].map((c) => c.clientWidth))")
    strip = page.locator("[data-dock-region-handle='right']").first
    box = strip.bounding_box()
    page.mouse.click(box["x"] + box["width"] * 0.4, box["y"] + box["height"] / 2)  # beside its chevron
    page.wait_for_timeout(800)
    assert page.evaluate("Math.max(...[...document.querySelectorAll('canvas')].map((c) => c.clientWidth))") == width
    page.locator("[data-dock-region-collapse='right']").click()  # its chevron: folds it away on purpose
    wider = wait_until(lambda: (w := page.evaluate(
        "Math.max(...[...document.querySelectorAll('canvas')].map((c) => c.clientWidth))")) > width + 100 and w,
        what="the folded panel")
    camera = app.viser.get_clients()[next(iter(app.tabs))].camera
    wait_until(lambda: abs(float(camera.position[2]) - camera_height(float(camera.aspect))) < 1e-3 * camera_height(1.0)
               and abs(float(camera.aspect) - wider / page.viewport_size["height"]) < 0.05,
               what="the arena fitted to its new width")
    page.locator("[data-dock-region='right'] [data-dock-minimize-all]").first.click()  # the rail's +
    wait_until(lambda: page.evaluate(
        "Math.max(...[...document.querySelectorAll('canvas')].map((c) => c.clientWidth))") == width,
        what="the panel back")


def test_an_slo_scene_plays_at_once_on_a_fresh_install(browser, tmp_path):
    """``shoal serve`` with an empty kernel cache (NUMBA_CACHE_DIR): the page chooses slo-walk,
    whose kernels have no numpy tick, and its generation counter moves while the kernels are
    still being compiled behind it (they run as Python meanwhile: nothing waits for numba). The
    seconds it took are printed (the benchmark's number), not asserted."""
    import os
    import re
    import subprocess
    import sys
    import time

    from browser_helpers import choose

    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    proc = subprocess.Popen([sys.executable, "-m", "shoal", "serve", "--port", "0", "--preset", "default"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        port = None
        while port is None:
            line = proc.stdout.readline()
            assert line, "the server stopped"
            if m := re.search(r"running at http://127\.0\.0\.1:(\d+)/", line):
                port = int(m.group(1))
        page, errors = _open(browser, port)
        page.wait_for_selector("label:has-text('robots')", timeout=120000)
        start = time.monotonic()
        choose(page, "preset", "slo-walk")
        step = re.compile(r"slo-walk · ▶ playing · gen (\d+)/\d+")
        seen: list[int] = []

        def moving():
            text = page.locator("body").inner_text()
            m = step.search(text)
            if m and (not seen or int(m.group(1)) != seen[-1]):
                seen.append(int(m.group(1)))
            return len(set(seen)) >= 3 and text
        text = wait_until(moving, timeout=120, what="slo-walk's generation counter moving")
        print(f"\nslo-walk's counter moved {seen} {time.monotonic() - start:.1f} s after it was chosen, kernels cold")
        assert "compiling kernels in the background" in text and "Python meanwhile" in text  # (not compiled yet)
        assert page.title() == "Shoal · slo-walk" and errors == []
        page.context.close()
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
