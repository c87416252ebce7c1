"""Engine step cost of Adapted PSO (Chapter 3), vectorised over runs × robots.

Run: python benchmarks/bench_ch3_step.py
Prints robot-steps per second for several swarm sizes and batch sizes.
"""

from __future__ import annotations

import time

from shoal.presets.build import build_simulation
from shoal.presets.io import load


def measure(robots: int, runs: int, steps: int = 200) -> tuple[float, float]:
    sim = build_simulation(load("default", [f"sim.robots={robots}"]), runs=runs, seed=0)
    sim.step()
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.step()
    elapsed = time.perf_counter() - t0
    return elapsed / steps * 1e3, robots * runs * steps / elapsed


def main() -> None:
    print(f"{'robots':>7} {'runs':>5} {'ms/step':>9} {'robot-steps/s':>14}")
    for robots, runs in [(10, 1), (100, 1), (1000, 1), (10, 100), (100, 100), (1000, 10)]:
        ms, rate = measure(robots, runs)
        print(f"{robots:>7} {runs:>5} {ms:>9.3f} {rate:>14,.0f}")


if __name__ == "__main__":
    main()
