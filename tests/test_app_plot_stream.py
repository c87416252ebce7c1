"""A time plot's data reaches the page as the rows that are new (``app/panel/plot_stream.py``),
once the page said it takes them; what the page then holds is what the server rendered."""

from __future__ import annotations

import time

import numpy as np

from shoal.app.panel.plot_stream import RESYNC_SECONDS, append_call, delta, js_number, js_value

from app_helpers import wire_tab
from browser.browser_helpers import wait_until
from viser_wire import PLOT_CALL, PagePlots


def test_delta_is_the_rows_a_window_gained_and_lost():
    x = np.arange(10.0)
    old = (x, x ** 2)
    new = (np.arange(3.0, 13.0), np.arange(3.0, 13.0) ** 2)
    drop, rows = delta(old, new)
    assert drop == 3 and [list(r) for r in rows] == [[10.0, 11.0, 12.0], [100.0, 121.0, 144.0]]
    assert delta(old, old)[0] == 0 and delta(old, old)[1][0].size == 0
    nan = (x, np.where(x > 4, np.nan, x))
    assert delta(nan, (x[2:], nan[1][2:]))[0] == 2  # NaN rows (no value yet) are rows like any
    assert delta(old, (x[:5], x[:5] ** 2)) is None  # a scrubbed cut: fewer rows than it had in common
    assert delta(old, (x, x ** 3)) is None  # a changed value (a new exponent): a keyframe
    assert delta(old, (x + 100.0, x)) is None  # a reset: nothing in common
    assert delta(old, (x,)) is None and delta((x[:0], x[:0]), old) is None


def test_the_call_reads_back_as_the_same_doubles():
    for v in (0.1, 1 / 3, 1e-300, -2.5e17, 5e-324, float("nan"), float("inf"), -float("inf")):
        back = float(js_number(v).replace("Infinity", "inf").replace("NaN", "nan"))
        assert back == v or (np.isnan(v) and np.isnan(back))
    assert js_value({"x": {"time": False, "range": (0.0, 1.5)}, "y": {"range": [None, 2]}}) == \
        '{"x":{"time":false,"range":[0.0,1.5]},"y":{"range":[null,2.0]}}'
    call = append_call("s", "u", np.array([0.1, 0.2]), 1, (np.array([0.3]), np.array([np.nan])), {"x": {}})
    page = PagePlots()
    page.data["u"] = [np.array([0.1, 0.2]), np.array([1.0, 2.0])]
    page.take({"type": "RunJavascriptMessage", "source": call})
    assert call.startswith(PLOT_CALL) and page.appends == 1
    np.testing.assert_array_equal(page.data["u"][0], [0.2, 0.3])
    assert page.data["u"][1][0] == 2.0 and np.isnan(page.data["u"][1][1])


def _charts(tab):
    return {key: h for key, h in tab.panels.handles.items() if type(h).__name__ == "GuiUplotHandle"}


def _same(tab, page: PagePlots) -> bool:
    """Does the page hold, for every chart, the data the server last rendered?"""
    with tab.session.lock:
        for h in _charts(tab).values():
            held = page.data.get(h._impl.uuid)
            want = h.data
            if held is None or len(held) != len(want):
                return False
            if not all(np.array_equal(a, b, equal_nan=True) for a, b in zip(held, want)):
                return False
    return True


def _caught_up(tab, page: PagePlots) -> bool:
    """The server rendered the step shown, and the page holds it."""
    speed = tab.panels.handles["speed"]
    return bool(speed.data[0][-1] == tab.session.clock()) and _same(tab, page)


def test_a_page_that_takes_appends_gets_the_new_rows_only_and_holds_what_was_rendered(server):
    c, cid = wire_tab(server, "plot sync", plots=True)
    c_plots = c.plots
    try:
        tab = server.tabs[cid]
        tab.session.pause()
        c.take_plot_appends()
        wait_until(lambda: tab.panels.plot_stream.appends, what="the page's answer")
        tab.session.play()
        wait_until(lambda: tab.session.k >= 120, timeout=120, what="120 steps")
        tab.session.pause()
        wait_until(lambda: _same(tab, c_plots), timeout=30, what="the page's plots equal the server's")
        stream = tab.panels.plot_stream
        assert stream.appended > 5 * stream.keyframes and c_plots.appends > 5 and c_plots.refused == 0
        assert c_plots.append_bytes / c_plots.appends < 2500  # a few rows, not the window
        tab.session.scrub(40)  # a cut at an earlier step: a keyframe, and the page holds it
        wait_until(lambda: _same(tab, c_plots) and len(next(iter(_charts(tab).values())).data[0]) <= 41,
                   timeout=30, what="the scrubbed plots")
    finally:
        c.close()


def test_a_page_that_never_answers_gets_the_whole_data_as_before(server):
    c, cid = wire_tab(server, "plot sync", plots=True)
    try:
        tab = server.tabs[cid]
        wait_until(lambda: tab.session.k >= 40, timeout=120, what="40 steps")
        time.sleep(0.6)
        assert not tab.panels.plot_stream.appends and c.plots.appends == 0 and c.plots.keyframes > 0
        tab.session.pause()
        wait_until(lambda: _same(tab, c.plots), timeout=30, what="the page's plots equal the server's")
    finally:
        c.close()


def test_a_page_that_missed_an_append_asks_and_gets_the_whole_data(server):
    c, cid = wire_tab(server, "plot sync", plots=True)
    try:
        tab = server.tabs[cid]
        c.take_plot_appends()
        wait_until(lambda: tab.panels.plot_stream.appends and tab.panels.plot_stream.appended >= 3, timeout=120,
                   what="appends")
        tab.session.pause()
        wait_until(lambda: _same(tab, c.plots), timeout=30, what="the page's plots equal the server's")
        speed = tab.panels.handles["speed"]._impl.uuid
        c.plots.data[speed] = [a[:-3] for a in c.plots.data[speed]]  # what a page that missed an append holds
        before = tab.panels.plot_stream.keyframes
        c.set_value("plot sync", "resync 2")  # what the page says when it does not hold an append's base
        # (at once, though the tab is paused and no refresh comes: every chart whole, as the server holds it)
        wait_until(lambda: _same(tab, c.plots), timeout=30, what="the page's plots equal the server's again")
        sent = tab.panels.plot_stream.keyframes
        assert sent > before
        c.set_value("plot sync", "<script>nonsense")  # anything else changes nothing
        time.sleep(0.3)
        assert tab.panels.plot_stream.keyframes == sent
        time.sleep(RESYNC_SECONDS)
        for i in range(40):  # a hostile client asking again and again gets one answer, not 40
            c.set_value("plot sync", f"resync {3 + i}")
        time.sleep(0.3)
        assert 0 < tab.panels.plot_stream.keyframes - sent <= 2 * (sent - before), (before, sent)
        sent = tab.panels.plot_stream.keyframes
        tab.session.play()  # and the appends that follow build on what was sent
        appended = tab.panels.plot_stream.appended
        wait_until(lambda: tab.panels.plot_stream.appended > appended + 3, timeout=60, what="appends again")
        tab.session.pause()
        wait_until(lambda: _same(tab, c.plots), timeout=30, what="the page's plots equal the server's")
        assert c.plots.refused == 0
    finally:
        c.close()


def test_plot_bytes_per_refresh_do_not_grow_with_the_run(server):
    """Step 100 and step 1,600 (the plots' 1,500-row window full): a refresh sends as much."""
    c, cid = wire_tab(server, "plot sync", plots=True)
    try:
        tab = server.tabs[cid]
        tab.session.pause()
        tab.session.choose_at_end("run on")  # (past the preset's 600 steps)
        c.take_plot_appends()
        wait_until(lambda: tab.panels.plot_stream.appends, what="the page's answer")

        def bytes_per_append(steps: int) -> float:
            a0, b0 = c.plots.appends, c.plots.append_bytes
            for _ in range(steps // 5):
                tab.session.step(5)
                wait_until(lambda n=c.plots.appends: c.plots.appends > n, timeout=30, what="an append")
            return (c.plots.append_bytes - b0) / max(c.plots.appends - a0, 1)

        tab.session.step(100)
        wait_until(lambda: _caught_up(tab, c.plots), timeout=30, what="the plots at step 100")
        early = bytes_per_append(40)
        tab.session.step(1500)
        wait_until(lambda: _caught_up(tab, c.plots), timeout=30, what="the plots at step 1,640")
        late = bytes_per_append(40)
        assert late <= 1.2 * early, (early, late)
    finally:
        c.close()


def test_appends_wait_while_the_page_falls_behind_and_a_keyframe_replaces_them(server):
    """viser never drops a script message, but a data update replaces the one still queued for the
    same chart: while many messages wait for a page, a refresh is a keyframe, so a stalled client
    holds a bounded queue."""
    from shoal.app.panel.plot_stream import MAX_BACKLOG, PlotStream

    calls: list[str] = []
    waiting = [0]
    stream = PlotStream(server.viser.gui, calls.append, lambda: waiting[0])
    stream.heard("appends 1")
    x = np.arange(5.0)
    h = server.viser.gui.add_uplot(data=(x, x * 2), series=({"label": "t"}, {"label": "y"}), aspect=2.0)
    slid = (np.arange(1.0, 7.0), np.arange(1.0, 7.0) * 2)
    stream.push(h, slid, {"x": {"range": (1.0, 6.0)}})
    assert len(calls) == 2 and calls[-1].startswith(PLOT_CALL) and stream.appended == 1  # (calls[0]: the sync)
    np.testing.assert_array_equal(h.data[0], slid[0])  # the handle holds what the page holds
    waiting[0] = MAX_BACKLOG + 1
    later = (np.arange(2.0, 8.0), np.arange(2.0, 8.0) * 2)
    stream.push(h, later, {"x": {"range": (2.0, 7.0)}})
    assert len(calls) == 2 and stream.keyframes == 1
    np.testing.assert_array_equal(h.data[1], later[1])
    h.remove()
    stream.remove()
