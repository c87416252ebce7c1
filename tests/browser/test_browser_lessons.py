"""A lesson walked end to end in a real headless Chromium: pick it, go to a step, Set up (the
panel and the swarm change), Play, reveal the answer; then a Set up that needs another kind
of scene keeps the lesson in view. The Python side is checked through ``server.tabs``."""

from __future__ import annotations

import shutil

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

pytest.importorskip("playwright.sync_api")

from shoal.app.panel.board import TITLE as BOARD  # noqa: E402

from browser_helpers import choose, dismiss_toasts, number_box, root_for, wait_until  # noqa: E402

STABILITY = "Ch. 3 · When does a swarm blow up? Stability of PSO"
DVC = "Ch. 4 · Through the obstacles: RPSO, Adapted RPSO and DVC"


def _visible_text(page, text: str, timeout: float = 30.0) -> None:
    wait_until(lambda: page.get_by_text(text, exact=False).first.is_visible(), timeout=timeout,
               what=f"'{text}' on the page")


def test_a_lesson_step_sets_up_the_scene_and_reveals_its_answer(server, page, cid):
    tab = server.tabs[cid]
    dismiss_toasts(page)
    page.get_by_role("tab", name="Lessons").click()
    choose(page, "lesson", STABILITY)
    wait_until(lambda: tab.lesson_progress.lesson == "03a-stability", what="the lesson picked")
    _visible_text(page, "Step 1 of 4: Inside both regions")
    for _ in range(2):
        page.get_by_role("button", name="Next ▶").click()
    _visible_text(page, "Step 3 of 4: An inertia weight above 1")
    assert not page.get_by_text("outside every region").first.is_visible()  # the answer waits

    page.get_by_role("button", name="Set up this step").click()
    wait_until(lambda: tab.session.scenario.name == "standard-pso", what="the step's scene")
    session = tab.session
    assert (session.scenario.controller.law, session.sim.policy.omega) == ("standard", 1.1)
    assert session.sim.state.k == 0 and not session.playing
    page.wait_for_selector(".mantine-Notification-root:has-text('Set up step 3')", timeout=20000)

    page.get_by_role("tab", name="Controller").click()  # the panel shows the step's law and ω
    wait_until(lambda: root_for(page, "law").input_value() == "standard", what="law = standard in the panel")
    wait_until(lambda: number_box(page, "omega ω").input_value() == "1.1", what="ω = 1.1 in the panel")

    page.get_by_role("button", name="Play", exact=True).click()  # the swarm diverges, as the step says
    wait_until(lambda: session.sim.state.k >= 60, what="60 steps")
    _visible_text(page, "20 outside the arena")

    page.get_by_role("tab", name="Lessons").click()
    page.get_by_role("button", name="Show answer").click()
    _visible_text(page, "outside every region")
    assert page.get_by_role("button", name="Hide answer").is_visible()
    page.get_by_role("button", name="Pause", exact=True).click()
    dismiss_toasts(page)


def test_a_set_up_of_another_kind_keeps_the_lesson_in_view(server, page, cid):
    tab = server.tabs[cid]
    choose(page, "lesson", DVC)
    _visible_text(page, "Step 1 of 6: The original RPSO")
    page.get_by_role("button", name="Set up this step").click()
    wait_until(lambda: tab.session.scenario.name == "course-rpso", what="the fleet scene")
    page.wait_for_selector("text=Arena view and selected robot", timeout=60000)  # the fleet's panel
    tabs = page.get_by_role("tab").filter(has_not_text=BOARD)  # (the board beside the arena has a tab of its own)
    wait_until(lambda: tabs.first.inner_text() == "Lessons", what="the Lessons tab first")
    assert tabs.first.get_attribute("aria-selected") == "true"
    _visible_text(page, "Step 1 of 6: The original RPSO")  # open on the same step, no click needed
    assert page.get_by_role("tab", name="World").count() == 1
    dismiss_toasts(page)
