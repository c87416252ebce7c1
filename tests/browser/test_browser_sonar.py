"""Chapter 6–8 scenes in a real headless Chromium: the preset switch through the dropdown, the
bearing rays and the correlation plot following the robot chosen in the GUI, and a mouse
drag that moves the source in the engine.

One server (started on a Chapter 3 preset) and one page for the module; tests run in file
order. Screen positions come from the tab's real camera, as in ``test_browser_fleet.py``.
"""

from __future__ import annotations

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

from browser_helpers import choose, dismiss_toasts, open_folder, root_for, to_pixel, wait_until  # noqa: E402


def _plot_matches(tab, robot: int) -> bool:
    b = tab.session.sim.state.bearing
    if b is None or tab.session.selected_robot != robot:
        return False
    x, y = (np.asarray(a) for a in tab.panels.handles["corr"].data[:2])
    first = np.zeros(len(x), bool)
    first[np.unique(x, return_index=True)[1]] = True  # τ_lag may sit on the grid (sample lag)
    on_grid = first & np.isin(x, b.lags * 1e3)
    return on_grid.sum() == b.corr.shape[-1] and np.allclose(y[on_grid], b.corr[0, robot])


def test_switching_to_sonar_draws_rays_and_the_correlation_follows_the_robot(server, page, cid):
    server.tabs[cid].session.pause()
    dismiss_toasts(page)
    choose(page, "preset", "sonar-xb-pso")
    wait_until(lambda: server.tabs[cid].session.kind.name == "sonar", what="an acoustic session")
    page.wait_for_selector("label:has-text('algorithm')", timeout=20000)
    tab = server.tabs[cid]
    page.get_by_role("button", name="Step", exact=True).click()
    wait_until(lambda: tab.session.sim.state.k >= 1, what="one step")
    session = tab.session
    wait_until(lambda: "rays_true" in tab.arena.nodes and tab.arena.nodes["rays_true"].visible, what="rays drawn")
    wait_until(lambda: not session.playing and tab.arena.drawn_revision == session.revision,
               what="the stepped scene drawn")  # (a moment after the click: TabApp.CONTROL_HOLD)
    x = session.sim.state.x[0]
    pts = np.asarray(tab.arena.nodes["rays_true"].points)
    np.testing.assert_allclose(pts[:, 0, :2], tab.arena.to_view(x)[:, :2], atol=1e-4)
    wait_until(lambda: _plot_matches(tab, 0), what="robot 0's R(τ) plotted")
    before = np.asarray(tab.panels.handles["corr"].data[1]).copy()
    open_folder(page, "Selected robot", "robot")  # closed at first: the controls fit
    field = root_for(page, "robot")
    field.fill("6")
    field.press("Enter")
    wait_until(lambda: session.selected_robot == 6, what="robot 6 selected")
    wait_until(lambda: _plot_matches(tab, 6), what="robot 6's R(τ) plotted")
    assert not np.allclose(np.asarray(tab.panels.handles["corr"].data[1]), before)
    page.get_by_role("tab", name="Plots").click()
    page.get_by_text("selected robot: R(τ)", exact=False).first.wait_for(timeout=30000)
    axes = tab.panels.handles["corr"].axes  # (uPlot draws the axes' labels on its canvas)
    assert axes[0]["label"] == "τ [ms]" and axes[1]["label"] == "R(τ)"


def test_dragging_the_source_with_the_mouse_moves_it_in_the_engine(server, page, cid):
    tab = server.tabs[cid]
    session = tab.session
    session.pause()
    dismiss_toasts(page)
    start = session.sim.state.source[0].copy()
    dest = start * 0.5 + np.array([0.0, -60.0])
    a, b = to_pixel(server, cid, page, start), to_pixel(server, cid, page, dest)
    for attempt in range(3):  # the first frames may still be on their way on a loaded machine
        time.sleep(1.0)
        page.mouse.move(float(a[0]), float(a[1]))
        page.mouse.down()
        for f in np.linspace(0.1, 1.0, 12):
            p = a + f * (b - a)
            page.mouse.move(float(p[0]), float(p[1]))
            time.sleep(0.05)
        page.mouse.up()
        try:
            wait_until(lambda: np.hypot(*(session.sim.state.source[0] - dest)) < 15.0, timeout=5.0,
                       what="the source moved")
            break
        except AssertionError:
            if attempt == 2:
                raise
    assert np.hypot(*(session.sim.state.source[0] - start)) > 100.0


def test_the_lessons_tab_marks_where_the_scenes_values_come_from(server, page, cid, tmp_path):
    tab = server.tabs[cid]
    dismiss_toasts(page)
    choose(page, "preset", "sonar-xb-pso")
    wait_until(lambda: tab.session.scenario.name == "sonar-xb-pso", what="the Chapter 7 preset")
    page.get_by_role("tab", name="Lessons").click()
    row = page.locator("li", has_text="acoustics.fs =").first
    if not (row.count() and row.is_visible()):  # (the folder may start closed)
        page.get_by_text("Where this scene's values come from", exact=True).first.click()
    wait_until(lambda: row.count() and "fitted" in row.inner_text(), what="the mark of acoustics.fs")
    row.scroll_into_view_if_needed()
    assert "4000" in row.inner_text() and "sample rate" in row.inner_text()
    page.screenshot(path=str(tmp_path / "marks.png"))
