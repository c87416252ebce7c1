"""Several real Chromium tabs on one server: independent sessions, the session cap, a tab
closed while playing.

One server capped at three sessions (a run that never ends) and one headless Chromium with
a context per tab. The steps run in file order: three tabs play side by side; a fourth is
told the server is full; one playing tab is closed; the fourth, reloaded, then gets the
freed session. (Three, not more: software-rendered pages on two cores are slow.)
"""

from __future__ import annotations

import shutil

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

sync_api = pytest.importorskip("playwright.sync_api")

from shoal.app.server import FULL_TITLE  # noqa: E402

from browser_helpers import ARGS, VIEWPORT, number_box, wait_until  # noqa: E402

CAP = 3
READY = "label:has-text('robots')"


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    from shoal.app.server import start_server
    from shoal.presets.io import load, to_toml

    path = tmp_path_factory.mktemp("trust") / "endless.toml"
    path.write_text(to_toml(load("default", ["sim.steps=10000000"])), encoding="utf-8")
    srv = start_server(str(path), port=0, max_sessions=CAP)
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture(scope="module")
def pages(browser, server):
    """``CAP`` tabs, each in its own browser context, all loaded."""
    opened = [browser.new_context(viewport=VIEWPORT).new_page() for _ in range(CAP)]
    for pg in opened:
        pg.goto(f"http://127.0.0.1:{server.port}/")
    for pg in opened:
        pg.wait_for_selector(READY, timeout=180_000)
    wait_until(lambda: len(server.tabs) == CAP, timeout=90, what=f"{CAP} sessions")
    yield opened
    for pg in opened:
        if not pg.is_closed():
            pg.context.close()


def _advancing(server, margin: int = 5) -> None:
    sessions = server.sessions
    before = {cid: s.sim.state.k for cid, s in sessions.items()}
    wait_until(lambda: all(s.sim.state.k >= before[cid] + margin for cid, s in sessions.items()),
               timeout=90, what="every session to advance")


def test_tabs_play_their_own_independent_simulations(server, pages):
    sessions = server.sessions
    assert len({id(s) for s in sessions.values()}) == CAP and len({id(s.sim) for s in sessions.values()}) == CAP
    _advancing(server)  # every tab plays from the start
    box = number_box(pages[1], "robots")
    box.fill("7")
    box.press("Enter")
    wait_until(lambda: sorted(s.sim.robots for s in server.sessions.values()) == [7] + [20] * (CAP - 1),
               what="7 robots in one tab only")
    _advancing(server)


def test_a_tab_beyond_the_cap_is_told_the_server_is_full(server, browser, pages):
    extra = browser.new_context(viewport=VIEWPORT).new_page()
    pages.append(extra)
    extra.goto(f"http://127.0.0.1:{server.port}/")
    extra.wait_for_selector("text=its maximum", timeout=180_000)
    assert extra.locator(f"text={FULL_TITLE}").count() >= 1
    assert len(server.tabs) == CAP and len(server.turned_away) == 1
    assert extra.locator(READY).count() == 0  # no panels: no simulation for it


def test_closing_a_playing_tab_frees_its_session_and_the_others_play_on(server, pages, capfd):
    wait_until(lambda: all(s.playing for s in server.sessions.values()), what="every session playing")
    before = set(server.tabs)
    pages[0].close()
    wait_until(lambda: len(server.tabs) == CAP - 1, what="the closed tab's session to go")
    assert set(server.tabs) < before
    _advancing(server)
    err = capfd.readouterr().err
    assert "Traceback" not in err and "tab update failed" not in err, err[-2000:]


def test_the_turned_away_tab_gets_the_freed_session_on_reload(server, pages):
    extra = pages[-1]
    extra.reload()
    extra.wait_for_selector(READY, timeout=180_000)
    wait_until(lambda: len(server.tabs) == CAP and not server.turned_away, what="a session for the reloaded tab")
    _advancing(server, margin=3)
