"""Shared fixtures of the real-browser tests: one app server and one Chromium page per module."""

from __future__ import annotations

import pytest

from browser_helpers import app_page, wait_until


@pytest.fixture(scope="module")
def server():
    from shoal.app.server import start_server

    srv = start_server("default", port=0)
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def page(server):
    with app_page(server) as pg:
        yield pg


@pytest.fixture(scope="module")
def cid(server, page):
    """The client id of the module's one tab."""
    wait_until(lambda: len(server.tabs) == 1, what="the tab")
    return next(iter(server.tabs))
