"""Shared fixtures of the real-browser tests: one app server and one Chromium page per module."""

from __future__ import annotations

import shutil

import pytest

from browser_helpers import ARGS, VIEWPORT, arena_in_view, wait_until

CHROMIUM = shutil.which("chromium")


@pytest.fixture(scope="module")
def server():
    from shoal.app.server import start_server

    srv = start_server("default", port=0)
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def page(server):
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        pg = arena_in_view(browser.new_page(viewport=VIEWPORT))
        pg.goto(f"http://127.0.0.1:{server.port}/")
        pg.wait_for_selector("label:has-text('robots')", timeout=90000)
        yield pg
        browser.close()


@pytest.fixture(scope="module")
def cid(server, page):
    """The client id of the module's one tab."""
    wait_until(lambda: len(server.tabs) == 1, what="the tab")
    return next(iter(server.tabs))
