"""No address in an escaped text becomes a link, in real Chromium (issue 30, case 4).

Viser's markdown has remark-gfm, whose autolinks turn ``https://…``, ``www.…`` and e-mail
addresses into ``<a>`` elements, found in the text after its escapes are read: 58 of 85 such
names of a preset or a replay were clickable in the lecturer's panel. Here viser renders the
same payloads twice, raw (as a control: most become links, so the count can fail) and through
``markdown.escape``: the escaped ones make no ``<a>``, show as written, and the page fetches
nothing from any other host. Then a preset named with addresses is uploaded into the app.
"""

from __future__ import annotations

import shutil
import socket
import time

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

from test_trust_text import hostile_preset  # noqa: E402

from browser_helpers import ARGS, VIEWPORT, dismiss_toasts, open_folder, upload_input, wait_until  # noqa: E402

HOSTS = ["evil.example", "uni.example", "a.b", "x-y.example.org"]
FORMS = ["https://{h}", "http://{h}/p?q=1#f", "HTTPS://{H}", "www.{h}", "WWW.{H}/x", "({h} www.{h})",
         "see www.{h}.", "student@{h}", "a.b+c@{h}", "mailto:me@{h}", "xmpp:me@{h}", "<https://{h}>",
         "<me@{h}>", "[x](https://{h})", "https://{h}/<b>x</b>", "ftp://{h}", "x https://{h}, y",
         "name@{h}, www.{h}", "https://{h}:8080/a@b", "//{h}/x", "https:/{h}"]
PAYLOADS = [f.format(h=h, H=h.upper()) for h in HOSTS for f in FORMS][:85]

COUNT = """
(marker) => {
  const p = [...document.querySelectorAll('p')].find(e => e.textContent.trim() === marker);
  if (!p) return null;
  const box = p.parentElement;
  return {links: box.querySelectorAll('a').length, media: box.querySelectorAll('img, iframe').length,
          text: box.innerText};
}
"""


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def chromium():
    sync_api = pytest.importorskip("playwright.sync_api")
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield browser
        finally:
            browser.close()


def test_escaped_addresses_make_no_link_and_show_as_written(chromium):
    import viser

    from shoal.app.markdown import escape

    assert len(PAYLOADS) == 84
    srv = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    try:
        srv.gui.add_markdown("\n\n".join(["RAWGROUP", *PAYLOADS]))
        srv.gui.add_markdown("\n\n".join(["ESCAPEDGROUP", *(escape(p) for p in PAYLOADS)]))
        page = chromium.new_page(viewport=VIEWPORT)
        outside: list[str] = []
        page.on("request", lambda r: None if r.url.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:"))
                else outside.append(r.url))
        page.goto(f"http://{srv.get_host()}:{srv.get_port()}/")
        raw = wait_until(lambda: page.evaluate(COUNT, "RAWGROUP"), timeout=90, what="the raw markdown")
        escaped = wait_until(lambda: page.evaluate(COUNT, "ESCAPEDGROUP"), timeout=30, what="the escaped markdown")
        time.sleep(1.0)
        assert raw["links"] >= 40, raw  # remark-gfm links most of them when they are not escaped
        assert escaped["links"] == 0, escaped
        lines = [line.replace("\u2060", "") for line in escaped["text"].split("\n") if line.strip()]
        assert lines[1:] == PAYLOADS, [(a, b) for a, b in zip(lines[1:], PAYLOADS) if a != b][:5]
        assert escaped["media"] == 0, escaped
        print(f"raw: {raw['links']} links of {len(PAYLOADS)} payloads; escaped: {escaped['links']}")
        assert outside == [], outside  # nothing fetched from anywhere else
        page.close()
    finally:
        srv.stop()


def test_a_preset_named_with_addresses_shows_no_link_in_the_panel(chromium):
    from shoal.app.server import start_server

    from browser_helpers import arena_in_view

    name = "www.evil.example https://x.example me@uni.example"
    srv = start_server("default", port=0)
    try:
        page = arena_in_view(chromium.new_page(viewport=VIEWPORT))
        outside: list[str] = []
        page.on("request", lambda r: None if r.url.startswith(("http://127.0.0.1", "ws://127.0.0.1", "data:", "blob:"))
                else outside.append(r.url))
        page.goto(f"http://127.0.0.1:{srv.port}/")
        page.wait_for_selector("label:has-text('robots')", timeout=90000)
        links = page.locator("a").count()  # viser's own, if any
        open_folder(page, "Replay and files", "Load replay")
        dismiss_toasts(page)
        upload_input(page, "Upload preset").set_input_files(
            {"name": "links.toml", "mimeType": "application/toml", "buffer": hostile_preset(name)})
        wait_until(lambda: any(t.session.scenario.name == name for t in srv.tabs.values()), what="the preset loaded")
        page.get_by_text("evil.example https", exact=False).first.wait_for(timeout=30000)
        time.sleep(1.0)
        assert page.locator("a").count() == links, page.locator("a").evaluate_all("es => es.map(e => e.outerHTML)")
        assert outside == [], outside
        page.close()
    finally:
        srv.stop()
