"""Lecture mode (issue 31 §2): the lecturer's tab drives one run, every class tab watches it.

Over viser's raw websocket (``viser_wire.WireClient``): a lecturer's tab (the ``/lecturer`` page
with the key in its cookie) and watchers (the class page ``/``) on one :class:`LectureServer`.
The watchers see the arena and the status line at the lecture's step, from frames serialised
once for all of them; they cannot drive the run, whatever they send; the lecturer's reload
finds the run where it was. ``shoal serve --lecture`` prints the key once, in its first line.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import msgspec
import numpy as np
import pytest
from viser import _messages
from websockets.exceptions import InvalidStatus

from shoal.app.hall import routes
from shoal.app.hall.command import start_lecture
from shoal.app.hall.watcher import TAKE_OVER

from browser.browser_helpers import wait_until
from hall_helpers import lecturer, newest, press, robots_of, status_of, watcher
from viser_wire import WireClient

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def lecture():
    srv = start_lecture("default", port=0, key=routes.new_key())
    yield srv
    srv.stop()


def test_the_lecturer_drives_and_every_watcher_sees_the_same_step(lecture):
    a, b = watcher(lecture), watcher(lecture)
    boss = lecturer(lecture)
    try:
        assert not a.uuid_of("playback") and not b.uuid_of("playback")  # no control of the run in the class
        assert not boss.uuid_of(TAKE_OVER)  # and none of the broadcast in the lecturer's tab
        press(boss, "Play")
        wait_until(lambda: lecture.lecture.session.k >= 30, what="the lecture playing")
        press(boss, "Pause")
        s = lecture.lecture.session
        wait_until(lambda: not s.playing, what="paused")
        k = s.k
        time.sleep(0.6)  # (a few ticks: the last draw and status line go out)
        assert s.k == k
        line = status_of(boss)
        assert f"step {k}/" in line, line
        for c in (a, b):
            wait_until(lambda c=c: status_of(c) == line, what="the class's status line at the lecturer's step")
            x = robots_of(c)
            assert x is not None
            want = lecture.broadcast.arena.to_view(s.sim.state.x[0])[:, :2]
            np.testing.assert_allclose(x[:, :2], want, rtol=0, atol=1e-4)
        assert lecture.broadcast.step_drawn == k
        frames = lecture.frames
        # Both watchers take most windows as one serialisation (viser's own producer: sent == encoded). A
        # watcher that lags on a loaded machine takes two frames as one window, serialised for it alone
        # (a CI run: 70 sent of 40 encoded); the window-by-window rule is tests/test_hall_fanout.py's.
        assert frames.sent >= 1.5 * frames.encoded, frames
    finally:
        for c in (a, b, boss):
            c.close()


def _everything_a_page_may_send(c: WireClient, uuids: list[str]) -> list[object]:
    """Every kind of message a watcher's page could send, for every element id it has seen."""
    out: list[object] = []
    for uuid in uuids:
        for updates in ({"value": "Play"}, {"value": 1e308}, {"value": True}, {"label": "hacked"},
                        {"visible": False}, {"content": "<b>hacked</b>"}, {"disabled": True}):
            out.append(_messages.GuiUpdateMessage(uuid, updates))
        out += [_messages.GuiButtonHoldMessage(uuid, 10.0), _messages.GuiFormSubmitMessage(uuid),
                _messages.GuiFormDirtyMessage(uuid), _messages.CommandTriggerMessage(uuid)]
        out.append(_messages.FileTransferStartUpload(source_component_uuid=uuid, transfer_uuid="t-" + uuid,
                                                     filename="p.toml", mime_type="text/plain", part_count=1,
                                                     size_bytes=20))
        out.append(_messages.FileTransferPart(source_component_uuid=uuid, transfer_uuid="t-" + uuid, part_index=0,
                                              content=b'name = "hacked"\n'))
    for kind in ("click", "rect-select"):
        out.append(_messages.ScenePointerMessage(kind, (0.0, 0.0, 5.0), (0.0, 0.0, -1.0), ((0.5, 0.5),), None))
    return out


def test_the_class_follows_the_lecturer_to_another_kind_of_scene_and_to_compare(lecture):
    """A preset of another kind (a fleet) and Compare's swarm B, chosen in the lecturer's tab,
    reach the class's arena; the lecture's run is the lecturer's tab's."""
    boss, w = lecturer(lecture), watcher(lecture)
    try:
        boss.set_value("preset", "course-dvc")
        wait_until(lambda: lecture.lecture.session.kind.name == "fleet", what="the lecture on a fleet", timeout=120)
        assert lecture.lecture.session is lecture.lecture.lecturer.session
        wait_until(lambda: lecture.broadcast.arena is not None and lecture.broadcast.arena.name == "fleet"
                   and w.saw("course-dvc"), what="the class on the fleet", timeout=120)
        wait_until(lambda: any(n.startswith("/fleet") and n.endswith("/robots") for n in w.points),
                   what="the fleet's robots on the class's page", timeout=120)
        boss.send(_messages.GuiUpdateMessage(newest(boss, "compare with swarm B"), {"value": True}))
        wait_until(lambda: lecture.lecture.session.twin is not None, what="swarm B on", timeout=120)
        press(boss, "Step")
        wait_until(lambda: any(n.startswith("/fleet") and "twin" in n for n in w.points),
                   what="swarm B on the class's page", timeout=120)
    finally:
        boss.send(_messages.GuiUpdateMessage(newest(boss, "preset"), {"value": "default"}))
        wait_until(lambda: lecture.lecture.session.kind.name != "fleet", what="back to the default scene", timeout=120)
        boss.close()
        w.close()


def test_a_class_tab_cannot_drive_the_lecture_whatever_it_sends(lecture):
    """A hostile watcher sends every GUI, upload, click and pointer message for every element id
    it saw and every id the lecturer's tab has: the run, its scenario and the other watcher's
    page stay as they were."""
    boss = lecturer(lecture)
    honest, hostile = watcher(lecture), watcher(lecture)
    try:
        press(boss, "Pause")
        s = lecture.lecture.session
        wait_until(lambda: not s.playing, what="paused")
        before = (s.k, s.scenario.model_dump_json(), s.playing, s.sim.robots, s.revision)
        shown = len(honest.gui)
        ids = sorted({m["uuid"] for m in hostile.gui + boss.gui if "uuid" in m})
        assert len(ids) > 20
        for m in _everything_a_page_may_send(hostile, ids):
            hostile.send(m)
        hostile.ws.send(msgspec.msgpack.encode({"type": "ViewerCameraMessage", "wxyz": [1, 0, 0, 0],
                                                "position": [0, 0, 1], "fov": 0.6, "near": 0.01, "far": 1e3,
                                                "image_height": 1, "image_width": 1, "look_at": [0, 0, 0],
                                                "up_direction": [0, 1, 0]}))
        time.sleep(3.0)  # (the message budget lets the flood through in a few seconds)
        assert (s.k, s.scenario.model_dump_json(), s.playing, s.sim.robots, s.revision) == before
        assert lecture.lecture.session is s
        hidden = {h._impl.uuid for _, h in lecture.broadcast._plots if not h.visible}  # (plots the run does not show)
        leaked = [m for m in honest.gui[shown:] if "hacked" in str(m) or (
            (m.get("updates") or {}).get("visible") is False and m.get("uuid") not in hidden)]
        assert leaked == []
        assert not honest.closed.is_set()
        press(boss, "Step")  # the lecturer still drives
        wait_until(lambda: s.k == before[0] + 1, what="the lecturer's step")
    finally:
        for c in (boss, honest, hostile):
            c.close()


def test_a_reload_of_the_lecturers_tab_finds_the_run_where_it_was(lecture):
    boss = lecturer(lecture)
    s = lecture.lecture.session
    k0 = s.k
    press(boss, "Step")
    wait_until(lambda: not s.playing and s.k == k0 + 1, what="a step")
    k = s.k
    boss.close()
    wait_until(lambda: lecture.lecture.lecturer is None, what="the lecturer gone")
    w = watcher(lecture)
    try:
        wait_until(lambda: "not connected" in status_of(w), what="the class told the run waits")
        again = lecturer(lecture)
        try:
            assert lecture.lecture.session is s and s.k == k
            second = lecturer(lecture)  # a second lecturer's tab takes the lecture from the first
            try:
                wait_until(lambda: again.saw("driven from another tab"), what="the first tab told")
                assert lecture.lecture.session is s
            finally:
                second.close()
        finally:
            again.close()
    finally:
        w.close()


@pytest.mark.parametrize("cookie", [None, "wrong", "x" * 5000])
def test_the_lecturers_page_without_the_key_drives_nothing(lecture, cookie):
    headers = {"Cookie": f"{routes.KEY_COOKIE}={cookie}"} if cookie is not None else None
    c = WireClient(lecture.port, decode=True, path=routes.LECTURER_PATH, headers=headers)
    try:
        wait_until(lambda: c.saw("This is the lecturer's page"), what="the lecturer-only notice")
        time.sleep(0.3)
        assert c.uuid_of("playback") is None and c.uuid_of(TAKE_OVER) is None
        assert lecture.lecture.lecturer is None or lecture.lecture.lecturer_client != c
    finally:
        c.close()


def test_the_pages_of_a_lecture_are_served_and_solo_is_a_fresh_private_address(lecture):
    base = f"http://127.0.0.1:{lecture.port}"
    for path in ("/", routes.LECTURER_PATH):
        with urllib.request.urlopen(base + path, timeout=10) as r:
            assert r.status == 200 and b"<html" in r.read(2000).lower()

    class NoRedirect(urllib.request.HTTPRedirectHandler):
        def redirect_request(self, *args, **kwargs):
            return None

    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.build_opener(NoRedirect).open(base + routes.SOLO_PATH, timeout=10)
    assert err.value.code == 302
    where = err.value.headers["Location"]
    assert routes.role(where) == routes.PRIVATE
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(base + "/nothing-here", timeout=10)
    assert err.value.code == 404


def test_serve_lecture_says_the_key_once_in_its_first_line(tmp_path):
    """The whole output of ``shoal serve --lecture`` (stdout and stderr) after a lecturer, a
    watcher, a wrong key, a foreign page and malformed messages: the key is in line 1 only."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "shoal", "serve", "--lecture", "--port", "0"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    lines: list[str] = []
    try:
        assert proc.stdout is not None
        while len(lines) < 2:
            line = proc.stdout.readline()
            assert line, "".join(lines)
            lines.append(line)
        m = re.search(r"lecturer: http://127\.0\.0\.1:(\d+)/lecturer#key=([A-Za-z0-9_-]+)", lines[0])
        assert m, lines
        port, key = int(m.group(1)), m.group(2)
        assert len(key) >= 22  # at least 128 bits
        assert lines[1].startswith(f"class:    http://127.0.0.1:{port}/"), lines
        boss = WireClient(port, decode=True, path=routes.LECTURER_PATH,
                          headers={"Cookie": f"{routes.KEY_COOKIE}={key}"})
        wait_until(lambda: boss.uuid_of("playback"), what="the lecturer's tab", timeout=90)
        w = WireClient(port, decode=True)
        wait_until(lambda: w.uuid_of(TAKE_OVER), what="a watcher")
        wrong = WireClient(port, decode=True, path=routes.LECTURER_PATH, headers={"Cookie": f"{routes.KEY_COOKIE}=x"})
        wait_until(lambda: wrong.saw("lecturer's page"), what="the notice")
        w.ws.send(b"\x00 not msgpack")
        with pytest.raises(InvalidStatus):
            WireClient(port, origin="http://evil.example")
        press(boss, "Play")
        time.sleep(1.0)
        for c in (boss, w, wrong):
            c.close()
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=60)
    text = "".join(lines) + out
    assert "refused a connection" in text and "dropped a malformed message" in text  # (things were said)
    assert text.count(key) == 1 and key in lines[0], text
