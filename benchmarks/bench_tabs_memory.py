"""Memory comes back when tabs leave: server RSS per cycle of tabs that connect and close.

Run: python benchmarks/bench_tabs_memory.py [--tabs 30] [--cycles 11] [--play 2] [--preset default]
     [--uploads 1000] [--diagnose]

The app server (``start_server`` on a free port) runs in this process and nothing else does;
the tabs are wire clients (``tests/viser_wire.py``: viser's websocket protocol without a
browser) in a child process, so the RSS printed is the server's alone. One cycle: ``--tabs``
clients connect, each gets its session, panels and arena, the sessions play for ``--play``
seconds, every client closes, and once the server has forgotten them all (and a
``gc.collect()``) the server's resident set size (RSS) is read. The first cycle pays for
imports and viser's first page; the cycles after it should add next to nothing.

``--uploads N`` then measures one hostile client that starts N uploads of 512 KiB (one part
each of a 2-part file, never finished) and leaves: RSS before, while it is connected, and
after it has gone.

``--diagnose`` prints, after each cycle, the object types whose counts grew and the
allocation sites that grew most (tracemalloc), to find what holds memory.
"""

from __future__ import annotations

import argparse
import gc
import multiprocessing as mp
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[0] / "tests"))
from bench_common import fmt, rss_mib, table, wait_for  # noqa: E402

LONG = "sim.steps=10000000"


# ------------------------------------------------------------------ the clients (child process)
def run_clients(port: int, orders: Any, done: Any) -> None:
    """Obey ``orders``: ("tabs", n) opens n clients until ("close",); ("uploads", n) starts n
    unfinished uploads from one client until ("close",); ("quit",) ends."""
    import uuid

    from viser import _messages as m

    from viser_wire import WireClient

    clients: list[WireClient] = []
    while True:
        order = orders.get()
        if order[0] == "tabs":
            clients = [WireClient(port, decode=True) for _ in range(order[1])]
            wait_for(lambda cs=clients: all(c.uuid_of("Upload preset") for c in cs), 300, "every tab's panels")
            done.put("open")
        elif order[0] == "uploads":
            c = WireClient(port, decode=True)
            clients = [c]
            wait_for(lambda c=c: c.uuid_of("Upload preset"), 300, "the upload button")
            button = c.uuid_of("Upload preset")
            part = b"#" * (512 * 1024)
            for _ in range(order[1]):
                tid = str(uuid.uuid4())
                c.send(m.FileTransferStartUpload(source_component_uuid=button, transfer_uuid=tid, filename="x.toml",
                                                 mime_type="application/toml", part_count=2,
                                                 size_bytes=2 * len(part)))
                c.send(m.FileTransferPart(source_component_uuid=button, transfer_uuid=tid, part_index=0,
                                          content=part))
            done.put("open")
        elif order[0] == "close":
            for c in clients:
                c.close()
            clients = []
            done.put("closed")
        else:
            return


# ------------------------------------------------------------------ the server (this process)
def settled_rss() -> float:
    """RSS after a full collection and a moment for viser's threads to finish their teardown."""
    time.sleep(1.0)
    gc.collect()
    return rss_mib()


def type_counts() -> Counter:
    return Counter(type(o).__qualname__ for o in gc.get_objects())


def diagnose(before: Counter, snap0: Any) -> tuple[Counter, Any]:
    import ctypes
    import threading
    import tracemalloc

    rss = rss_mib()
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    print(f"  RSS {rss:.0f} MiB, after malloc_trim {rss_mib():.0f} MiB; {threading.active_count()} threads",
          file=sys.stderr)

    after = type_counts()
    grown = [(n, after[n] - before.get(n, 0)) for n in after if after[n] - before.get(n, 0) > 50]
    print("  object types grown:", sorted(grown, key=lambda g: -g[1])[:15], file=sys.stderr)
    snap = tracemalloc.take_snapshot()
    if snap0 is not None:
        for stat in snap.compare_to(snap0, "lineno")[:8]:
            print("   ", stat, file=sys.stderr)
    return after, snap


def measure(preset: str, tabs: int, cycles: int, play: float, uploads: int, diag: bool) -> dict[str, Any]:
    import tempfile

    from shoal.app.server import start_server
    from shoal.presets.io import load, to_toml

    if diag:
        import tracemalloc

        tracemalloc.start(8)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"{preset}-long.toml"
        path.write_text(to_toml(load(preset, [LONG])), encoding="utf-8")
        server = start_server(str(path), port=0, max_sessions=max(tabs, 1))
    ctx = mp.get_context("spawn")
    orders, done = ctx.Queue(), ctx.Queue()
    child = ctx.Process(target=run_clients, args=(server.port, orders, done), daemon=True)
    child.start()
    out: dict[str, Any] = {"rss0": settled_rss(), "cycles": [], "peaks": []}
    counts, snap = (type_counts(), None) if diag else (None, None)
    try:
        for i in range(cycles):
            orders.put(("tabs", tabs))
            assert done.get(timeout=600) == "open"
            wait_for(lambda: len(server.tabs) == tabs, 120, f"{tabs} sessions")
            time.sleep(play)
            out["peaks"].append(rss_mib())
            orders.put(("close",))
            assert done.get(timeout=600) == "closed"
            wait_for(lambda: not server.tabs and not server.viser.get_clients(), 120, "every tab to be forgotten")
            out["cycles"].append(settled_rss())
            print(f"cycle {i + 1}: {out['peaks'][-1]:.0f} MiB with {tabs} tabs, {out['cycles'][-1]:.0f} MiB after",
                  file=sys.stderr, flush=True)
            if diag:
                counts, snap = diagnose(counts, snap)
        if uploads:
            out["up0"] = settled_rss()
            orders.put(("uploads", uploads))
            assert done.get(timeout=600) == "open"
            time.sleep(2.0)
            out["up1"] = rss_mib()
            orders.put(("close",))
            assert done.get(timeout=600) == "closed"
            wait_for(lambda: not server.tabs and not server.viser.get_clients(), 120, "the uploader to be forgotten")
            out["up2"] = settled_rss()
    finally:
        orders.put(("quit",))
        child.join(timeout=60)
        if child.is_alive():
            child.kill()
        server.stop()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--preset", default="default")
    ap.add_argument("--tabs", type=int, default=30)
    ap.add_argument("--cycles", type=int, default=11, help="the first one and ten more")
    ap.add_argument("--play", type=float, default=2.0, help="seconds every cycle's sessions play")
    ap.add_argument("--uploads", type=int, default=1000, help="unfinished 512 KiB uploads of one client (0: none)")
    ap.add_argument("--diagnose", action="store_true")
    args = ap.parse_args()
    r = measure(args.preset, args.tabs, args.cycles, args.play, args.uploads, args.diagnose)
    c = r["cycles"]
    rows = [[str(i + 1), fmt(p), fmt(v), fmt(v - c[0])] for i, (p, v) in enumerate(zip(r["peaks"], c))]
    print(f"preset `{args.preset}`, {args.tabs} wire tabs a cycle, {args.play:g} s of play; server RSS "
          f"{fmt(r['rss0'])} MiB before the first tab\n")
    print(table(["cycle", "RSS MiB with the tabs", "after they closed", "growth since cycle 1"], rows))
    print(f"\nafter cycle 1: {fmt(c[0])} MiB; after cycle {len(c)}: {fmt(c[-1])} MiB "
          f"({fmt(c[-1] - c[0])} MiB over {len(c) - 1} more cycles)")
    if args.uploads:
        print(f"\n{args.uploads} unfinished 512 KiB uploads from one client: RSS {fmt(r['up0'])} MiB before, "
              f"{fmt(r['up1'])} while it is connected, {fmt(r['up2'])} after it left")


if __name__ == "__main__":
    main()
