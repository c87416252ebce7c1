"""A tab's cost as it ages, its bytes on the wire, and the tabs one process holds at full rate:
this tree and another (``--base``, default ``main``) side by side, in one run.

Run: nice -n 10 python benchmarks/bench_tab_cost.py [--base main] [--only age bytes tabs]
     [--minutes 10] [--tabs 12] [--bytes-minutes 6] [--many 24] [--seconds 60]

Each tree's app server runs in its own child interpreter with ``PYTHONPATH`` at its ``src`` (the
base is checked out with ``git worktree add --detach`` into a temporary folder and removed at the
end; both trees' kernels are compiled first with ``shoal warmup``), so each server's CPU time is
its own. The tabs are wire clients (``tests/viser_wire.py``: viser's websocket protocol as a page
speaks it, nothing rendered) in this process. Every tab sets *at the end* to ``run on``. Where the
tree's page script takes plot appends (a hidden *plot sync* control), the client says so, as the
page does once it has found viser's store (``app/panel/plot_stream.py``); a tree without it gets
what its pages get, the whole plot data on every refresh.

- ``age``: ``--tabs`` tabs of ``default`` play for ``--minutes`` minutes; each minute, a tab's
  scene updates per second (arena draws the server sent: each moves the robots; median and
  lowest over the tabs) and steps per second, its KiB/s, and the server's CPU (% of one core, and
  ms per update). The trees run one after the other.
- ``bytes``: one tab of ``default`` and one of ``course-dvc`` (trails on, as shipped) per tree,
  all four at once, for ``--bytes-minutes`` minutes: KiB/s a tab and bytes per scene update, each
  minute (a plot's window is full after 1,500 rows: 75 s at 20 steps/s, 5 min at 5).
- ``tabs``: ``--many`` tabs of ``default`` in one process, measured for ``--seconds`` after 30 s:
  updates/s a tab (median, lowest) and the server's CPU. The trees run one after the other.

Nothing is asserted (the tests check behaviour); the machine's load is printed with the numbers.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Iterator

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT / "tests"))
from bench_common import fmt, load_note, table  # noqa: E402

SERVER = r"""
import json, sys
from shoal.app.server import start_server
from shoal.app.view.view import View

draws = {}  # arena → scene updates drawn (a robot update sent each)
draw = View.draw


def counted(self, snap):
    draws[id(self)] = draws.get(id(self), 0) + 1
    draw(self, snap)


View.draw = counted
srv = start_server(sys.argv[1], port=0, max_sessions=int(sys.argv[2]))
print("PORT", srv.port, flush=True)
for line in sys.stdin:
    tabs = list(srv.tabs.values())
    print("COUNTS", json.dumps([[draws.get(id(t.arena), 0), int(t.session.k)] for t in tabs]), flush=True)
srv.stop()
"""


class Server:
    """An app server of the tree at ``src`` showing ``preset``, in a child interpreter."""

    def __init__(self, src: Path, preset: str, tabs: int) -> None:
        env = dict(os.environ, PYTHONPATH=str(src))
        self.proc = subprocess.Popen([sys.executable, "-c", SERVER, preset, str(tabs + 1)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env)
        line = ""
        while not line.startswith("PORT"):
            line = self.proc.stdout.readline()  # type: ignore[union-attr]
            if not line and self.proc.poll() is not None:
                raise RuntimeError(f"the server of {src} did not start")
        self.port = int(line.split()[1])

    def counts(self, tabs: int = 0) -> np.ndarray:
        """(tabs, 2): scene updates drawn and engine steps of every tab so far (waiting until there
        are ``tabs`` of them)."""
        for _ in range(600):
            out = self._counts()
            if len(out) >= tabs:
                return out
            time.sleep(0.1)
        raise RuntimeError(f"the server has {len(out)} tabs, not {tabs}")

    def _counts(self) -> np.ndarray:
        self.proc.stdin.write("counts\n")  # type: ignore[union-attr]
        self.proc.stdin.flush()  # type: ignore[union-attr]
        line = ""
        while not line.startswith("COUNTS"):
            line = self.proc.stdout.readline()  # type: ignore[union-attr]
            if not line:
                raise RuntimeError("the server stopped")
        import json

        return np.array(json.loads(line.split(" ", 1)[1]), dtype=float).reshape(-1, 2)

    def cpu(self) -> float:
        """CPU seconds of the server process so far (all its threads)."""
        import psutil

        t = psutil.Process(self.proc.pid).cpu_times()
        return t.user + t.system

    def stop(self) -> None:
        import psutil

        kids = psutil.Process(self.proc.pid).children(recursive=True)
        try:
            self.proc.stdin.close()  # type: ignore[union-attr]
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        for p in kids:
            with contextlib.suppress(psutil.Error):
                p.kill()


def open_tabs(port: int, n: int) -> list[Any]:
    """``n`` wire tabs, each running on at the end and (where the tree offers it) taking plot appends;
    then they only count what they receive (decoding it would take the machine's CPU from the server)."""
    from viser_wire import WireClient

    tabs = [WireClient(port, decode=True) for _ in range(n)]
    for c in tabs:
        end = time.monotonic() + 300
        while not c.uuid_of("Run experiment") and time.monotonic() < end:  # (the panel's last control)
            time.sleep(0.05)
        time.sleep(0.5)  # (the tab is registered once its panel is built)
        if c.uuid_of("plot sync"):
            c.take_plot_appends()
        c.set_value("at the end", "run on")
        c.decode = False
    return tabs


def read(tabs: list[Any]) -> np.ndarray:
    """(tabs,): bytes received so far."""
    return np.array([c.counts()[1] for c in tabs], dtype=float)


@contextlib.contextmanager
def trees(base: str) -> Iterator[dict[str, Path]]:
    """{"<base>": its src, "this": this tree's src}, the base checked out for the run."""
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp) / "base"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(where), base], check=True,
                       capture_output=True)
        try:
            yield {base: where / "src", "this": ROOT / "src"}
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(where)], check=False,
                           capture_output=True)


def warm(src: Path) -> None:
    """Compile the tree's kernels before anything is measured (cached for later runs)."""
    subprocess.run([sys.executable, "-m", "shoal", "warmup"], env=dict(os.environ, PYTHONPATH=str(src)),
                   check=True, capture_output=True)


def window(server: Server, tabs: list[Any], seconds: float) -> dict[str, Any]:
    """Over the next ``seconds``: each tab's scene updates/s and steps/s, its KiB/s, the server's CPU."""
    c0, b0, cpu0, t0 = server.counts(len(tabs)), read(tabs), server.cpu(), time.monotonic()
    time.sleep(seconds)
    c1, b1, cpu1, t1 = server.counts(), read(tabs), server.cpu(), time.monotonic()
    span = t1 - t0
    n = min(len(c0), len(c1))
    d = (c1[:n] - c0[:n]) / span
    updates = d[:, 0]
    return {"updates": updates, "steps": d[:, 1], "kib": (b1 - b0) / span / 1024, "cpu": (cpu1 - cpu0) / span * 100,
            "ms_per_update": (cpu1 - cpu0) * 1e3 / max(updates.sum() * span, 1.0)}


def say(label: str, r: dict[str, Any]) -> None:
    print(f"  {label}: updates/s {np.median(r['updates']):.1f} (lowest {r['updates'].min():.1f}), steps/s "
          f"{np.median(r['steps']):.1f}, CPU {r['cpu']:.0f} %, {r['ms_per_update']:.2f} ms/update, "
          f"{np.median(r['kib']):.0f} KiB/s a tab; {load_note()}", file=sys.stderr, flush=True)


def run_age(srcs: dict[str, Path], n: int, minutes: float) -> str:
    rows = []
    for name, src in srcs.items():
        server = Server(src, "default", n)
        tabs = open_tabs(server.port, n)
        try:
            time.sleep(10.0)
            for minute in range(1, int(minutes) + 1):
                r = window(server, tabs, 60.0)
                say(f"age {name} minute {minute}", r)
                rows.append([name, str(minute), f"{fmt(np.median(r['updates']))} / {fmt(r['updates'].min())}",
                             fmt(np.median(r["steps"])), fmt(np.median(r["kib"])), fmt(r["cpu"]),
                             fmt(r["ms_per_update"])])
        finally:
            for c in tabs:
                c.close()
            server.stop()
    return (f"**age**: {n} tabs of `default` playing on, each minute ({load_note()} at the end)\n\n"
            + table(["tree", "minute", "scene updates/s a tab (median / lowest)", "steps/s", "KiB/s a tab",
                     "server CPU %", "server CPU ms per update"], rows))


def run_bytes(srcs: dict[str, Path], minutes: float) -> str:
    servers: dict[tuple[str, str], Server] = {}
    tabs: dict[tuple[str, str], list[Any]] = {}
    rows = []
    try:
        for name, src in srcs.items():
            for preset in ("default", "course-dvc"):
                servers[name, preset] = Server(src, preset, 1)
                tabs[name, preset] = open_tabs(servers[name, preset].port, 1)
        last = {key: (read(tb)[0], servers[key].counts(1)[0, 0]) for key, tb in tabs.items()}
        t0 = t_last = time.monotonic()
        for minute in range(1, int(minutes) + 1):
            time.sleep(max(0.0, t0 + 60.0 * minute - time.monotonic()))
            now = {key: (read(tb)[0], servers[key].counts(1)[0, 0]) for key, tb in tabs.items()}
            t = time.monotonic()
            for key in tabs:
                kib = (now[key][0] - last[key][0]) / (t - t_last) / 1024
                updates = (now[key][1] - last[key][1]) / (t - t_last)
                rows.append([key[0], key[1], str(minute), fmt(kib), fmt(updates), fmt(kib * 1024 / max(updates, 1e-9))])
                print(f"  bytes {key[0]} {key[1]} minute {minute}: {kib:.1f} KiB/s, {updates:.1f} updates/s",
                      file=sys.stderr, flush=True)
            last, t_last = now, t
    finally:
        for tb in tabs.values():
            for c in tb:
                c.close()
        for s in servers.values():
            s.stop()
    rows.sort(key=lambda r: (r[1], int(r[2]), r[0]))
    return (f"**bytes**: one tab of each preset per tree, all at once, trails on ({load_note()} at the end)\n\n"
            + table(["tree", "preset", "minute", "KiB/s a tab", "scene updates/s", "bytes per update"], rows))


def run_tabs(srcs: dict[str, Path], n: int, seconds: float) -> str:
    rows = []
    for name, src in srcs.items():
        server = Server(src, "default", n)
        tabs = open_tabs(server.port, n)
        try:
            time.sleep(30.0)
            r = window(server, tabs, seconds)
        finally:
            for c in tabs:
                c.close()
            server.stop()
        say(f"tabs {name}", r)
        rows.append([name, str(n), f"{fmt(np.median(r['updates']))} / {fmt(r['updates'].min())}",
                     str(int(np.sum(r["updates"] >= 18.0))), fmt(np.median(r["steps"])), fmt(np.median(r["kib"])),
                     fmt(r["cpu"]), fmt(r["ms_per_update"])])
    return (f"**tabs**: {n} tabs of `default` in one process, {seconds:.0f} s after 30 s of play ({load_note()})\n\n"
            + table(["tree", "tabs", "scene updates/s a tab (median / lowest)", "tabs at ≥ 18/s", "steps/s",
                     "KiB/s a tab", "server CPU %", "server CPU ms per update"], rows))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", default="main", help="the other tree: a git revision")
    ap.add_argument("--only", nargs="+", choices=["age", "bytes", "tabs"], default=["age", "bytes", "tabs"])
    ap.add_argument("--minutes", type=float, default=10.0, help="age: minutes of play")
    ap.add_argument("--tabs", type=int, default=12, help="age: tabs")
    ap.add_argument("--bytes-minutes", type=float, default=6.0)
    ap.add_argument("--many", type=int, default=24, help="tabs: tabs in one process")
    ap.add_argument("--seconds", type=float, default=60.0, help="tabs: measuring window")
    args = ap.parse_args()
    out = []
    with trees(args.base) as srcs:
        for src in srcs.values():
            warm(src)
        if "age" in args.only:
            out.append(run_age(srcs, args.tabs, args.minutes))
            print(out[-1], file=sys.stderr, flush=True)
        if "bytes" in args.only:
            out.append(run_bytes(srcs, args.bytes_minutes))
            print(out[-1], file=sys.stderr, flush=True)
        if "tabs" in args.only:
            out.append(run_tabs(srcs, args.many, args.seconds))
    print("\n\n".join(out))


if __name__ == "__main__":
    main()
