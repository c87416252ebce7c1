"""The app server of one tree (this working tree, or an earlier commit) in a child process, and
the page-side counters the browser benchmarks share. Not a script: ``bench_browser_fps.py``,
``bench_control_latency.py`` and ``bench_page_profile.py`` import it.

A tree runs in its own interpreter (``--base REV`` is exported with ``git archive`` into a
temporary folder), so both trees of a before/after comparison run the same way; the child is
instrumented from outside with wrappers of names both sides have (``TabApp._tick``,
``Panel.press``, ``View.draw``) and answers a few commands on stdin.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "browser"))
from browser_helpers import ARENA_IN_VIEW, ARGS, VIEWPORT  # noqa: E402

CHROMIUM = shutil.which("chromium")
SUBPACKAGES = {"app": "app", "engine": "engine", "presets": "presets", "static": "static"}  # before src/shoal

# The child: the tree's app server with counters; commands on stdin, answers on stdout after "@@".
SERVER = r"""
import json, sys, time
from shoal.app import tab as tab_mod
from shoal.app.panel import panel as panel_mod
from shoal.app.view import view as view_mod
from shoal.app.server import start_server

ticks, presses, draws = [], [], [0]
_tick = tab_mod.TabApp._tick
def timed_tick(self, now, plots=True):
    t0 = time.perf_counter()
    _tick(self, now, plots)
    ticks.append((time.perf_counter() - t0) * 1e3)
tab_mod.TabApp._tick = timed_tick
_press = panel_mod.Panel.press
def timed_press(self, what):
    presses.append((what, time.time() * 1e3))
    return _press(self, what)
panel_mod.Panel.press = timed_press
_draw = view_mod.View.draw
def counted_draw(self, snap):
    draws[0] += 1
    return _draw(self, snap)
view_mod.View.draw = counted_draw

server = start_server(sys.argv[1], port=0)
print("@@" + json.dumps({"port": server.port}), flush=True)
for line in sys.stdin:
    cmd = line.strip()
    tabs = list(server.tabs.values())
    if cmd == "reset":
        ticks.clear(); presses.clear()
    elif cmd == "stats":
        print("@@" + json.dumps({"ticks": list(ticks), "presses": list(presses), "draws": draws[0],
                                 "tabs": len(tabs), "drawn": [t.arena.drawn_revision for t in tabs],
                                 "steps": sum(int(t.session.sim.state.k) for t in tabs),
                                 "playing": [bool(t.session.playing) for t in tabs],
                                 "light": [bool(getattr(getattr(t, "display", None), "light", False))
                                           for t in tabs]}), flush=True)
    elif cmd in ("play", "pause", "reset_run"):
        for t in tabs:
            getattr(t.session, "reset" if cmd == "reset_run" else cmd)()
    elif cmd == "stop":
        break
server.stop()
"""

# Page-side counters, installed before the app loads: requestAnimationFrame callbacks (how often
# the page could run its render loop) and main-thread time in long tasks (> 50 ms).
PAGE_COUNTERS = """
(() => {
  window.__shoalRaf = 0;
  (function tick() { window.__shoalRaf += 1; requestAnimationFrame(tick); })();
  window.__shoalLong = 0;
  try {
    new PerformanceObserver((list) => { for (const e of list.getEntries()) window.__shoalLong += e.duration; })
      .observe({type: "longtask", buffered: false});
  } catch (e) {}
})();
"""


def tree_of(rev: str | None, tmp: Path) -> Path:
    """A folder holding a ``shoal`` package of the working tree (None) or of commit ``rev``."""
    src = ROOT
    if rev is not None:
        src = tmp / "src"
        src.mkdir()
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev], check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(src)], input=archive, check=True)
    if (src / "src" / "shoal").is_dir():  # the src layout: the package as it is
        return src / "src"
    pkg = tmp / "pkg" / "shoal"  # an older tree: its folders mapped as its installer did
    pkg.mkdir(parents=True)
    for item in (src / "shoal").iterdir():
        (pkg / item.name).symlink_to(item)
    for name, folder in SUBPACKAGES.items():
        (pkg / name).symlink_to(src / folder)
    return tmp / "pkg"


class ChildServer:
    """``with ChildServer(pkg, preset) as server``: the app of the tree in ``pkg`` serving the
    preset file ``preset`` on ``server.port``; ``ask("stats")`` and friends talk to it."""

    def __init__(self, pkg: Path, preset: Path, label: str = "app") -> None:
        self.pkg, self.preset, self.label = pkg, preset, label
        self.lock = threading.Lock()

    def __enter__(self) -> "ChildServer":
        env = {**os.environ, "PYTHONPATH": str(self.pkg)}
        self.child = subprocess.Popen([sys.executable, "-c", SERVER, str(self.preset)], cwd=str(self.pkg), env=env,
                                      text=True, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                      stderr=subprocess.DEVNULL)
        try:
            self.port = int(self._answer()["port"])
        except BaseException:
            self.child.kill()
            raise
        return self

    def _answer(self) -> dict:
        assert self.child.stdout is not None
        while not (line := self.child.stdout.readline()).startswith("@@"):  # viser's banner, its messages
            if not line:
                raise RuntimeError(f"the {self.label} server stopped")
        return json.loads(line[2:])

    def ask(self, cmd: str) -> dict | None:
        """Send ``cmd``: reset (the counters), stats (returns them), play, pause, reset_run (every
        tab's run back to step 0, playing: both trees then measure the same stretch of the run,
        whatever a tree spent starting, e.g. compiling its kernels)."""
        assert self.child.stdin is not None
        with self.lock:
            self.child.stdin.write(cmd + "\n")
            self.child.stdin.flush()
            return self._answer() if cmd == "stats" else None

    def __exit__(self, *exc: Any) -> None:
        try:
            self.ask("stop")
            self.child.wait(timeout=20)
        except Exception:
            self.child.kill()
            self.child.wait()


def write_preset(preset: str, overrides: list[str], path: Path) -> Path:
    """The preset ``preset`` with ``overrides`` as a TOML file at ``path``."""
    from shoal.presets.io import load, to_toml

    path.write_text(to_toml(load(preset, overrides)), encoding="utf-8")
    return path


def open_page(playwright: Any, port: int, on_frame: Callable[[bytes | str], None] | None = None) -> tuple[Any, Any]:
    """(browser, page): Debian's Chromium at 1280×800 on the app at ``port``, with the page
    counters and the in-view shim of the browser tests (``on_frame``: called with every
    websocket frame the page receives); waits for the panel."""
    if CHROMIUM is None:
        raise SystemExit("needs Debian's chromium on the PATH (apt-get install chromium)")
    browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
    page = browser.new_page(viewport=VIEWPORT)
    page.add_init_script(ARENA_IN_VIEW)
    page.add_init_script(PAGE_COUNTERS)
    if on_frame is not None:
        page.on("websocket", lambda ws: ws.on("framereceived", on_frame))
    page.goto(f"http://127.0.0.1:{port}/")
    page.wait_for_selector("canvas", timeout=120_000)
    page.wait_for_selector("button:has-text('Play'), button:has-text('Pause')", timeout=120_000)
    return browser, page


def page_counters(page: Any) -> tuple[float, float]:
    """(rAF callbacks, long-task ms) counted by the page so far."""
    raf, long = page.evaluate("[window.__shoalRaf, window.__shoalLong]")
    return float(raf), float(long)


LONG = "sim.steps=10000000"  # a run that never ends while measured
# (label, preset, overrides): the browser benchmarks' scenes; the 1000- and 200-robot fleets
# keep the packing of 100 robots on their course
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
    ("Ch. 3 swarm, 1000 robots + trails, playback 20 steps/s (preset rate)", "default",
     ["sim.robots=1000", LONG]),
]


def same_stretch(server: ChildServer, page: Any, warmup: float) -> None:
    """Play a few steps (a fresh tree compiles its kernels on the first ones), then start the
    run again and play ``warmup`` seconds: every tree measures the same stretch of its run."""
    server.ask("play")
    start = time.monotonic()
    while server.ask("stats")["steps"] < 5 and time.monotonic() - start < 300:
        page.wait_for_timeout(500)
    server.ask("reset_run")
    page.wait_for_timeout(warmup * 1000)

