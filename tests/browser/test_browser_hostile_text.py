"""A hostile preset and a hostile replay uploaded in real Chromium run no script, and their text
shows literally (issue 20, case 1).

Viser renders markdown with raw HTML. The preset's ``name`` and the replay's ``meta.name`` and
``meta.shoal`` below are HTML that would run script in the page (an ``<iframe srcdoc>`` setting
``parent.__pwn``, an ``<img onerror>``) and open websockets, as a student's file shown to a
lecturer might. The page must show them as text: no iframe or img from them, no script run,
no extra websocket, and the status line and the replay badge read them character for character.
"""

from __future__ import annotations

import shutil
import time

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

from test_trust_text import IFRAME, hostile_preset, hostile_replay  # noqa: E402

from browser_helpers import dismiss_toasts, open_folder, upload_input, wait_until  # noqa: E402

NAME = IFRAME  # (a preset's name has at most 80 characters)
REPLAY_NAME = ('<iframe srcdoc="<script>parent.__pwn=3;for(let i=0;i<3;i++)new parent.WebSocket(parent.location.href'
               '.replace(/^http/,\'ws\'))</script>"></iframe>')  # as the audit's replay, which opened 30
SHOAL = "<img src=x onerror=\"window.__pwn=2\">"
COUNT_SOCKETS = """
(() => {
  const Native = window.WebSocket;
  window.__sockets = 0;
  window.WebSocket = class extends Native { constructor(...a) { super(...a); window.__sockets += 1; } };
})();
"""


@pytest.fixture(scope="module")
def hostile_page(server):
    from browser_helpers import app_page

    with app_page(server, COUNT_SOCKETS) as pg:
        yield pg


def _no_script_ran(page, sockets: int) -> None:
    time.sleep(2.0)  # the text is on the page (the status line refreshes 4 times a second): a script would have run
    assert page.evaluate("window.__pwn") is None
    assert page.locator("iframe").count() == 0 and page.locator("img[src=x]").count() == 0
    assert page.evaluate("window.__sockets") == sockets  # no websocket opened by the text


def test_a_hostile_preset_runs_no_script_and_its_name_shows_literally(server, hostile_page):
    page = hostile_page
    sockets = page.evaluate("window.__sockets")
    open_folder(page, "Replay and files", "Load replay")
    dismiss_toasts(page)
    upload_input(page, "Upload preset").set_input_files(
        {"name": "student.toml", "mimeType": "application/toml", "buffer": hostile_preset(NAME)})
    wait_until(lambda: any(t.session.scenario.name == NAME for t in server.tabs.values()), what="the preset loaded")
    _no_script_ran(page, sockets)
    page.get_by_text(NAME + " ·", exact=False).first.wait_for(timeout=30000)  # the status line, literally


def test_a_hostile_replay_runs_no_script_and_its_names_show_literally(server, hostile_page):
    page = hostile_page
    sockets = page.evaluate("window.__sockets")
    dismiss_toasts(page)
    upload_input(page, "Load replay").set_input_files(
        {"name": "student.npz", "mimeType": "application/octet-stream",
         "buffer": hostile_replay(REPLAY_NAME, SHOAL)})
    wait_until(lambda: any(t.session.replaying is not None for t in server.tabs.values()), what="the replay loaded")
    _no_script_ran(page, sockets)
    badge = page.locator("p").filter(has_text=f"Replay of {REPLAY_NAME}, seed").filter(has_text=f"(shoal {SHOAL})")
    badge.first.wait_for(timeout=30000)  # the badge (a toast says "Replay of …" too, without the version)
