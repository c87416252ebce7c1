"""The first start after an install: how long the first run and the first fleet scene wait for
numba, for this tree and (``--base REV``) an earlier commit, in one run.

Run: python benchmarks/bench_first_start.py [--base main] [--only run_default ...]

Each tree runs in its own child interpreter (``--base`` is exported with ``git archive``, see
``page_server.tree_of``) with ``NUMBA_CACHE_DIR`` pointing at a new empty folder: nothing is
compiled yet, as after ``pip install``. Wall-clock seconds of:

- **run_default**: ``shoal run default --steps 10`` (a new process; then ``run_default_again``,
  the same command with the kernels now in the cache);
- **run_fleet**: ``shoal run course-dvc --steps 10``;
- **serve_page**: ``shoal serve`` until it listens (the page can load);
- **first_pause**: a tab (viser's protocol spoken from Python, ``tests/viser_wire.py``) opens
  as soon as the server listens and presses Pause once its panel is there: seconds until the
  status line says "paused" (the controls while the kernels compile);
- **fleet_switch**: then it chooses ``course-dvc`` in the preset dropdown and waits until the
  new scene's robots have moved 3 times on screen (3 robot updates sent; the preset plays 5
  steps/s, so 0.4 s of it is the playback itself); measured from the choice;
- **warmup** (this tree only): ``shoal warmup``, cold, then again with the cache filled.

Nothing is asserted; the machine is shared, so read the two trees side by side.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tests"))
from page_server import tree_of  # noqa: E402

MEASURES = ("run_default", "run_fleet", "serve_page", "first_pause", "fleet_switch", "warmup")


def _env(pkg: Path, cache: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(pkg), "NUMBA_CACHE_DIR": str(cache)}


def _shoal(pkg: Path, cache: Path, *args: str) -> float:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "shoal", *args], env=_env(pkg, cache), capture_output=True,
                          text=True, timeout=1800)
    if done.returncode != 0:
        raise RuntimeError(f"shoal {' '.join(args)} failed: {done.stderr[-2000:]}")
    return time.perf_counter() - start


def _fleet_switch(pkg: Path, cache: Path) -> tuple[float, float, float]:
    """Seconds until the server listens, from Pause to "paused" shown, and from choosing
    course-dvc to its third robot update."""
    from viser_wire import WireClient

    start = time.perf_counter()
    child = subprocess.Popen([sys.executable, "-m", "shoal", "serve", "--port", "0", "--preset", "default"],
                             env=_env(pkg, cache), stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        port = None
        while port is None:
            line = child.stdout.readline()
            if not line:
                raise RuntimeError("the server stopped")
            if m := re.search(r"running at http://127\.0\.0\.1:(\d+)/", line):
                port = int(m.group(1))
        listening = time.perf_counter() - start
        tab = WireClient(port, decode=True)
        try:
            deadline = time.monotonic() + 600
            while tab.uuid_of("preset") is None or tab.uuid_of("playback") is None:
                if time.monotonic() > deadline:
                    raise RuntimeError("the tab's panel never arrived")
                time.sleep(0.05)
            seen = len(tab.texts)
            pressed = time.perf_counter()
            tab.set_value("playback", "Pause")
            while not any(" · paused" in t for t in tab.texts[seen:]):
                if time.monotonic() > deadline:
                    raise RuntimeError("the status never said paused")
                time.sleep(0.02)
            paused = time.perf_counter() - pressed
            time.sleep(1.0)  # default's last updates pass
            before = tab.counts()[2]
            chosen = time.perf_counter()
            tab.set_value("preset", "course-dvc")
            while tab.counts()[2] < before + 3:
                if time.monotonic() > deadline:
                    raise RuntimeError("course-dvc never moved")
                time.sleep(0.02)
            return listening, paused, time.perf_counter() - chosen
        finally:
            tab.close()
    finally:
        child.terminate()
        child.wait(timeout=60)


def measure(pkg: Path, only: tuple[str, ...], this: bool) -> dict[str, float]:
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        if "run_default" in only:
            out["run_default"] = _shoal(pkg, t / "c1", "run", "default", "--steps", "10", "--out", str(t / "r1"))
            out["run_default_again"] = _shoal(pkg, t / "c1", "run", "default", "--steps", "10", "--seed", "2",
                                              "--out", str(t / "r1b"))
        if "run_fleet" in only:
            out["run_fleet"] = _shoal(pkg, t / "c2", "run", "course-dvc", "--steps", "10", "--out", str(t / "r2"))
        if {"serve_page", "first_pause", "fleet_switch"} & set(only):
            out["serve_page"], out["first_pause"], out["fleet_switch"] = _fleet_switch(pkg, t / "c3")
        if "warmup" in only and this:
            out["warmup"] = _shoal(pkg, t / "c4", "warmup")
            out["warmup_again"] = _shoal(pkg, t / "c4", "warmup")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", help="an earlier commit to measure beside this tree (e.g. main)")
    ap.add_argument("--only", nargs="+", choices=MEASURES, default=list(MEASURES))
    args = ap.parse_args()
    results: dict[str, dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        trees = [("this", None)] + ([(args.base, args.base)] if args.base else [])
        for label, rev in reversed(trees):
            folder = Path(tmp) / label.replace("/", "_")
            folder.mkdir()
            pkg = tree_of(rev, folder)
            results[label] = measure(pkg, tuple(args.only), this=rev is None)
            print(label, json.dumps({k: round(v, 1) for k, v in results[label].items()}), flush=True)
    keys = sorted({k for r in results.values() for k in r}, key=lambda k: [*MEASURES, k].index(k.split("_again")[0]))
    print(f"\n| measure | {' | '.join(results)} |\n|---|{'---:|' * len(results)}")
    for k in keys:
        print(f"| {k} | " + " | ".join(f"{r[k]:.1f} s" if k in r else "–" for r in results.values()) + " |")
    print(f"\nload average: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
