"""Control → visible feedback in a real headless Chromium, and where the time goes, for this
tree and (``--base REV``) an earlier commit, in one run.

Run: python benchmarks/bench_control_latency.py [--base main~1] [--reps 5] [--robots 100]

For each tree, an app server runs in a child process (the tree's own code: ``--base`` is
exported with ``git archive`` into a temporary folder) playing ``default`` with ``--robots``
robots and trails, and Debian's Chromium (playwright, software WebGL, 1280×800) opens it. After
a warm-up, each action is timed ``--reps`` times, in the page's own clock, from the input
event the page dispatched to the moment the page's DOM shows the feedback:

- **Pause**: a click on *Pause* → the status line says "paused" (then Play → "playing");
- **U typed**: a new U typed into the number box beside its slider (Enter) → the readout
  below the sliders shows it;
- **U → stability title**: a new U typed → the (ω, ĉ) plot's title shows the new ω (where the
  plot is on another tab, as on the base commit, the tab is clicked right after Enter).

The Pause path is split where the time goes: the page's click → the server's handler starts
(``Panel.press``, server clock) → the first websocket frame carrying "paused" reaches the page
(playwright's frame event, stamped when the script sees it) → the DOM shows it. Before that, over
5 s of play: the traffic the page receives (frames/s, KiB/s: playwright's websocket events, which
it delivers only while the script is inside a playwright call, so the window is a playwright
wait), the page's requestAnimationFrame rate and long tasks (ms of main-thread work in tasks
> 50 ms per second, counted in the page) and the server's tick (ms per tick of the tab,
median/p95). The server of each tree is ``page_server.ChildServer``. Nothing here is asserted;
the machine is shared, so run both trees in one go and compare.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT / "tests" / "browser"))
sys.path.insert(0, str(ROOT / "tests"))
from bench_common import load_note, table  # noqa: E402
from page_server import ChildServer, open_page, page_counters, tree_of  # noqa: E402

from browser_helpers import dismiss_toasts, number_box  # noqa: E402
from viser_wire import decode_frame  # noqa: E402

WAITER = """
([pred]) => {
  const now = () => performance.timeOrigin + performance.now();
  window.__act = null;
  window.__done = new Promise((resolve) => {
    const test = new Function("return (" + pred + ")();");
    const check = () => { if (test()) { obs.disconnect(); resolve(now()); } };
    const obs = new MutationObserver(check);
    obs.observe(document.body, {subtree: true, childList: true, characterData: true});
    check();
  });
}
"""
ACT_CLOCK = """
(() => {
  const now = () => performance.timeOrigin + performance.now();
  for (const type of ["click", "keydown", "input"]) {  // a number box sends its value as it is typed
    document.addEventListener(type, () => { if (window.__act === null) window.__act = now(); }, true);
  }
})();
"""
STATUS_SAYS = "() => [...document.querySelectorAll('p, div')].some(e => e.childElementCount < 4 && " \
              "e.textContent.includes('{name}') && e.textContent.includes('{word}'))"
# the readout shows β: a table cell (before) or "β = …" in a line (now), the whole number (β = 0.4 must not
# match the 0.411 of the previous value: that read as a negative time)
READOUT_SAYS = ("() => [...document.querySelectorAll('td')].some(td => td.textContent.trim() === {text}) || "
                "[...document.querySelectorAll('p')].some(p => p.textContent.split('β = ').slice(1)"
                ".some(s => (s.match(/^[-+0-9.e]+/) || [''])[0] === {text}))")
TITLE_SAYS = "() => [...document.querySelectorAll('text.gtitle')].some(e => e.textContent.includes({text}))"


class Traffic:
    """Frames the page receives: counts, bytes, and when the first one saying ``word`` came."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.frames = self.bytes = 0
        self.word: str | None = None
        self.seen: float | None = None

    def on_frame(self, payload: bytes | str) -> None:
        t = time.time() * 1e3
        data = payload.encode() if isinstance(payload, str) else payload
        with self.lock:
            self.frames += 1
            self.bytes += len(data)
            word = self.word
        if word is not None:
            try:
                found = word in json.dumps(decode_frame(data), default=str, ensure_ascii=False)
            except Exception:
                found = False
            with self.lock:
                if found and self.seen is None:
                    self.seen = t

    def expect(self, word: str) -> None:
        with self.lock:
            self.word, self.seen = word, None

    def read(self) -> tuple[int, int]:
        with self.lock:
            return self.frames, self.bytes


def feedback(page, act, pred: str, timeout: float = 60.0) -> tuple[float, float]:
    """(page time of the input event, page time the DOM satisfied ``pred``), epoch ms."""
    page.evaluate(WAITER, [pred])
    act()
    done = page.evaluate(f"Promise.race([window.__done, new Promise(r => setTimeout(() => r(null), {timeout * 1e3}))])")
    if done is None:
        titles = page.evaluate("[...document.querySelectorAll('text.gtitle')].map(e => e.textContent)")
        raise TimeoutError(f"no feedback: {pred}; plot titles: {titles}")
    return float(page.evaluate("window.__act")), float(done)


def summary(values: list[float]) -> str:
    if not values:
        return "–"
    return f"{statistics.median(values):.0f} ({min(values):.0f}–{max(values):.0f})"


def measure(label: str, pkg: Path, preset: Path, reps: int, warmup: float) -> dict[str, str]:
    from playwright.sync_api import sync_playwright

    traffic = Traffic()
    out: dict[str, list[float]] = {k: [] for k in ("pause", "play", "server", "wire", "client", "typed", "title")}
    with ChildServer(pkg, preset, label) as server, sync_playwright() as p:
        ask = server.ask
        browser, page = open_page(p, server.port, traffic.on_frame)
        try:
            page.wait_for_selector("text=playback", timeout=120_000)
            page.evaluate(ACT_CLOCK)
            page.wait_for_timeout(warmup * 1000)
            dismiss_toasts(page)
            name = preset.stem
            # Traffic while playing. Playwright delivers frame events only while it is called, so the
            # window is a playwright wait (a plain sleep counted only the frames of the next call).
            ask("reset")
            f0, b0 = traffic.read()
            (raf0, long0), t0 = page_counters(page), time.monotonic()
            page.wait_for_timeout(5000)
            (raf1, long1), seconds = page_counters(page), time.monotonic() - t0
            f1, b1 = traffic.read()
            ticks = ask("stats")["ticks"]
            for _ in range(reps):
                traffic.expect("paused")
                ask("reset")
                act, seen = feedback(page, lambda: page.get_by_role("button", name="Pause", exact=True).click(),
                                     STATUS_SAYS.format(name=name, word="paused"))
                presses = [t for what, t in ask("stats")["presses"] if what == "Pause"]
                out["pause"].append(seen - act)
                if presses and traffic.seen is not None:
                    out["server"].append(presses[0] - act)
                    out["wire"].append(traffic.seen - presses[0])
                    out["client"].append(seen - traffic.seen)
                act, seen = feedback(page, lambda: page.get_by_role("button", name="Play", exact=True).click(),
                                     STATUS_SAYS.format(name=name, word="playing"))
                out["play"].append(seen - act)
                page.wait_for_timeout(1000)
            for i in range(reps):
                u = 7.0 + 0.5 * i
                box = number_box(page, "U [m/s]")
                if page.get_by_role("tab", name="Controller").count():
                    page.get_by_role("tab", name="Controller").click()
                    page.wait_for_timeout(500)

                def type_u(box=box, u=u) -> None:
                    box.fill(f"{u:g}")
                    box.press("Enter")

                beta = f"{30.0 * 0.1 / u:.4g}"  # the readout's β = A+Δt/U
                act, seen = feedback(page, type_u, READOUT_SAYS.format(text=json.dumps(beta)))
                out["typed"].append(seen - act)
                page.wait_for_timeout(1000)
                omega = 1.0 - 30.0 * 0.1 / (u + 0.3)  # ω = 1 − β after U → u + 0.3 (on the slider's 0.1 grid)
                text = json.dumps(f"({omega:.3g}, ")
                on_controller = page.locator("text.gtitle").filter(has_text="(ω, ĉ)").count() > 0 and \
                    page.locator("text.gtitle").filter(has_text="(ω, ĉ)").first.is_visible()

                def type_and_look(box=box, u=u, on_controller=on_controller) -> None:
                    box.fill(f"{u + 0.3:g}")
                    box.press("Enter")
                    if not on_controller:
                        page.get_by_role("tab", name="Plots").click()

                act, seen = feedback(page, type_and_look, TITLE_SAYS.format(text=text))
                out["title"].append(seen - act)
                page.wait_for_timeout(1000)
        finally:
            browser.close()
    ticks = sorted(ticks) or [0.0]
    return {
        "tree": label,
        "Pause → 'paused' ms": summary(out["pause"]),
        "Play → 'playing' ms": summary(out["play"]),
        "U typed → readout ms": summary(out["typed"]),
        "U typed → stability title ms": summary(out["title"]),
        "Pause: click → server ms": summary(out["server"]),
        "server → frame at page ms": summary(out["wire"]),
        "frame → DOM ms": summary(out["client"]),
        "frames/s": f"{(f1 - f0) / seconds:.1f}",
        "KiB/s": f"{(b1 - b0) / seconds / 1024:.0f}",
        "long tasks ms/s": f"{(long1 - long0) / seconds:.0f}",
        "page rAF/s": f"{(raf1 - raf0) / seconds:.1f}",
        "tick ms p50 / p95": f"{ticks[len(ticks) // 2]:.1f} / {ticks[int(0.95 * (len(ticks) - 1))]:.1f}",
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", default=None, help="also measure this commit (e.g. main~1), first")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--robots", type=int, default=100)
    ap.add_argument("--warmup", type=float, default=8.0)
    args = ap.parse_args()
    from shoal.presets.io import load, to_toml

    print(f"{load_note()}; {args.robots} robots, {args.reps} repetitions\n", file=sys.stderr)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        preset = Path(tmp) / "latency.toml"
        preset.write_text(to_toml(load("default", [f"sim.robots={args.robots}", "sim.steps=10000000",
                                                   "name=latency"])), encoding="utf-8")
        trees = ([(f"base {args.base}", args.base)] if args.base else []) + [("this tree", None)]
        for i, (label, rev) in enumerate(trees):
            where = Path(tmp) / f"tree{i}"
            where.mkdir()
            rows.append(measure(label, tree_of(rev, where), preset, args.reps, args.warmup))
            print(f"  {label}: {rows[-1]}", file=sys.stderr)
    keys = list(rows[0])
    print(table(keys, [[r[k] for k in keys] for r in rows]))
    print(f"\nafter the run: {load_note()}")


if __name__ == "__main__":
    main()
