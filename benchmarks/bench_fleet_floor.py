"""The fleet tick against its compiled floor, and against another tree's tick (issue 35, item 2),
plus batched fleets on one thread and on every core (item 1).

Run: python benchmarks/bench_fleet_floor.py [--base PATH] [--sizes 10 100 1000 10000 100000] [--reps 3]

- **Tick**: ``Fleet.step()`` of ``course-dvc``'s controller (omni DVC, sequential update,
  kinematic) with N robots in a start square of side 2√N m on an obstacle course 10 m wider
  (bench_scaling's same density at every size), one run, wall time per tick over T ticks from
  the start.
- **Floor**: :func:`floor_ticks` below, a numba kernel that does the same T ticks in one call:
  for every tick, the whole tick of every run (``robots/tick_kernels.fleet_runs``: bests, the
  draws, the attractors, phase B, the metrics) into buffers reused from tick to tick, with no
  Python between ticks. The script checks that the floor ends in the very bytes the ticks
  end in (state and generators) before it reports a number: it does the same work.
- **Base**: the same ticks in another tree (``--base``: a checkout of main, e.g. from ``git
  worktree add`` or ``git archive``), in a child process with ``PYTHONPATH`` at its ``src``.
- **Batched**: 100 runs × 10 robots, per tick, on 1 thread and on every core
  (``engine/core/parallel.py``), and the base tree's.

Each size runs tick, floor and base in turn, ``--reps`` times (A B C A B C), each from a fresh
fleet, after a warm-up pass; the table gives the median and the range.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, table  # noqa: E402


def make_fleet(robots: int, runs: int = 1):
    """``course-dvc``'s fleet (the default FleetParams: omni DVC, sequential, kinematic) on an
    obstacle course whose start square has side 2√N m, 10 m narrower than the course."""
    from shoal.engine.kinds.fleet import Fleet, FleetParams
    from shoal.engine.robots.world import obstacle_course

    side = round(2.0 * math.sqrt(robots), 1)
    world = obstacle_course(seed=0, length=max(60.0, 2 * side + 30), width=side + 10, start_size=side)
    return Fleet(world=world, robots=robots, params=FleetParams(), runs=runs, seed=0)


def ticks_for(robots: int, quick: bool) -> int:
    return max(3, min(2000, (20_000 if quick else 100_000) // robots))


def tick_seconds(robots: int, ticks: int, runs: int = 1) -> float:
    """Wall seconds a tick of ``Fleet.step()`` takes, over ``ticks`` ticks from the start."""
    fleet = make_fleet(robots, runs)
    t0 = time.perf_counter()
    for _ in range(ticks):
        fleet.step()
    return (time.perf_counter() - t0) / ticks


# ---------------------------------------------------------------------- the floor
_FLOOR = None


def _floor_kernel():
    global _FLOOR
    if _FLOOR is None:
        from numba import njit

        from shoal.engine.robots.tick_kernels import fleet_runs

        @njit(cache=False, error_model="numpy", nogil=True)
        def floor_ticks(ticks, a, b, f, yg, best, source, fn, states, terms, per_component, params, world, grid, out,
                        layers, stall_speed, stall_steps, com, max_speed, counts):
            """``ticks`` whole ticks of every run, the states alternating between ``a`` and ``b``."""
            runs = f.shape[0]
            for t in range(ticks):
                if t % 2 == 0:
                    fleet_runs(0, runs, a[:8], b, f, yg, best, source, fn, states, terms, per_component, params,
                               world, grid, out, layers, stall_speed, stall_steps, com, max_speed, counts)
                else:
                    fleet_runs(0, runs, b[:8], a, f, yg, best, source, fn, states, terms, per_component, params,
                               world, grid, out, layers, stall_speed, stall_steps, com, max_speed, counts)

        _FLOOR = floor_ticks
    return _FLOOR


def floor_seconds(robots: int, ticks: int, check: bool = True) -> float:
    """Wall seconds a tick takes in :func:`floor_ticks`; with ``check``, the ticks' end state is
    compared with ``Fleet.step()``'s, byte for byte (AssertionError if it differs)."""
    from shoal.engine.kinds.fleet import STALL_SPEED, STALL_STEPS

    fleet = make_fleet(robots)
    s = fleet.state
    R, N = s.status.shape
    terms, per_component = fleet._draw_layout()
    gen = fleet._compiled_draws()
    source, layers, params, world, grid = fleet._kernel_constants()
    a = tuple(np.array(getattr(s, name)) for name in ("x", "heading", "u", "cmd", "status", "slow", "y", "f_y"))
    a, b = a + (np.empty_like(s.x),), tuple(np.empty_like(v) for v in a) + (np.empty_like(s.x),)  # + commanded
    f, yg, best, com, max_speed = np.empty((R, N)), np.empty((R, 2)), np.empty(R), np.empty(R), np.empty(R)
    counts = np.empty((4, R), np.int64)
    out = (np.empty((R, N)), np.empty((terms, R, N)), np.empty((R, N, 2)), np.empty((R, N, 6)),
           np.empty((R, N, 6, 2)), np.empty((R, N, 6, 2)), np.empty((R, N, 6), bool))
    args = (f, yg, best, source, gen.address, gen.states, terms, per_component, params, world, grid, out, layers,
            STALL_SPEED, STALL_STEPS, com, max_speed, counts)
    kernel = _floor_kernel()
    t0 = time.perf_counter()
    kernel(ticks, a, b, *args)
    seconds = (time.perf_counter() - t0) / ticks
    if check:
        ref = make_fleet(robots)
        for _ in range(ticks):
            ref.step()
        end = b if ticks % 2 else a
        for name, v in zip(("x", "heading", "u", "cmd", "status", "slow", "y", "f_y"), end):
            assert getattr(ref.state, name).tobytes() == v.tobytes(), f"the floor's {name} differs from the tick's"
        assert ref.state.best_fitness.tobytes() == best.tobytes()
        assert [g.random() for g in ref.rngs] == [g.random() for g in fleet.rngs], "the floor drew otherwise"
    return seconds


# ---------------------------------------------------------------------- another tree, in a child process
CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
from bench_fleet_floor import tick_seconds
for line in sys.stdin:
    robots, ticks, runs = map(int, line.split())
    print(json.dumps(tick_seconds(robots, ticks, runs)), flush=True)
"""


class Base:
    """A child process ticking fleets in another tree."""

    def __init__(self, tree: Path) -> None:
        env = os.environ | {"PYTHONPATH": str(tree / "src")}
        env.pop("NUMBA_NUM_THREADS", None)
        self.proc = subprocess.Popen([sys.executable, "-c", CHILD, str(Path(__file__).resolve().parent)], env=env,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def __call__(self, robots: int, ticks: int, runs: int = 1) -> float:
        assert self.proc.stdin and self.proc.stdout
        self.proc.stdin.write(f"{robots} {ticks} {runs}\n")
        self.proc.stdin.flush()
        return float(json.loads(self.proc.stdout.readline()))

    def close(self) -> None:
        if self.proc.stdin:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


def spread(xs: list[float], scale: float = 1e3) -> str:
    xs = sorted(x * scale for x in xs)
    return f"{fmt(xs[len(xs) // 2])} ({fmt(xs[0])}–{fmt(xs[-1])})"


def ratios(a: list[float], b: list[float]) -> str:
    """The median and range of the ratios a[i] / b[i] (measured in the same turn)."""
    r = sorted(x / y for x, y in zip(a, b))
    return f"{r[len(r) // 2]:.2f}× ({r[0]:.2f}–{r[-1]:.2f})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", type=Path, help="another tree (its src/ is imported in a child process)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000, 10_000, 100_000])
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--batched-runs", type=int, default=100)
    args = ap.parse_args()
    from shoal.engine.core import parallel

    base = Base(args.base) if args.base else None
    print(f"# {load_note()} (before)", flush=True)
    rows = []
    for n in args.sizes:
        ticks = ticks_for(n, args.quick)
        floor_seconds(n, min(ticks, 5))  # compiles, and checks the floor does the tick's work
        tick_seconds(n, 3)
        if base:
            base(n, 3)
        t, fl, bs = [], [], []
        for _ in range(args.reps):
            t.append(tick_seconds(n, ticks))
            fl.append(floor_seconds(n, ticks, check=False))
            if base:
                bs.append(base(n, ticks))
        row = [str(n), str(ticks), spread(fl), spread(t), ratios(t, fl)]
        if base:
            row += [spread(bs), ratios(bs, fl)]
        rows.append(row)
        print(" | ".join(row), flush=True)
    head = ["robots", "ticks", "floor ms/tick", "tick ms/tick", "tick / floor"]
    if base:
        head += ["base tick ms/tick", "base / floor"]
    print(table(head, rows))

    runs, robots = args.batched_runs, 10
    ticks = 50 if args.quick else 200
    brows = []
    tick_seconds(robots, 3, runs)
    one, every, bs = [], [], []
    for _ in range(args.reps):
        parallel.set_threads(1)
        one.append(tick_seconds(robots, ticks, runs))
        parallel.set_threads(None)
        every.append(tick_seconds(robots, ticks, runs))
        if base:
            bs.append(base(robots, ticks, runs))
    brows.append([f"{runs} × {robots}", "1 thread", spread(one), spread([t / (runs * robots) for t in one], 1e6)])
    brows.append([f"{runs} × {robots}", f"{parallel.threads()} threads", spread(every),
                  spread([t / (runs * robots) for t in every], 1e6)])
    if base:
        brows.append([f"{runs} × {robots}", "base", spread(bs), spread([t / (runs * robots) for t in bs], 1e6)])
    print(table(["runs × robots", "tree", "ms/tick", "µs/robot-tick"], brows))
    print(f"# {load_note()} (after)")
    if base:
        base.close()


if __name__ == "__main__":
    main()
