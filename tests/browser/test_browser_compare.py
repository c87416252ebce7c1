"""A/B comparison and replays in a real headless Chromium.

One server (``default``, a Chapter 3 swarm) and one page for the module; tests run in file
order. The first switches swarm B on from the Compare tab and finds it in the picture (blue
where B's robots are, apart from A's) and in the plot's legend. The second exports a replay
from that page, loads it into a second server started on a fleet scene, scrubs the
timeline and checks the robots drawn there are the recorded ones, and swarm B's in blue.
"""

from __future__ import annotations

import io
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

from shoal.app import replay  # noqa: E402
from shoal.app.kinds.swarm import ROBOT_SIZE  # noqa: E402
from shoal.app.server import start_server  # noqa: E402

from browser_helpers import (  # noqa: E402
    ARGS,
    VIEWPORT,
    arena_in_view,
    canvas_box,
    dismiss_toasts,
    number_box,
    open_folder,
    page_camera,
    point_radius_px,
    root_for,
    server_camera,
    to_pixel,
    upload_input,
    wait_until,
)


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


def open_page(browser, port: int, ready: str):
    context = arena_in_view(browser.new_context(accept_downloads=True, viewport=VIEWPORT))
    pg = context.new_page()
    pg.goto(f"http://127.0.0.1:{port}/")
    pg.wait_for_selector(f"label:has-text('{ready}')", timeout=90000)
    return pg


@pytest.fixture(scope="module")
def page(browser, server):
    pg = open_page(browser, server.port, "robots")
    yield pg
    pg.context.close()


@pytest.fixture(scope="module")
def cid(server, page):
    wait_until(lambda: len(server.tabs) == 1, what="the tab")
    return next(iter(server.tabs))


def screenshot(page) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB")).astype(int)


def radius_px(server, cid, page) -> float:
    """A robot's radius on screen."""
    return point_radius_px(server, cid, page, ROBOT_SIZE)


def seen(page, pixels: np.ndarray, colour_ok, attempts: int = 6, reach: int = 1) -> int:
    """How many of ``pixels`` show the colour (one pixel that passes within ``reach`` pixels),
    retried while a loaded machine is still drawing the last frame."""
    hits = 0
    for attempt in range(attempts):
        time.sleep(1.5 if attempt == 0 else 1.0)
        img = screenshot(page)
        hits = sum(bool(colour_ok(img[max(y - reach, 0): y + reach + 1, max(x - reach, 0): x + reach + 1]).any())
                   for x, y in pixels)
        if hits >= 0.9 * len(pixels):
            break
    return hits


def blue(patch: np.ndarray) -> np.ndarray:
    r, g, b = patch[..., 0], patch[..., 1], patch[..., 2]
    return (r < 100) & (g > 130) & (b > 130)


def red(patch: np.ndarray) -> np.ndarray:
    r, g, b = patch[..., 0], patch[..., 1], patch[..., 2]
    return (r > 170) & (g < 110) & (b < 110)


# ---------------------------------------------------------------------------- compare
def test_compare_runs_b_in_lock_step_and_draws_it_in_teal(server, page, cid, tmp_path):
    session = server.tabs[cid].session
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not session.playing, what="pause")
    page.get_by_role("tab", name="Controller").click()  # no trails: A's would be drawn over B's robots
    box = number_box(page, "trail [s]")
    box.fill("0")
    box.press("Enter")
    wait_until(lambda: session.scenario.view.trail_seconds == 0, what="trails off")
    open_folder(page, "Compare with swarm B", "compare with swarm B")
    root_for(page, "compare with swarm B").click()
    wait_until(lambda: session.twin is not None, what="swarm B")
    assert session.twin.scenario.controller.law == "standard"  # the first quick choice
    assert session.sim.state.k == 0  # A restarted with B
    page.get_by_role("button", name="Play", exact=True).click()
    wait_until(lambda: session.sim.state.k >= 40, what="40 steps")
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not session.playing, what="pause")
    tab = server.tabs[cid]  # the scene follows a moment after a control event (TabApp.CONTROL_HOLD)
    wait_until(lambda: tab.arena.drawn_revision == session.revision, what="the paused step drawn")
    assert session.twin.sim.state.k == session.sim.state.k
    dismiss_toasts(page)
    # B's robots that lie clear of A's are blue on screen, within a robot's diameter of where B is
    xa, xb = session.sim.state.x[0], session.twin.sim.state.x[0]
    body = ROBOT_SIZE / tab.arena.scale  # a robot's radius in metres
    clear = np.sqrt(((xb[:, None] - xa[None]) ** 2).sum(-1)).min(axis=1) > 4 * body
    inside = (np.abs(xb) < session.scenario.arena.half_size - 2 * body).all(axis=1)
    b = to_pixel(server, cid, page, xb)
    box = canvas_box(page)
    r = radius_px(server, cid, page)
    pixels = np.round(b[clear & inside]).astype(int)
    assert len(pixels) >= 3, (f"B should have moved apart from A: A about {xa.mean(axis=0).round(2)} m, B about "
                              f"{xb.mean(axis=0).round(2)} m")
    hits = seen(page, pixels, blue, reach=int(np.ceil(2 * r)))
    if hits < 0.8 * len(pixels):
        shot = tmp_path / "compare.png"
        shot.write_bytes(page.screenshot())
        x0, y0 = int(box["x"]), int(box["y"])
        arena = screenshot(page)[y0: y0 + int(box["height"]), x0: x0 + int(box["width"])]
        found = np.argwhere(blue(arena))[:, ::-1] + (x0, y0)  # (x, y) of every blue pixel in the arena
        where = (f"{len(found)} blue pixels in x {found[:, 0].min()}–{found[:, 0].max()}, y {found[:, 1].min()}–"
                 f"{found[:, 1].max()}" if len(found) else "no blue in the arena")
        raise AssertionError(f"only {hits}/{len(pixels)} of B's robots seen in blue, expected about "
                             f"{pixels.mean(axis=0).round(1)}, {where}; page camera {page_camera(page)}, "
                             f"reported {server_camera(server, cid)}; screenshot {shot}")
    # ...and its curve is in the speed plot
    page.get_by_role("tab", name="Plots").click()
    page.wait_for_selector("text=B: max |u|", timeout=20000)


# ---------------------------------------------------------------------------- replay
def test_a_replay_exported_here_plays_back_in_another_server(server, browser, page, cid):
    session = server.tabs[cid].session
    page.get_by_role("button", name="Play", exact=True).click()  # a recording past the step scrubbed to below
    wait_until(lambda: session.sim.state.k >= 20, what="20 steps")
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not session.playing, what="pause")
    open_folder(page, "Replay and files", "Export replay")
    with page.expect_download(timeout=30000) as dl:
        page.get_by_role("button", name="Export replay").click()
    data = open(dl.value.path(), "rb").read()
    rec = replay.from_bytes(data, dl.value.suggested_filename)
    assert dl.value.suggested_filename.endswith("-replay.npz")
    assert rec.name == "default" and rec.frames == len(session.frames)

    other = start_server("course-dvc", port=0)  # another user's server, on a fleet scene
    try:
        page2 = open_page(browser, other.port, "controller")
        try:
            wait_until(lambda: len(other.tabs) == 1, what="the second server's tab")
            cid2 = next(iter(other.tabs))
            open_folder(page2, "Replay and files", "Load replay")
            upload_input(page2, "Load replay").set_input_files(
                {"name": "run-replay.npz", "mimeType": "application/octet-stream", "buffer": data})
            wait_until(lambda: getattr(other.tabs[cid2].session, "replaying", None) is not None, what="the replay")
            tab2 = other.tabs[cid2]
            assert tab2.session.kind.name == "swarm" and tab2.session.scenario.name == "default"
            page2.wait_for_selector("text=Replay of default, seed 1", timeout=30000)
            page2.wait_for_selector(".mantine-Notification-root:has-text('verified')", timeout=30000)
            # scrub to step 12: the arena shows the recorded robots of that step
            k = 12
            open_folder(page2, "Replay and files", "timeline [step]")  # (the panel was rebuilt: closed again)
            box = number_box(page2, "timeline [step]")
            box.fill(str(k))
            box.press("Enter")
            wait_until(lambda: tab2.session.cursor == k, what=f"the timeline at step {k}")
            x = rec.robots(int(np.flatnonzero(rec.k == k)[0]))[0]
            wait_until(lambda: tab2.arena.drawn_revision == tab2.session.revision, what="the frame drawn")
            np.testing.assert_allclose(np.asarray(tab2.arena.nodes["robots"].points)[:, :2],
                                       tab2.arena.to_view(x)[:, :2], atol=1e-5)
            dismiss_toasts(page2)
            pixels = np.round(to_pixel(other, cid2, page2, x)).astype(int)
            hits = seen(page2, pixels, red)
            assert hits >= 0.9 * len(pixels), f"only {hits}/{len(pixels)} recorded robots seen where they were"
            assert tab2.session.sim.state.k == 0  # a replay does not advance the engine
            # Compare was on when it was exported: swarm B is in the file and drawn in blue where it was
            last = int(rec.k[-1])
            x_b = rec.twin(rec.frames - 1)[0]
            box.fill(str(last))
            box.press("Enter")
            wait_until(lambda: tab2.session.cursor == last, what=f"the timeline at step {last}")
            wait_until(lambda: tab2.arena.drawn_revision == tab2.session.revision, what="the last frame drawn")
            np.testing.assert_allclose(np.asarray(tab2.arena.nodes["twin"].points)[:, :2],
                                       tab2.arena.to_view(x_b)[:, :2], atol=1e-5)
            a = to_pixel(other, cid2, page2, rec.robots(rec.frames - 1)[0])
            b = to_pixel(other, cid2, page2, x_b)
            r = radius_px(other, cid2, page2)
            cb = canvas_box(page2)
            clear = np.sqrt(((b[:, None] - a[None]) ** 2).sum(-1)).min(axis=1) > 2 * r + 3
            inside = (b[:, 0] > cb["x"] + 5) & (b[:, 0] < cb["x"] + cb["width"] - 5) & (b[:, 1] > cb["y"] + 5) & (
                b[:, 1] < cb["y"] + cb["height"] - 5)
            pixels = np.round(b[clear & inside]).astype(int)
            assert len(pixels) >= 3, "B should lie apart from A at the last step"
            dismiss_toasts(page2)
            hits = seen(page2, pixels, blue)
            assert hits >= 0.8 * len(pixels), f"only {hits}/{len(pixels)} of B's recorded robots seen in blue"
            page2.wait_for_selector("text=with swarm B (blue)", timeout=30000)
        finally:
            page2.context.close()
    finally:
        other.stop()


def test_a_loaded_replay_plays_from_its_first_step_on_play(server, page, cid):
    """A replay opens paused at its first step; Play plays it through, Reset goes back to its
    first step, *Run live* leaves it for a live run of its preset."""
    from shoal.app.kinds.registry import session_for
    from shoal.presets import io as presets_io

    src = session_for(presets_io.load("default", ["sim.seed=7"]))
    src.advance(80)
    data = src.export_replay()
    dismiss_toasts(page)
    open_folder(page, "Replay and files", "Load replay")
    upload_input(page, "Load replay").set_input_files(
        {"name": "seven-replay.npz", "mimeType": "application/octet-stream", "buffer": data})
    tab = server.tabs[cid]
    wait_until(lambda: tab.session.replaying is not None and tab.session.replaying.seed == 7, what="the replay")
    s = tab.session
    assert s.cursor == 0 and not s.playing
    page.wait_for_selector("text=replay · step 0 of 80", timeout=20000)
    page.wait_for_selector("text=Play plays it, Reset goes back to its first step", timeout=20000)
    wait_until(lambda: tab.arena.drawn_revision == s.revision, what="step 0 drawn")
    np.testing.assert_allclose(np.asarray(tab.arena.nodes["robots"].points)[:, :2],
                               tab.arena.to_view(src.frames[0].x)[:, :2], atol=1e-5)

    page.get_by_role("button", name="Play", exact=True).click()
    wait_until(lambda: (s.cursor or 0) >= 20, timeout=30, what="the replay playing on from step 0")
    page.wait_for_selector("text=/replay · step [1-9][0-9]* of 80/", timeout=20000)
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not s.playing, what="pause")
    k = s.cursor
    wait_until(lambda: tab.arena.drawn_revision == s.revision, what="the paused step drawn")
    np.testing.assert_allclose(np.asarray(tab.arena.nodes["robots"].points)[:, :2],
                               tab.arena.to_view(src.frames[k].x)[:, :2], atol=1e-5)
    assert s.sim.state.k == 0  # the engine stayed where it was

    page.get_by_role("button", name="Reset", exact=True).click()
    wait_until(lambda: s.cursor == 0, what="Reset: the replay's first step")
    assert s.replaying is not None
    page.get_by_role("button", name="Run live (leave the replay)").click()
    wait_until(lambda: s.replaying is None and s.playing, what="a live run")
    wait_until(lambda: s.k > 3, what="the live run stepping")
    assert not page.get_by_role("button", name="Run live (leave the replay)").is_visible()
    dismiss_toasts(page)
