"""The arena's page in a real headless Chromium, which draws WebGL in software (SwiftShader), as a
classroom PC without a GPU does: the light drawing comes on by itself and viser's software-WebGL
toast goes; a mouse drag pans the top view and never tips it, unless the user asks for 3-D;
projector mode. One server and one page for the module, the tests in file order."""

from __future__ import annotations

import math
import shutil

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

pytest.importorskip("playwright.sync_api")

from shoal.app.panel.view_row import SWITCH, TEXT_SCALE  # noqa: E402
from shoal.app.view.page import LIGHT_DPR, SOFTWARE_TOAST  # noqa: E402

from browser_helpers import canvas_box, root_for, wait_until  # noqa: E402

SOFTWARE = ("swiftshader", "llvmpipe", "softpipe", "software")
ARENA = ("(() => [...document.querySelectorAll('canvas')]"
         ".reduce((a, c) => (!a || c.width * c.height > a.width * a.height) ? c : a, null))()")


def tilt(camera) -> float:
    """Degrees between the camera's view and straight down."""
    p, look = ([float(v) for v in q] for q in (camera.position, camera.look_at))
    d = [b - a for a, b in zip(p, look)]
    return math.degrees(math.acos(max(-1.0, min(1.0, -d[2] / math.hypot(*d)))))


def drag(page, dx: float, dy: float, steps: int = 15) -> None:
    """A left-button drag from the middle of the arena."""
    box = canvas_box(page)
    x, y = box["x"] + 0.45 * box["width"], box["y"] + 0.5 * box["height"]
    page.mouse.move(x, y)
    page.mouse.down()
    for i in range(1, steps + 1):
        page.mouse.move(x + dx * i / steps, y + dy * i / steps)
        page.wait_for_timeout(30)
    page.mouse.up()


class Reports:
    """Every camera report of a client from now on, as (tilt, look_at)."""

    def __init__(self, camera) -> None:
        self.seen: list[tuple[float, tuple[float, ...]]] = []
        camera.on_update(lambda c: self.seen.append((tilt(c), tuple(float(v) for v in c.look_at))))


def tick_box(page, label: str) -> None:
    """Click the Display box ``label`` (the view row's *Display* button shows the boxes first)."""
    box = page.locator("label").filter(has_text=label).first
    if not box.is_visible():
        page.get_by_role("button", name="Display", exact=True).click()
        box.wait_for(state="visible", timeout=30000)
    root_for(page, label).click()


@pytest.fixture(scope="module")
def camera(server, cid):
    return server.viser.get_clients()[cid].camera


def test_a_page_drawn_in_software_gets_the_light_drawing_and_no_toast(server, page, cid):
    renderer = page.evaluate("""(() => { const gl = document.createElement('canvas').getContext('webgl');
        const e = gl && gl.getExtension('WEBGL_debug_renderer_info');
        return e ? String(gl.getParameter(e.UNMASKED_RENDERER_WEBGL)) : ''; })()""")
    if not any(s in renderer.lower() for s in SOFTWARE):
        pytest.skip(f"this Chromium draws on a GPU ({renderer})")
    tab = wait_until(lambda: server.tabs.get(cid), what="the tab")
    wait_until(lambda: tab.display.light and tab.arena.canvas.light, what="the light drawing, ticked by the page")
    page.wait_for_timeout(1500)  # (viser shows its toast as the page loads)
    assert page.locator(".mantine-Notification-root", has_text=SOFTWARE_TOAST).count() == 0
    note = page.get_by_text("Light drawing", exact=True)
    assert note.is_visible()
    box = tab.panels.view_gui.boxes["light"]
    assert box.value  # ticked through the box (the page showed the boxes a moment for it, and hid them again)
    wait_until(lambda: not tab.panels.view_gui.showing_boxes, what="the Display boxes hidden again")
    # the arena renders at LIGHT_DPR of its CSS pixels
    wait_until(lambda: abs(page.evaluate(f"{ARENA}.width / {ARENA}.clientWidth") - LIGHT_DPR) < 0.02,
               what="the arena at half resolution")
    assert not tab.arena.canvas.shown("trails") and tab.arena.canvas.shown("trails_dots")


def test_a_drag_on_the_arena_pans_and_never_tips_the_top_view(server, page, cid, camera):
    server.tabs[cid].session.pause()
    page.wait_for_timeout(500)
    assert tilt(camera) < 0.5
    before = tuple(float(v) for v in camera.look_at)
    reports = Reports(camera)
    drag(page, 180, 90)
    # (scene units: the arena is ±10; a loaded machine's page may report the camera seconds late)
    wait_until(lambda: reports.seen and math.dist(before[:2], reports.seen[-1][1][:2]) > 0.5, timeout=30,
               what="the drag to pan the view")
    assert max(t for t, _ in reports.seen) < 1.0, "the drag tipped the view"
    page.locator("body").press("ArrowLeft")  # viser orbits on the arrow keys (→ also steps the run)
    page.keyboard.down("ArrowUp")
    page.wait_for_timeout(400)
    page.keyboard.up("ArrowUp")
    page.wait_for_timeout(800)
    assert tilt(camera) < 1.0
    assert max(t for t, _ in reports.seen) < 1.0


def test_the_3d_view_orbits_on_request_and_the_top_view_holds_again_after(server, page, cid, camera):
    tab = server.tabs[cid]
    tick_box(page, "3-D view")
    wait_until(lambda: tab.display.orbit, what="the 3-D view")
    page.wait_for_timeout(800)
    drag(page, 200, 120)
    wait_until(lambda: tilt(camera) > 5.0, timeout=30, what="the drag to orbit the camera")
    tick_box(page, "3-D view")
    wait_until(lambda: not tab.display.orbit and tilt(camera) < 0.5, what="the top view again")
    page.wait_for_timeout(800)
    reports = Reports(camera)
    drag(page, -150, 100)
    page.wait_for_timeout(1000)
    assert max((t for t, _ in reports.seen), default=0.0) < 1.0 and tilt(camera) < 1.0


def test_projector_mode_is_one_box_on_the_first_screen(server, page, cid):
    tab = server.tabs[cid]
    width = canvas_box(page)["width"]
    box = root_for(page, SWITCH)
    assert box.is_visible()  # not behind the Display button
    box.click()
    wait_until(lambda: tab.display.projector and tab.arena.canvas.text_scale == TEXT_SCALE, what="projector mode")
    wait_until(lambda: page.evaluate(
        "getComputedStyle(document.documentElement).getPropertyValue('--mantine-scale')").strip()
        in (str(TEXT_SCALE), str(int(TEXT_SCALE))), what="the page's text scaled")
    # the panel twice as wide, the board moved from beside the arena to under the controls
    wait_until(lambda: abs(canvas_box(page)["width"] - width) > 20 and tab.panels.board.placed is True,
               what="a wider panel, the board under it")
    root_for(page, SWITCH).click()
    wait_until(lambda: abs(canvas_box(page)["width"] - width) < 2 and tab.arena.canvas.text_scale == 1.0,
               what="the usual text again")


def test_unticking_light_drawing_gives_viser_its_own_resolution_back(server, page, cid):
    tab = server.tabs[cid]
    tick_box(page, "light drawing")
    wait_until(lambda: not tab.display.light and "Light drawing" not in tab.panels.status.content,
               what="the full drawing")
    wait_until(lambda: page.evaluate("window.__shoalPage.viewer().useDevSettings.get().fixedDpr") is None,
               what="viser's adaptive resolution")
    tab.session.step(3)
    wait_until(lambda: tab.arena.canvas.shown("trails") and not tab.arena.canvas.shown("trails_dots"),
               what="trails as lines")
