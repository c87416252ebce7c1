"""SIGTERM and SIGINT stop ``shoal serve`` and its sweep workers within seconds, whatever runs
(issue 20, case 3): a tab's experiment is running on the worker process (a long cell, started
over viser's raw websocket) when the signal comes; the server exits, and no process it
started (the forkserver, the worker) is left."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import time

import psutil
import pytest

from browser.browser_helpers import wait_until
from viser_wire import WireClient

CLI = [sys.executable, "-m", "shoal"]


def _serve() -> tuple[subprocess.Popen, list[str], int]:
    proc = subprocess.Popen([*CLI, "serve", "--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # (xdist ignores SIGINT)
    lines: list[str] = []
    threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True).start()  # type: ignore[arg-type]
    url = wait_until(lambda: next((line.split()[4] for line in lines if "Shoal is running" in line), None),
                     timeout=120, what="the server to start")
    return proc, lines, int(url.rstrip("/").rsplit(":", 1)[1])


@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_signal_stops_serve_and_its_workers_while_a_sweep_runs(sig, code):
    proc, lines, port = _serve()
    started: list[psutil.Process] = []
    try:
        c = WireClient(port, decode=True)
        wait_until(lambda: c.uuid_of("Run experiment"), timeout=60, what="the Sweep tab")  # (serve compiles meanwhile)
        for _ in range(60):  # (a value sent while a loaded server still builds the tab may come before its callback)
            c.set_value("field 1", "sim.robots")
            seen = time.monotonic() + 2.0
            while not c.saw("now 20") and time.monotonic() < seen:
                time.sleep(0.05)
            if c.saw("now 20"):
                break
        assert c.saw("now 20"), "the field's description never came"
        time.sleep(0.5)
        c.set_value("values 1", "1000, 999")
        c.set_value("runs per cell", 60)
        c.set_value("steps per run", 10000)
        c.set_value("Run experiment", True)
        wait_until(lambda: c.saw("running:"), timeout=60, what="the experiment running")
        time.sleep(3.0)  # the worker process is busy with the first chunk
        started = psutil.Process(proc.pid).children(recursive=True)
        assert started, "no worker processes"
        start = time.monotonic()
        proc.send_signal(sig)
        proc.wait(timeout=60)
        took = time.monotonic() - start
        err = proc.stderr.read() if proc.stderr else ""
    finally:
        started += psutil.Process(proc.pid).children(recursive=True) if proc.poll() is None else []
        if proc.poll() is None:
            proc.kill()
        gone, alive = psutil.wait_procs(started, timeout=10)
        for p in alive:  # (what this test started: a failing server leaves no process behind)
            p.kill()
    assert took < 30.0, took  # (a few seconds on a quiet machine; the old server never exited)
    assert proc.returncode in (0, code), err[-2000:]
    assert "Traceback" not in err, err[-2000:]
    assert not alive, "left running: " + ", ".join(" ".join(p.cmdline()[:4]) for p in alive)
