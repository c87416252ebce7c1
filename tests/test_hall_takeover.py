"""Take over, and back (issue 31 §3): a class tab's private session starts from the lecture's exact
state and goes on with the same bits as a headless run continued from the same snapshot
(``shoal.make(snapshot=...)``); *Back to the lecture* returns the tab to watching.

The first test takes each kind's run over in process (capture, restore); the second does it all
over viser's raw websocket: a lecturer plays, edits a value and turns Compare on, a watcher
presses *Take over*, its page opens the private address it is sent, and that tab's session is
stepped 100 times beside the lecture's own run and a headless scene.
"""

from __future__ import annotations

import re
import time

import numpy as np
import pytest
from viser import _messages

import shoal
from shoal.app.hall import routes, takeover
from shoal.app.hall.command import start_lecture
from shoal.app.hall.private import BACK
from shoal.app.hall.watcher import TAKE_OVER
from shoal.app.kinds.fleet_world import EditRefused
from shoal.app.kinds.registry import session_for
from shoal.presets.io import load

from browser.browser_helpers import wait_until
from hall_helpers import lecturer, press, watcher
from viser_wire import WireClient

STEPS_BEFORE, STEPS_AFTER = 7, 100
KINDS = ["default", "course-dvc", "sonar-xb-pso", "slo-walk"]  # one preset of each scene kind


def bits(state) -> bytes:
    parts = [np.asarray(getattr(state, n)).tobytes() for n in ("x", "u", "heading", "status")]
    if hasattr(state, "best_fitness"):
        parts.append(np.asarray(state.best_fitness).tobytes())
    return b"".join(parts)


@pytest.mark.parametrize("preset", KINDS)
def test_a_taken_over_run_goes_on_as_the_lecture_and_a_headless_run_from_its_snapshot(preset):
    lecture = session_for(load(preset))
    lecture.advance(STEPS_BEFORE)
    state = takeover.capture(lecture)
    private, _ = takeover.restore(state)
    headless = shoal.make(snapshot=takeover.snapshot_bytes(state))
    assert private.k == headless.k == lecture.k == STEPS_BEFORE
    assert bits(private.sim.state) == bits(headless.state) == bits(lecture.sim.state)
    for _ in range(STEPS_AFTER):
        private.advance(1)
        headless.step()
    lecture.advance(STEPS_AFTER)
    assert private.k == STEPS_BEFORE + STEPS_AFTER
    assert bits(private.sim.state) == bits(headless.state) == bits(lecture.sim.state)


def test_a_take_over_keeps_the_obstacles_as_edited():
    lecture = session_for(load("course-dvc"))
    lecture.advance(3)
    x, y = lecture.sim.state.x[0].mean(axis=0) + (2.5, 0.0)  # just ahead of the robots
    added = None
    for dx in np.linspace(0.0, 6.0, 13):
        try:
            added = lecture.driver.add_obstacle(float(x + dx), float(y), 0.4)
            break
        except EditRefused:  # (on a robot or another obstacle: a little further on)
            continue
    assert added is not None
    circles = lecture.sim.world.circles.copy()
    private, _ = takeover.restore(takeover.capture(lecture))
    np.testing.assert_array_equal(private.sim.world.circles, circles)
    private.advance(STEPS_AFTER)
    lecture.advance(STEPS_AFTER)
    assert bits(private.sim.state) == bits(lecture.sim.state)


def test_take_over_on_the_wire_and_back_to_the_lecture():
    srv = start_lecture("default", port=0)
    boss, w = lecturer(srv), watcher(srv)
    try:
        s = srv.lecture.session
        press(boss, "Play")
        wait_until(lambda: s.k >= 5, what="the lecture playing")
        s.apply({"controller.c1": 1.7})  # the scenario as edited: a value changed mid-run
        s.enable_compare({"sim.robots": 10})  # Compare's swarm B on (A and B restart together)
        press(boss, "Play")
        wait_until(lambda: s.k >= 9, what="the lecture playing with B")
        press(boss, "Pause")
        wait_until(lambda: not s.playing, what="paused")
        w.send(_messages.GuiUpdateMessage(w.wait_uuid(TAKE_OVER), {"value": True}))
        wait_until(lambda: "RunJavascriptMessage" in w.last and "/p/" in w.last["RunJavascriptMessage"]["source"],
                   what="the page sent to its private address")
        path = re.search(r'"(/p/[A-Za-z0-9_-]+)"', w.last["RunJavascriptMessage"]["source"]).group(1)
        pid = routes.private_id(path)
        state = srv.desk._records[pid].state
        k = s.k
        w.close()
        mine = WireClient(srv.port, decode=True, path=path)
        try:
            wait_until(lambda: mine.uuid_of("playback") and mine.uuid_of(BACK)
                       and any(p == pid and c in srv.tabs for c, p in srv.held.items()), what="the private tab")
            (cid,) = [c for c, p in srv.held.items() if p == pid]
            private = srv.tabs[cid].session
            assert private is not s and private.k == k and private.scenario.controller.c1 == 1.7
            assert private.twin is not None and private.twin.robots == 10
            assert bits(private.sim.state) == bits(s.sim.state)
            assert bits(private.twin.sim.state) == bits(s.twin.sim.state)
            headless = shoal.make(snapshot=takeover.snapshot_bytes(state))
            press(mine, "Pause")
            wait_until(lambda: not private.playing, what="the private tab paused")
            for _ in range(STEPS_AFTER):
                private.advance(1)
                headless.step()
            s.advance(STEPS_AFTER)
            assert bits(private.sim.state) == bits(headless.state) == bits(s.sim.state)
            assert bits(private.twin.sim.state) == bits(s.twin.sim.state)
            # the same id cannot be opened by a second tab while this one holds it
            other = WireClient(srv.port, decode=True, path=path)
            wait_until(lambda: other.saw("open in another tab"), what="the second tab refused")
            other.close()
            mine.send(_messages.GuiUpdateMessage(mine.wait_uuid(BACK), {"value": True}))
            wait_until(lambda: "RunJavascriptMessage" in mine.last
                       and mine.last["RunJavascriptMessage"]["source"] == routes.go_script("/"),
                       what="back to the class page")
        finally:
            mine.close()
        wait_until(lambda: pid not in srv.desk.holders(), what="the id let go")
        back = watcher(srv)  # the class page again: a watcher, no session of its own
        assert back.uuid_of("playback") is None
        back.close()
    finally:
        boss.close()
        srv.stop()


def test_a_class_tab_that_presses_take_over_again_and_again_keeps_one_state():
    """Each take-over holds the run's state in memory until its tab opens it: a tab that presses
    *Take over* fifty times is refused while one is on its way, and keeps at most its last one."""
    srv = start_lecture("default", port=0)
    w = watcher(srv)
    try:
        before = len(srv.desk)
        for _ in range(50):
            w.send(_messages.GuiUpdateMessage(w.wait_uuid(TAKE_OVER), {"value": True}))
        wait_until(lambda: any("on its way" in body for _, body, _ in w.notifications()), what="a refusal")
        time.sleep(2.5)
        w.send(_messages.GuiUpdateMessage(w.wait_uuid(TAKE_OVER), {"value": True}))
        wait_until(lambda: sum("/p/" in m.get("source", "") for m in [w.last.get("RunJavascriptMessage", {})]),
                   what="a take-over")
        time.sleep(0.5)
        assert len(srv.desk) - before == 1
    finally:
        w.close()
        srv.stop()
