"""Interactive budget on ONE core: is one tick of the scenes the browser app runs well under
one frame (33 ms at 30 fps)?

Run: python benchmarks/bench_interactive.py [--quick] [--steps 300]

For each scene (one run, as in the app): the engine tick alone, and the app's session step
(tick + history ring buffer + metrics) plus the snapshot the arena draws from. Median and
95th percentile over ``--steps`` consecutive ticks after a short warm-up, so the dense
start of the fleet and the later spread-out phase both count. BLAS/OpenMP threads are set
to 1 and the process is pinned to one CPU before numpy is imported.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, one_core, summary, table, timed  # noqa: E402

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
]


def measure(preset: str, overrides: list[str], steps: int) -> tuple[dict, dict]:
    """(engine tick, session step + snapshot) summaries in ms for ``steps`` ticks each."""
    from shoal.app.tab import session_for
    from shoal.presets.build import build
    from shoal.presets.io import load

    scenario = load(preset, overrides)
    engine = build(scenario, runs=1)
    engine_ms = timed(engine.step, steps, warmup=WARMUP)
    session = session_for(scenario)

    def app_step() -> None:
        session.step(1)
        session.snapshot()

    app_ms = timed(app_step, steps, warmup=WARMUP)
    return summary(engine_ms), summary(app_ms)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="40 ticks per case instead of --steps")
    ap.add_argument("--steps", type=int, default=300, help="timed ticks per case")
    args = ap.parse_args()
    steps = 40 if args.quick else args.steps
    print(f"one core: {one_core()}; {steps} ticks per case after {WARMUP} warm-up ticks\n")
    rows = []
    for label, preset, overrides in CASES:
        eng, app = measure(preset, overrides, steps)
        rows.append([label, fmt(eng["median"]), fmt(eng["p95"]), fmt(app["median"]), fmt(app["p95"]),
                     f"{app['p95'] / FRAME_MS:.0%}"])
        print(f"  {label}: engine median {eng['median']:.2f} ms, p95 {eng['p95']:.2f} ms", file=sys.stderr)
    print(table(["scene (one run)", "engine ms median", "engine ms p95", "app step + snapshot ms median",
                 "app p95", "app p95 / 33 ms frame"], rows))


if __name__ == "__main__":
    main()
