"""The speed targets of the compiled kernels, before and after, side by side in one run.

Run: python benchmarks/bench_speed.py --before PYTHON [--quick]

PYTHON is the interpreter of an environment where the previous release of Shoal is installed
(e.g. a checkout of the release before the kernels, ``pip install -e .`` into its own venv).
Every measure runs in this interpreter ("after") and, in a subprocess, in that one ("before"),
with the same code (this file), so both sides do the same work; the anchors run here:
pyswarms 1.3 (``pip install -e '.[bench]'``) for standard PSO. VMAS needs PyTorch, which is
not installed on these machines: its batched cost is quoted from issue 13 (20–31 µs a
robot-step on the same machine kind).

Times are this thread's CPU time (robust while other jobs share the machine), median per tick:
- fleet: Chapter 4 omni DVC, sequential update, kinematic, on the 80 m × 40 m course with the
  robots packed in a 14 m square (the slowest phase; ``bench_fleet_step.py``); 1000 robots in
  a 2√N m square of a course 10 m wider (``bench_scaling.py``); batched: 100 runs of 10 robots;
  physics: 200 robots (mecanum, pymunk);
- standard PSO [2.1]/[2.2] with a global best, D = 10, 30 particles, Sphere
  (``bench_pso_compare.py`` part b): one seed per call, and 20 seeds in one call;
- SLO-PSO on Sphere, Low errors, CSS, knn 5, 20 particles × 31 runs: one generation, and one
  generation plus the six series a reproduction keeps (before: every metric, always).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, table  # noqa: E402

VMAS_US = "20–31"  # µs per robot-step, batched, quoted from issue 13


def _first(*paths: str) -> Any:
    """The first importable of ``module:name`` paths (the engine moved between releases)."""
    from importlib import import_module

    for path in paths:
        module, name = path.split(":")
        try:
            return getattr(import_module(module), name)
        except (ImportError, AttributeError):
            continue
    raise ImportError(f"none of {paths}")


def _median_ms(step: Callable[[], object], ticks: int, warmup: int = 1) -> float:
    for _ in range(warmup):
        step()
    times = []
    for _ in range(ticks):
        t0 = time.thread_time()
        step()
        times.append((time.thread_time() - t0) * 1e3)
    times.sort()
    return times[len(times) // 2]


def _fleet(robots: int, runs: int, packed: bool, **params: Any):
    Fleet = _first("shoal.engine.kinds.fleet:Fleet", "shoal.engine.fleet:Fleet")
    FleetParams = _first("shoal.engine.kinds.fleet:FleetParams", "shoal.engine.fleet:FleetParams")
    course = _first("shoal.engine.robots.world:obstacle_course", "shoal.engine.world:obstacle_course")
    if packed:  # bench_fleet_step.py
        world = course(seed=0, length=80.0, width=40.0, start_size=14.0)
    else:  # bench_scaling.py: the same density at every size
        side = round(2.0 * math.sqrt(robots), 1)
        world = course(seed=0, length=max(60.0, 2 * side + 30), width=side + 10, start_size=side)
    return Fleet(world=world, robots=robots, params=FleetParams(**params), runs=runs, seed=0)


def _pso(runs: int):
    import numpy as np

    Simulation = _first("shoal.engine.kinds.swarm:Simulation", "shoal.engine.sim:Simulation")
    Objective = _first("shoal.engine.core.objectives:Objective", "shoal.engine.objectives:Objective")
    Constant = _first("shoal.engine.pso.coeffs:Constant", "shoal.engine.coeffs:Constant")
    Law = _first("shoal.engine.pso.laws:Law", "shoal.engine.laws:Law")
    return Simulation(robots=30, d=10, dt=1.0, law=Law("standard"), policy=Constant(0.7298, (1.49618, 1.49618)),
                      objective=Objective("sphere", source=np.zeros(10)), runs=runs, seed=0,
                      init_center=np.zeros(10), init_spread=10.24, init_speed=0.0)


def _slo():
    SLOSwarm = _first("shoal.engine.kinds.slo_swarm:SLOSwarm", "shoal.engine.slo:SLOSwarm")
    return SLOSwarm(runs=31, seed=0, particles=20, selection="css", errors="low")


KEPT = ("e_abs_mean", "e_rel_median", "distance_median", "best_fitness", "quality_met_at", "dead_reckoning")


def measure(quick: bool, before: bool) -> dict[str, float]:
    """Every measure (ms per tick) in this interpreter; ``before`` spends fewer ticks on the slow ones."""
    few = 3 if quick else (5 if before else 30)
    out: dict[str, float] = {}

    def note(name: str, value: float) -> None:
        out[name] = value
        print(f"  {'before' if before else 'after'}: {name} {value:.4g} ms", file=sys.stderr, flush=True)

    f = _fleet(100, 1, packed=True)
    note("fleet_100", _median_ms(f.step, 10 if before else 200))
    f = _fleet(10, 100, packed=False)
    note("fleet_batched", _median_ms(f.step, few))
    f = _fleet(200, 1, packed=False, motion="physics", drive="mecanum")
    note("physics_200", _median_ms(f.step, few))
    f = _fleet(1000, 1, packed=False)
    note("fleet_1000", _median_ms(f.step, few))
    sw = _slo()
    note("slo", _median_ms(sw.step, 30 if quick else 100, warmup=3))
    sw = _slo()
    if hasattr(sw.step(), "series"):  # since the kernels: only the series asked for are worked out
        def kept() -> object:
            return sw.step().series(KEPT)
    else:  # the previous release worked out every metric in each step, columns() flattened them
        def kept() -> object:
            return sw.step().columns()
    note("slo_kept", _median_ms(kept, 30 if quick else 100, warmup=3))
    iters = 200 if quick else 1000
    for runs, name in ((1, "pso_one"), (20, "pso_20")):
        sim = _pso(runs)
        sim.step()
        t0 = time.thread_time()
        for _ in range(iters):
            sim.step()
        note(name, (time.thread_time() - t0) * 1e3 / iters)
    return out


def pyswarms_ms(quick: bool) -> float | None:
    """ms per iteration of pyswarms' GlobalBestPSO on the same problem, or None if missing."""
    try:
        import pyswarms  # noqa: F401
    except ImportError:
        return None
    from bench_pso_compare import pyswarms_standard

    sim = _pso(1)
    x0 = sim.state.x[0].copy()
    iters = 200 if quick else 1000
    pyswarms_standard("sphere", 10, x0, 50, 0)  # warm-up
    return pyswarms_standard("sphere", 10, x0, iters, 0)[1] * 1e3 / iters


def run_before(python: str, quick: bool) -> dict[str, float]:
    cmd = [python, str(Path(__file__).resolve()), "--child"] + (["--quick"] if quick else [])
    done = subprocess.run(cmd, capture_output=True, text=True)
    sys.stderr.write(done.stderr)
    if done.returncode:
        raise SystemExit(f"the previous release failed to measure (exit {done.returncode})")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", help="python of an environment with the previous release installed")
    ap.add_argument("--quick", action="store_true", help="fewer ticks")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:  # measuring for the parent, in the other release
        print(json.dumps(measure(args.quick, before=True)))
        return
    print(f"{load_note()}\n", flush=True)
    after = measure(args.quick, before=False)
    before = run_before(args.before, args.quick) if args.before else {}
    anchor = pyswarms_ms(args.quick)

    def row(label: str, key: str, unit: str, scale: float, target: str) -> list[str]:
        b, a = before.get(key, math.nan), after[key]
        return [label, fmt(b * scale) + unit, fmt(a * scale) + unit, f"{b / a:.1f}×" if b == b else "–", target]

    rows = [
        row("fleet tick, 100 robots, omni DVC, sequential, kinematic", "fleet_100", " ms", 1, "≤ 1 ms"),
        row("fleet tick, 1000 robots (same density)", "fleet_1000", " ms", 1, "≤ 15 ms"),
        row("batched fleets, 100 runs × 10 robots, per robot-step", "fleet_batched", " µs", 1e3 / 1000,
            f"≤ 5 µs (VMAS {VMAS_US} µs, quoted)"),
        row("fleet tick, 200 robots, pymunk physics (mecanum)", "physics_200", " ms", 1, "20 updates/s in the app"),
        row("SLO generation, 20 particles × 31 runs", "slo", " ms", 1, "≥ 4× faster"),
        row("SLO generation + the six kept series", "slo_kept", " ms", 1, "≥ 4× faster"),
        row("standard PSO, D = 10, 30 particles, one seed, per iteration", "pso_one", " µs", 1e3,
            "≥ 3× pyswarms"),
        row("standard PSO, 20 seeds in one call, per iteration and seed", "pso_20", " µs", 1e3 / 20,
            "≥ 10× pyswarms"),
    ]
    print(table(["measure (CPU, median)", "before", "after", "ratio", "target"], rows, "lrrrl"))
    if anchor is not None:
        print(f"\npyswarms GlobalBestPSO, same problem: {fmt(anchor * 1e3)} µs per iteration; after/pyswarms: "
              f"one seed {anchor / after['pso_one']:.1f}× faster, 20 seeds batched "
              f"{anchor / (after['pso_20'] / 20):.1f}× faster per seed")
    else:
        print("\npyswarms is not installed (pip install -e '.[bench]'): no anchor for standard PSO")


if __name__ == "__main__":
    main()
