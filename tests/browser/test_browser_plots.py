"""The plots in a real page take their new rows only (``panel/plot_stream.py`` and the page
script's ``plot``), and draw what the server rendered: the chart uPlot draws holds the same
numbers as the server's handle, row for row."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not on PATH (apt-get install chromium)"),
]

sync_api = pytest.importorskip("playwright.sync_api")

from browser_helpers import wait_until  # noqa: E402

DRAWN = """(uuid) => {
  const tp = window.__viserTestpoints && window.__viserTestpoints.uplots && window.__viserTestpoints.uplots[uuid];
  return tp ? tp.chart.data.map((a) => Array.from(a, (v) => (Number.isNaN(v) ? null : v))) : null;
}"""
HELD = """(uuid) => {
  const v = window.__shoalPage.viewer(), conf = v && v.useGuiConfig.get(uuid);
  return conf ? conf.props.data.map((a) => Array.from(a, (v) => (Number.isNaN(v) ? null : v))) : null;
}"""


def _equal(page_data, handle) -> bool:
    if page_data is None:
        return False
    want = [np.asarray(a, dtype=float) for a in handle.data]
    got = [np.array([np.nan if v is None else v for v in a], dtype=float) for a in page_data]
    return len(got) == len(want) and all(np.array_equal(g, w, equal_nan=True) for g, w in zip(got, want))


def _page_holds_every_chart(tab, page) -> None:
    """Every chart the page holds, drawn or not, comes to the server's data (a chart whose append
    the page could not take is sent whole once the page asks: a message or two later)."""
    for key, h in tab.panels.handles.items():
        if type(h).__name__ == "GuiUplotHandle" and h.visible:
            wait_until(lambda h=h: _equal(page.evaluate(HELD, h._impl.uuid), h), timeout=30,
                       what=f"the page's {key} chart equal to the server's")


MISS = """(uuid) => {
  const P = window.__shoalPage, s = P.viewer().useGuiConfig, conf = s.get(uuid);
  const data = conf.props.data.map((a) => a.slice(0, a.length - 3));  // a page that missed an append
  s.set({[uuid]: {...conf, props: {...conf.props, data: data}}});
  P.plot(P.plotSync, uuid, -1, 0, 0, 0, data.map(() => []), conf.props.scales);  // and the next one
}"""


def test_the_page_takes_appended_rows_and_draws_what_the_server_rendered(server, page, cid):
    tab = server.tabs[cid]
    stream = tab.panels.plot_stream
    wait_until(lambda: stream.appends, timeout=60, what="the page's answer: it takes appended rows")
    # (the tab plays from its first view: until a slow page has said it takes appends, every
    # refresh is rightly a keyframe, so the count starts here)
    keyframes = stream.keyframes
    tab.session.choose_at_end("run on")
    tab.session.play()
    wait_until(lambda: tab.session.k >= 200, timeout=120, what="200 steps")
    page.get_by_role("tab", name="Plots").click()
    speed = tab.panels.handles["speed"]
    uuid = speed._impl.uuid
    page.wait_for_function(f"() => !!(window.__viserTestpoints && window.__viserTestpoints.uplots"
                           f" && window.__viserTestpoints.uplots[{uuid!r}])", timeout=30000)
    appended = stream.appended
    wait_until(lambda: stream.appended > appended + 8, timeout=60, what="appends while the chart is drawn")
    tab.session.pause()
    wait_until(lambda: _equal(page.evaluate(DRAWN, uuid), speed), timeout=30,
               what="uPlot's data equal to the server's speed plot")
    _page_holds_every_chart(tab, page)
    since = stream.keyframes - keyframes
    assert stream.appended > 10 * max(since, 1) // 2, (stream.appended, since, keyframes)
    assert len(speed.data[0]) > 100 and speed.data[0][-1] == pytest.approx(tab.session.clock())


def test_a_chart_the_page_missed_comes_whole_though_the_tab_is_paused(server, page, cid):
    """Two misses within the page's second between asks: the second is asked at the second's end,
    and the server sends every chart whole at once, though no refresh comes."""
    tab = server.tabs[cid]
    tab.session.pause()
    _page_holds_every_chart(tab, page)
    charts = [h for h in tab.panels.handles.values() if type(h).__name__ == "GuiUplotHandle" and h.visible]
    for h in charts[:2]:
        page.evaluate(MISS, h._impl.uuid)
    assert not _equal(page.evaluate(HELD, charts[1]._impl.uuid), charts[1])
    _page_holds_every_chart(tab, page)
