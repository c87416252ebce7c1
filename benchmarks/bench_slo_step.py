"""Engine step cost of SLO (Mai thesis): one generation of SLO-PSO on Sphere with Low error,
vectorised over runs × particles, for each selection method.

Run: python benchmarks/bench_slo_step.py [--metrics] [--only css]
Prints ms per generation and µs per particle-generation; with ``--metrics`` each generation
also works out every metric series (as ``shoal run`` does for metrics.csv), the best of 3 repeats.
"""

from __future__ import annotations

import argparse
import time

from shoal.engine.kinds.slo_swarm import SLOSwarm


def measure(selection: str, particles: int, runs: int, steps: int = 100, metrics: bool = False) -> tuple[float, float]:
    sw = SLOSwarm(runs=runs, seed=0, particles=particles, selection=selection, errors="low")
    first = sw.step()
    if metrics:
        first.series()
    t0 = time.perf_counter()
    for _ in range(steps):
        info = sw.step()
        if metrics:
            info.series()
    elapsed = time.perf_counter() - t0
    return elapsed / steps * 1e3, elapsed / (steps * particles * runs) * 1e6


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--metrics", action="store_true", help="every metric series each generation")
    ap.add_argument("--only", nargs="*", default=["css", "rts", "akcan"], help="selections to measure")
    args = ap.parse_args()
    print(f"{'selection':>9} {'particles':>9} {'runs':>5} {'ms/gen':>8} {'µs/particle-gen':>16}")
    for selection in args.only:
        for particles, runs in [(20, 1), (20, 31), (50, 1), (50, 10)]:
            repeats = 3 if args.metrics else 1
            ms, us = min(measure(selection, particles, runs, metrics=args.metrics) for _ in range(repeats))
            print(f"{selection:>9} {particles:>9} {runs:>5} {ms:>8.2f} {us:>16.1f}")


if __name__ == "__main__":
    main()
