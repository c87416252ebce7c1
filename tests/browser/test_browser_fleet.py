"""Chapter 4–5 scenes in a real headless Chromium: the preset switch through the dropdown, a
mouse click on the canvas that adds an obstacle, a drag that moves one, and the sector view
following the robot chosen in the GUI or clicked in the arena.

One server (started on a Chapter 3 preset) and one page for the module; tests run in file
order. Screen positions come from the tab's real camera (straight down, vertical field of
view ``fov``), as in ``test_browser.py``.
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

from shoal.app.kinds import fleet  # noqa: E402

from browser_helpers import choose, dismiss_toasts, open_folder, root_for, to_pixel, wait_until  # noqa: E402


def screenshot(page) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB")).astype(int)


def pause(server, cid, page):
    session = server.tabs[cid].session
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not session.playing, what="pause")
    return session


def free_point(session, x_min: float, x_max: float) -> np.ndarray:
    """A spot clear of obstacles (2 m) and robots (3 m) in the strip x_min < x < x_max."""
    world, x = session.sim.world, session.sim.state.x[0]
    for px in np.linspace(x_min, x_max, 9):
        for py in np.linspace(-8.0, 8.0, 17):
            p = np.array([px, py])
            if world.obstacle_distance(*p).min() > 2.0 and np.hypot(*(x - p).T).min() > 3.0:
                return p
    raise AssertionError("no free point")


# ---------------------------------------------------------------------------- switch
def test_the_preset_dropdown_switches_to_the_obstacle_course(server, page, cid):
    server.tabs[cid].session.pause()
    dismiss_toasts(page)
    choose(page, "preset", "course-dvc")
    wait_until(lambda: server.tabs[cid].session.kind.name == "fleet", what="a fleet session")
    tab = server.tabs[cid]
    page.wait_for_selector("label:has-text('controller')", timeout=20000)
    wait_until(lambda: "obstacles" in tab.arena.nodes, what="the obstacles drawn")
    session = tab.session
    assert session.playing  # every scene opens playing, whatever the one before did
    session.pause()  # (a still scene renders faster)
    circles = session.sim.world.circles
    node = tab.arena.nodes["obstacles"]
    np.testing.assert_allclose(np.asarray(node.batched_positions)[:, :2],
                               tab.arena.to_view(circles[:, :2])[:, :2], atol=1e-5)
    # ...and the picture has an obstacle where each one is
    dismiss_toasts(page)
    centres = np.round(to_pixel(server, cid, page, circles[:, :2])).astype(int)
    for _attempt in range(30):  # a loaded machine (software WebGL) may need many seconds for the first frames
        time.sleep(1.0)
        img = screenshot(page)
        dark = 0
        for cx, cy in centres:
            patch = img[cy - 1: cy + 2, cx - 1: cx + 2]
            dark += bool(np.all(patch.max(axis=-1) < 150) and np.all(patch[..., 2] >= patch[..., 0]))
        if dark >= 0.9 * len(circles):
            break
    assert dark >= 0.9 * len(circles), f"only {dark}/{len(circles)} obstacles seen where the world has them"
    ground = to_pixel(server, cid, page, free_point(session, 20.0, 40.0)).round().astype(int)
    assert img[ground[1], ground[0]].min() > 200  # and free ground is light


# ---------------------------------------------------------------------------- click
def test_a_click_in_the_arena_adds_an_obstacle_there(server, page, cid):
    session = pause(server, cid, page)
    n = len(session.sim.world.circles)
    target = free_point(session, 20.0, 40.0)
    px, py = to_pixel(server, cid, page, target)
    page.mouse.click(float(px), float(py))
    wait_until(lambda: len(session.sim.world.circles) == n + 1, what="a new obstacle")
    new = session.sim.world.circles[-1]
    assert np.hypot(*(new[:2] - target)) < 0.3, f"added at {new[:2]}, clicked {target}"
    assert new[2] == pytest.approx(fleet.driver(session).obstacle_radius)
    wait_until(lambda: len(server.tabs[cid].arena.nodes["obstacles"].batched_positions) == n + 1,
               what="the new obstacle drawn")


def test_dragging_an_obstacle_moves_it(server, page, cid):
    session = pause(server, cid, page)
    i = len(session.sim.world.circles) - 1  # the one just added
    start = session.sim.world.circles[i, :2].copy()
    dest = free_point(session, 42.0, 52.0)
    a, b = to_pixel(server, cid, page, start), to_pixel(server, cid, page, dest)
    page.mouse.move(float(a[0]), float(a[1]))
    page.mouse.down()
    for f in np.linspace(0.1, 1.0, 10):
        p = a + f * (b - a)
        page.mouse.move(float(p[0]), float(p[1]))
        time.sleep(0.05)
    page.mouse.up()
    wait_until(lambda: np.hypot(*(session.sim.world.circles[i, :2] - dest)) < 0.5, what="the obstacle moved")
    assert len(session.sim.world.circles) == i + 1


# ---------------------------------------------------------------------------- selected robot
def _sector_centre(tab) -> np.ndarray:
    return tab.arena.to_world(np.asarray(tab.arena.nodes["sectors"].batched_positions)[0, :2]
                              + np.asarray(tab.arena.nodes["root"].position)[:2])


def test_the_sector_view_follows_the_robot_chosen_in_the_gui(server, page, cid):
    session = pause(server, cid, page)
    tab = server.tabs[cid]
    open_folder(page, "Arena view and selected robot", "robot")  # closed at first: the controls fit
    field = root_for(page, "robot")  # a number input
    field.fill("3")
    field.press("Enter")
    wait_until(lambda: session.selected_robot == 3, what="robot 3 selected")
    wait_until(lambda: np.allclose(_sector_centre(tab), session.sim.state.x[0, 3], atol=1e-4),
               what="the sectors on robot 3")
    # clicking a robot selects it too
    j = 5
    px, py = to_pixel(server, cid, page, session.sim.state.x[0, j])
    page.mouse.click(float(px), float(py))
    wait_until(lambda: session.selected_robot == j, what=f"robot {j} selected by a click")
    wait_until(lambda: np.allclose(_sector_centre(tab), session.sim.state.x[0, j], atol=1e-4),
               what=f"the sectors on robot {j}")
    wait_until(lambda: field.input_value() == str(j), what="the robot box to show the clicked robot")
    assert f"robot {j}" in tab.panels.handles["budget"].content
