"""Scene updates per second that a real headless Chromium receives from the app, and how often
the page can run its render loop meanwhile, for this tree and (``--base REV``) an earlier commit.

Run: python benchmarks/bench_browser_fps.py [--quick] [--seconds 20] [--cases 0 4 5] [--base main]

For each case and tree the app server runs in a child process (``page_server.ChildServer``: the
tree's own code) with the case's preset written to a temporary TOML file (a run long enough never
to stop), Debian's Chromium opens the page (playwright with ``executable_path``, never a
downloaded browser, and the browser tests' in-view shim) and the scene plays. Counted over the
measuring window:

- in the browser: viser websocket frames received by the page, and among their messages
  the updates of the robots' point cloud (``SceneNodeUpdateMessage`` for ``…/robots`` with
  new ``points``), decoded from the frames as the page got them; the page's
  ``requestAnimationFrame`` rate (how often the browser could run its render loop), while
  playing and for 3 s after a pause, and its main-thread time in long tasks (> 50 ms);
- on the server: engine steps per second and arena draws per second (``View.draw`` calls), and
  whether the tab drew lightly (the light drawing a page without a GPU turns on by itself; "–"
  for a tree without it).

"min 1-s" is the lowest count in any whole second of the window. The app draws at most
``TabApp.SCENE_HZ`` (30) times a second and only after a step, so the scene rate is
min(playback steps/s, 30).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, table  # noqa: E402
from page_server import CASES, ChildServer, open_page, page_counters, same_stretch, tree_of, write_preset  # noqa: E402

from browser_helpers import wait_until  # noqa: E402


@dataclass
class FrameCounter:
    """Websocket frames the page received, and robot point-cloud updates among them."""

    frames: int = 0
    bytes: int = 0
    robot_updates: int = 0
    undecoded: int = 0
    lock: threading.Lock = field(default_factory=threading.Lock)

    def on_frame(self, payload: bytes | str) -> None:
        if isinstance(payload, str):
            payload = payload.encode()
        n = robot_updates(payload)
        with self.lock:
            self.frames += 1
            self.bytes += len(payload)
            if n < 0:
                self.undecoded += 1
            else:
                self.robot_updates += n

    def read(self) -> tuple[int, int, int]:
        with self.lock:
            return self.frames, self.bytes, self.robot_updates


def robot_updates(payload: bytes) -> int:
    """How many updates of a ``…/robots`` point cloud one viser frame carries (−1: not a
    viser message frame). Frame layout (viser 1.x): 8-byte msgpack size, 8-byte compressed
    size, zstd-compressed msgpack ``{"messages": [...]}``, then raw binary buffers."""
    import msgspec
    import zstandard

    if len(payload) < 16:
        return -1
    size = int.from_bytes(payload[:8], "little")
    csize = int.from_bytes(payload[8:16], "little")
    try:
        inner = zstandard.ZstdDecompressor().decompress(payload[16:16 + csize], max_output_size=size)
        doc = msgspec.msgpack.decode(inner)
    except Exception:
        return -1
    count = 0
    for m in doc.get("messages", ()):
        if (m.get("type") == "SceneNodeUpdateMessage" and str(m.get("name", "")).endswith("/robots")
                and "points" in (m.get("updates") or {})):
            count += 1
    return count


def measure(label: str, pkg: Path, preset: Path, seconds: float, warmup: float,
            shot: Path | None = None) -> dict[str, float]:
    from playwright.sync_api import sync_playwright

    counter = FrameCounter()
    with ChildServer(pkg, preset, label) as server, sync_playwright() as p:
        browser, page = open_page(p, server.port, counter.on_frame)
        try:
            wait_until(lambda: any(d >= 0 for d in server.ask("stats")["drawn"]), timeout=120, what="the first scene")
            same_stretch(server, page, warmup)

            def sample() -> tuple[float, ...]:
                raf, long = page_counters(page)
                stats = server.ask("stats")
                f, b, r = counter.read()
                return time.monotonic(), f, b, r, stats["steps"], stats["draws"], raf, long

            if shot is not None:
                page.screenshot(path=str(shot))
            samples = [sample()]
            for _ in range(int(seconds)):
                page.wait_for_timeout(1000)  # (playwright delivers the frame events while it waits)
                samples.append(sample())
            light = any(server.ask("stats").get("light") or [False])
            server.ask("pause")  # the render loop with nothing arriving, for comparison
            page.wait_for_timeout(1000)
            raf0, t0 = page_counters(page)[0], time.monotonic()
            page.wait_for_timeout(3000)
            raf_paused = (page_counters(page)[0] - raf0) / (time.monotonic() - t0)
        finally:
            browser.close()
    t = [s[0] for s in samples]
    span = t[-1] - t[0]

    def per_s(i: int) -> float:
        return (samples[-1][i] - samples[0][i]) / span

    per_window = [(b[3] - a[3]) / (b[0] - a[0]) for a, b in zip(samples, samples[1:])]
    return {
        "robot_updates": per_s(3), "robot_updates_min": min(per_window), "frames": per_s(1),
        "kib": per_s(2) / 1024, "steps": per_s(4), "draws": per_s(5), "raf": per_s(6), "long": per_s(7),
        "raf_paused": raf_paused, "undecoded": counter.undecoded, "seconds": span, "light": light,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="6 s per case instead of --seconds, first case only")
    ap.add_argument("--seconds", type=float, default=20.0, help="measuring window per case")
    ap.add_argument("--warmup", type=float, default=5.0, help="seconds of play before counting")
    ap.add_argument("--cases", type=int, nargs="*", help="indices of the cases to run (0-based)")
    ap.add_argument("--base", default=None, help="also measure this commit (e.g. main), before this tree")
    ap.add_argument("--shots", type=Path, default=None, help="a folder for a 1280×800 screenshot of each case and tree")
    args = ap.parse_args()
    cases = [CASES[i] for i in args.cases] if args.cases else CASES[:1] if args.quick else CASES
    seconds = 6.0 if args.quick else args.seconds
    print(load_note(), file=sys.stderr)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        trees = ([(f"base {args.base}", args.base)] if args.base else []) + [("this tree", None)]
        pkgs = []
        for i, (label, rev) in enumerate(trees):
            (Path(tmp) / f"tree{i}").mkdir()
            pkgs.append((label, tree_of(rev, Path(tmp) / f"tree{i}")))
        for j, (case, preset, overrides) in enumerate(cases):
            path = write_preset(preset, overrides, Path(tmp) / f"case{j}.toml")
            for t, (label, pkg) in enumerate(pkgs):
                name = f"case{CASES.index((case, preset, overrides))}-tree{t}.png"
                shot = None if args.shots is None else args.shots / name
                m = measure(label, pkg, path, seconds, args.warmup, shot)
                print(f"  {case} [{label}]: {m}", file=sys.stderr)
                rows.append([case, label, "on" if m["light"] else "off", fmt(m["robot_updates"]),
                             fmt(m["robot_updates_min"]), fmt(m["frames"]), fmt(m["kib"]), fmt(m["raf"]),
                             fmt(m["long"]), fmt(m["raf_paused"]), fmt(m["steps"]), fmt(m["draws"])])
    print(table(["case", "tree", "light drawing", "robot updates/s in the browser", "min 1-s", "ws frames/s", "KiB/s",
                 "browser rAF/s", "long tasks ms/s", "rAF/s paused", "server steps/s", "server draws/s"], rows))
    print(f"\nafter the run: {load_note()}")


if __name__ == "__main__":
    main()
