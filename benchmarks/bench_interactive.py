"""Interactive budget on ONE core: is one tick of the scenes the browser app runs well under
one frame (33 ms at 30 fps)?

Run: python benchmarks/bench_interactive.py [--quick] [--steps 300]

For each scene (one run, as in the app): the engine tick alone, and the app's session step
(tick + history ring buffer + metrics) plus the snapshot the arena draws from. Median and
95th percentile over ``--steps`` consecutive ticks after a short warm-up, so the dense
start of the fleet and the later spread-out phase both count, of the CPU time (what a tick
costs on a core of its own) and of the wall time (what it took on the machine as shared at
the time). BLAS/OpenMP threads are set to 1 and the process is pinned to one CPU before
numpy is imported.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, one_core, summary, table, timed_cpu  # noqa: E402

FRAME_MS = 1000.0 / 30.0
WARMUP = 5

# (label, preset, overrides): 100 robots among obstacles with six-sector sensing, and the
# 10-robot waveform-level acoustic presets.
FLEET = ["sim.robots=100", "world.length=80", "world.width=40", "world.start_size=14", "sim.steps=100000"]
CASES = [
    ("100 robots, obstacle course, sensing + DVC, pymunk physics (mecanum)", "course-physics", FLEET),
    ("100 robots, obstacle course, sensing + DVC, kinematic", "course-dvc", FLEET),
    ("100 robots, non-omni DVC, empty arena, kinematic", "open-nonomni",
     ["sim.robots=100", "world.width=60", "world.start_size=24", "sim.steps=100000"]),
    ("10 robots, XB-PSO, waveform acoustics (sonar-xb-pso)", "sonar-xb-pso", []),
    ("10 robots, GT-PSO non-omni, waveform acoustics (sonar-gt-pso)", "sonar-gt-pso", []),
    ("40 robots, GT-PSO escorting a still source, waveform (escort-stationary)", "escort-stationary", []),
    ("40 robots, GT-PSO escorting a moving source, waveform (escort-moving)", "escort-moving", []),
    ("100 robots, Adapted PSO, free space (default)", "default", ["sim.robots=100", "sim.steps=100000"]),
    ("1000 robots, obstacle course, sensing + DVC, kinematic (compiled tick)", "course-dvc",
     ["sim.robots=1000", "world.length=160", "world.width=73.2", "world.start_size=63.2", "sim.steps=100000"]),
    ("200 robots, obstacle course, sensing + DVC, pymunk physics (mecanum)", "course-physics",
     ["sim.robots=200", "world.length=90", "world.width=38.3", "world.start_size=28.3", "sim.steps=100000"]),
]


def measure(preset: str, overrides: list[str], steps: int) -> dict[str, dict]:
    """Wall and CPU summaries (ms) of the engine tick and of the session step + snapshot."""
    from shoal.app.kinds.registry import session_for
    from shoal.presets.build import build
    from shoal.presets.io import load

    scenario = load(preset, overrides)
    engine = build(scenario, runs=1)
    engine_wall, engine_cpu = timed_cpu(engine.step, steps, warmup=WARMUP)
    session = session_for(scenario)

    def app_step() -> None:
        session.step(1)
        session.snapshot()

    app_wall, app_cpu = timed_cpu(app_step, steps, warmup=WARMUP)
    return {"engine": summary(engine_wall), "engine_cpu": summary(engine_cpu), "app": summary(app_wall),
            "app_cpu": summary(app_cpu)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="40 ticks per case instead of --steps")
    ap.add_argument("--steps", type=int, default=300, help="timed ticks per case")
    ap.add_argument("--cases", type=int, nargs="*", help="indices of the cases to run (0-based)")
    args = ap.parse_args()
    steps = 40 if args.quick else args.steps
    print(f"one core: {one_core()}; {steps} ticks per case after {WARMUP} warm-up ticks; {load_note()}\n")
    rows = []
    for label, preset, overrides in [CASES[i] for i in args.cases] if args.cases else CASES:
        m = measure(preset, overrides, steps)
        e, ec, a, ac = m["engine"], m["engine_cpu"], m["app"], m["app_cpu"]
        rows.append([label, fmt(ec["median"]), fmt(ec["p95"]), fmt(ac["median"]), fmt(ac["p95"]),
                     f"{ac['p95'] / FRAME_MS:.0%}", fmt(e["median"]), fmt(e["p95"]), fmt(a["median"]), fmt(a["p95"])])
        print(f"  {label}: engine CPU median {ec['median']:.2f} ms, p95 {ec['p95']:.2f} ms", file=sys.stderr)
    print(table(["scene (one run)", "engine CPU ms median", "p95", "app step + snapshot CPU ms median", "p95",
                 "app CPU p95 / 33 ms", "engine wall ms median", "p95", "app wall ms median", "p95"], rows))
    print(f"\nafter the run: {load_note()}")


if __name__ == "__main__":
    main()
