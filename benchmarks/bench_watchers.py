"""Watchers of a lecture (issue 31 §2, §5): what one class tab costs the lecture's process.

Run: python benchmarks/bench_watchers.py [--watchers 200] [--seconds 20] [--warmup 10]
     [--preset default] [--set KEY=VALUE ...] [--no-share]

The lecture (``start_lecture`` on a free port) runs in this process and nothing else does. A
child process opens the lecturer's tab (a raw-websocket client with the key's cookie; it presses
Play) and ``--watchers`` class tabs: asyncio websocket clients that speak viser's protocol as a
page does (they report a camera, then read). Every watcher counts its frames and bytes; one in
``--decode-every`` also decodes each frame and counts the robots' point-cloud updates (the
arena's moves), so the clients stay cheap.

Measured over the window (after ``--warmup`` seconds of play), per watcher (lowest, median):
robot updates/s and frames/s, KiB/s; the lecture's engine steps/s and broadcast draws/s; the
server process's CPU (% of one core), its CPU per watcher and per update sent; the
serialisations against frames sent (:class:`shoal.app.hall.fanout.Frames`). ``--no-share``
serialises every frame for every watcher, as viser does by itself (the cost the broadcast saves).

Nothing here is asserted: ``tests/test_hall_lecture.py`` checks the behaviour.
"""

from __future__ import annotations

import argparse
import asyncio
import multiprocessing as mp
import os
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parents[0] / "tests"))
sys.path.insert(0, str(HERE.parents[0] / "tests" / "browser"))
from bench_common import fmt, load_note, rss_mib, table, wait_for  # noqa: E402


def cpu_seconds(pid: int | None = None) -> float:
    with open(f"/proc/{pid or os.getpid()}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


# ------------------------------------------------------------------ the clients (child process)
def run_clients(port: int, key: str, n: int, decode_every: int, ready: Any, go: Any, stop: Any, out: Any) -> None:
    import msgspec
    import viser
    from viser import _messages
    from websockets.asyncio.client import connect

    from shoal.app.hall import routes

    from viser_wire import WireClient, decode_frame

    boss = WireClient(port, decode=True, path=routes.LECTURER_PATH,
                      headers={"Cookie": f"{routes.KEY_COOKIE}={key}"})
    wait_for(lambda: boss.uuid_of("playback"), 300, "the lecturer's tab")
    camera = _messages.ViewerCameraMessage(
        wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 40.0), fov=0.6, near=0.01, far=1000.0,
        image_height=800, image_width=1280, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 1.0, 0.0))
    hello = msgspec.msgpack.encode(camera.as_serializable_dict())
    counts = [[0, 0, 0] for _ in range(n)]  # frames, bytes, robot updates

    async def watch(i: int) -> None:
        async with connect(f"ws://127.0.0.1:{port}/", subprotocols=[f"viser-v{viser.__version__}"],  # type: ignore[list-item]
                           max_size=None, open_timeout=120, ping_interval=None) as ws:
            await ws.send(hello)
            decode = i % decode_every == 0
            async for payload in ws:
                c = counts[i]
                c[0] += 1
                c[1] += len(payload)
                if decode and isinstance(payload, bytes):
                    c[2] += sum(1 for m in decode_frame(payload) if m.get("type") == "SceneNodeUpdateMessage"
                                and str(m.get("name", "")).endswith("/robots") and "points" in (m.get("updates") or {}))

    async def main() -> None:
        tasks = [asyncio.create_task(watch(i)) for i in range(n)]
        while sum(1 for c in counts if c[0]) < n:
            await asyncio.sleep(0.2)
        boss.send(_messages.GuiUpdateMessage(boss.uuid_of("playback"), {"value": "Play"}))
        ready.set()
        while not go.is_set():
            await asyncio.sleep(0.05)
        c0, t0, cpu0 = [c[:] for c in counts], time.monotonic(), cpu_seconds()
        while not stop.is_set():
            await asyncio.sleep(0.05)
        c1, t1, cpu1 = [c[:] for c in counts], time.monotonic(), cpu_seconds()
        span = t1 - t0
        out.put({"frames": [(b[0] - a[0]) / span for a, b in zip(c0, c1)],
                 "kib": [(b[1] - a[1]) / span / 1024 for a, b in zip(c0, c1)],
                 "updates": [(b[2] - a[2]) / span for i, (a, b) in enumerate(zip(c0, c1)) if i % decode_every == 0],
                 "cpu": (cpu1 - cpu0) / span * 100.0})
        for t in tasks:
            t.cancel()

    asyncio.run(main())
    boss.close()


# ------------------------------------------------------------------ the lecture (this process)
def measure(preset: str, sets: list[str], n: int, seconds: float, warmup: float, share: bool,
            decode_every: int) -> dict[str, Any]:
    import tempfile

    from shoal.app.hall import fanout
    from shoal.app.hall.command import start_lecture
    from shoal.app.warmup import WARMUP
    from shoal.presets.io import load, to_toml

    WARMUP.run()  # compiled kernels first: the numbers are the steady state
    scenario = load(preset, ["sim.steps=10000000", *sets])
    with tempfile.NamedTemporaryFile("wb", suffix=".toml", delete=False) as fh:
        fh.write(to_toml(scenario).encode())
    server = start_lecture(fh.name, port=0, max_watchers=n + 10)
    os.unlink(fh.name)
    if not share:  # every watcher's frame serialised for it alone, as viser's own producer does
        def each(self: fanout.Frames, window: Any) -> bytes:
            data = fanout.encode(window)
            self.encoded, self.sent, self.bytes_sent = self.encoded + 1, self.sent + 1, self.bytes_sent + len(data)
            return data

        fanout.Frames.bytes_for = each  # type: ignore[method-assign]
    ctx = mp.get_context("spawn")
    ready, go, stop, out = ctx.Event(), ctx.Event(), ctx.Event(), ctx.Queue()
    child = ctx.Process(target=run_clients, args=(server.port, server.key, n, decode_every, ready, go, stop, out))
    child.start()
    try:
        ready.wait(timeout=600)
        time.sleep(warmup)
        s = server.lecture.session
        k0, d0, e0, f0 = s.k, server.broadcast.draws, server.frames.encoded, server.frames.sent
        cpu0, t0 = cpu_seconds(), time.monotonic()
        go.set()
        time.sleep(seconds)
        stop.set()
        cpu1, t1 = cpu_seconds(), time.monotonic()
        k1, d1, e1, f1 = s.k, server.broadcast.draws, server.frames.encoded, server.frames.sent
        got = out.get(timeout=120)
        rss = rss_mib()
    finally:
        child.join(timeout=60)
        server.stop()
    span = t1 - t0
    got.update(steps=(k1 - k0) / span, draws=(d1 - d0) / span, server_cpu=(cpu1 - cpu0) / span * 100.0,
               encoded=(e1 - e0) / span, sent=(f1 - f0) / span, rss=rss, robots=scenario.sim.robots)
    return got


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--watchers", type=int, default=200)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--warmup", type=float, default=10.0)
    ap.add_argument("--preset", default="default")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--no-share", action="store_true", help="serialise every frame per watcher (viser's way)")
    ap.add_argument("--decode-every", type=int, default=10, help="one watcher in this many decodes its frames")
    a = ap.parse_args()
    r = measure(a.preset, a.set, a.watchers, a.seconds, a.warmup, not a.no_share, a.decode_every)
    med = lambda xs: sorted(xs)[len(xs) // 2]  # noqa: E731
    per_update = r["server_cpu"] / 100.0 / max(r["sent"], 1e-9) * 1e6
    print(f"## {a.watchers} watchers of `{a.preset}` ({r['robots']} robots{', ' + ', '.join(a.set) if a.set else ''}), "
          f"{'frames serialised once' if not a.no_share else 'every frame serialised per watcher'}")
    print(f"\n{load_note()}; {a.seconds:g} s after {a.warmup:g} s of play\n")
    print(table(["", "lowest", "median"], [
        ["robot updates/s a watcher", fmt(min(r["updates"])), fmt(med(r["updates"]))],
        ["frames/s a watcher", fmt(min(r["frames"])), fmt(med(r["frames"]))],
        ["KiB/s a watcher", fmt(min(r["kib"])), fmt(med(r["kib"]))],
    ]))
    print()
    print(table(["the lecture's process", ""], [
        ["engine steps/s", fmt(r["steps"])],
        ["broadcast draws/s", fmt(r["draws"])],
        ["CPU, % of one core", fmt(r["server_cpu"])],
        ["CPU a watcher, % of one core", fmt(r["server_cpu"] / a.watchers, 3)],
        ["CPU per frame sent, µs", fmt(per_update)],
        ["serialisations/s : frames sent/s", f"{fmt(r['encoded'])} : {fmt(r['sent'])}"],
        ["RSS, MiB", fmt(r["rss"])],
        ["the clients' CPU, % of one core", fmt(r["cpu"])],
    ]))


if __name__ == "__main__":
    main()
