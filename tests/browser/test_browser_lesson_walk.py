"""Every step of every shipped lesson walked in a real headless Chromium, as a lecturer would:
go to the step, press *Set up* (the arena shows the step's scene at step 0, paused, at the speed
the step sets), reveal the answer. The first step of each lesson with numbers is also played for
a few seconds (the robots move and the arena draws them), run on to the step the lesson's
numbers need, and its numbers read off the page under the question: each equals what the
headless check (``lessons/verify.py``) computes for that scene. No step may leave an error in
the page's console.

The numbers of every other step, and the numbers the answers quote, are compared headless
(``tests/test_lessons.py``: the app's own session read as this page reads it, and each
``quote`` against its reading), which is what this walk spent four minutes on before.

One server and one page for the module; one test per lesson, in file order. Running the runs
to the check's step is done on the server (``Session.advance``, what Play at full speed does).
"""

from __future__ import annotations

import functools
import shutil
import time

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

pytest.importorskip("playwright.sync_api")

from shoal.app.lessons import readings  # noqa: E402
from shoal.app.lessons.library import shipped  # noqa: E402
from shoal.app.lessons.scenes import load_scene  # noqa: E402
from shoal.app.lessons.verify import run_metrics  # noqa: E402
from shoal.app.panel.lesson_run import same_scene  # noqa: E402

from browser_helpers import choose, dismiss_toasts, wait_until  # noqa: E402

LESSONS, _ = shipped()
PLAY_SECONDS = 1.5  # at least, and at least MIN_STEPS steps
MIN_STEPS = 3
COMPILE = 600.0  # s: a first scene of a kind may compile its kernels (on a busy machine)


@functools.cache
def headless(lesson_id: str, index: int) -> list[readings.Reading]:
    (preset, values), check = readings.step_check(LESSONS[lesson_id], index)
    return readings.headless(check, run_metrics(preset, values, check.steps, check.runs))


@pytest.fixture(scope="module")
def console(page):
    """Errors the page reports (console errors and uncaught exceptions), as they come."""
    errors: list[str] = []
    page.on("console", lambda m: errors.append(f"console: {m.text}") if m.type == "error" else None)
    page.on("pageerror", lambda e: errors.append(f"page error: {e}"))
    return errors


def _text(page) -> str:
    return " ".join(page.locator("body").inner_text().split())


def _shows(page, text: str, timeout: float = 30.0) -> None:
    wait_until(lambda: text in _text(page), timeout=timeout, what=f"'{text}' on the page")


def _set_up(page, server, cid, scene) -> object:
    """Press Set up; returns the session once it shows the step's scene at step 0, paused."""
    want = load_scene(*scene)
    page.get_by_role("button", name="Set up this step").click()

    def loaded():
        s = server.tabs[cid].session
        with s.lock:
            return s if same_scene(s.scenario, want) and s.k == 0 and not s.playing else None
    s = wait_until(loaded, timeout=COMPILE, what=f"the scene {scene[0]} at step 0, paused")
    page.wait_for_selector(".mantine-Notification-root:has-text('Set up step')", timeout=60000)
    return s


def _play_a_few_seconds(page, server, cid) -> object:
    """Play until the robots have moved for a few seconds, then pause; returns the session."""
    s = server.tabs[cid].session
    with s.lock:
        k0, x0 = (0 if s.finished else s.k), s.sim.state.x[0].copy()  # a finished run plays again from step 0
    page.get_by_role("button", name="Play", exact=True).click()
    start = time.monotonic()
    wait_until(lambda: s.k >= k0 + MIN_STEPS and time.monotonic() - start >= PLAY_SECONDS, timeout=COMPILE,
               what="a few seconds of play")
    page.get_by_role("button", name="Pause", exact=True).click()
    wait_until(lambda: not s.playing, what="pause")
    with s.lock:
        moved = float(np.nanmax(np.abs(s.sim.state.x[0] - x0)))
    assert moved > 0, "the robots did not move"
    tab = server.tabs[cid]
    wait_until(lambda: tab.arena.drawn_revision == s.revision, what="the arena drawn")
    return s


@pytest.mark.parametrize("lesson_id", sorted(LESSONS))
def test_every_step_of_the_lesson_sets_up_plays_and_reads_what_it_says(server, page, cid, console, lesson_id):
    lesson = LESSONS[lesson_id]
    dismiss_toasts(page)
    page.get_by_role("tab", name="Lessons").click()
    choose(page, "lesson", lesson.label)
    n = len(lesson.steps)
    played = next((i for i in range(n) if readings.step_check(lesson, i) is not None), 0)  # (the thin browser layer)
    for i, step in enumerate(lesson.steps):
        where = f"{lesson_id}, step {i + 1} '{step.title}'"
        _shows(page, f"Step {i + 1} of {n}: {step.title}")
        scene = lesson.scene(i)
        if scene is not None:
            s = _set_up(page, server, cid, scene)
            assert s.scenario.view.steps_per_second == load_scene(*scene).view.steps_per_second, where
        else:
            assert not page.get_by_role("button", name="Set up this step").is_visible(), where
        found = readings.step_check(lesson, i) if i == played else None
        if i == played:
            s = _play_a_few_seconds(page, server, cid)
        if found is not None:
            _, check = found
            with s.lock:
                k = s.k
            if k < check.steps:
                s.advance(check.steps - k)  # (Play at full speed, run on the server)
            for r in headless(lesson_id, i):
                assert r.complete, where
                _shows(page, f"{r.label}, {r.span}: {r.shown}")  # the number the step asks about, on screen
        elif readings.step_check(lesson, i) is None:
            assert "Read on screen" not in _text(page), where
        page.get_by_role("button", name="Show answer").click()
        page.get_by_role("button", name="Hide answer").wait_for(state="visible", timeout=30000)
        assert page.get_by_text("Answer:", exact=False).first.is_visible(), where
        assert console == [], f"{where}: {console}"
        dismiss_toasts(page)
        page.get_by_role("button", name="Next ▶").click()
    _shows(page, "Try it yourself")
