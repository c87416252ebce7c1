"""Where the page's main thread goes while a scene plays: a Chromium trace and a CPU profile of
the app's page in real headless Chromium (software WebGL, 1280×800).

Run: python benchmarks/bench_page_profile.py [--cases 0 1] [--seconds 6] [--base main]

For each case the app server of this tree (or, with ``--base REV``, of that commit too) runs in a
child process, Chromium opens the page and the scene plays. After a warm-up, three windows:

1. counters: the page's requestAnimationFrame rate, its long-task time, the websocket frames and
   bytes it received, the server's steps and arena draws;
2. a trace (``devtools.timeline`` and ``toplevel`` categories): each thread's busy time, and the
   renderer main thread's self time by event (script, style/layout, paint, GC, GPU client);
3. a CPU profile of the main thread (CDP ``Profiler``): self time by JavaScript function, each
   function put in a group (three.js rendering, line geometry, React, viser's message handling,
   plotly, uPlot, ...) by the words its own source holds (viser's client is one minified bundle,
   but property and method names survive minification), and the JS entry points (the outermost
   function of each sample: a requestAnimationFrame callback, a message from the websocket
   worker, React's scheduler) with their total time.

Nothing is asserted; the machine is shared, so compare trees in one run.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import threading
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from bench_common import load_note, table  # noqa: E402
from page_server import CASES as PAGE_CASES  # noqa: E402
from page_server import ChildServer, open_page, page_counters, same_stretch, tree_of, write_preset  # noqa: E402

# the scenes: cases 0 (100 robots), 4 (1000 robots) and 5 (200 physics robots) of page_server
CASES = [PAGE_CASES[i] for i in (0, 4, 5)]

TRACE_CATEGORIES = ["devtools.timeline", "disabled-by-default-devtools.timeline", "toplevel", "v8.execute",
                    "blink", "gpu", "cc", "disabled-by-default-v8.gc"]

# Renderer main thread: trace event name → group (first matching pattern wins)
EVENT_GROUPS = [
    ("GC", re.compile(r"GC|Scavenge|Sweep|Mark|BlinkGC|ThreadState|MinorGC|MajorGC", re.I)),
    ("style / layout", re.compile(r"UpdateLayoutTree|RecalculateStyle|Layout|HitTest|ParseAuthorStyleSheet|"
                                  r"StyleInvalidat|UpdateStyle|ScheduleStyle|InvalidateLayout", re.I)),
    ("paint / composite", re.compile(r"Paint|Layeriz|UpdateLayer|Composit|Commit|Raster|Decode|"
                                     r"ProxyMain|BeginMainFrame|Animate|LocalFrameView|Frame", re.I)),
    ("WebGL / GPU client", re.compile(r"WebGL|GLES|gpu|Gpu|CommandBuffer|SharedImage|Canvas|"
                                      r"DrawingBuffer|Texture|Buffer", re.I)),
    ("script (JS)", re.compile(r"FunctionCall|EvaluateScript|V8|v8|RunMicrotasks|TimerFire|EventDispatch|"
                               r"HandlePostMessage|FireAnimationFrame|Script|Callback|Microtask|compile", re.I)),
]

# JS function source → group (first match wins; looked for in the function's own first chars)
JS_GROUPS = [
    ("line geometry (trails, segments)", ["setPositions", "computeLineDistances", "instanceStart",
                                          "InstancedInterleavedBuffer", "instanceDistance", "LineSegmentsGeometry"]),
    ("three.js render / WebGL calls", ["drawElements", "drawArrays", "bufferData", "bufferSubData", "uniformMatrix",
                                       "useProgram", "bindBuffer", "renderBufferDirect", "WebGLRenderer",
                                       "vertexAttribPointer", "texImage2D", "texSubImage2D", "getUniforms",
                                       "projectObject", "renderObjects", "setProgram", "onBeforeRender",
                                       "matrixWorld", "updateMatrix", "frustum", "program", "uniforms",
                                       "needsUpdate", "geometry"]),
    ("msgpack / zstd decode", ["Unrecognized type byte", "decodeUtf8", "ExtensionCodec", "msgpack", "zstd"]),
    ("plotly", ["Plotly", "_fullLayout", "_fullData", "plotly"]),
    ("uPlot", ["uPlot", "u-legend", "u-over", "setScale", "valToPos"]),
    ("React", ["memoizedState", "pendingProps", "memoizedProps", "__reactFiber", "Minified React error",
               "alternate", "lanes", "flags", "stateNode", "dependencies"]),
    ("viser message handling / stores", ["SceneNodeUpdateMessage", "SetSceneNodeVisibilityMessage", "GuiUpdateMessage",
                                         "messages", "parkAttr", "subscribe", "setState", "getState"]),
    ("styles (emotion / mantine)", ["insertRule", "mantine", "emotion", "cssText", "className"]),
]
NATIVE_WEBGL = re.compile(r"^(draw|buffer|uniform|bind|vertexAttrib|tex|useProgram|enable|disable|get|"
                          r"createBuffer|deleteBuffer|blend|depth|viewport|clear|readPixels|flush|finish)")


# ---------------------------------------------------------------------------- trace
def _threads(events: list[dict]) -> dict[tuple[int, int], str]:
    procs = {e["pid"]: e["args"].get("name", "") for e in events
             if e.get("ph") == "M" and e.get("name") == "process_name"}
    names = {}
    for e in events:
        if e.get("ph") == "M" and e.get("name") == "thread_name":
            names[(e["pid"], e["tid"])] = f"{procs.get(e['pid'], '?')}: {e['args'].get('name', '?')}"
    return names


def _spans(events: list[dict]) -> dict[tuple[int, int], list[tuple[float, float, str]]]:
    """(start µs, end µs, name) of every duration event, by thread (B/E pairs joined)."""
    out: dict[tuple[int, int], list[tuple[float, float, str]]] = defaultdict(list)
    open_: dict[tuple[int, int], list[tuple[float, str]]] = defaultdict(list)
    for e in sorted((e for e in events if e.get("ph") in ("X", "B", "E")), key=lambda e: e.get("ts", 0)):
        key = (e["pid"], e["tid"])
        if e["ph"] == "X" and "dur" in e:
            out[key].append((e["ts"], e["ts"] + e["dur"], e["name"]))
        elif e["ph"] == "B":
            open_[key].append((e["ts"], e["name"]))
        elif e["ph"] == "E" and open_[key]:
            ts, name = open_[key].pop()
            out[key].append((ts, e["ts"], name))
    return out


def self_times(spans: list[tuple[float, float, str]]) -> tuple[dict[str, float], float]:
    """Self time (µs) by event name, nesting by containment, and the busy time (top-level spans)."""
    own: dict[str, float] = defaultdict(float)
    stack: list[tuple[float, str]] = []  # (end, name) of the spans that contain the current one
    busy = 0.0
    for start, end, name in sorted(spans, key=lambda s: (s[0], -s[1])):
        while stack and stack[-1][0] <= start:
            stack.pop()
        if stack:
            end = min(end, stack[-1][0])
            own[stack[-1][1]] -= end - start
        else:
            busy += end - start
        own[name] += end - start
        stack.append((end, name))
    return own, busy


def trace_report(raw: bytes, seconds: float) -> tuple[list[list[str]], list[list[str]], dict[str, float]]:
    """Rows of the per-thread busy table, of the main thread's events, and its groups (ms/s)."""
    doc = json.loads(raw)
    events = doc["traceEvents"] if isinstance(doc, dict) else doc
    names = _threads(events)
    spans = _spans(events)
    busy_rows, main = [], None
    per_thread = []
    for key, sp in spans.items():
        own, busy = self_times(sp)
        per_thread.append((busy, names.get(key, str(key)), own))
    per_thread.sort(reverse=True)
    for busy, name, own in per_thread[:10]:
        busy_rows.append([name, f"{busy / 1e3 / seconds:.0f}"])
        if main is None and name.endswith("CrRendererMain"):
            main = own
    groups: dict[str, float] = defaultdict(float)
    event_rows = []
    if main is not None:
        for name, us in sorted(main.items(), key=lambda kv: -kv[1]):
            group = next((g for g, pat in EVENT_GROUPS if pat.search(name)), "other")
            groups[group] += us / 1e3 / seconds
            if len(event_rows) < 15:
                event_rows.append([name, group, f"{us / 1e3 / seconds:.1f}"])
    return busy_rows, event_rows, dict(groups)


# ---------------------------------------------------------------------------- CPU profile
def classify(frame: dict, sources: dict[str, str]) -> str:
    name, url = frame.get("functionName", ""), frame.get("url", "")
    if name.startswith("("):
        return name  # (program), (idle), (garbage collector)
    if not url and NATIVE_WEBGL.match(name):
        return "three.js render / WebGL calls"
    src = sources.get(frame.get("scriptId", ""), "")
    if src:
        lines = src.split("\n")
        ln = frame.get("lineNumber", 0)
        line = lines[ln] if 0 <= ln < len(lines) else ""
        body = line[frame.get("columnNumber", 0):frame.get("columnNumber", 0) + 1200]
        for group, words in JS_GROUPS:
            if any(w in body for w in words):
                return group
    if not url:
        return "native (no script)"
    return "other JS"


def snippet(frame: dict, sources: dict[str, str]) -> str:
    src = sources.get(frame.get("scriptId", ""), "")
    lines = src.split("\n")
    ln, col = frame.get("lineNumber", 0), frame.get("columnNumber", 0)
    text = lines[ln][col:col + 70] if 0 <= ln < len(lines) else ""
    return text.replace("|", "¦").replace("\n", " ")


def profile_report(profile: dict, sources: dict[str, str], top: int) -> tuple[list, list, list, float]:
    nodes = {n["id"]: n for n in profile["nodes"]}
    parent = {c: n["id"] for n in profile["nodes"] for c in n.get("children", ())}
    samples, deltas = profile["samples"], profile["timeDeltas"]
    span_us = float(profile["endTime"] - profile["startTime"])
    self_us: dict[int, float] = defaultdict(float)
    entry_us: dict[tuple, float] = defaultdict(float)
    for i, nid in enumerate(samples):
        dt = deltas[i + 1] if i + 1 < len(deltas) else 0.0
        self_us[nid] += dt
        chain, n = [], nid  # the outermost JS frame below (root)
        while n in parent:
            chain.append(n)
            n = parent[n]
        if chain:
            cf = nodes[chain[-1]]["callFrame"]
            entry_us[(cf["functionName"] or "(anonymous)", cf.get("scriptId", ""), cf.get("lineNumber", 0),
                      cf.get("columnNumber", 0))] += dt
    by_fn: dict[tuple, list] = {}
    groups: dict[str, float] = defaultdict(float)
    for nid, us in self_us.items():
        cf = nodes[nid]["callFrame"]
        key = (cf["functionName"] or "(anonymous)", cf.get("scriptId", ""), cf.get("lineNumber", 0),
               cf.get("columnNumber", 0))
        group = classify(cf, sources)
        groups[group] += us
        if key not in by_fn:
            by_fn[key] = [0.0, group, snippet(cf, sources)]
        by_fn[key][0] += us
    seconds = span_us / 1e6
    fn_rows = [[name, f"{col}", group, f"`{snip}`", f"{us / 1e3 / seconds:.1f}"]
               for (name, _, _, col), (us, group, snip) in sorted(by_fn.items(), key=lambda kv: -kv[1][0])[:top]]
    group_rows = [[g, f"{us / 1e3 / seconds:.1f}"] for g, us in sorted(groups.items(), key=lambda kv: -kv[1])]
    entries = []
    for (name, sid, ln, col), us in sorted(entry_us.items(), key=lambda kv: -kv[1])[:8]:
        cf = {"functionName": name, "scriptId": sid, "lineNumber": ln, "columnNumber": col}
        entries.append([name, f"{col}", f"`{snippet(cf, sources)}`", f"{us / 1e3 / seconds:.1f}"])
    return fn_rows, group_rows, entries, seconds


# ---------------------------------------------------------------------------- one case
class Frames:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.frames = self.bytes = 0

    def on_frame(self, payload: bytes | str) -> None:
        with self.lock:
            self.frames += 1
            self.bytes += len(payload)

    def read(self) -> tuple[int, int]:
        with self.lock:
            return self.frames, self.bytes


def measure(label: str, pkg: Path, preset: Path, seconds: float, warmup: float, top: int) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright

    out: dict[str, Any] = {"tree": label}
    with ChildServer(pkg, preset, label) as server, sync_playwright() as p:
        frames = Frames()
        browser, page = None, None
        try:
            browser, page = open_page(p, server.port, frames.on_frame)
            same_stretch(server, page, warmup)
            # 1. counters
            s0, f0, c0, t0 = server.ask("stats"), frames.read(), page_counters(page), time.monotonic()
            page.wait_for_timeout(seconds * 1000)
            s1, f1, c1, t1 = server.ask("stats"), frames.read(), page_counters(page), time.monotonic()
            dt = t1 - t0
            out["counters"] = {"rAF/s": (c1[0] - c0[0]) / dt, "long tasks ms/s": (c1[1] - c0[1]) / dt,
                               "ws frames/s": (f1[0] - f0[0]) / dt, "KiB/s": (f1[1] - f0[1]) / dt / 1024,
                               "server steps/s": (s1["steps"] - s0["steps"]) / dt,
                               "server draws/s": (s1["draws"] - s0["draws"]) / dt}
            # 2. trace
            browser.start_tracing(page=page, categories=TRACE_CATEGORIES)
            t0 = time.monotonic()
            page.wait_for_timeout(seconds * 1000)
            raw = browser.stop_tracing()
            out["trace"] = trace_report(raw, time.monotonic() - t0)
            # 3. CPU profile of the main thread
            cdp = page.context.new_cdp_session(page)
            scripts: list[str] = []
            cdp.on("Debugger.scriptParsed", lambda e: scripts.append(e["scriptId"]))
            cdp.send("Debugger.enable")
            cdp.send("Profiler.enable")
            cdp.send("Profiler.setSamplingInterval", {"interval": 250})
            cdp.send("Profiler.start")
            page.wait_for_timeout(seconds * 1000)
            profile = cdp.send("Profiler.stop")["profile"]
            used = {n["callFrame"].get("scriptId") for n in profile["nodes"]} - {"", "0", None}
            sources = {}
            for sid in used:
                try:
                    sources[sid] = cdp.send("Debugger.getScriptSource", {"scriptId": sid})["scriptSource"]
                except Exception:
                    pass
            cdp.send("Debugger.disable")
            out["profile"] = profile_report(profile, sources, top)
        finally:
            if browser is not None:
                browser.close()
    return out


def report(case: str, m: dict[str, Any]) -> None:
    print(f"\n### {case}: {m['tree']}\n")
    c = m["counters"]
    print(table(list(c), [[f"{v:.1f}" for v in c.values()]]))
    busy_rows, event_rows, groups = m["trace"]
    print("\nBusy time by thread (trace, ms per second):\n")
    print(table(["thread", "busy ms/s"], busy_rows))
    print("\nRenderer main thread, self time by group (trace, ms per second):\n")
    print(table(["group", "ms/s"], [[g, f"{v:.0f}"] for g, v in sorted(groups.items(), key=lambda kv: -kv[1])]))
    print("\nRenderer main thread, top events by self time (ms per second):\n")
    print(table(["event", "group", "ms/s"], event_rows))
    fn_rows, group_rows, entries, secs = m["profile"]
    print(f"\nJavaScript on the main thread, self time by group (CPU profile over {secs:.1f} s, ms per second):\n")
    print(table(["group", "ms/s"], group_rows))
    print("\nTop functions by self time (minified names; the column and first characters of the function):\n")
    print(table(["function", "column", "group", "source starts", "ms/s"], fn_rows))
    print("\nJS entry points (the outermost function of each sample), total time:\n")
    print(table(["entry", "column", "source starts", "ms/s"], entries))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", type=int, nargs="*", default=[0, 1], help="indices of CASES (0-based)")
    ap.add_argument("--seconds", type=float, default=6.0, help="length of each of the three windows")
    ap.add_argument("--warmup", type=float, default=8.0, help="seconds of play before the first window")
    ap.add_argument("--base", default=None, help="also profile this commit (e.g. main), first")
    ap.add_argument("--top", type=int, default=15, help="functions listed")
    args = ap.parse_args()
    print(f"{load_note()}", file=sys.stderr)
    with tempfile.TemporaryDirectory() as tmp:
        trees = ([(f"base {args.base}", args.base)] if args.base else []) + [("this tree", None)]
        pkgs = []
        for i, (label, rev) in enumerate(trees):
            where = Path(tmp) / f"tree{i}"
            where.mkdir()
            pkgs.append((label, tree_of(rev, where)))
        for ci in args.cases:
            case, preset, overrides = CASES[ci]
            path = write_preset(preset, overrides, Path(tmp) / f"{preset}-profile.toml")
            for label, pkg in pkgs:
                report(case, measure(label, pkg, path, args.seconds, args.warmup, args.top))
    print(f"\nafter the run: {load_note()}")


if __name__ == "__main__":
    main()
