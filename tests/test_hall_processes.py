"""A class across processes (issue 31 §5): ``shoal hall`` runs the lecture, two workers and the real
nginx (Debian's package), over viser's raw websocket through nginx.

- The lecturer drives through the proxy, watchers see the same step; a take-over lands on a
  worker (the least-loaded: nginx's ``least_conn``).
- A worker killed: its tab reconnects to the other worker and is told it starts again; the
  lecture goes on; the hall starts the worker again.
- The proxy's origin check: a foreign page or Host is refused through nginx; a request straight
  to a process that names the proxy without its key is refused.
- SIGTERM to ``shoal hall`` leaves no process and no file behind; the lecturer's key is in the
  first line of its output and nowhere else.
"""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest
from viser import _messages
from websockets.exceptions import InvalidStatus

from shoal.app.hall import routes
from shoal.app.hall.channel import RemoteDesk
from shoal.app.hall.private import BACK
from shoal.app.hall.supervisor import Hall
from shoal.app.hall.watcher import TAKE_OVER

from browser.browser_helpers import wait_until
from hall_helpers import press, status_of
from viser_wire import WireClient


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture(scope="module")
def hall():
    h = Hall("default", workers=2, port=free_port())
    h.start()
    procs = [psutil.Process(p.pid) for p in [h.proxy, *(c.proc for c in [h.lecture, *h.pool])] if p is not None]
    yield h
    folder = h.folder
    h.stop()
    assert folder is not None and not folder.exists()
    assert not any(p.is_running() and p.status() != psutil.STATUS_ZOMBIE for p in procs)


def boss_of(h: Hall) -> WireClient:
    c = WireClient(h.port, decode=True, path=routes.LECTURER_PATH, headers={"Cookie": f"{routes.KEY_COOKIE}={h.key}"})
    wait_until(lambda: c.uuid_of("playback"), what="the lecturer's tab through nginx", timeout=120)
    return c


def watcher_of(h: Hall) -> WireClient:
    c = WireClient(h.port, decode=True)
    wait_until(lambda: c.uuid_of(TAKE_OVER), what="a watcher through nginx", timeout=60)
    return c


def desk_of(h: Hall) -> RemoteDesk:
    assert h.folder is not None
    return RemoteDesk(str(h.folder / "desk.sock"), h.channel_key, "worker-test")


def take_over(w: WireClient) -> str:
    w.send(_messages.GuiUpdateMessage(w.wait_uuid(TAKE_OVER), {"value": True}))
    wait_until(lambda: "/p/" in w.last.get("RunJavascriptMessage", {}).get("source", ""), what="the private address")
    return re.search(r'"(/p/[A-Za-z0-9_-]+)"', w.last["RunJavascriptMessage"]["source"]).group(1)


def test_the_lecture_through_nginx_and_a_take_over_on_a_worker(hall):
    boss, a, b = boss_of(hall), watcher_of(hall), watcher_of(hall)
    desk = desk_of(hall)
    try:
        press(boss, "Play")
        time.sleep(1.5)
        press(boss, "Pause")
        wait_until(lambda: "paused" in status_of(boss), what="paused")
        time.sleep(0.6)
        line = status_of(boss)
        for c in (a, b):
            wait_until(lambda c=c: status_of(c) == line, what="the watchers at the lecturer's step")
        path = take_over(a)
        mine = WireClient(hall.port, decode=True, path=path)
        try:
            wait_until(lambda: mine.uuid_of("playback") and mine.uuid_of(BACK), what="the private tab on a worker")
            holder = desk.holders()[routes.private_id(path)]
            assert holder[0] in ("worker-1", "worker-2")
            m = re.search(r"step (\d+)/", line)
            wait_until(lambda: re.search(rf"step {m.group(1)}/", status_of(mine)), what="the take-over's step")
            # a second private tab goes to the other worker: the least-loaded one
            other = WireClient(hall.port, decode=True, path=take_over(b))
            try:
                wait_until(lambda: other.uuid_of("playback"), what="a second private tab")
                holders = desk.holders()
                assert {h[0] for h in holders.values()} == {"worker-1", "worker-2"}, holders
            finally:
                other.close()
        finally:
            mine.close()
    finally:
        for c in (boss, a, b):
            c.close()
        desk.close()


def test_a_worker_that_dies_loses_only_its_tabs_which_reconnect_elsewhere(hall):
    boss, w = boss_of(hall), watcher_of(hall)
    desk = desk_of(hall)
    try:
        path = take_over(w)
        pid = routes.private_id(path)
        mine = WireClient(hall.port, decode=True, path=path)
        wait_until(lambda: mine.uuid_of("playback"), what="the private tab")
        owner = desk.holders()[pid][0]
        victim = next(c for c in hall.pool if f"worker-{c.name.split()[-1]}" == owner)
        survivor = next(c for c in hall.pool if c is not victim)
        old = victim.proc.pid
        frames = w.counts()[0]
        victim.proc.send_signal(signal.SIGKILL)
        wait_until(lambda: mine.closed.is_set(), what="the dead worker's tab cut off")
        again = WireClient(hall.port, decode=True, path=path)  # the page reconnects to the same address
        try:
            wait_until(lambda: again.uuid_of("playback"), what="the tab on the other worker", timeout=60)
            wait_until(lambda: any(t == "Started again" for t, _, _ in again.notifications()), what="the tab told")
            assert desk.holders()[pid][0] == f"worker-{survivor.name.split()[-1]}"
            press(boss, "Step")  # the lecture goes on
            wait_until(lambda: w.counts()[0] > frames, what="the class still watching")
            assert not w.closed.is_set() and not boss.closed.is_set()
            hall.check()  # the hall starts the dead worker again
            wait_until(lambda: victim.proc is not None and victim.proc.pid != old and victim.port is not None,
                       what="the worker started again")
        finally:
            again.close()
            mine.close()
    finally:
        boss.close()
        w.close()
        desk.close()


def test_the_proxys_origin_check(hall):
    ok = WireClient(hall.port, decode=True, origin=f"http://127.0.0.1:{hall.port}")
    ok.close()
    with pytest.raises(InvalidStatus):
        WireClient(hall.port, origin="http://evil.example")
    with pytest.raises(InvalidStatus):
        WireClient(hall.port, host=f"evil.example:{hall.port}")
    worker = hall.pool[0].port
    with pytest.raises(InvalidStatus):  # straight to a worker, naming the proxy without its key
        WireClient(worker, path="/p/" + "x" * 22, headers={"X-Shoal-Proxy": "guess",
                                                           "X-Shoal-Arrived": f"127.0.0.1:{hall.port}"})


def _descendants(pid: int) -> list[psutil.Process]:
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def test_sigterm_stops_the_whole_hall_and_leaves_nothing(tmp_path):
    before = {p.name for p in Path(os.environ.get("TMPDIR", "/tmp")).glob("shoal-hall-*")}
    proc = subprocess.Popen([sys.executable, "-m", "shoal", "hall", "--workers", "2", "--port", str(free_port())],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        assert proc.stdout is not None
        lines = [proc.stdout.readline() for _ in range(3)]
        assert lines[0].startswith("lecturer: ") and lines[1].startswith("class:"), lines
        key = lines[0].split("#key=", 1)[1].split()[0]
        kids = _descendants(proc.pid)
        assert any("nginx" in k.name() for k in kids) and len(kids) >= 4, kids
        made = {p.name for p in Path(os.environ.get("TMPDIR", "/tmp")).glob("shoal-hall-*")} - before
        assert len(made) == 1
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=90)
    gone = lambda: not any(k.is_running() and k.status() != psutil.STATUS_ZOMBIE for k in kids)  # noqa: E731
    wait_until(gone, what="every process of the hall gone", timeout=30)
    assert {p.name for p in Path(os.environ.get("TMPDIR", "/tmp")).glob("shoal-hall-*")} == before
    assert list(tmp_path.iterdir()) == []
    assert "Traceback" not in out, out
    assert (("".join(lines) + out).count(key), lines[0].count(key)) == (1, 1)  # the key in the first line only
