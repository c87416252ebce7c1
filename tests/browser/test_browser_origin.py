"""Only the server's own pages get a session, in real Chromium.

- the app's page at ``http://127.0.0.1:PORT/`` and ``http://localhost:PORT/`` works as ever;
- a page of another origin (here a page served on another local port) that opens a websocket
  to the app is refused: no session, no GUI;
- DNS rebinding: a name that resolves to 127.0.0.1 (Chromium's ``--host-resolver-rules``
  stands in for the attacker's DNS) gets 403 for the page itself and for its websocket.
"""

from __future__ import annotations

import http.server
import shutil
import threading

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

sync_api = pytest.importorskip("playwright.sync_api")

from browser_helpers import ARGS, VIEWPORT, wait_until  # noqa: E402

READY = "label:has-text('robots')"
REBOUND = "rebound.example"
ATTACK = """<!doctype html><title>another site</title><script>
window.result = "pending";
const ws = new WebSocket("ws://127.0.0.1:{port}", ["viser-v{version}"]);
ws.onopen = () => {{ window.result = "open"; }};
ws.onerror = () => {{ if (window.result === "pending") window.result = "refused"; }};
ws.onclose = () => {{ if (window.result === "pending") window.result = "refused"; }};
</script>"""


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM,
                              args=ARGS + [f"--host-resolver-rules=MAP {REBOUND} 127.0.0.1"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def other_site(server):
    """A page on another local port (another origin) that tries to open a session on the app."""
    import viser

    page = ATTACK.format(port=server.port, version=viser.__version__).encode()

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self) -> None:  # noqa: N802
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(page)))
            self.end_headers()
            self.wfile.write(page)

        def log_message(self, *args) -> None:
            pass

    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}/"
    httpd.shutdown()
    httpd.server_close()


@pytest.mark.parametrize("host", ["127.0.0.1", "localhost"])
def test_the_apps_own_page_gets_a_session(server, browser, host):
    context = browser.new_context(viewport=VIEWPORT)
    try:
        page = context.new_page()
        page.goto(f"http://{host}:{server.port}/")
        page.wait_for_selector(READY, timeout=180_000)
        wait_until(lambda: len(server.tabs) == 1, what="its session")
    finally:
        context.close()
    wait_until(lambda: not server.tabs, what="the session to go")


def test_a_page_of_another_origin_gets_no_session(server, browser, other_site, capfd):
    context = browser.new_context(viewport=VIEWPORT)
    try:
        page = context.new_page()
        page.goto(other_site)
        wait_until(lambda: page.evaluate("window.result") != "pending", what="the websocket's fate")
        assert page.evaluate("window.result") == "refused"
        assert not server.tabs and not server.viser.get_clients()
    finally:
        context.close()
    assert f"Origin '{other_site.rstrip('/')}' is not this server's page" in capfd.readouterr().err


def test_a_rebound_name_gets_neither_the_page_nor_a_session(server, browser):
    context = browser.new_context(viewport=VIEWPORT)
    try:
        page = context.new_page()
        response = page.goto(f"http://{REBOUND}:{server.port}/")
        assert response is not None and response.status == 403
        assert "is not this server" in page.content()
        assert page.locator(READY).count() == 0 and not server.tabs
    finally:
        context.close()
