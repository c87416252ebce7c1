"""The example plug-in in the browser: with ``examples/plugin`` installed, the app's server (a
child process) offers its law and objective in the Chapter 3 panel's dropdowns and its preset,
whose scene kind the app then shows, in the preset menu."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time

import pytest

from browser_helpers import ARGS, VIEWPORT, arena_in_view, choose, root_for, wait_until
from plugin_env import plugin_env

pytestmark = pytest.mark.browser

SERVER = """
import sys, time
from shoal.app.server import start_server
srv = start_server("default", port=0)
print(f"PORT {srv.port}", flush=True)
sys.stdin.read()  # until the test closes our input
srv.stop()
"""


@pytest.fixture(scope="module")
def plugin_server(example_plugin):
    child = subprocess.Popen([sys.executable, "-c", SERVER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                             text=True, env=plugin_env(example_plugin))
    try:
        line = ""
        while not line.startswith("PORT "):  # (viser prints a banner first)
            line = child.stdout.readline()
            assert line, "the server did not start"
        yield int(line.split()[1])
    finally:
        child.stdin.close()
        try:
            child.wait(timeout=30)
        except subprocess.TimeoutExpired:
            child.kill()


def options_of(page, label: str) -> list[str]:
    root_for(page, label).click()
    options = page.get_by_role("option")
    wait_until(lambda: options.count() > 0, what=f"the {label} options")
    names = [options.nth(i).inner_text().strip() for i in range(options.count())]
    page.keyboard.press("Escape")
    return names


def test_the_plugins_law_objective_and_kind_are_in_the_apps_menus(plugin_server, tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=shutil.which("chromium"), args=ARGS)
        page = arena_in_view(browser.new_page(viewport=VIEWPORT))
        page.goto(f"http://127.0.0.1:{plugin_server}/")
        page.wait_for_selector("label:has-text('robots')", timeout=90000)
        assert "clamped" in options_of(page, "law")
        assert "himmelblau" in options_of(page, "objective")
        choose(page, "mode", "raw")  # (the preset's physical mode needs an Adapted law)
        wait_until(lambda: page.get_by_text("Raw mode:").count() > 0, what="raw mode")
        choose(page, "law", "clamped")
        choose(page, "objective", "himmelblau")
        wait_until(lambda: "Clamped PSO (example plug-in): ĉ has no unit" in page.content(),
                   what="the law's own readout")
        page.screenshot(path=str(tmp_path / "plugin-chapter3.png"))
        assert "gather-demo" in options_of(page, "preset")
        choose(page, "preset", "gather-demo")
        page.wait_for_selector("label:has-text('speed [m/s]')", timeout=60000)
        wait_until(lambda: "spread round the centroid" in page.content() and page.get_by_text("· spread").count(),
                   what="the gather kind's panel and status line")
        time.sleep(1.0)
        page.screenshot(path=str(tmp_path / "plugin-gather.png"))
        assert "spread" in page.content()
        browser.close()
