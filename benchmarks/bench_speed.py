"""The speed targets of the compiled kernels, before and after, side by side in one run.

Run: python benchmarks/bench_speed.py --before PYTHON [--first PYTHON] [--quick]

PYTHON is the interpreter of an environment where the previous release of Shoal is installed
(e.g. a checkout of the release before the kernels, ``pip install -e .`` into its own venv).
Every measure runs in this interpreter ("after") and, in a subprocess each, in those ones
("before", "first" pass), with the same code (this file), so every side does the same work;
measure by measure, the releases take turns (``--reps`` rounds, median), so a load that
drifts while the script runs touches them alike; the anchors run here, between rounds:
pyswarms 1.3 (``pip install -e '.[bench]'``) for standard PSO. VMAS needs PyTorch, which is
not installed on these machines: its batched cost is quoted from issue 13 (20–31 µs a
robot-step on the same machine kind).

Times are this thread's CPU time (robust while other jobs share the machine), median per tick:
- fleet: Chapter 4 omni DVC, sequential update, kinematic, on the 80 m × 40 m course with the
  robots packed in a 14 m square (the slowest phase; ``bench_fleet_step.py``); 1000 robots in
  a 2√N m square of a course 10 m wider (``bench_scaling.py``); batched: 100 runs of 10 robots;
  physics: 200 robots (mecanum, pymunk), and fig4-6's physics batches: 25 runs of 6 robots
  (Adapted RPSO + DVC, mecanum) on the default course, per run and tick;
- standard PSO [2.1]/[2.2] with a global best, D = 10, 30 particles, Sphere
  (``bench_pso_compare.py`` part b): one seed per call, and 20 seeds in one call;
- SLO-PSO on Sphere, Low errors, CSS, knn 5, 20 particles × 31 runs: one generation, and one
  generation plus the six series a reproduction keeps (before: every metric, always); the same
  with the RTS and the Akcan selections;
- the acoustic swarm (``sonar-xb-pso``, waveform mode, each release's own preset): one run (the
  interactive case), and 5, 20 and 100 runs batched.
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


def _physics_batch():
    """fig4-6's physics chunks: 25 runs of 6 robots on the default course, mecanum, DVC."""
    Fleet = _first("shoal.engine.kinds.fleet:Fleet", "shoal.engine.fleet:Fleet")
    FleetParams = _first("shoal.engine.kinds.fleet:FleetParams", "shoal.engine.fleet:FleetParams")
    course = _first("shoal.engine.robots.world:obstacle_course", "shoal.engine.world:obstacle_course")
    return Fleet(world=course(seed=0), robots=6, params=FleetParams(motion="physics", drive="mecanum"), runs=25,
                 seed=0)


def _pso(runs: int):
    import numpy as np

    Simulation = _first("shoal.engine.kinds.swarm:Simulation", "shoal.engine.sim:Simulation")
    Objective = _first("shoal.engine.core.objectives:Objective", "shoal.engine.objectives:Objective")
    Constant = _first("shoal.engine.pso.coeffs:Constant", "shoal.engine.coeffs:Constant")
    Law = _first("shoal.engine.pso.laws:Law", "shoal.engine.laws:Law")
    return Simulation(robots=30, d=10, dt=1.0, law=Law("standard"), policy=Constant(0.7298, (1.49618, 1.49618)),
                      objective=Objective("sphere", source=np.zeros(10)), runs=runs, seed=0,
                      init_center=np.zeros(10), init_spread=10.24, init_speed=0.0)


def _slo(selection: str = "css"):
    SLOSwarm = _first("shoal.engine.kinds.slo_swarm:SLOSwarm", "shoal.engine.slo:SLOSwarm")
    return SLOSwarm(runs=31, seed=0, particles=20, selection=selection, errors="low")


KEPT = ("e_abs_mean", "e_rel_median", "distance_median", "best_fitness", "quality_met_at", "dead_reckoning")


def _kept(sw: Any) -> Callable[[], object]:
    """A generation plus the kept series (the previous release worked out every metric in each
    step, and columns() flattened them)."""
    if hasattr(sw.step(), "series"):
        return lambda: sw.step().series(KEPT)
    return lambda: sw.step().columns()


def _pso_ms(runs: int, iters: int, headless: bool) -> float:
    sim = _pso(runs)
    sim.step()
    if headless:  # since the second pass: a headless run loop
        if not hasattr(sim, "run"):
            return math.nan
        sim.run(10)
        t0 = time.thread_time()
        sim.run(iters)
    else:
        t0 = time.thread_time()
        for _ in range(iters):
            sim.step()
    return (time.thread_time() - t0) * 1e3 / iters


def _sonar(runs: int, *overrides: str):
    build_sonar, load = _first("shoal.presets.build:build_sonar"), _first("shoal.presets.io:load")
    return build_sonar(load("sonar-xb-pso", list(overrides)), runs=runs, seed=0)


def measures(quick: bool, slow: bool) -> dict[str, Callable[[], float]]:
    """Every measure (ms per tick) by name; ``slow`` (a release without the kernels) spends
    fewer ticks on the fleets."""
    few = 3 if quick else (5 if slow else 30)
    iters = 200 if quick else 1000
    return {
        "fleet_100": lambda: _median_ms(_fleet(100, 1, packed=True).step, 10 if slow else 200),
        "fleet_batched": lambda: _median_ms(_fleet(10, 100, packed=False).step, few),
        "physics_200": lambda: _median_ms(_fleet(200, 1, packed=False, motion="physics", drive="mecanum").step, few),
        "physics_batched": lambda: _median_ms(_physics_batch().step, 5 if quick else 20, warmup=5),
        "fleet_1000": lambda: _median_ms(_fleet(1000, 1, packed=False).step, few),
        "slo": lambda: _median_ms(_slo().step, 30 if quick else 100, warmup=3),
        "slo_kept": lambda: _median_ms(_kept(_slo()), 30 if quick else 100, warmup=3),
        "slo_rts_kept": lambda: _median_ms(_kept(_slo("rts")), 10 if quick else 40, warmup=3),
        "slo_akcan_kept": lambda: _median_ms(_kept(_slo("akcan")), 10 if quick else 40, warmup=3),
        **{f"sonar_{runs}": (lambda runs=runs: _median_ms(_sonar(runs).step, 20 if quick or runs == 100 else 60,
                                                          warmup=2)) for runs in (1, 5, 20, 100)},
        "sonar_1_48k": lambda: _median_ms(_sonar(1, "acoustics.fs=48000").step, 50 if quick else 300, warmup=2),
        "pso_one": lambda: _pso_ms(1, iters, False),
        "pso_one_run": lambda: _pso_ms(1, iters, True),
        "pso_20": lambda: _pso_ms(20, iters, False),
        "pso_20_run": lambda: _pso_ms(20, iters, True),
    }


def serve(quick: bool) -> None:
    """Measure the names read from stdin, one a line, answering each with a JSON number."""
    try:
        _first("shoal.engine.core.compiled:kernel")
        slow = False
    except ImportError:  # a release without the kernels
        slow = True
    table_ = measures(quick, slow)
    for line in sys.stdin:
        print(json.dumps(table_[line.strip()]()), flush=True)


class Side:
    """Another release measuring in its own interpreter, a measure at a time (``--serve``)."""

    def __init__(self, python: str, quick: bool) -> None:
        cmd = [python, str(Path(__file__).resolve()), "--serve"] + (["--quick"] if quick else [])
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def __call__(self, name: str) -> float:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(name + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise SystemExit(f"the {name} measure failed in another release")
        return float(json.loads(line))

    def close(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        self.proc.wait()


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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", help="python of an environment with the previous release installed")
    ap.add_argument("--first", help="python of an environment with the first pass of the kernels installed")
    ap.add_argument("--quick", action="store_true", help="fewer ticks")
    ap.add_argument("--reps", type=int, default=3, help="rounds of each measure in every release (median)")
    ap.add_argument("--only", nargs="*", help="measure only these names (default: all)")
    ap.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.serve:  # measuring for the parent, in another release
        serve(args.quick)
        return
    print(f"{load_note()}\n", flush=True)
    here = measures(args.quick, slow=False)
    sides: dict[str, Callable[[str], float]] = {"after": lambda name: here[name]()}
    for label, python in (("first", args.first), ("before", args.before)):
        if python:
            sides[label] = Side(python, args.quick)
    anchor: list[float] = []
    results: dict[str, dict[str, list[float]]] = {label: {} for label in sides}
    for name in args.only or here:  # measure by measure, the releases in turn, so they share the load
        for rep in range(args.reps):
            order = list(sides)[rep % len(sides):] + list(sides)[:rep % len(sides)]
            for label in order:
                value = sides[label](name)
                results[label].setdefault(name, []).append(value)
                print(f"  {label}: {name} {value:.4g} ms ({load_note()})", file=sys.stderr, flush=True)
            if name.startswith("pso_one") and (ms := pyswarms_ms(args.quick)) is not None:
                anchor.append(ms)
    for side in sides.values():
        if isinstance(side, Side):
            side.close()
    med = {label: {k: sorted(v)[len(v) // 2] for k, v in r.items()} for label, r in results.items()}
    after, first, before = med["after"], med.get("first", {}), med.get("before", {})
    print(f"\n{load_note()}\n", flush=True)

    def row(label: str, key: str, unit: str, scale: float, target: str, was: str | None = None) -> list[str]:
        b, f, a = before.get(was or key, math.nan), first.get(was or key, math.nan), after.get(key, math.nan)
        return [label, fmt(b * scale) + unit, fmt(f * scale) + unit, fmt(a * scale) + unit,
                f"{b / a:.1f}×" if b == b else "–", f"{f / a:.1f}×" if f == f else "–", target]

    rows = [
        row("fleet tick, 100 robots, omni DVC, sequential, kinematic", "fleet_100", " ms", 1, "≤ 1 ms"),
        row("fleet tick, 1000 robots (same density)", "fleet_1000", " ms", 1, "≤ 15 ms"),
        row("batched fleets, 100 runs × 10 robots, per robot-step", "fleet_batched", " µs", 1e3 / 1000,
            f"≤ 5 µs (VMAS {VMAS_US} µs, quoted)"),
        row("fleet tick, 200 robots, pymunk physics (mecanum)", "physics_200", " ms", 1, "20 updates/s in the app"),
        row("physics fleets, 25 runs × 6 robots (fig4-6's batches), per run-tick", "physics_batched", " µs", 1e3 / 25,
            "fig4-6 ≤ 60 s"),
        row("SLO generation, 20 particles × 31 runs", "slo", " ms", 1, "≥ 4× faster"),
        row("SLO generation + the six kept series", "slo_kept", " ms", 1, "≥ 4× faster"),
        row("SLO generation + kept series, RTS selection", "slo_rts_kept", " ms", 1, "(slo-pso)"),
        row("SLO generation + kept series, Akcan selection", "slo_akcan_kept", " ms", 1, "(slo-pso)"),
        row("standard PSO, D = 10, 30 particles, one seed, per iteration (step)", "pso_one", " µs", 1e3,
            "≥ 3× pyswarms"),
        row("standard PSO, one seed, per iteration (`run`; before: step)", "pso_one_run", " µs", 1e3,
            "≥ 3× pyswarms", was="pso_one"),
        row("standard PSO, 20 seeds in one call, per iteration and seed (step)", "pso_20", " µs", 1e3 / 20,
            "≥ 10× pyswarms"),
        row("standard PSO, 20 seeds, per iteration and seed (`run`; before: step)", "pso_20_run", " µs", 1e3 / 20,
            "≥ 10× pyswarms", was="pso_20"),
        row("acoustic swarm (`sonar-xb-pso`, 10 robots, waveform), one run, per tick", "sonar_1", " ms", 1,
            "lag table cached"),
        row("acoustic swarm, one run, fs = 48 kHz (51 lags, not 7), per tick", "sonar_1_48k", " ms", 1,
            "lag table cached"),
        row("acoustic swarm, 5 runs batched, per robot-step", "sonar_5", " µs", 1e3 / 50, "(5 runs a batch)"),
        row("acoustic swarm, 20 runs batched, per robot-step", "sonar_20", " µs", 1e3 / 200, "(20 runs a batch)"),
        row("acoustic swarm, 100 runs batched, per robot-step", "sonar_100", " µs", 1e3 / 1000,
            "(fig7-2's batches now)"),
    ]
    rows = [r for r in rows if r[3] != "– ms" and r[3] != "– µs"]  # measured in this run
    print(table(["measure (CPU, median)", "before", "first pass", "after", "after/before", "after/first", "target"],
                rows, "lrrrrrl"))
    if anchor and all(k in after for k in ("pso_one", "pso_one_run", "pso_20", "pso_20_run")):
        p = sorted(anchor)[len(anchor) // 2]
        print(f"\npyswarms GlobalBestPSO, same problem, measured between Shoal's PSO measures: {fmt(p * 1e3)} µs "
              f"per iteration (median of {len(anchor)}); Shoal is faster by: one seed {p / after['pso_one']:.1f}× "
              f"(step), {p / after['pso_one_run']:.1f}× (run); 20 seeds batched, per seed "
              f"{p / (after['pso_20'] / 20):.1f}× (step), {p / (after['pso_20_run'] / 20):.1f}× (run)"
              + (f"; first pass: one seed {p / first['pso_one']:.1f}×, 20 seeds {p / (first['pso_20'] / 20):.1f}×"
                 if first else ""))
    else:
        print("\npyswarms is not installed (pip install -e '.[bench]'): no anchor for standard PSO")


if __name__ == "__main__":
    main()
