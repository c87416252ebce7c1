"""Scene updates per second that a real headless Chromium receives from the app, with 100
robots and their trails.

Run: python benchmarks/bench_browser_fps.py [--quick] [--seconds 20]

For each case the app server starts in this process (``start_server`` on a free port) with
the case's preset written to a temporary TOML file (100 robots, a run long enough never to
stop), Debian's Chromium opens the page (playwright with ``executable_path``, never a
downloaded browser) and the swarm plays. Counted over the measuring window:

- in the browser: viser websocket frames received by the page, and among their messages
  the updates of the robots' point cloud (``SceneNodeUpdateMessage`` for ``…/robots`` with
  new ``points``), decoded from the frames as the page got them; also the page's
  ``requestAnimationFrame`` rate (how often the browser could run its render loop), while
  playing and for 3 s after a pause;
- on the server: engine steps per second and arena draws per second (the tab's
  ``arena.draw`` calls).

"min 1-s" is the lowest count in any whole second of the window. The app draws at most
``TabApp.SCENE_HZ`` (30) times a second and only after a step, so the scene rate is
min(playback steps/s, 30).
"""

from __future__ import annotations

import argparse
import contextlib
import shutil
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "browser"))
from bench_common import fmt, table  # noqa: E402

from browser_helpers import ARGS, VIEWPORT, wait_until  # noqa: E402

CHROMIUM = shutil.which("chromium")
LONG = "sim.steps=10000000"
# (label, preset, overrides)
CASES = [
    ("Ch. 3 swarm, 100 robots + trails, playback 20 steps/s (preset rate)", "default",
     ["sim.robots=100", LONG]),
    ("Ch. 3 swarm, 100 robots + trails, playback 60 steps/s", "default",
     ["sim.robots=100", "view.steps_per_second=60", LONG]),
    ("Ch. 4 fleet, 100 robots + trails, obstacles, pymunk physics, 20 steps/s", "course-physics",
     ["sim.robots=100", "world.length=80", "world.width=40", "world.start_size=14",
      "view.steps_per_second=20", LONG]),
    ("for comparison: Ch. 3 swarm, 100 robots, NO trails, playback 60 steps/s", "default",
     ["sim.robots=100", "view.steps_per_second=60", "view.trail_seconds=0", LONG]),
    ("Ch. 4 fleet, 1000 robots + trails, obstacles, kinematic (compiled tick), 20 steps/s", "course-dvc",
     ["sim.robots=1000", "world.length=160", "world.width=73.2", "world.start_size=63.2",
      "view.steps_per_second=20", LONG]),
    ("Ch. 4 fleet, 200 robots + trails, obstacles, pymunk physics, 20 steps/s", "course-physics",
     ["sim.robots=200", "world.length=90", "world.width=38.3", "world.start_size=28.3",
      "view.steps_per_second=20", LONG]),
]

COUNT_RAF = """
window.__shoalRaf = 0;
(function tick() { window.__shoalRaf += 1; requestAnimationFrame(tick); })();
"""


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


def write_preset(preset: str, overrides: list[str], folder: Path) -> Path:
    from shoal.presets.io import load, to_toml

    path = folder / f"{preset}-bench.toml"
    path.write_text(to_toml(load(preset, overrides)), encoding="utf-8")
    return path


def measure(preset: str, overrides: list[str], seconds: float, warmup: float) -> dict[str, float]:
    from playwright.sync_api import sync_playwright

    from shoal.app.server import start_server

    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(sys.stderr):  # viser's banner
        server = start_server(str(write_preset(preset, overrides, Path(tmp))), port=0)
    counter = FrameCounter()
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                page = browser.new_page(viewport=VIEWPORT)
                page.add_init_script(COUNT_RAF)
                page.on("websocket", lambda ws: ws.on("framereceived", counter.on_frame))
                page.goto(f"http://127.0.0.1:{server.port}/")
                page.wait_for_selector("canvas", timeout=120_000)
                wait_until(lambda: len(server.tabs) == 1, timeout=120, what="the tab")
                tab = next(iter(server.tabs.values()))
                wait_until(lambda: tab.arena.drawn_revision >= 0, timeout=120, what="the first scene")
                page.wait_for_selector("button:has-text('Play'), button:has-text('Pause')", timeout=120_000)
                draws = [0]
                draw = tab.arena.draw

                def counted(snap):  # the tab's arena, counted
                    draws[0] += 1
                    return draw(snap)

                tab.arena.draw = counted
                if not tab.session.playing:
                    page.get_by_role("button", name="Play", exact=True).click()
                wait_until(lambda: tab.session.playing, what="play")
                page.wait_for_timeout(warmup * 1000)

                def sample() -> tuple[float, ...]:
                    raf = float(page.evaluate("window.__shoalRaf"))
                    f, b, r = counter.read()
                    return time.monotonic(), f, b, r, tab.session.sim.state.k, draws[0], raf

                samples = [sample()]
                for _ in range(int(seconds)):
                    page.wait_for_timeout(1000)
                    samples.append(sample())
                tab.session.pause()  # the render loop with nothing arriving, for comparison
                page.wait_for_timeout(1000)
                raf0, t0 = float(page.evaluate("window.__shoalRaf")), time.monotonic()
                page.wait_for_timeout(3000)
                raf_paused = (float(page.evaluate("window.__shoalRaf")) - raf0) / (time.monotonic() - t0)
            finally:
                browser.close()
    finally:
        with contextlib.redirect_stdout(sys.stderr):
            server.stop()
    t = [s[0] for s in samples]
    span = t[-1] - t[0]

    def per_s(i: int) -> float:
        return (samples[-1][i] - samples[0][i]) / span

    per_window = [(b[3] - a[3]) / (b[0] - a[0]) for a, b in zip(samples, samples[1:])]
    return {
        "robot_updates": per_s(3), "robot_updates_min": min(per_window), "frames": per_s(1),
        "kib": per_s(2) / 1024, "steps": per_s(4), "draws": per_s(5), "raf": per_s(6),
        "raf_paused": raf_paused,
        "undecoded": counter.undecoded, "seconds": span,
    }


def main() -> None:
    if CHROMIUM is None:
        raise SystemExit("bench_browser_fps: needs Debian's chromium on the PATH (apt-get install chromium)")
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="6 s per case instead of --seconds, first case only")
    ap.add_argument("--seconds", type=float, default=20.0, help="measuring window per case")
    ap.add_argument("--warmup", type=float, default=5.0, help="seconds of play before counting")
    ap.add_argument("--cases", type=int, nargs="*", help="indices of the cases to run (0-based)")
    args = ap.parse_args()
    cases = [CASES[i] for i in args.cases] if args.cases else CASES[:1] if args.quick else CASES
    seconds = 6.0 if args.quick else args.seconds
    rows = []
    for label, preset, overrides in cases:
        m = measure(preset, overrides, seconds, args.warmup)
        print(f"  {label}: {m}", file=sys.stderr)
        rows.append([label, fmt(m["robot_updates"]), fmt(m["robot_updates_min"]), fmt(m["frames"]),
                     fmt(m["kib"]), fmt(m["raf"]), fmt(m["raf_paused"]), fmt(m["steps"]), fmt(m["draws"])])
    print(table(["case", "robot updates/s in the browser", "min 1-s", "ws frames/s", "KiB/s", "browser rAF/s",
                 "rAF/s paused", "server steps/s", "server draws/s"], rows))


if __name__ == "__main__":
    main()
