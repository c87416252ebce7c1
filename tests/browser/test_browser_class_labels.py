"""The arena's labels a lecture's class sees, in real Chromium (issues 31 and 32): the same
HTML labels over the canvas as the lecturer's tab (sharp, dark on white, never under the page's
smallest text), following the lecturer to a scene of another kind, and given whole to a class
tab that joins late.

The broadcast draws its arena once for every watcher; its labels' state travels in one element
of the broadcast's panel (``shoal.app.view.overlay.ClassLabels``), which each watcher's page
follows. Before, a watcher's labels were viser's, drawn into the WebGL canvas at 10–11 px.
"""

from __future__ import annotations

import shutil

import pytest

from shoal.app.hall import routes
from shoal.app.hall.command import start_lecture
from shoal.app.hall.watcher import TAKE_OVER
from shoal.app.view.projector import MIN_PX

from browser_helpers import ARGS, VIEWPORT, arena_in_view, choose, wait_until

pytestmark = pytest.mark.browser

LABELS_JS = """() => [...document.querySelectorAll('#shoal-labels > div')]
  .filter((e) => e.style.display !== 'none' && e.getBoundingClientRect().width > 0)
  .map((e) => [e.textContent, parseFloat(getComputedStyle(e).fontSize)]).sort()"""


def labels(page) -> list[tuple[str, float]]:
    """The labels a page shows over its arena: (text, CSS font size), sorted."""
    return [(t, round(px, 1)) for t, px in page.evaluate(LABELS_JS)]


def same_labels(a, b) -> list | None:
    """The labels of pages ``a`` and ``b`` once they agree and show some (else None)."""
    la, lb = labels(a), labels(b)
    return la if la and la == lb else None


def test_the_class_sees_the_lecturers_labels_and_follows_them_to_another_kind():
    sync_api = pytest.importorskip("playwright.sync_api")
    srv = start_lecture("default", port=0)
    try:
        with sync_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
            try:
                def open_page(path: str):
                    page = arena_in_view(browser.new_context(viewport=VIEWPORT)).new_page()
                    page.goto(srv.url.rstrip("/") + path)
                    return page

                boss = open_page(f"{routes.LECTURER_PATH}#key={srv.key}")
                boss.get_by_role("button", name="Play", exact=True).first.wait_for(state="visible", timeout=120000)
                class_tab = open_page("/")
                class_tab.get_by_role("button", name=TAKE_OVER, exact=True).wait_for(state="visible", timeout=120000)

                shown = wait_until(lambda: same_labels(boss, class_tab), timeout=60, what="the class's labels")
                texts = {t for t, _ in shown}
                assert {"source", "cost f", "5 m"} <= texts, shown
                small = [(t, px) for t, px in shown if px < MIN_PX - 0.05]
                assert small == [], f"labels under {MIN_PX} px: {small}"
                assert class_tab.locator("[data-shoal-labels]").count() == 1  # the holder, hidden
                assert not class_tab.locator("[data-shoal-labels]").first.is_visible()

                choose(boss, "preset", "course-dvc")  # a fleet: its obstacle layers are labelled
                moved = wait_until(lambda: (lambda s: s if s and any(t.startswith("layer ") for t, _ in s) else None)(
                    same_labels(boss, class_tab)), timeout=90, what="the class's labels of the course")
                assert "cost f" not in {t for t, _ in moved}, moved  # the swarm's colour bar went with its scene

                late = open_page("/")  # joins now: gets the labels whole
                late.get_by_role("button", name=TAKE_OVER, exact=True).wait_for(state="visible", timeout=120000)
                assert wait_until(lambda: same_labels(boss, late), timeout=60, what="a late class tab's labels") == \
                    labels(class_tab)
            finally:
                browser.close()
    finally:
        srv.stop()



def test_serve_lecture_projector_opens_the_lecturers_tab_in_projector_mode():
    """``shoal serve --lecture --projector``: the lecturer's tab (the one on the projector) opens
    with every text twice its size, the arena's labels too. A class tab stays in the normal mode:
    it is a student's own screen, and the broadcast's plots are sized once for every watcher."""
    sync_api = pytest.importorskip("playwright.sync_api")
    srv = start_lecture("default", port=0, projector=True)
    projecting = "() => document.documentElement.classList.contains('shoal-projector')"
    try:
        with sync_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
            try:
                def open_page(path: str):
                    page = arena_in_view(browser.new_context(viewport={"width": 1920, "height": 1080})).new_page()
                    page.goto(srv.url.rstrip("/") + path)
                    return page

                boss = open_page(f"{routes.LECTURER_PATH}#key={srv.key}")
                boss.get_by_role("button", name="Play", exact=True).first.wait_for(state="visible", timeout=120000)
                wait_until(lambda: boss.evaluate(projecting), timeout=60, what="the lecturer's projector mode")
                shown = wait_until(lambda: labels(boss), timeout=60, what="the lecturer's labels")
                assert min(px for _, px in shown) >= 2 * MIN_PX - 0.05, shown
                class_tab = open_page("/")
                class_tab.get_by_role("button", name=TAKE_OVER, exact=True).wait_for(state="visible", timeout=120000)
                shown = wait_until(lambda: labels(class_tab), timeout=60, what="the class's labels")
                assert not class_tab.evaluate(projecting) and min(px for _, px in shown) >= MIN_PX - 0.05
            finally:
                browser.close()
    finally:
        srv.stop()
