"""Private tabs of a lecture hall at full rate, with 1 worker against 2 (issue 31 §5).

Run: python benchmarks/bench_hall.py [--tabs 8 16 24] [--workers 1 2] [--seconds 15] [--warmup 8]

For each number of workers, ``shoal hall`` (:class:`shoal.app.hall.supervisor.Hall`: the lecture,
the workers, Debian's nginx) starts on a free port; a child process opens ``--tabs`` private
tabs through nginx (``/p/<id>``: plain sessions of the preset, each playing at its
``view.steps_per_second`` and set to run on at the end), as raw-websocket clients that decode their frames and count the
robots' point-cloud updates, and say (as a real page's script does) that they take the plots'
appended rows. Measured over the window, after ``--warmup`` seconds: robot
updates/s a tab (lowest, median; a tab at full rate gets about its steps/s), KiB/s a tab, and
the CPU of each process of the hall (% of one core: the workers together, the lecture, nginx)
and of the clients. Tabs are spread by nginx (``least_conn``).

Nothing is asserted: ``tests/test_hall_processes.py`` checks the behaviour.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import socket
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[0] / "tests"))
sys.path.insert(0, str(HERE.parents[0] / "tests" / "browser"))
from bench_common import fmt, load_note, table, wait_for  # noqa: E402


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def run_clients(port: int, paths: list[str], ready: Any, go: Any, stop: Any, out: Any) -> None:
    import psutil

    from viser_wire import WireClient

    clients = [WireClient(port, decode=True, path=p) for p in paths]
    wait_for(lambda: all(c.counts()[2] > 0 for c in clients), 300, "every tab's first robots")
    for c in clients:  # say what a real page's script says: plots may come as appended rows
        wait_for(lambda c=c: c.uuid_of("plot sync"), 60, "the tab's plot sync control")
        c.take_plot_appends()
        c.set_value("at the end", "run on")  # (the preset stops at step 600: 30 s; the window must not see it)
    ready.set()
    go.wait()
    me = psutil.Process()
    c0, t0, cpu0 = [c.counts() for c in clients], time.monotonic(), sum(me.cpu_times()[:2])
    stop.wait()
    c1, t1, cpu1 = [c.counts() for c in clients], time.monotonic(), sum(me.cpu_times()[:2])
    span = t1 - t0
    out.put({"updates": [(b[2] - a[2]) / span for a, b in zip(c0, c1)],
             "kib": [(b[1] - a[1]) / span / 1024 for a, b in zip(c0, c1)], "cpu": (cpu1 - cpu0) / span * 100})
    for c in clients:
        c.close()


def measure(workers: int, tabs: int, seconds: float, warmup: float, preset: str) -> dict[str, Any]:
    import psutil

    from shoal.app.hall.channel import RemoteDesk
    from shoal.app.hall.supervisor import Hall

    hall = Hall(preset, workers=workers, port=free_port(), max_sessions=max(24, tabs))
    hall.start()
    try:
        assert hall.folder is not None
        desk = RemoteDesk(str(hall.folder / "desk.sock"), hall.channel_key, "worker-bench")
        paths = [f"/p/{desk.issue_plain()}" for _ in range(tabs)]
        desk.close()
        ctx = mp.get_context("spawn")
        ready, go, stop, out = ctx.Event(), ctx.Event(), ctx.Event(), ctx.Queue()
        child = ctx.Process(target=run_clients, args=(hall.port, paths, ready, go, stop, out))
        child.start()
        ready.wait(timeout=600)
        time.sleep(warmup)
        procs = {"workers": [psutil.Process(c.proc.pid) for c in hall.pool if c.proc is not None],
                 "lecture": [psutil.Process(hall.lecture.proc.pid)] if hall.lecture and hall.lecture.proc else [],
                 "nginx": [psutil.Process(hall.proxy.pid)] + psutil.Process(hall.proxy.pid).children()
                 if hall.proxy else []}

        def cpu() -> dict[str, float]:
            return {k: sum(sum(p.cpu_times()[:2]) for p in ps) for k, ps in procs.items()}

        a, t0 = cpu(), time.monotonic()
        go.set()
        time.sleep(seconds)
        stop.set()
        b, t1 = cpu(), time.monotonic()
        got = out.get(timeout=120)
        child.join(timeout=60)
    finally:
        hall.stop()
    span = t1 - t0
    got.update({f"{k}_cpu": (b[k] - a[k]) / span * 100 for k in a})
    return got


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tabs", type=int, nargs="+", default=[8, 16, 24])
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seconds", type=float, default=15.0)
    ap.add_argument("--warmup", type=float, default=8.0)
    ap.add_argument("--preset", default="default")
    a = ap.parse_args()
    from shoal.app.warmup import WARMUP

    WARMUP.run()  # (the kernels in the cache: every process starts compiled)
    rows = []
    med = lambda xs: sorted(xs)[len(xs) // 2]  # noqa: E731
    for tabs in a.tabs:
        for workers in a.workers:
            r = measure(workers, tabs, a.seconds, a.warmup, a.preset)
            rows.append([f"{tabs}", f"{workers}", fmt(min(r["updates"])), fmt(med(r["updates"])), fmt(med(r["kib"])),
                         fmt(r["workers_cpu"]), fmt(r["workers_cpu"] / tabs, 3), fmt(r["lecture_cpu"]),
                         fmt(r["nginx_cpu"]), fmt(r["cpu"])])
            print(" | ".join(rows[-1]), flush=True)
    print(f"\n## Private tabs of `{a.preset}` through nginx, 1 against 2 workers\n\n{load_note()}; "
          f"{a.seconds:g} s after {a.warmup:g} s of play\n")
    print(table(["tabs", "workers", "updates/s a tab, lowest", "median", "KiB/s a tab", "workers' CPU %",
                 "CPU % a tab", "lecture CPU %", "nginx CPU %", "clients' CPU %"], rows))


if __name__ == "__main__":
    main()
