"""A lecture hall in real Chromium (issue 31 §5): ``shoal hall`` with two workers behind Debian's
nginx, every page through the proxy.

One walk, four pages at 1280×800: the lecturer opens the address with the key (the page moves
the key into its cookie and out of the address bar, and loads again), drives the run; two class
tabs show the same step; a lesson's question goes to the class as a round, both answer, the
lecturer reveals it and the run plays; one class tab takes over and lands, full panel, on a
worker; *Back to the lecture* returns it to watching.
"""

from __future__ import annotations

import re
import shutil
import socket

import pytest

from shoal.app.hall import routes
from shoal.app.hall.channel import RemoteDesk
from shoal.app.hall.private import BACK
from shoal.app.hall.supervisor import Hall
from shoal.app.hall.watcher import TAKE_OVER

from browser_helpers import ARGS, VIEWPORT, arena_in_view, wait_until

pytestmark = pytest.mark.browser
STEP = re.compile(r"step (\d+)/(\d+)")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def step_of(page) -> int | None:
    """The step the page's status line names (the first "step k/N" on the page)."""
    m = STEP.search(page.locator("body").inner_text(timeout=10000))
    return int(m.group(1)) if m else None


def button(page, name: str):
    return page.get_by_role("button", name=name, exact=True).first


def test_a_lecture_hall_in_chromium():
    sync_api = pytest.importorskip("playwright.sync_api")
    hall = Hall("default", workers=2, port=free_port())
    hall.start()
    try:
        with sync_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
            try:
                _walk(browser, hall)
            finally:
                browser.close()
    finally:
        hall.stop()


def _walk(browser, hall: Hall) -> None:
    def open_page(path: str):
        page = arena_in_view(browser.new_context(viewport=VIEWPORT)).new_page()
        page.goto(hall.url.rstrip("/") + path)
        return page

    boss = open_page(f"{routes.LECTURER_PATH}#key={hall.key}")
    button(boss, "Play").wait_for(state="visible", timeout=120000)
    assert boss.url.endswith(routes.LECTURER_PATH) and hall.key not in boss.url  # the key left the address bar
    a, b = open_page("/"), open_page("/")
    for w in (a, b):
        button(w, TAKE_OVER).wait_for(state="visible", timeout=120000)
        assert button(w, "Play").count() == 0  # a class tab has no control of the run

    # the lecturer drives; both class tabs show the lecture's step
    button(boss, "Play").click()
    wait_until(lambda: (step_of(a) or 0) >= 10, what="the class watching the run play", timeout=90)
    button(boss, "Pause").click()
    wait_until(lambda: step_of(boss) is not None and step_of(boss) == step_of(a) == step_of(b),
               what="the lecturer and both class tabs at the same step", timeout=30)

    # a lesson step's question as a round, end to end
    boss.get_by_role("tab", name="Lessons").click()
    button(boss, "Ask the class").click()
    for w, choice in ((a, "A"), (b, "B")):
        button(w, choice).wait_for(state="visible", timeout=30000)
        button(w, choice).click()
    wait_until(lambda: boss.get_by_text("2 answers", exact=False).count() > 0, what="the lecturer's live count")
    k = step_of(a) or 0
    button(boss, "Reveal and play").click()
    for w in (a, b):  # (the page's text, case and all: "Your answer: Inside" is not the answer revealed)
        wait_until(lambda w=w: all(t in w.locator("body").inner_text() for t in ("Answer: Inside", "2 answers:",
                                                                               "(50 %)")),
                   what="the distribution and the answer on every class tab", timeout=30)
    wait_until(lambda: (step_of(a) or 0) > k + 5, what="the run playing out on the class's screens", timeout=60)

    # take over: the class tab opens a private session on a worker, then goes back to watching
    button(b, TAKE_OVER).click()
    b.wait_for_url(re.compile(r"/p/[A-Za-z0-9_-]+$"), timeout=60000)
    button(b, BACK).wait_for(state="visible", timeout=120000)
    button(b, "Play").wait_for(state="visible", timeout=60000)
    pid = routes.private_id(b.url.split(str(hall.port), 1)[1])
    assert hall.folder is not None
    desk = RemoteDesk(str(hall.folder / "desk.sock"), hall.channel_key, "worker-test")
    try:
        assert desk.holders()[pid][0] in ("worker-1", "worker-2")
    finally:
        desk.close()
    button(b, BACK).click()
    b.wait_for_url(re.compile(r":\d+/$"), timeout=30000)
    button(b, TAKE_OVER).wait_for(state="visible", timeout=60000)
