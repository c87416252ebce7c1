"""Engine step cost of SLO (Mai thesis): one generation of SLO-PSO on Sphere with Low error,
vectorised over runs × particles, for each selection method.

Run: python benchmarks/bench_slo_step.py
Prints ms per generation and µs per particle-generation.
"""

from __future__ import annotations

import time

from shoal.engine.kinds.slo_swarm import SLOSwarm


def measure(selection: str, particles: int, runs: int, steps: int = 100) -> tuple[float, float]:
    sw = SLOSwarm(runs=runs, seed=0, particles=particles, selection=selection, errors="low")
    sw.step()
    t0 = time.perf_counter()
    for _ in range(steps):
        sw.step()
    elapsed = time.perf_counter() - t0
    return elapsed / steps * 1e3, elapsed / (steps * particles * runs) * 1e6


def main() -> None:
    print(f"{'selection':>9} {'particles':>9} {'runs':>5} {'ms/gen':>8} {'µs/particle-gen':>16}")
    for selection in ("css", "rts", "akcan"):
        for particles, runs in [(20, 1), (20, 31), (50, 1), (50, 10)]:
            ms, us = measure(selection, particles, runs)
            print(f"{selection:>9} {particles:>9} {runs:>5} {ms:>8.2f} {us:>16.1f}")


if __name__ == "__main__":
    main()
