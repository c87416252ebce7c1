"""Cost of one Chapter 4–5 fleet tick: sensing (pymunk queries), DVC, velocity, motion.

Run: python benchmarks/bench_fleet_step.py
"""

from __future__ import annotations

import time

from shoal.engine.kinds.fleet import Fleet, FleetParams
from shoal.engine.robots.world import obstacle_course


def measure(robots: int, runs: int, params: FleetParams, steps: int = 30) -> float:
    world = obstacle_course(seed=0, length=80.0, width=40.0, start_size=14.0)
    fleet = Fleet(world=world, robots=robots, params=params, runs=runs, seed=0)
    fleet.step()
    t0 = time.perf_counter()
    for _ in range(steps):
        fleet.step()
    return (time.perf_counter() - t0) / steps * 1e3


def main() -> None:
    cases = {
        "omni DVC, kinematic, sequential": FleetParams(),
        "omni DVC, kinematic, simultaneous": FleetParams(update="simultaneous"),
        "omni DVC, physics (mecanum)": FleetParams(motion="physics", drive="mecanum"),
        "non-omni DVC, kinematic, sequential": FleetParams(law="nonomni", drive="differential", guard=True),
    }
    print(f"{'case':40s} {'robots':>6} {'runs':>5} {'ms/step':>9} {'µs/robot-step':>14}")
    for name, p in cases.items():
        for robots, runs in [(6, 1), (100, 1), (6, 100)]:
            ms = measure(robots, runs, p)
            print(f"{name:40s} {robots:>6} {runs:>5} {ms:>9.2f} {ms * 1e3 / (robots * runs):>14.1f}")


if __name__ == "__main__":
    main()
