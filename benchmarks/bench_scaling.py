"""How the Chapter 3 step and the Chapter 4–5 fleet step scale with robots and with runs
batched into one call, and a PNG of the curves.

Run: python benchmarks/bench_scaling.py [--quick] [--png benchmarks/scaling.png]

- Ch. 3 (``default`` preset, Adapted PSO): robots 10, 100, 1000 × runs 1, 10, 100 (full grid).
- Fleet (``course-dvc``: omni DVC, sequential, kinematic; ``course-physics``: pymunk bodies,
  mecanum): robots 10, 100, 1000 with one run, and runs 1, 10, 100 of 10 robots. The start
  square grows as 2√N m (same density at every size) inside a course 10 m wider than it.

Each point: median ms per step over a few CPU seconds of steps (at least 5, at most 200)
after warm-up steps, as this thread's CPU time (robust on a shared machine) and as wall time;
robot-steps/s = robots × runs / median CPU time of a step.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, rate, save_png, summary, table  # noqa: E402

SIZES = (10, 100, 1000)
BATCHES = (1, 10, 100)
FLEETS = {"fleet, kinematic (course-dvc)": "course-dvc", "fleet, physics (course-physics)": "course-physics"}
CH3 = "Ch. 3 Adapted PSO (default)"


def fleet_overrides(robots: int) -> list[str]:
    side = round(2.0 * math.sqrt(robots), 1)
    return [f"sim.robots={robots}", f"world.start_size={side}", f"world.width={side + 10}",
            f"world.length={max(60.0, 2 * side + 30)}"]


def step_ms(engine, budget_s: float, warmup: int = 2, min_steps: int = 5, max_steps: int = 200) -> tuple[float, float]:
    """Median (CPU, wall) ms of ``engine.step()`` over about ``budget_s`` seconds of CPU."""
    for _ in range(warmup):
        engine.step()
    cpu: list[float] = []
    wall: list[float] = []
    start = time.thread_time()
    while len(cpu) < max_steps and (len(cpu) < min_steps or time.thread_time() - start < budget_s):
        c0, t0 = time.thread_time(), time.perf_counter()
        engine.step()
        wall.append((time.perf_counter() - t0) * 1e3)
        cpu.append((time.thread_time() - c0) * 1e3)
    return summary(cpu)["median"], summary(wall)["median"]


def measure(budget_s: float) -> list[dict]:
    from shoal.presets.build import build
    from shoal.presets.io import load

    points = []
    for runs in BATCHES:
        for robots in SIZES:
            sim = build(load("default", [f"sim.robots={robots}"]), runs=runs)
            cpu, wall = step_ms(sim, budget_s)
            points.append({"engine": CH3, "robots": robots, "runs": runs, "ms": cpu, "wall": wall})
    for label, preset in FLEETS.items():
        grid = [(n, 1) for n in SIZES] + [(10, r) for r in BATCHES if r > 1]
        for robots, runs in grid:
            fleet = build(load(preset, fleet_overrides(robots)), runs=runs)
            cpu, wall = step_ms(fleet, budget_s)
            points.append({"engine": label, "robots": robots, "runs": runs, "ms": cpu, "wall": wall})
            print(f"  {label}: {robots} robots × {runs} runs: {points[-1]['ms']:.1f} ms", file=sys.stderr)
    for p in points:
        p["rate"] = p["robots"] * p["runs"] / (p["ms"] / 1e3)
    return points


def plot(points: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(10.5, 4.2), sharey=True)
    engines = [CH3, *FLEETS]
    for i, (engine, marker) in enumerate(zip(engines, "osD")):
        for runs, style in zip(BATCHES, ("-", "--", ":")):
            pts = [p for p in points if p["engine"] == engine and p["runs"] == runs]
            if len(pts) > 1:
                left.plot([p["robots"] for p in pts], [p["rate"] for p in pts], style, marker=marker, color=f"C{i}",
                          label=f"{engine}, {runs} run{'s' if runs > 1 else ''}")
        pts = [p for p in points if p["engine"] == engine and p["robots"] == 10]
        right.plot([p["runs"] for p in pts], [p["rate"] for p in pts], "-", marker=marker, color=f"C{i}",
                   label=f"{engine}, 10 robots")
    for ax, xlabel, title in ((left, "robots per run", "robots"), (right, "runs batched in one step", "runs")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_title(f"scaling with {title}")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    left.set_ylabel("robot-steps per second (one process)")
    fig.tight_layout()
    save_png(fig, path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="0.3 s per point instead of 3 s")
    ap.add_argument("--png", type=Path, default=Path(__file__).resolve().parent / "scaling.png")
    args = ap.parse_args()
    points = measure(0.3 if args.quick else 3.0)
    rows = [[p["engine"], str(p["robots"]), str(p["runs"]), fmt(p["ms"]), fmt(p["wall"]), rate(p["rate"]),
             fmt(p["ms"] * 1e3 / (p["robots"] * p["runs"]))] for p in points]
    print(f"{load_note()}\n")
    print(table(["engine", "robots", "runs", "CPU ms/step", "wall ms/step", "robot-steps/s (CPU)",
                 "µs/robot-step (CPU)"], rows))
    plot(points, args.png)
    print(f"\nplot: {args.png}")


if __name__ == "__main__":
    main()
