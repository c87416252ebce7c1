"""Hostile clients against one ``shoal serve``: what another tab keeps, and what a hostile
preset costs (issue 20), this version side by side with a previous one in one run.

Run: python benchmarks/bench_hostile.py [--against main] [--seconds 10] [--only idle upload ...]

Each version's server runs in a child process started from that version's ``src`` (the
previous one is ``git archive``'d to a temporary folder), with one Sweep worker as ``shoal
serve`` has by default. This process holds the clients (``tests/viser_wire.py``):

- an **observer** tab plays the default scene and counts its robot point-cloud updates; its
  rate over ``--seconds`` is measured idle, then while another tab does the worst it can:
- **upload**: uploads a 99 KiB preset of one dotted key of 20,000 parts (``a.a.a…=1``), again
  as soon as it is refused;
- **replay**: uploads the largest replay the server reads (400,000 robot rows), again and again;
- **sweep**: runs the costliest experiment the server accepts (1000-robot swarms, 100 runs
  a cell, 10,000 steps) on the worker; and, where a version accepts it, the audit's
  ``sim.steps = 10000000, 9999999`` sweep;
- **flood**: sends 20,000 values no control can hold, as fast as the socket takes them;
- (issue 30) **upload-d**: uploads a 2 KB preset of 2,000 robots in ``sim.d = 1000``, again and
  again; **compare-d**: applies swarm B = A with ``sim.d = 1000, sim.robots = 1000``, again and
  again; **sweep-d**: runs the Sweep tab's ``sim.d = 2, 500, 1000`` sweep of 2,000 robots;
  **forest**: uploads a forest of 17,000 trees (width 1,000 m, density 0.5), again and again.
  The hostile tab pauses its own scene first.
  For these the server's resident memory is read too, at the end of the load and 10 s after
  the hostile tab closed (``--rss``).

Also, in this process: the time to refuse each of several 99 KiB hostile TOML texts
(``parse_upload``, which bounds the text before ``tomllib``), and ``tomllib`` itself on them
in a child process given at most ``--parse-limit`` seconds (the previous version's path).

A scenario's load is stopped (its tab closed, its server restarted) before the next. Nothing
here is asserted: the tests check behaviour (``tests/test_trust_*.py``), this measures.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Callable

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT / "tests"))
from bench_common import load_note, table  # noqa: E402

SERVER = """
import sys, time
from shoal.app.server import start_server
srv = start_server("default", port=0)
print("PORT", srv.port, flush=True)
sys.stdin.read()
srv.stop()
"""
SCENARIOS = ("idle", "upload", "replay", "sweep", "sweep-steps", "flood", "upload-d", "compare-d", "sweep-d", "forest")
MEMORY_CAP = 4 * 2**30  # address space of the child that runs tomllib alone (the machine is shared)


def hostile_toml() -> dict[str, bytes]:
    """99 KiB texts that make ``tomllib`` slow or deep."""
    size = 99 * 1024
    return {
        "dotted key, 20,000 parts (the audit's)": (b"a" + b".a" * 20_000 + b" = 1\n"),
        "dotted key, 50,000 parts": (b"a" + b".a" * 50_000)[: size - 5] + b" = 1\n",
        "table header, 50,000 parts": (b"[" + b"a." * 50_000)[: size - 2] + b"]\n",
        "inline table, dotted": (b"x = {" + b"a." * 50_000)[: size - 6] + b" = 1}\n",
        "nested arrays": b"x = " + b"[" * 50_000 + b"]" * 50_000,
        "one key of 99 KiB": b"a" * (size - 5) + b" = 1\n",
    }


def time_bounds(texts: dict[str, bytes], parse_limit: float) -> list[list[str]]:
    from shoal.app.session.upload import parse_upload
    from shoal.presets.io import PresetError

    rows = []
    for name, data in texts.items():
        t0 = time.perf_counter()
        try:
            parse_upload("x.toml", data)
            verdict = "accepted"
        except PresetError as err:
            verdict = err.messages[0][:60]
        ms = (time.perf_counter() - t0) * 1e3
        with tempfile.NamedTemporaryFile(suffix=".toml", delete=False) as f:
            f.write(data)
        code = ("import resource, sys, time, tomllib; t = time.perf_counter()\n"
                f"resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_CAP}, {MEMORY_CAP}))\n"
                "try: tomllib.loads(open(sys.argv[1]).read()); how = ''\n"
                "except MemoryError: how = ' MemoryError'\nexcept Exception: how = ''\n"
                "print(time.perf_counter() - t, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, how)")
        try:
            out = subprocess.run([sys.executable, "-c", code, f.name], capture_output=True, text=True,
                                 timeout=parse_limit).stdout.split()
            raw = f"{float(out[0]):.2f} s, {float(out[1]):.0f} MiB peak" + (
                f", out of memory at the {MEMORY_CAP / 2**30:.0f} GiB cap" if len(out) > 2 else "")
        except subprocess.TimeoutExpired:
            raw = f"> {parse_limit:.0f} s (stopped)"
        os.unlink(f.name)
        rows.append([name, f"{len(data) / 1024:.0f} KiB", f"{ms:.2f} ms", verdict, raw])
    return rows


class Server:
    """A ``shoal serve`` of the version in ``src`` in a child process."""

    def __init__(self, src: Path) -> None:
        env = dict(os.environ, PYTHONPATH=str(src))
        self.proc = subprocess.Popen([sys.executable, "-c", SERVER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.DEVNULL, text=True, env=env)
        line = ""
        while not line.startswith("PORT"):
            line = self.proc.stdout.readline()  # type: ignore[union-attr]
            if not line and self.proc.poll() is not None:
                raise RuntimeError("the server did not start")
        self.port = int(line.split()[1])

    def stop(self) -> None:
        import psutil

        kids = psutil.Process(self.proc.pid).children(recursive=True)
        try:
            self.proc.stdin.close()  # type: ignore[union-attr]
            self.proc.wait(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        for p in kids:
            if p.is_running():
                p.kill()


def tab(port: int) -> Any:
    from viser_wire import WireClient

    c = WireClient(port, decode=True)
    end = time.monotonic() + 120
    while not c.uuid_of("Run experiment") and time.monotonic() < end:
        time.sleep(0.05)
    return c


def rate(observer: Any, seconds: float) -> float:
    _, _, a = observer.counts()
    t0 = time.monotonic()
    time.sleep(seconds)
    _, _, b = observer.counts()
    return (b - a) / (time.monotonic() - t0)


def load_upload(c: Any, stop: threading.Event) -> None:
    data = hostile_toml()["dotted key, 20,000 parts (the audit's)"]
    while not stop.is_set():
        n = len(c.notifications())
        c.upload("Upload preset", "hostile.toml", data)
        while len(c.notifications()) == n and not stop.is_set():
            time.sleep(0.02)


def big_replay() -> bytes:
    import numpy as np

    from shoal.app import replay
    from shoal.app.kinds.registry import session_for
    from shoal.presets.io import load

    session = session_for(load("default", ["sim.robots=2000"]))
    session.step(2)
    rec = replay.from_bytes(session.export_replay())
    frames, robots = 200, 2000  # 400,000 rows: the most a replay holds
    rng = np.random.default_rng(1)
    xs = [rng.uniform(-5, 5, (robots, 2)) for _ in range(frames)]
    big = replay.from_frames(rec.meta, list(range(frames)), [0.1 * k for k in range(frames)], xs,
                             [np.zeros(robots) for _ in xs], [np.zeros(robots, np.int8) for _ in xs],
                             np.zeros((frames, len(rec.metric_names))))
    return replay.to_bytes(big)


def load_replay(c: Any, stop: threading.Event, data: bytes) -> None:
    while not stop.is_set():
        n = len(c.notifications())
        c.upload("Load replay", "big.npz", data, parts=max(1, len(data) // (512 * 1024) + 1))
        while len(c.notifications()) == n and not stop.is_set():
            time.sleep(0.02)


def _experiment(c: Any, field: str, values: str, runs: int, steps: int) -> None:
    c.set_value("field 1", field)
    time.sleep(1.0)  # (the panel suggests values for the field first)
    c.set_value("values 1", values)
    c.set_value("runs per cell", runs)
    c.set_value("steps per run", steps)
    c.set_value("Run experiment", True)


def load_sweep(c: Any, stop: threading.Event) -> None:
    _experiment(c, "sim.robots", "1000, 999", 100, 10_000)
    stop.wait()


def load_sweep_steps(c: Any, stop: threading.Event) -> None:
    _experiment(c, "sim.steps", "10000000, 9999999", 100, 10_000)
    stop.wait()


def _preset(sets: list[str]) -> bytes:
    from shoal.presets.io import load, to_toml

    return to_toml(load("forest-dvc" if any(s.startswith("world.") for s in sets) else "default", sets)).encode()


def _pause(c: Any) -> None:
    """The hostile tab's own scene paused: only what it asks of the server counts."""
    c.set_value("playback", "Pause")
    time.sleep(0.5)


def _uploads(c: Any, stop: threading.Event, data: bytes) -> None:
    _pause(c)
    while not stop.is_set():
        n = len(c.notifications())
        c.upload("Upload preset", "hostile.toml", data)
        end = time.monotonic() + 20  # (an accepted one says nothing: upload it again after a while)
        while len(c.notifications()) == n and not stop.is_set() and time.monotonic() < end:
            time.sleep(0.02)


def load_upload_d(c: Any, stop: threading.Event) -> None:
    _uploads(c, stop, _preset(["sim.robots=2000", "sim.d=1000"]))


def load_forest(c: Any, stop: threading.Event) -> None:
    _uploads(c, stop, _preset(["world.width=1000", "world.density=0.5"]))


def load_compare_d(c: Any, stop: threading.Event) -> None:
    _pause(c)
    c.set_value("B overrides", "sim.d = 1000\nsim.robots = 1000")
    while not stop.is_set():
        n = len(c.notifications())
        c.set_value("Apply to B", True)
        end = time.monotonic() + 20
        while len(c.notifications()) == n and not stop.is_set() and time.monotonic() < end:
            time.sleep(0.02)


def load_sweep_d(c: Any, stop: threading.Event) -> None:
    _pause(c)
    c.set_value("robots", 2000)
    time.sleep(1.0)
    _experiment(c, "sim.d", "2, 500, 1000", 10, 1000)
    stop.wait()


def load_flood(c: Any, stop: threading.Event) -> None:
    from viser import _messages

    uuid = c.uuid_of("robots")
    for _ in range(20_000):
        if stop.is_set():
            return
        c.send(_messages.GuiUpdateMessage(uuid, {"value": "lots"}))
    stop.wait()


def rss_mb(server: Server) -> float:
    import psutil

    return psutil.Process(server.proc.pid).memory_info().rss / 2**20


def measure(src: Path, seconds: float, only: tuple[str, ...], replay_bytes: bytes) -> dict[str, Any]:
    loads: dict[str, Callable[..., None]] = {
        "upload": load_upload, "replay": lambda c, s: load_replay(c, s, replay_bytes), "sweep": load_sweep,
        "sweep-steps": load_sweep_steps, "flood": load_flood, "upload-d": load_upload_d, "compare-d": load_compare_d,
        "sweep-d": load_sweep_d, "forest": load_forest}
    out: dict[str, Any] = {}
    for name in only:
        server = Server(src)
        observer = tab(server.port)
        try:
            start = observer.counts()[2]  # the observer's run is under way (its kernels compiled)
            end = time.monotonic() + 300
            while observer.counts()[2] < start + 20 and time.monotonic() < end:
                time.sleep(0.1)
            if name == "idle":
                out[name] = rate(observer, seconds)
                continue
            hostile, stop = tab(server.port), threading.Event()
            before = rss_mb(server)
            worker = threading.Thread(target=loads[name], args=(hostile, stop), daemon=True)
            worker.start()
            time.sleep(2.0 if name in ("sweep", "sweep-steps", "sweep-d") else 0.5)  # the load is on
            out[name] = rate(observer, seconds)
            loaded = rss_mb(server)
            stop.set()
            hostile.ws.close()
            time.sleep(10.0)
            out[f"{name}:rss"] = (before, loaded, rss_mb(server))
        finally:
            observer.ws.close()
            server.stop()
    return out


def previous_src(rev: str, into: Path) -> Path:
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "src"], capture_output=True, check=True)
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive.stdout, check=True)
    return into / "src"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--against", default="main", help="the previous version (a git revision)")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--parse-limit", type=float, default=60.0, help="s tomllib may take on a hostile text")
    ap.add_argument("--only", nargs="*", default=list(SCENARIOS), choices=SCENARIOS)
    ap.add_argument("--no-parse", action="store_true", help="skip the tomllib timings")
    args = ap.parse_args()
    print(f"# bench_hostile ({load_note()})\n")
    if not args.no_parse:
        print("## A 99 KiB hostile preset: refused before tomllib (this version), tomllib alone (the previous path)\n")
        print(table(["text", "size", "refused in", "verdict", "tomllib alone"], time_bounds(hostile_toml(),
                                                                                              args.parse_limit)))
    only = tuple(dict.fromkeys(["idle", *args.only]))
    replay_bytes = big_replay()
    with tempfile.TemporaryDirectory() as tmp:
        versions = {args.against: previous_src(args.against, Path(tmp)), "this": ROOT / "src"}
        results = {v: measure(src, args.seconds, only, replay_bytes) for v, src in versions.items()}
    print(f"\n## Another tab's robot updates a second while one tab does the worst it can ({args.seconds:.0f} s "
          "each)\n")
    rows = []
    for name in only:
        row = [name]
        for v in versions:
            r, idle = results[v].get(name, float("nan")), results[v]["idle"]
            row += [f"{r:.1f}", f"{100 * r / idle:.0f} %" if idle else "–"]
        rows.append(row)
    heads = ["load"] + [h for v in versions for h in (f"{v}: updates/s", f"{v}: of idle")]
    print(table(heads, rows))
    rows = [[name] + [" → ".join(f"{m:,.0f}" for m in results[v][f"{name}:rss"]) for v in versions]
            for name in only if any(f"{name}:rss" in results[v] for v in versions)]
    print("\n## The server's resident memory (MiB): before the load → at its end → 10 s after its tab closed\n")
    print(table(["load", *versions], rows))


if __name__ == "__main__":
    main()
