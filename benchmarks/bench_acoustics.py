"""Cost of the waveform-level acoustics per control step: band synthesis + two-hydrophone
receiver, vectorised over runs × robots × hydrophones.

Run: python benchmarks/bench_acoustics.py
Prints the best and median wall time per step (ms) and per robot-step (µs) for a few
batch sizes and bands, and the same for the APPROXIMATE surrogate mode. The machine may be
shared: read the best time as the cost and the median as what a busy machine gives.
"""

from __future__ import annotations

import time

import numpy as np

from shoal.engine.acoustics.band import Band
from shoal.engine.acoustics.receiver import bearing
from shoal.engine.acoustics.signals import hydrophone_positions, synthesise
from shoal.engine.acoustics.surrogate import surrogate


def measure(runs: int, robots: int, band: Band, full_lag: bool = False, reps: int = 30) -> tuple[float, float, float]:
    """(best, median) ms per step of synthesise + bearing, and the synthesis share of the best."""
    D = band.lam_c / 2
    rng = np.random.default_rng(0)
    rngs = [np.random.default_rng([0, i]) for i in range(runs)]
    x = rng.uniform(-50, 50, (runs, robots, 2))
    o = rng.uniform(-np.pi, np.pi, (runs, robots))
    src = rng.uniform(-400, 400, (runs, 2))
    pos = hydrophone_positions(x, o, D)
    total, synth = [], []
    for _ in range(reps + 1):
        t0 = time.perf_counter()
        sp = synthesise(rngs, pos, src, band, 1000.0)
        t1 = time.perf_counter()
        bearing(sp, band, D, o, full_lag=full_lag)
        t2 = time.perf_counter()
        total.append(t2 - t0)
        synth.append(t1 - t0)
    total, synth = np.array(total[1:]) * 1e3, np.array(synth[1:]) * 1e3
    return float(total.min()), float(np.median(total)), float(synth.min() / total.min())


def measure_surrogate(runs: int, robots: int, band: Band, reps: int = 30) -> tuple[float, float]:
    """(best, median) ms per step of the APPROXIMATE surrogate (intensity + bearing)."""
    D = band.lam_c / 2
    rng = np.random.default_rng(0)
    rngs = [np.random.default_rng([0, i]) for i in range(runs)]
    o = rng.uniform(-np.pi, np.pi, (runs, robots))
    pos = hydrophone_positions(rng.uniform(-50, 50, (runs, robots, 2)), o, D)
    src = rng.uniform(-400, 400, (runs, 2))
    times = []
    for _ in range(reps + 1):
        t0 = time.perf_counter()
        surrogate(rngs, pos, src, band, 1000.0, heading=o, D=D)
        times.append(time.perf_counter() - t0)
    times = np.array(times[1:]) * 1e3
    return float(times.min()), float(np.median(times))


def main() -> None:
    cases = [
        ("default Q=1.5 TBP=100", 100, 10, Band(), False),
        ("default Q=1.5 TBP=100", 1, 10, Band(), False),
        ("default Q=1.5 TBP=100", 1000, 10, Band(), False),
        ("narrow Q=20 D=λ/2", 100, 10, Band(Q=20), False),
        ("full-lag search", 100, 10, Band(), True),
        ("full-lag search", 1, 10, Band(), True),
    ]
    print(f"{'case':<24} {'runs':>5} {'robots':>6} {'K':>4} {'best ms':>8} {'median ms':>9} "
          f"{'µs/robot-step':>13} {'synth %':>7}")
    for name, runs, robots, band, full in cases:
        best, med, share = measure(runs, robots, band, full, reps=10 if full or runs > 100 else 30)
        per = best * 1e3 / (runs * robots)
        print(f"{name:<24} {runs:>5} {robots:>6} {band.K:>4} {best:>8.2f} {med:>9.2f} {per:>13.2f} {100 * share:>7.0f}")
    for runs in (100, 1000):
        best, med = measure_surrogate(runs, 10, Band())
        print(f"{'surrogate (approximate)':<24} {runs:>5} {10:>6} {Band().K:>4} {best:>8.2f} {med:>9.2f} "
              f"{best * 1e3 / (runs * 10):>13.2f} {'-':>7}")


if __name__ == "__main__":
    main()
