"""Memory stays bounded: (a) an hour-long interactive session, (b) a 10,000-run batch.

Run: python benchmarks/bench_memory.py [--quick] [--minutes 60] [--runs 10000] [--skip-session]
     [--skip-batch] [--png benchmarks/memory.png]

(a) For each scene kind (Ch. 3 swarm, Ch. 4–5 fleet, Ch. 7 acoustic swarm, SLO walk), in a
    fresh Python process each, the app's tab (session, panels, plots and arena on a real viser
    server, no browser) is ticked
    headless as the server's 60 Hz ticking thread would, on a simulated clock, with playback
    at 30 steps/s and a run that never ends: ``--minutes`` of session time are
    1800 × minutes scene frames. The resident set size (RSS) of the process, the history
    lengths and the number of messages viser keeps for late-joining clients are recorded
    every simulated minute; the plot shows RSS against scene frames.
(b) ``shoal sweep`` (``run_sweep``, in this process) of ``default`` with 10 robots and 20 steps
    over 100 start spreads × ``--runs``/100 runs per cell, with 1 and 2 worker processes: RSS
    of this process plus its workers, sampled every 0.05 s, against the runs of the cells
    saved so far. Also the runner underneath: ``iter_jobs``/``run_jobs`` over ``--runs``
    one-run jobs of the same scene (every job another spread), RSS after every 1000 finished
    runs, streaming the results away (``iter_jobs``) and keeping them all (``run_jobs``).
"""

from __future__ import annotations

import argparse
import gc
import json
import subprocess
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, peak_rss_mib, rss_mib, save_png, table  # noqa: E402

SCENES = {"Ch. 3 swarm (default, 20 robots)": "default", "Ch. 4 fleet (course-dvc, 6 robots)": "course-dvc",
          "Ch. 7 acoustic swarm (sonar-xb-pso, 10 robots)": "sonar-xb-pso", "SLO walk (slo-walk)": "slo-walk"}
TICK_HZ = 60
STEPS_PER_S = 30


def viser_backlog(server) -> int:
    """Messages viser keeps for clients that connect later (-1 if its internals moved)."""
    try:
        return len(server.viser._websock_server._broadcast_buffer.message_from_id)
    except AttributeError:
        return -1


def session_memory_isolated(preset: str, minutes: float) -> list[dict]:
    """:func:`session_memory` in a fresh Python process, so every scene starts from the same
    baseline (memory an earlier scene freed is not reused by the next)."""
    out = subprocess.run([sys.executable, __file__, "--one-session", preset, "--minutes", str(minutes)],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def session_memory(preset: str, minutes: float) -> list[dict]:
    """Samples of one simulated minute each: frames drawn, RSS, history lengths."""
    from shoal.app.server import ShoalServer
    from shoal.presets.io import load

    scenario = load(preset, ["sim.steps=10000000", f"view.steps_per_second={STEPS_PER_S}"])
    server = ShoalServer(scenario, port=0)
    try:
        tab = server.open_tab(0, server.viser.gui, server.viser.scene, auto_tick=False)
        frames = [0]
        draw = tab.arena.draw

        def counted(snap):
            frames[0] += 1
            return draw(snap)

        tab.arena.draw = counted
        tab.session.play()
        samples = []
        ticks = int(minutes * 60 * TICK_HZ)
        t0 = time.perf_counter()
        for k in range(ticks + 1):
            tab.tick(k / TICK_HZ)
            if k % (60 * TICK_HZ) == 0:
                gc.collect()
                s = tab.session
                samples.append({"minute": k / (60 * TICK_HZ), "frames": frames[0], "steps": s.sim.state.k,
                                "rss": rss_mib(), "history": len(s.frames), "metrics": len(s.metrics),
                                "backlog": viser_backlog(server), "wall": time.perf_counter() - t0})
        return samples
    finally:
        server.stop()


# ---------------------------------------------------------------------- (b) batches
class RssSampler:
    """RSS of this process and its children, sampled by a thread (peak kept)."""

    def __init__(self, every: float = 0.2) -> None:
        self.every, self.peak = every, 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def total(self) -> float:
        try:
            import psutil  # optional: counts the pool's worker processes too

            me = psutil.Process()
            return sum(p.memory_info().rss for p in [me, *me.children(recursive=True)]) / 2**20
        except Exception:
            return rss_mib()

    def _run(self) -> None:
        while not self._stop.is_set():
            self.peak = max(self.peak, self.total())
            self._stop.wait(self.every)

    def __enter__(self) -> "RssSampler":
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()


def batch_memory(runs: int, workers: int, keep: bool) -> list[dict]:
    """RSS after every 1000 finished runs of ``runs`` one-run jobs."""
    from shoal.studies.experiments.runner import Job, iter_jobs

    jobs = [Job(key=("spread", i), preset="default", overrides=("sim.robots=10", f"init.spread={1 + i % 97 / 10}"),
                seed=i, runs=1, steps=20) for i in range(runs)]
    kept: dict = {}
    samples: list[dict] = []
    done = [0]
    gc.collect()
    with RssSampler() as sampler:
        start_rss, t0 = sampler.total(), time.perf_counter()
        samples.append({"runs": 0, "rss": start_rss, "kept": 0})

        def progress(n: int) -> None:
            before, done[0] = done[0], done[0] + n
            if done[0] // 1000 > before // 1000:
                samples.append({"runs": done[0], "rss": sampler.total(), "kept": len(kept),
                                "wall": time.perf_counter() - t0})

        for key, result in iter_jobs(jobs, workers=workers, progress=progress):
            if keep:
                kept[key] = result
    samples[-1]["peak"] = sampler.peak
    return samples


def sweep_memory(runs: int, workers: int) -> list[dict]:
    """RSS (this process + workers) against runs saved, over a ``runs``-run ``run_sweep``."""
    import tempfile

    from shoal.studies.sweep.run import run_sweep

    cells, per_cell = 100, max(1, runs // 100)
    grid = ["init.spread=" + ",".join(f"{1 + i / 10:g}" for i in range(cells))]
    samples: list[dict] = []
    gc.collect()
    with tempfile.TemporaryDirectory() as tmp, RssSampler() as sampler:
        out = Path(tmp) / "sweep"
        stop = threading.Event()
        t0 = time.perf_counter()

        def watch() -> None:
            while not stop.is_set():
                saved = len(list((out / "cells").glob("*.csv"))) if (out / "cells").is_dir() else 0
                samples.append({"runs": saved * per_cell, "rss": sampler.total(), "wall": time.perf_counter() - t0})
                stop.wait(0.05)

        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
        try:
            run_sweep("default", grid, out, runs=per_cell, steps=20, sets=["sim.robots=10"], workers=workers,
                      progress=False)
        finally:
            stop.set()
            watcher.join()
        samples.append({"runs": cells * per_cell, "rss": sampler.total(), "wall": time.perf_counter() - t0,
                        "peak": sampler.peak})
    return samples


def per_thousand(samples: list[dict]) -> list[dict]:
    """The first sample at or past every 1000 runs (and the last)."""
    out, mark = [samples[0]], 1000
    for s in samples:
        if s["runs"] >= mark:
            out.append(s)
            mark = (s["runs"] // 1000 + 1) * 1000
    return out + ([samples[-1]] if out[-1] is not samples[-1] else [])


def plot(sessions: dict[str, list[dict]], batches: dict[str, list[dict]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [p for p in (sessions, batches) if p]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.6 * len(panels), 4.0), squeeze=False)
    axes = list(axes[0])
    if sessions:
        ax = axes.pop(0)
        for label, samples in sessions.items():
            ax.plot([s["frames"] / 1000 for s in samples], [s["rss"] for s in samples], marker=".", label=label)
        ax.set_xlabel("scene frames drawn (thousands; 30 per second of session)")
        ax.set_ylabel("process RSS (MiB)")
        ax.set_title("(a) interactive session, headless ticks")
        ax.set_ylim(bottom=0)
        ax.legend(fontsize=7, loc="lower right")
        ax.grid(True, alpha=0.3)
    if batches:
        ax = axes.pop(0)
        for label, samples in batches.items():
            ax.plot([s["runs"] for s in samples], [s["rss"] for s in samples], marker=".", label=label)
        ax.set_xlabel("runs finished")
        ax.set_ylabel("RSS (MiB), main process + workers")
        ax.set_title("(b) 10,000-run sweep and batch")
        ax.set_ylim(bottom=0)
        ax.legend(fontsize=7)
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    save_png(fig, path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="5 simulated minutes, first scene only, 2000 runs")
    ap.add_argument("--minutes", type=float, default=60.0, help="simulated session minutes per scene")
    ap.add_argument("--runs", type=int, default=10_000, help="one-run jobs in the batch measurement")
    ap.add_argument("--skip-session", action="store_true")
    ap.add_argument("--skip-batch", action="store_true")
    ap.add_argument("--png", type=Path, default=Path(__file__).resolve().parent / "memory.png")
    ap.add_argument("--one-session", metavar="PRESET", help=argparse.SUPPRESS)  # child process of (a)
    args = ap.parse_args()
    if args.one_session:
        print(json.dumps(session_memory(args.one_session, args.minutes)))
        return
    minutes, runs = (5.0, 2000) if args.quick else (args.minutes, args.runs)
    scenes = dict(list(SCENES.items())[:1]) if args.quick else SCENES
    sessions: dict[str, list[dict]] = {}
    if not args.skip_session:
        rows = []
        for label, preset in scenes.items():
            s = session_memory_isolated(preset, minutes)
            sessions[label] = s
            first, tenth, last = s[1] if len(s) > 1 else s[0], s[min(10, len(s) - 1)], s[-1]
            rows.append([label, str(last["frames"]), fmt(first["rss"]), fmt(tenth["rss"]), fmt(last["rss"]),
                         fmt(last["rss"] - tenth["rss"]), str(last["history"]), str(last["metrics"]),
                         str(last["backlog"]), fmt(last["wall"])])
            print(f"  {label}: {[(x['frames'], round(x['rss'], 1)) for x in s]}", file=sys.stderr)
        print(f"(a) {minutes:g} simulated minutes per scene at {STEPS_PER_S} steps/s, ticks at {TICK_HZ} Hz\n")
        print(table(["scene", "frames drawn", "RSS MiB at 1 min", "at 10 min", "at the end", "growth after 10 min",
                     "history steps", "metric rows", "viser backlog msgs", "wall s"], rows))
    batches: dict[str, list[dict]] = {}
    if not args.skip_batch:
        import matplotlib.pyplot  # noqa: F401  (imported once up front: the sweep plots its medians at the end)

        import shoal.studies.sweep.run  # noqa: F401

        rows = []
        for workers in (1, 2):
            label = f"shoal sweep (100 cells), {workers} worker{'s' * (workers > 1)}"
            s = sweep_memory(runs, workers)
            batches[label] = s
            marks = per_thousand(s)
            first = marks[1]["rss"] if len(marks) > 1 else s[0]["rss"]
            rows.append([label, str(s[-1]["runs"]), fmt(s[0]["rss"]), fmt(first),
                         fmt(s[-1]["rss"]), fmt(s[-1]["peak"]), " ".join(str(round(x["rss"])) for x in marks[1:]),
                         fmt(s[-1]["wall"])])
            print(f"  {label}: {[(x['runs'], round(x['rss'])) for x in marks]}", file=sys.stderr)
        for workers in (1, 2):
            for keep in (False, True):
                kind = "run_jobs (keep all)" if keep else "iter_jobs (stream)"
                label = f"{kind}, {workers} worker{'s' * (workers > 1)}"
                s = batch_memory(runs, workers, keep)
                batches[label] = s
                per_k = [round(x["rss"]) for x in s[1:]]
                rows.append([label, str(s[-1]["runs"]), fmt(s[0]["rss"]), fmt(s[1]["rss"]), fmt(s[-1]["rss"]),
                             fmt(s[-1]["peak"]), " ".join(map(str, per_k)), fmt(s[-1]["wall"])])
                print(f"  {label}: {per_k}", file=sys.stderr)
        print(f"\n(b) {runs} runs (default, 10 robots, 20 steps); RSS of this process + workers, MiB\n")
        print(table(["how", "runs", "RSS before", "after 1000 runs", "at the end", "peak",
                     "RSS after each 1000 runs", "wall s"], rows))
    if sessions or batches:
        plot(sessions, batches, args.png)
        print(f"\nplot: {args.png}")
    print(f"peak RSS of this process: {peak_rss_mib():.0f} MiB")


if __name__ == "__main__":
    main()
