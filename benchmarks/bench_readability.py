"""Readable from the back row (issue 32): what the page's text, colours and controls give a hall,
for this tree and (``--base REV``) an earlier commit, in one run.

Run: python benchmarks/bench_readability.py [--base main] [--presets default fig3-4a …]
                                            [--viewports 1280x800 1920x1080] [--skip-slo]

Each tree serves its app from its own child interpreter (``--base`` is exported with ``git
archive``, see ``page_server.tree_of``); one headless Chromium page per tree and mode loads
every preset in turn (the panel's preset dropdown, from the server) at each window size and
measures, once the scene has settled:

- **text**: every visible text node of the page (``tests/browser/readability.py``): its
  computed font size (median and smallest) and its WCAG 2.1 contrast against the background it
  is drawn on (the lowest); text drawn into canvases counts too, at the size it is drawn: the
  arena's viser labels (12 px × their scale) and the plots' axes (the fonts uPlot draws with,
  caught by an init script);
- **unnamed controls**: the controls Playwright's ARIA snapshot gives no accessible name;
- in the **normal** and the **projector** mode: the tree's projector switch (``?projector=1``)
  where it has one, else its *large text* box (the nearest thing it has).

Then, from each tree's own colour constants, the **smallest colour-blind ΔE** of each pair of
colours that tells two things apart (Machado 2009 protan, deutan and tritan simulation at
severity 1, then CIEDE2000, by ColorAide), and the luminance contrast of Compare's swarms and
trails against the heat map; and the **SLO first frame** on a fresh install: ``shoal serve``
with an empty ``NUMBA_CACHE_DIR``, a page opened on it, ``slo-walk`` chosen in its preset
dropdown: seconds until the status line's step counter moves (and the same for a server
started on ``slo-walk`` itself).

Nothing is asserted; the machine is shared, so read the two trees side by side (the load is
printed with the numbers).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests" / "browser"))
import readability  # noqa: E402
from page_server import ARENA_IN_VIEW, ARGS, CHROMIUM, tree_of  # noqa: E402

VIEWPORTS = ("1280x800", "1920x1080")
MODES = ("normal", "projector")
SETTLE = 2.5  # s after a preset's scene is drawn before it is measured

# The child: the tree's app server; commands on stdin, answers on stdout after "@@".
SERVER = r"""
import json, sys, time
from shoal.app.server import start_server

server = start_server(sys.argv[1], port=0)
print("@@" + json.dumps({"port": server.port}), flush=True)

def tab():
    while not server.tabs:
        time.sleep(0.1)
    return next(iter(server.tabs.values()))

def projector(t, on):
    if hasattr(t, "set_projector"):
        t.set_projector(on)
    else:  # a tree without projector mode: its large text
        with t._ticking:
            t.display.large_text = on
            t._show_display()

def canvas_text(t):
    out = []
    for key, node in t.arena.canvas.nodes.items():
        if type(node).__name__ == "LabelHandle" and node.visible:
            out.append({"text": str(node.text), "size": 12.0 * float(node.font_screen_scale)})
    return out

for line in sys.stdin:
    cmd, _, arg = line.strip().partition(" ")
    if cmd == "load":
        t = tab()
        t.panels.load_preset(arg)
        t = tab()
        s = t.session
        print("@@" + json.dumps({"name": s.scenario.name, "kind": t.panels.name}), flush=True)
    elif cmd == "drawn":
        t = tab()
        drawn = t.arena.drawn_revision >= 0 and t.session.scene_revision == t.arena.built_revision
        print("@@" + json.dumps({"drawn": drawn}), flush=True)
    elif cmd == "projector":
        projector(tab(), arg == "on")
        print("@@{}", flush=True)
    elif cmd == "canvas":
        print("@@" + json.dumps(canvas_text(tab())), flush=True)
    elif cmd == "stop":
        break
server.stop()
"""



class Child:
    """The app of the tree in ``pkg`` serving ``preset``; ``ask(cmd)`` answers its command."""

    def __init__(self, pkg: Path, preset: str, env: dict[str, str] | None = None) -> None:
        self.pkg, self.preset, self.env = pkg, preset, env or {}
        self.lock = threading.Lock()

    def __enter__(self) -> "Child":
        env = {**os.environ, "PYTHONPATH": str(self.pkg), **self.env}
        self.proc = subprocess.Popen([sys.executable, "-c", SERVER, self.preset], cwd=str(self.pkg), env=env,
                                     text=True, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL)
        self.port = int(self._answer()["port"])
        return self

    def _answer(self) -> Any:
        assert self.proc.stdout is not None
        while not (line := self.proc.stdout.readline()).startswith("@@"):
            if not line:
                raise RuntimeError("the app server stopped")
        return json.loads(line[2:])

    def ask(self, cmd: str) -> Any:
        assert self.proc.stdin is not None
        with self.lock:
            self.proc.stdin.write(cmd + "\n")
            self.proc.stdin.flush()
            return None if cmd == "stop" else self._answer()

    def __exit__(self, *exc: Any) -> None:
        try:
            self.ask("stop")
            self.proc.wait(timeout=20)
        except Exception:
            self.proc.kill()
            self.proc.wait()


def has_projector(pkg: Path) -> bool:
    """Does the tree have a projector mode (its page takes ``?projector=1``)?"""
    return (pkg / "shoal" / "app" / "view" / "projector.py").exists()


def measure_page(page: Any, child: Child, canvas: bool = True) -> dict[str, Any]:
    """The numbers of what ``page`` shows now."""
    items = readability.texts(page)
    dom = readability.summary(items)
    drawn = page.evaluate("window.__shoalCanvasFonts ? window.__shoalCanvasFonts() : []") if canvas else []
    labels = child.ask("canvas") if canvas else []
    sizes = [t["size"] for t in items] + [t["size"] for t in drawn] + [t["size"] for t in labels]
    unnamed = readability.unnamed_controls(page)
    return {**dom.row(), "all_texts": len(sizes), "all_median_px": round(statistics.median(sizes), 1),
            "all_min_px": round(min(sizes), 1), "canvas_min_px": round(min((t["size"] for t in drawn + labels),
                                                                           default=float("nan")), 1),
            "unnamed": len(unnamed), "smallest": dom.smallest[:6], "palest": dom.palest[:6],
            "canvas_smallest": sorted(((round(t["size"], 1), t["text"]) for t in drawn + labels))[:4]}


def walk(pkg: Path, label: str, presets: list[str], viewports: list[str], playwright: Any) -> list[dict]:
    """Every preset × mode × window size of the tree in ``pkg``."""
    rows = []
    projector = has_projector(pkg)
    for mode in MODES:
        with Child(pkg, "default") as child:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                w, h = (int(v) for v in viewports[0].split("x"))
                page = browser.new_page(viewport={"width": w, "height": h})
                page.add_init_script(ARENA_IN_VIEW)
                page.add_init_script(readability.CANVAS_FONTS)
                query = "?projector=1" if mode == "projector" and projector else ""
                page.goto(f"http://127.0.0.1:{child.port}/{query}")
                page.wait_for_selector("label:has-text('robots')", timeout=180_000)
                if mode == "projector" and not projector:
                    child.ask("projector on")
                page.wait_for_timeout(3000)
                for preset in presets:
                    child.ask(f"load {preset}")
                    end = time.monotonic() + 120
                    while not child.ask("drawn")["drawn"] and time.monotonic() < end:
                        time.sleep(0.2)
                    for vp in viewports:
                        w, h = (int(v) for v in vp.split("x"))
                        page.set_viewport_size({"width": w, "height": h})
                        page.wait_for_timeout(SETTLE * 1000)
                        row = {"tree": label, "mode": mode, "viewport": vp, "preset": preset,
                               **measure_page(page, child)}
                        rows.append(row)
                        print(f"  {label:>8} {mode:>9} {vp:>9} {preset:<22} median {row['all_median_px']:>5} px, "
                              f"min {row['all_min_px']:>5} px (page text {row['min_px']}), contrast "
                              f"{row['min_contrast']:.2f}, unnamed {row['unnamed']}", flush=True)
            finally:
                browser.close()
    return rows


# ----------------------------------------------------------------------------- colours
COLOURS = r"""
import json
from shoal.app.kinds import fleet, sonar, swarm, mai
from shoal.app.view import layers
from shoal.app.view.layers import HeatScale
import numpy as np

def get(mod, *names):
    for n in names:
        if hasattr(mod, n):
            return [int(v) for v in getattr(mod, n)]
    return None

out = {
  "pairs": {
    "sonar: bearing ray / mirror ray": [get(sonar, "RAY_TRUE"), get(sonar, "RAY_MIRROR")],
    "fleet: global best / selected robot": [get(fleet, "GBEST"), get(fleet, "SELECTED")],
    "sonar: global best / selected robot": [get(sonar, "GBEST"), get(sonar, "SELECTED")],
    "compare: A's robots / B's robots": [get(swarm, "ROBOT", "RED") or [220, 50, 50], get(layers, "TWIN")],
    "compare: A's trail / B's trail": [get(swarm, "TRAIL") or [110, 150, 255], get(layers, "TWIN_TRAIL")],
    "Mai: low error / high error": [[int(v) for v in layers.ERR_LOW], [int(v) for v in layers.ERR_HIGH]],
  },
  "map": [[int(v) for v in c] for c in HeatScale.rgb(np.linspace(0, 1, 33))],
  "on_map": {"A's robots": get(layers, "OUTLINE") or get(swarm, "ROBOT"),  # an outline, where the tree draws one
             "B's robots": get(layers, "OUTLINE") or get(layers, "TWIN"),
             "A's trail": get(swarm, "TRAIL"), "B's trail": get(layers, "TWIN_TRAIL")},
  "outlined": hasattr(layers, "OUTLINE"),
}
print(json.dumps(out))
"""


def colour_numbers(pkg: Path) -> dict[str, Any]:
    """The smallest CVD ΔE of each pair and the lowest map contrast of Compare's swarms, from the
    tree's own colour constants."""
    done = subprocess.run([sys.executable, "-c", COLOURS], cwd=str(pkg), env={**os.environ, "PYTHONPATH": str(pkg)},
                          capture_output=True, text=True, check=True)
    data = json.loads(done.stdout.strip().splitlines()[-1])
    from shoal.app.view.palette import cvd_delta_e

    pairs = {name: round(cvd_delta_e(tuple(a), tuple(b)), 1) for name, (a, b) in data["pairs"].items()
             if a is not None and b is not None}
    on_map = {name: round(min(readability.contrast(tuple(c), tuple(m)) for m in data["map"]), 2)
              for name, c in data["on_map"].items() if c is not None}
    return {"delta_e": pairs, "map_contrast": on_map, "outlined": data["outlined"]}


# ----------------------------------------------------------------------------- SLO first frame
STEP = re.compile(r"slo-walk\b[^\n]*?\b(?:step|gen) (\d+)/\d+")


def _first_frame(pkg: Path, playwright: Any, switch: bool) -> float:
    """Seconds from opening a page on a fresh server (empty kernel cache) to slo-walk's step
    counter moving: the page opened on ``shoal serve --preset slo-walk``, or (``switch``) on
    ``default`` with slo-walk then chosen in the preset dropdown (timed from the choice)."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "PYTHONPATH": str(pkg), "NUMBA_CACHE_DIR": cache}
        preset = "default" if switch else "slo-walk"
        proc = subprocess.Popen([sys.executable, "-m", "shoal", "serve", "--port", "0", "--preset", preset],
                                cwd=str(pkg), env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        browser = None
        try:
            assert proc.stdout is not None
            port = None
            while port is None:
                line = proc.stdout.readline()
                if not line:
                    raise RuntimeError("the server stopped")
                if m := re.search(r"running at http://127\.0\.0\.1:(\d+)/", line):
                    port = int(m.group(1))
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.add_init_script(ARENA_IN_VIEW)
            start = time.perf_counter()
            page.goto(f"http://127.0.0.1:{port}/")
            page.wait_for_selector("label:has-text('preset')", timeout=300_000)
            if switch:
                page.wait_for_selector("label:has-text('robots')", timeout=300_000)
                from browser_helpers import choose

                start = time.perf_counter()
                choose(page, "preset", "slo-walk")
            first = None
            while time.perf_counter() - start < 600:
                m = STEP.search(page.locator("body").inner_text())
                if m is not None:
                    k = int(m.group(1))
                    if first is None:
                        first = k
                    elif k > first:
                        return time.perf_counter() - start
                page.wait_for_timeout(100)
            return float("inf")
        finally:
            if browser is not None:
                browser.close()
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--base", help="an earlier commit to measure beside this tree (e.g. main)")
    ap.add_argument("--presets", nargs="*", help="presets to walk (default: every shipped preset)")
    ap.add_argument("--viewports", nargs="*", default=list(VIEWPORTS))
    ap.add_argument("--skip-slo", action="store_true", help="leave out the SLO first frame (minutes on a cold cache)")
    ap.add_argument("--skip-pages", action="store_true", help="only the colours and the SLO first frame")
    ap.add_argument("--out", type=Path, help="write every row as JSON here")
    args = ap.parse_args()
    if CHROMIUM is None:
        raise SystemExit("needs Debian's chromium on the PATH (apt-get install chromium)")
    from playwright.sync_api import sync_playwright

    from shoal.presets.io import list_presets

    presets = args.presets or list_presets()
    print(f"load: {os.getloadavg()}", flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "a").mkdir()
        trees = [("this", tree_of(None, Path(tmp) / "a"))]
        if args.base:
            (Path(tmp) / "b").mkdir()
            trees.append((args.base, tree_of(args.base, Path(tmp) / "b")))
        rows: list[dict] = []
        results: dict[str, Any] = {}
        with sync_playwright() as p:
            for label, pkg in trees:
                results[label] = {"colours": colour_numbers(pkg)}
                if not args.skip_pages:
                    rows += walk(pkg, label, presets, args.viewports, p)
            if not args.skip_slo:
                for label, pkg in trees:
                    results[label]["slo_switch_s"] = round(_first_frame(pkg, p, switch=True), 1)
                    results[label]["slo_open_s"] = round(_first_frame(pkg, p, switch=False), 1)
                    print(f"  {label}: SLO first frame {results[label]}", flush=True)
    print(f"load: {os.getloadavg()}\n")
    report(rows, results)
    if args.out:
        args.out.write_text(json.dumps({"rows": rows, "results": results}, indent=1, default=str))


def report(rows: list[dict], results: dict[str, Any]) -> None:
    trees = list(results)
    if rows:
        print("| tree | mode | window | median text px (median over presets) | smallest px | lowest contrast | "
              "unnamed controls (most on a preset) |\n|---|---|---|---:|---:|---:|---:|")
        for mode in MODES:
            for vp in sorted({r["viewport"] for r in rows}):
                for tree in trees:
                    sel = [r for r in rows if r["tree"] == tree and r["mode"] == mode and r["viewport"] == vp]
                    if not sel:
                        continue
                    worst = min(sel, key=lambda r: r["all_min_px"])
                    pale = min(sel, key=lambda r: r["min_contrast"])
                    print(f"| {tree} | {mode} | {vp} | {statistics.median(r['all_median_px'] for r in sel):.1f} | "
                          f"{worst['all_min_px']:.1f} ({worst['preset']}) | {pale['min_contrast']:.2f} "
                          f"({pale['preset']}) | {max(r['unnamed'] for r in sel)} |")
    print()
    for tree in trees:
        c = results[tree]["colours"]
        print(f"{tree}: smallest CVD ΔE2000 {min(c['delta_e'].values()):.1f}: {c['delta_e']}")
        print(f"{tree}: lowest contrast on the heat map {c['map_contrast']} (outlined: {c['outlined']})")
        if "slo_switch_s" in results[tree]:
            print(f"{tree}: SLO first frame, empty NUMBA_CACHE_DIR: slo-walk chosen {results[tree]['slo_switch_s']} s, "
                  f"served {results[tree]['slo_open_s']} s")


if __name__ == "__main__":
    main()
