"""Cost of the Chapter 7–8 acoustic swarm and of the waveform-level Fig. 7-2 reproduction.

Run: python benchmarks/bench_fig7_2.py [--runs 20] [--workers 2] [--skip-ticks] [--skip-target]

1. One ``AcousticSwarm.step()`` per algorithm and controller (listen, bests, velocity, move,
   metrics) for 100 runs × 10 robots (and 20 runs × 40 robots for escorting): best and median
   ms per tick and µs per robot-step, no runs stopped.
2. ``shoal reproduce fig7-2`` with ``--runs`` runs per case (12 cases: A/X/B/XB-PSO at
   SNR0 = 10, 4, 0 dB, at most 6000 steps, converged runs stopped) on ``--workers``
   processes: wall time, robot-steps actually simulated, wall µs per robot-step, and the
   linear extrapolation to the default 100 runs per case (robot-steps scale with the runs;
   bigger batches are a little cheaper per robot-step, so it is an upper bound).

The machine may be shared: read best times as the cost and medians as a busy machine.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from shoal.engine.kinds.sonar import AcousticSwarm, SonarParams
from shoal.studies.experiments import reproduce

TICK_CASES = [
    ("A-PSO, adapted", SonarParams(algorithm="a-pso"), 100, 10),
    ("X-PSO, adapted", SonarParams(algorithm="x-pso"), 100, 10),
    ("B-PSO, adapted", SonarParams(algorithm="b-pso"), 100, 10),
    ("XB-PSO, adapted", SonarParams(algorithm="xb-pso"), 100, 10),
    ("XB-PSO, adapted, surrogate (approx.)", SonarParams(algorithm="xb-pso", mode="surrogate"), 100, 10),
    ("GT-PSO, non-omni", SonarParams(algorithm="gt-pso", controller="nonomni"), 100, 10),
    ("XB-PSO, non-omni", SonarParams(algorithm="xb-pso", controller="nonomni"), 100, 10),
    ("GT-PSO, non-omni, escort r = 50 m", SonarParams(algorithm="gt-pso", controller="nonomni", r_trap=50.0), 20, 40),
]


def tick_cost(params: SonarParams, runs: int, robots: int, ticks: int = 40) -> tuple[float, float]:
    """(best, median) ms per tick after a short warm-up."""
    sw = AcousticSwarm(params, robots=robots, runs=runs, seed=0)
    for _ in range(5):
        sw.step()
    times = []
    for _ in range(ticks):
        t0 = time.perf_counter()
        sw.step()
        times.append(time.perf_counter() - t0)
    t = np.array(times) * 1e3
    return float(t.min()), float(np.median(t))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=20, help="runs per case of the fig7-2 measurement")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--skip-ticks", action="store_true")
    ap.add_argument("--skip-target", action="store_true")
    args = ap.parse_args()
    if not args.skip_ticks:
        print(f"{'case':40s} {'runs':>5s} {'robots':>6s} {'best ms':>8s} {'median ms':>9s} {'µs/robot-step':>13s}")
        for name, p, runs, robots in TICK_CASES:
            best, med = tick_cost(p, runs, robots)
            print(f"{name:40s} {runs:5d} {robots:6d} {best:8.2f} {med:9.2f} {best * 1e3 / (runs * robots):13.2f}")
    if not args.skip_target:
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            s = reproduce("fig7-2", Path(tmp) / "out", runs=args.runs, workers=args.workers, progress=False)
            wall = time.perf_counter() - t0
        cost = s["cost"]
        scale = 100 / args.runs
        print(json.dumps({"runs_per_case": args.runs, "workers": args.workers, "wall_s": round(wall, 1),
                          "robot_steps": cost["robot_steps"], "wall_us_per_robot_step": cost["wall_us_per_robot_step"],
                          "extrapolated_100_runs_wall_s": round(wall * scale, 0),
                          "extrapolated_100_runs_min": round(wall * scale / 60, 1)}, indent=1))


if __name__ == "__main__":
    main()
