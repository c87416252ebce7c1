"""Measured against estimated: the CPU of one tick of every kind, and of laying out a world,
beside what ``shoal.studies.cost`` prices them at; ``--fit`` also fits the constants.

Run: python benchmarks/bench_costs.py [--fit] [--quick]

Each case builds one run of a shipped preset with overrides and times ticks on this thread's
CPU clock (``time.thread_time``: what a tick costs on a core of its own, even on a busy
machine), after one untimed tick (numba kernels compile on first use; run ``shoal warmup``
first). The terms that scale the work: robots, ``sim.d`` (Chapter 3), ordered pairs of robots
(SLO), obstacles (fleet), band bins × lags searched or the full-lag FFT (waveform acoustics),
and the trees a forest lays out. ``--fit`` solves, kind by kind, for non-negative constants
that minimise the squared *relative* error over its cases (``scipy.optimize.nnls``), so that a
small case counts as much as a large one.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
from bench_common import load_note, one_core

# (kind in TICK_COSTS, preset, overrides, ticks timed)
TICKS: list[tuple[str, str, list[str], int]] = [
    ("swarm", "default", ["sim.robots=100"], 40),
    ("swarm", "default", ["sim.robots=2000"], 40),
    ("swarm", "default", ["sim.robots=2000", "sim.d=10"], 20),
    ("swarm", "default", ["sim.robots=500", "sim.d=100"], 10),
    ("swarm", "default", ["sim.robots=2000", "sim.d=100"], 10),
    ("swarm", "default", ["sim.robots=200", "sim.d=1000"], 5),
    ("swarm", "default", ["sim.robots=2000", "sim.d=1000"], 3),
    ("slo_swarm", "slo-walk", ["sim.robots=25"], 10),
    ("slo_swarm", "slo-walk", ["sim.robots=100"], 5),
    ("fleet", "course-dvc", ["sim.robots=10"], 40),
    ("fleet", "course-dvc", ["sim.robots=100"], 20),
    ("fleet", "course-dvc", ["sim.robots=1000", "world.length=160", "world.width=73.2", "world.start_size=63.2"], 10),
    ("fleet", "forest-dvc", ["sim.robots=10", "world.width=1000", "world.density=0.5"], 20),
    ("fleet", "forest-dvc", ["sim.robots=10", "world.width=200", "world.density=0.2"], 20),
    ("fleet/physics", "course-physics", ["sim.robots=20"], 10),
    ("fleet/physics", "course-physics", ["sim.robots=200", "world.length=90", "world.width=38.3",
                                         "world.start_size=28.3"], 5),
    ("sonar", "sonar-xb-pso", ["sim.robots=20"], 20),
    ("sonar", "sonar-xb-pso", ["sim.robots=100"], 10),
    ("sonar", "sonar-xb-pso", ["sim.robots=20", "acoustics.tbp=1000"], 10),
    ("sonar", "sonar-xb-pso", ["sim.robots=100", "acoustics.tbp=5000"], 3),
    ("sonar", "sonar-xb-pso", ["sim.robots=100", "acoustics.fs=1000000"], 5),
    ("sonar", "sonar-xb-pso", ["sim.robots=20", "acoustics.fs=1000000", "acoustics.full_lag=true"], 3),
    ("sonar", "sonar-xb-pso", ["sim.robots=100", "acoustics.fs=1000000", "acoustics.full_lag=true"], 2),
    ("sonar", "sonar-gt-pso", ["sim.robots=40"], 10),
    ("sonar/surrogate", "sonar-xb-pso", ["sim.robots=20", "acoustics.mode=surrogate"], 20),
    ("sonar/surrogate", "sonar-xb-pso", ["sim.robots=100", "acoustics.mode=surrogate"], 20),
    ("swarm+slo", "slo-adapted", ["sim.robots=25"], 10),
    ("swarm+slo", "slo-adapted", ["sim.robots=100"], 5),
]
# The terms each kind's constants are fitted on (the others are 0 for it, or collinear: a
# fleet's robot_dim is 2 × robot); "swarm+slo" fits the pairs a swarm on SLO positions adds.
FITTED = {"swarm": ["run", "robot", "robot_dim"], "slo_swarm": ["run", "robot", "pair"],
          "fleet": ["run", "robot", "obstacle"], "fleet/physics": ["run", "robot", "obstacle"],
          "sonar": ["run", "robot", "bin", "bin_lag", "fft"], "sonar/surrogate": ["run", "robot"],
          "swarm+slo": ["run", "robot", "pair"]}
QUICK = {0, 1, 4, 6, 7, 10, 12, 14, 16, 17, 21, 24, 26}

# (preset, overrides) of worlds laid out
WORLDS: list[tuple[str, list[str]]] = [
    ("forest-dvc", []),
    ("forest-dvc", ["world.width=80", "world.density=0.2"]),
    ("forest-dvc", ["world.width=200", "world.density=0.2"]),
    ("forest-dvc", ["world.width=400", "world.density=0.3"]),
    ("forest-dvc", ["world.width=1000", "world.density=0.5"]),
    ("course-dvc", ["world.layers=30", "world.length=1000", "world.width=1000", "world.start_size=20"]),
]


def tick_seconds(scenario: Any, ticks: int) -> float:
    from shoal.presets.build import build

    engine = build(scenario, runs=1)
    engine.step()  # (compiles what has not been compiled yet)
    t0 = time.thread_time()
    for _ in range(ticks):
        engine.step()
    return (time.thread_time() - t0) / ticks


def world_seconds(scenario: Any) -> tuple[float, int]:
    from shoal.presets.build import world_for

    t0 = time.thread_time()
    world = world_for(scenario.world)
    return time.thread_time() - t0, len(world.circles)


def fit(rows: list[tuple[dict[str, float], float]], names: list[str]) -> dict[str, float]:
    """Non-negative constants of ``names`` minimising the squared relative error."""
    from scipy.optimize import nnls

    a = np.array([[q.get(n, 0.0) / m for n in names] for q, m in rows])
    keep = [j for j in range(len(names)) if np.any(a[:, j] > 0)]
    x, _ = nnls(a[:, keep], np.ones(len(rows)))
    out = dict.fromkeys(names, 0.0)
    out.update({names[j]: float(v) for j, v in zip(keep, x)})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--fit", action="store_true", help="fit the constants of every kind to these cases")
    ap.add_argument("--quick", action="store_true", help="a subset of the cases")
    args = ap.parse_args()
    print(f"one core: {one_core()}; {load_note()}\n")

    from shoal.presets.io import load
    from shoal.studies.cost import quantities, tick_cost, variant, world_cost

    print("| kind | preset, overrides | measured ms/tick | estimated ms/tick | estimated / measured |")
    print("|---|---|---:|---:|---:|")
    by_kind: dict[str, list[tuple[dict[str, float], float]]] = {}
    for i, (kind, preset, sets, ticks) in enumerate(TICKS):
        if args.quick and i not in QUICK:
            continue
        sc = load(preset, sets)
        measured = tick_seconds(sc, ticks)
        estimated = tick_cost(sc)
        key = variant(sc)
        by_kind.setdefault(kind, []).append((quantities(sc), measured))
        print(f"| {key} | {preset} {' '.join(sets)} | {measured * 1e3:,.3f} | {estimated * 1e3:,.3f} | "
              f"{estimated / measured:.2f} |", flush=True)

    print("\n| world | overrides | obstacles | measured CPU s | estimated CPU s | estimated / measured |")
    print("|---|---|---:|---:|---:|---:|")
    worlds: list[tuple[dict[str, float], float]] = []
    for preset, sets in WORLDS:
        sc = load(preset, sets)
        measured, count = world_seconds(sc)
        estimated = world_cost(sc)
        worlds.append(({"trees": _trees(sc), "world": 1.0}, measured))
        print(f"| {preset} | {' '.join(sets)} | {count:,} | {measured:.3f} | {estimated:.3f} | "
              f"{estimated / measured if measured > 0 else float('nan'):.2f} |", flush=True)

    if args.fit:
        print("\nfitted constants (CPU s; relative least squares):")
        for key, rows in by_kind.items():
            found = fit(rows, FITTED[key])
            print(f"  {key}: " + ", ".join(f"{t}={found[t]:.3g}" for t in FITTED[key]))
        found = fit(worlds, ["world", "trees"])
        print(f"  world: WORLD_SECONDS={found['world']:.3g}, TREE_SECONDS={found['trees']:.3g}")


def _trees(scenario: Any) -> float:
    from shoal.studies.cost import forest_trees

    return forest_trees(scenario)


if __name__ == "__main__":
    main()
