"""Load: many concurrent browser sessions on one ``shoal serve``, each its own simulation.

Run: python benchmarks/bench_load.py [--sessions 20] [--clients wire browser] [--seconds 20]
     [--warmup 8] [--preset default] [--quick]

The app server (``start_server`` on a free port) runs in this process and nothing else does:
the clients live in a child process, so this process's CPU time and resident set size (RSS)
are the server's alone. Two kinds of client, ``--sessions`` of them at once:

- ``wire``: viser's websocket protocol spoken from Python (``tests/viser_wire.py``): each
  connects, reports a camera like a page does and counts the frames it gets. Nothing renders,
  so this isolates what the server costs per session.
- ``browser``: one headless Chromium (Debian's, through playwright with ``executable_path``,
  never a downloaded browser), one context and page per session; Play is pressed in each.
  On 2 cores the software-rendered pages compete with the server for the CPU.

Measured over the window (after ``--warmup`` seconds of play):

- per session (median and lowest over the sessions): engine steps/s (the preset asks for
  ``view.steps_per_second``), arena draws/s on the server, scene updates (robot point-cloud
  updates) and websocket frames received per client per second;
- the ticking thread: gaps between two ticks of the same tab (p50, p99, max; 1/60 s when idle);
- server: process CPU in % of one core; RSS with no tab, after one tab came and went (the
  one-time cost of the first: imports, viser's page) and with all sessions running, the
  growth from the second to the third divided by the sessions being the cost of one session;
  the clients' CPU (the child process, plus Chromium's processes in browser mode);
- responsiveness under load: one more tab connecting (a wire client) until its session
  exists and its first scene update arrives, and an HTTP GET of the page.

Nothing here is asserted: tests check behaviour (``tests/test_trust_sessions.py``,
``tests/browser/test_browser_trust.py``), this script measures.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import shutil
import sys
import time
import urllib.request
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[0] / "tests"))
sys.path.insert(0, str(HERE.parents[0] / "tests" / "browser"))
from bench_common import fmt, rss_mib, table, wait_for  # noqa: E402

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
LONG = "sim.steps=10000000"


def cpu_seconds(pid: int | None = None) -> float:
    """User + system CPU seconds of a process so far (from /proc)."""
    with open(f"/proc/{pid or os.getpid()}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


# ------------------------------------------------------------------ the clients (child process)
def run_clients(kind: str, port: int, n: int, ready: Any, go: Any, stop: Any, out: Any) -> None:
    """Open ``n`` clients, signal ``ready``, count between ``go`` and ``stop``, report on ``out``."""
    import psutil

    me = psutil.Process()

    def own_cpu() -> float:
        procs = [me] + me.children(recursive=True)
        total = 0.0
        for p in procs:
            try:
                t = p.cpu_times()
                total += t.user + t.system
            except psutil.Error:
                pass
        return total

    if kind == "wire":
        from viser_wire import WireClient

        clients = [WireClient(port, decode=True) for _ in range(n)]
        ready.set()
        go.wait()
        c0, t0 = [c.counts() for c in clients], time.monotonic()
        cpu0 = own_cpu()
        stop.wait()
        c1, t1 = [c.counts() for c in clients], time.monotonic()
        cpu1 = own_cpu()
        for c in clients:
            c.close()
    else:
        from bench_browser_fps import FrameCounter
        from playwright.sync_api import sync_playwright

        from browser_helpers import ARGS, VIEWPORT

        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            counters = [FrameCounter() for _ in range(n)]
            pages = []
            for counter in counters:
                page = browser.new_context(viewport=VIEWPORT).new_page()
                page.on("websocket", lambda ws, c=counter: ws.on("framereceived", c.on_frame))
                page.goto(f"http://127.0.0.1:{port}/", timeout=600_000)  # 20 software-GL pages load slowly
                pages.append(page)
            for page in pages:
                page.wait_for_selector("label:has-text('robots')", timeout=300_000)
                page.get_by_role("button", name="Play", exact=True).click(timeout=120_000)
            ready.set()
            while not go.is_set():
                pages[0].wait_for_timeout(200)
            c0, t0 = [c.read() for c in counters], time.monotonic()
            cpu0 = own_cpu()
            while not stop.is_set():
                pages[0].wait_for_timeout(200)
            c1, t1 = [c.read() for c in counters], time.monotonic()
            cpu1 = own_cpu()
            browser.close()
        # FrameCounter.read() is (frames, bytes, robot updates), as WireClient.counts()
    span = t1 - t0
    out.put({
        "frames": [(b[0] - a[0]) / span for a, b in zip(c0, c1)],
        "kib": [(b[1] - a[1]) / span / 1024 for a, b in zip(c0, c1)],
        "updates": [(b[2] - a[2]) / span for a, b in zip(c0, c1)],
        "cpu": (cpu1 - cpu0) / span * 100.0,
    })


# ------------------------------------------------------------------ the server (this process)
class TickLog:
    """Wraps each tab's ``tick`` and ``arena.draw``: when a tab was ticked, how often it drew."""

    def __init__(self) -> None:
        self.stamps: dict[int, list[float]] = {}
        self.draws: dict[int, int] = {}

    def attach(self, cid: int, tab: Any) -> None:
        if cid in self.stamps:
            return
        self.stamps[cid], self.draws[cid] = [], 0
        tick, draw = tab.tick, tab.arena.draw

        def counted_tick(now: float | None = None, **kwargs: Any) -> None:
            self.stamps[cid].append(time.monotonic())
            tick(now, **kwargs)

        def counted_draw(snap: Any) -> None:
            self.draws[cid] += 1
            draw(snap)

        tab.tick, tab.arena.draw = counted_tick, counted_draw


def one_more_tab(server: Any) -> tuple[float, float]:
    """Seconds until one more tab has a session, and until its first scene update arrives."""
    from viser_wire import WireClient

    before = set(server.tabs)
    t0 = time.monotonic()
    client = WireClient(server.port, decode=True)
    try:
        wait_for(lambda: set(server.tabs) - before, 60, "one more session")
        t_session = time.monotonic() - t0
        wait_for(lambda: client.counts()[2] > 0, 60, "its first scene update")
        return t_session, time.monotonic() - t0
    finally:
        client.close()


def first_tab_rss(server: Any) -> float:
    """RSS (MiB) after one tab came and went: what the first session costs once (imports of the
    plotting and scene code, viser's client page) is then paid, so later growth is per session."""
    from viser_wire import WireClient

    client = WireClient(server.port)
    wait_for(lambda: server.tabs, 120, "a first session")
    time.sleep(2.0)
    client.close()
    wait_for(lambda: not server.tabs, 60, "the first session to go")
    return rss_mib()


def http_get_seconds(port: int) -> float:
    t0 = time.monotonic()
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=60) as r:
        r.read()
    return time.monotonic() - t0


def measure(kind: str, preset: str, n: int, seconds: float, warmup: float) -> dict[str, Any]:
    import tempfile

    from shoal.app.server import start_server
    from shoal.presets.io import load, to_toml

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{preset}-load.toml"
        path.write_text(to_toml(load(preset, [LONG])), encoding="utf-8")
        server = start_server(str(path), port=0, max_sessions=n + 1)
    ctx = mp.get_context("spawn")
    ready, go, stop, out = ctx.Event(), ctx.Event(), ctx.Event(), ctx.Queue()
    child = ctx.Process(target=run_clients, args=(kind, server.port, n, ready, go, stop, out), daemon=True)
    try:
        time.sleep(1.0)
        rss0 = rss_mib()
        rss_first = first_tab_rss(server)
        child.start()
        if not ready.wait(timeout=600):
            raise TimeoutError("the clients did not connect")
        wait_for(lambda: len(server.tabs) >= n, 120, f"{n} sessions")
        log = TickLog()
        for cid, tab in dict(server.tabs).items():
            tab.session.play()  # (a page pressed Play already; a wire client has no button)
            log.attach(cid, tab)
        time.sleep(warmup)
        sessions = dict(server.sessions)
        k0 = {cid: s.sim.state.k for cid, s in sessions.items()}
        d0 = dict(log.draws)
        cpu0, t0 = cpu_seconds(), time.monotonic()
        go.set()
        time.sleep(seconds)
        stop.set()
        span = time.monotonic() - t0
        cpu = (cpu_seconds() - cpu0) / span * 100.0
        rss1 = rss_mib()
        steps = [(s.sim.state.k - k0[cid]) / span for cid, s in sessions.items()]
        draws = [(log.draws[cid] - d0[cid]) / span for cid in sessions]
        gaps = np.concatenate([np.diff([t for t in log.stamps[cid] if t >= t0]) for cid in sessions])
        clients = out.get(timeout=120)
        t_session, t_first = one_more_tab(server)
        t_http = http_get_seconds(server.port)
        asked = float(load(preset).view.steps_per_second)
    finally:
        stop.set()
        child.join(timeout=120)
        if child.is_alive():
            child.kill()
        server.stop()
    return {
        "kind": kind, "n": n, "asked": asked, "steps": steps, "draws": draws, "gaps_ms": gaps * 1e3,
        "cpu": cpu, "rss0": rss0, "rss_first": rss_first, "rss1": rss1, "clients": clients,
        "t_session": t_session, "t_first": t_first, "t_http": t_http,
    }


def report(results: list[dict[str, Any]], preset: str) -> str:
    per = []
    for r in results:
        c = r["clients"]
        per.append([
            f"{r['n']} {r['kind']} clients", f"{fmt(r['asked'])}",
            f"{fmt(np.median(r['steps']))} / {fmt(min(r['steps']))}",
            f"{fmt(np.median(r['draws']))} / {fmt(min(r['draws']))}",
            f"{fmt(np.median(c['updates']))} / {fmt(min(c['updates']))}",
            f"{fmt(np.median(c['frames']))}", f"{fmt(np.median(c['kib']))}",
            f"{fmt(np.percentile(r['gaps_ms'], 50))} / {fmt(np.percentile(r['gaps_ms'], 99))} / "
            f"{fmt(r['gaps_ms'].max())}",
        ])
    cost = []
    for r in results:
        cost.append([
            f"{r['n']} {r['kind']} clients", fmt(r["cpu"]), fmt(r["cpu"] / r["n"]),
            fmt(r["rss0"]), fmt(r["rss_first"]), fmt(r["rss1"]), fmt((r["rss1"] - r["rss_first"]) / r["n"]),
            fmt(r["clients"]["cpu"]), f"{fmt(r['t_session'])} / {fmt(r['t_first'])}", fmt(r["t_http"] * 1e3),
        ])
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    return "\n\n".join([
        f"preset `{preset}` (playback asks {fmt(results[0]['asked'])} steps/s); per session: median / lowest; "
        f"machine load average at the end {load} on {os.cpu_count()} cores",
        table(["clients", "asked steps/s", "engine steps/s", "server draws/s", "scene updates recv/s",
               "ws frames recv/s", "KiB recv/s", "tick gap ms p50 / p99 / max"], per),
        table(["clients", "server CPU %", "CPU % per session", "RSS MiB, no tab", "after a first tab",
               "with all", "MiB per session", "clients' CPU %", "one more tab: session / first update s",
               "GET page ms"],
              cost),
    ])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sessions", type=int, default=20)
    ap.add_argument("--clients", nargs="+", choices=["wire", "browser"], default=["wire", "browser"])
    ap.add_argument("--preset", default="default")
    ap.add_argument("--seconds", type=float, default=20.0, help="measuring window")
    ap.add_argument("--warmup", type=float, default=8.0, help="seconds of play before counting")
    ap.add_argument("--quick", action="store_true", help="5 sessions, 6 s window, wire clients only")
    args = ap.parse_args()
    if args.quick:
        args.sessions, args.seconds, args.warmup, args.clients = 5, 6.0, 3.0, ["wire"]
    results = []
    for kind in args.clients:
        r = measure(kind, args.preset, args.sessions, args.seconds, args.warmup)
        print(report([r], args.preset), file=sys.stderr, flush=True)  # (kept if a later kind fails)
        results.append(r)
    print(report(results, args.preset))


if __name__ == "__main__":
    main()
