"""The browser app in a real headless Chromium (Debian's ``chromium``, driven by playwright).

One server and one page for the module; the tests run in file order and each one leaves
the page usable for the next. The Python side is checked through ``server.sessions``.
"""

from __future__ import annotations

import csv
import io
import re
import shutil
import time

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

sync_api = pytest.importorskip("playwright.sync_api")

from shoal.app.kinds.swarm import ROBOT, ROBOT_SIZE  # noqa: E402
from shoal.app.panel.board import TITLE as BOARD  # noqa: E402

from browser_helpers import (  # noqa: E402
    ARGS,
    VIEWPORT,
    arena_in_view,
    canvas_box,
    choose,
    dismiss_toasts,
    number_box,
    open_folder,
    point_radius_px,
    to_pixel,
    upload_input,
    wait_until,
)

TAB_TOPS = ("[...new Set([...document.querySelectorAll('[role=tab]')].filter(e => e.textContent.trim() !== "
            f"{BOARD!r})"  # (the board beside the arena has a tab of its own)
            ".map(e => Math.round(e.getBoundingClientRect().top)))]")  # the tops of the tabs, measured in one go


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def page(browser, server):
    context = arena_in_view(browser.new_context(accept_downloads=True, viewport=VIEWPORT))
    pg = context.new_page()
    pg.goto(f"http://127.0.0.1:{server.port}/")
    pg.wait_for_selector("label:has-text('robots')", timeout=90000)
    yield pg
    context.close()


@pytest.fixture(scope="module")
def client_id(server, page):
    wait_until(lambda: len(server.sessions) == 1, what="the tab's session")
    return next(iter(server.sessions))


# ---------------------------------------------------------------------------- (a) load
def test_page_loads_with_its_own_session(server, page, client_id):
    for text in ("law", "Δt [s]", "robots", "speed [steps/s]", "seed"):
        assert page.locator("label", has_text=text).count() >= 1, text
    for tab in ("Controller", "Plots", "Lessons"):
        assert page.get_by_role("tab", name=tab).count() == 1
    tops = page.evaluate(TAB_TOPS)  # in one go: the status line may grow meanwhile
    assert len(tops) == 1, f"the tab row wraps: tabs at y = {sorted(tops)}"
    session = server.sessions[client_id]
    assert session.scenario.name == "default"
    k0 = session.sim.state.k
    wait_until(lambda: session.sim.state.k > k0, what="the swarm to play")  # playing on arrival


# ---------------------------------------------------------------------------- (b) slider
def test_typing_omega_in_the_browser_changes_the_engine(server, page, client_id):
    session = server.sessions[client_id]
    page.get_by_role("tab", name="Controller").click()
    choose(page, "mode", "raw")
    wait_until(lambda: session.scenario.controller.mode == "raw", what="raw mode")
    box = number_box(page, "omega ω")
    box.fill("0.77")
    box.press("Enter")
    wait_until(lambda: getattr(session.sim.policy, "omega", None) == pytest.approx(0.77), what="ω = 0.77")
    assert session.scenario.controller.omega == pytest.approx(0.77)

    # An Adapted law refuses ω ≥ 1: red toast, engine and box keep 0.77.
    box.fill("1.1")
    box.press("Enter")
    page.wait_for_selector(".mantine-Notification-root:has-text('Refused')", timeout=30000)
    assert session.sim.policy.omega == pytest.approx(0.77)
    wait_until(lambda: box.input_value() == "0.77", what="the box to show 0.77 again")
    dismiss_toasts(page)


# ---------------------------------------------------------------------------- (c) picture
def test_the_picture_shows_the_robots_where_the_engine_has_them(server, page, client_id):
    from PIL import Image

    session = server.sessions[client_id]
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not session.playing, what="pause")
    dismiss_toasts(page)
    x = session.sim.state.x[0].copy()
    box = canvas_box(page)
    for attempt in range(6):  # a loaded machine may need a few seconds for the last frame
        time.sleep(1.5 if attempt == 0 else 1.0)
        png = page.screenshot(clip=box)
        img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
        h = img.shape[0]
        # Project with the camera the page draws with (straight down), into the clipped image.
        cols, rows = (to_pixel(server, client_id, page, x) - (box["x"], box["y"])).T

        red = (np.abs(img[..., 0] - ROBOT[0]) < 45) & (img[..., 1] < 110) & (img[..., 2] < 110)
        hits = 0
        for r, c in zip(rows, cols):
            r0, c0 = int(round(r)), int(round(c))
            window = red[max(r0 - 3, 0): r0 + 4, max(c0 - 3, 0): c0 + 4]
            hits += bool(window.any())
        if hits >= 0.9 * len(x):
            break
    assert red.any(), "no robot-coloured pixel at all"
    assert hits >= 0.9 * len(x), f"only {hits}/{len(x)} robots seen where the engine has them"
    # ...and every robot-coloured pixel belongs to a robot: none lies further from the nearest
    # projected robot centre than a robot's radius on screen (plus anti-aliasing).
    ys, xs = np.nonzero(red)
    keep = ~((ys > h - 90) & (xs < 90))  # viser's orientation gizmo (red x axis) sits bottom left
    ys, xs = ys[keep], xs[keep]
    dist = np.sqrt((ys[:, None] - rows[None, :]) ** 2 + (xs[:, None] - cols[None, :]) ** 2).min(axis=1)
    radius_px = point_radius_px(server, client_id, page, ROBOT_SIZE)
    assert dist.max() <= radius_px + 4, f"robot colour {dist.max():.1f} px from any robot (radius {radius_px:.1f})"


# ---------------------------------------------------------------------------- (d) export
def test_export_csv_download_matches_the_engine(server, page, client_id):
    session = server.sessions[client_id]
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not session.playing, what="pause")
    open_folder(page, "Replay and files", "Export CSV")
    with page.expect_download(timeout=20000) as dl:
        page.get_by_role("button", name="Export CSV").click()
    download = dl.value
    assert download.suggested_filename.endswith(".csv")
    with open(download.path(), encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["run", "step", "t", "robot", "x", "y", "heading", "vx", "vy", "status"]
    k = session.sim.state.k
    last = sorted((r for r in rows if int(r["step"]) == k), key=lambda r: int(r["robot"]))
    assert len(last) == session.sim.robots
    xy = np.array([[float(r["x"]), float(r["y"])] for r in last])
    np.testing.assert_allclose(xy, session.sim.state.x[0], rtol=1e-8, atol=1e-8)


def test_bad_upload_shows_the_field_and_keeps_the_scene(server, page, client_id):
    session = server.sessions[client_id]
    sim, k = session.sim, session.sim.state.k
    open_folder(page, "Replay and files", "Export CSV")
    dismiss_toasts(page)  # the page shows only a few toasts at once
    upload_input(page, "Upload preset").set_input_files(
        {"name": "bad.toml", "mimeType": "application/toml", "buffer": b"[controller]\nomega = 7\n"})
    page.wait_for_selector(".mantine-Notification-root:has-text('controller.omega')", timeout=30000)
    assert session.sim is sim and session.sim.state.k == k
    for _ in range(10):  # the page's own "File uploaded successfully." would show just before the verdict
        toasts = page.locator(".mantine-Notification-root").all_inner_texts()
        assert not any("uploaded successfully" in t for t in toasts), toasts  # only the verdict
        time.sleep(0.1)
    dismiss_toasts(page)


def test_a_second_tab_gets_its_own_session(server, browser, page, client_id):
    other = arena_in_view(browser.new_page(viewport=VIEWPORT))
    try:
        other.goto(f"http://127.0.0.1:{server.port}/")
        other.wait_for_selector("label:has-text('robots')", timeout=90000)
        wait_until(lambda: len(server.sessions) == 2, what="a second session")
        second = next(cid for cid in server.sessions if cid != client_id)
        box = number_box(other, "robots")
        box.fill("7")
        box.press("Enter")
        wait_until(lambda: server.sessions[second].sim.robots == 7, what="7 robots in the second tab")
        assert server.sessions[client_id].sim.robots == 20
    finally:
        other.close()
    wait_until(lambda: len(server.sessions) == 1, what="the closed tab's session to go")


# ---------------------------------------------------------------------------- keys
def test_space_arrow_and_r_drive_the_playback_but_not_inside_a_box(server, page, client_id):
    """Real key presses: space toggles Play/Pause, → steps, r resets (a paused run stays paused);
    a key typed into a number box is the box's. (The keys click the playback buttons, whose
    hostile values are refused in tests/test_trust_inputs.py.)"""
    session = server.sessions[client_id]
    dismiss_toasts(page)
    page.get_by_role("button", name="Reset", exact=True).click()  # (the run may have reached its last step)
    wait_until(lambda: session.sim.state.k < 100, what="a fresh run")
    if not session.playing:
        page.get_by_role("button", name="Play", exact=True).click()
        wait_until(lambda: session.playing, what="playing")
    page.evaluate("document.activeElement && document.activeElement.blur()")
    page.keyboard.press(" ")
    wait_until(lambda: not session.playing, what="space pauses")

    def still() -> bool:  # (a step the ticker began before the pause may still land)
        k0 = session.sim.state.k
        time.sleep(0.5)
        return session.sim.state.k == k0
    wait_until(still, what="the run to stand still")
    k = session.sim.state.k
    after = 1 if session.finished else k + 1  # (a finished run starts again on a Step, as on Play)
    page.keyboard.press("ArrowRight")
    wait_until(lambda: session.sim.state.k == after, what=f"→ steps once (from step {k})")
    page.keyboard.press("r")
    wait_until(lambda: session.sim.state.k == 0, what="r resets")
    assert not session.playing
    page.keyboard.press("ArrowRight")
    wait_until(lambda: session.sim.state.k == 1, what="→ steps once more")
    box = number_box(page, "seed")
    box.click()
    box.press("r")  # the box's, not a Reset...
    box.press("ArrowRight")  # ...nor a Step
    page.get_by_role("button", name="Step", exact=True).click()  # after the keys: the page keeps the order
    wait_until(lambda: session.sim.state.k == 2, what="the Step click")
    assert session.sim.state.k == 2 and not session.playing
    page.evaluate("document.activeElement && document.activeElement.blur()")
    page.keyboard.press(" ")
    wait_until(lambda: session.playing, what="space plays")


# ---------------------------------------------------------------------------- layout


@pytest.mark.parametrize("preset, kind, folder, inside", [
    ("course-dvc", "fleet", "Arena view and selected robot", "zoom"),
    ("sonar-xb-pso", "sonar", "Selected robot", "robot"),
    ("slo-walk", "mai", "Replay and files", "Export CSV"),
    ("default", "swarm", "Positions", "error set"),
])
def test_every_kind_fits_its_tab_row_on_one_line_with_its_folders_closed(server, page, client_id, preset, kind,
                                                                         folder, inside):
    dismiss_toasts(page)
    choose(page, "preset", preset)
    wait_until(lambda: server.tabs[client_id].session.scenario.name == preset, what=preset)
    page.get_by_role("tab", name="Lessons").wait_for(timeout=60000)
    page.get_by_text(folder, exact=True).first.wait_for(timeout=60000)
    seen: list = []

    def one_row_high_up() -> bool:  # (measured once the new panel has settled)
        seen[:] = page.evaluate(TAB_TOPS)
        # header, view row, legend and the closed folders take at most two thirds: the kind's first controls show
        return len(seen) == 1 and seen[0] < 2 / 3 * VIEWPORT["height"]
    wait_until(one_row_high_up, timeout=30.0, what=f"{preset}: one tab row in the upper two thirds of the page")
    for closed in ("Export CSV", "compare with swarm B", inside):  # Replay and files, Compare, the kind's own
        exact = re.compile(rf"^\s*{re.escape(closed)}\s*$")  # a control's label (the legend says "robot" too)
        probe = page.locator("label").filter(has_text=exact).or_(page.get_by_role("button", name=closed, exact=True))
        assert not any(probe.nth(i).is_visible() for i in range(probe.count())), f"{preset}: {closed!r} shows"
