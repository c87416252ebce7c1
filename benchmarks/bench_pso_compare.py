"""Shoal's vectorised PSO against (a) a plain per-robot Python loop of the same Adapted PSO
step and (b) pyswarms' ``GlobalBestPSO`` running standard PSO.

Run: python benchmarks/bench_pso_compare.py [--quick]   (part b needs: pip install -e '.[bench]')

(a) ``loop_step`` below is a reference written only for this comparison: one robot and one
    component at a time with Python floats and ``math``, the equations of
    ``engine/pso/laws.py``/``engine/kinds/swarm.py`` (bests [3.2]/[3.3], Adapted PSO [3.11], position
    [3.10], acceleration [3.22], heading). Both sides start from the same state with copies of
    the same generators, so they draw the same numbers; the script asserts that positions,
    velocities, accelerations and bests agree bit for bit (headings to 2 ulp) before it
    reports any time (and
    ``tests/test_loop_reference.py`` keeps that check in the suite).
(b) Standard PSO [2.1]/[2.2] with a global best on Sphere and Rastrigin: same dimension, swarm
    size, iterations, coefficients (ω = 0.7298, c1 = c2 = 1.49618), the same objective callable
    (Shoal's, checked against pyswarms' own functions), the same start positions (Shoal's,
    passed to pyswarms as ``init_pos``) and zero start velocities; no bounds or velocity clamp
    on either side. Reported: median wall time per iteration and the median best fitness
    reached over the seeds. Shoal also runs all seeds as one batch (runs = seeds), which is how
    the experiments use it.

Times are this thread's CPU time (robust while other jobs share the machine).
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, table  # noqa: E402

# ---------------------------------------------------------------------- (a) the loop reference


@dataclass
class LoopSwarm:
    """Plain nested lists, [run][robot][component], of one swarm per run."""

    x: list[list[list[float]]]
    u: list[list[list[float]]]
    a: list[list[list[float]]]
    y: list[list[list[float]]]
    f_y: list[list[float]]
    yg: list[list[float]]
    best_fitness: list[float]
    heading: list[list[float]]

    @classmethod
    def from_state(cls, s) -> "LoopSwarm":
        """Copy a :class:`shoal.engine.kinds.swarm.SwarmState` into lists."""
        return cls(x=s.x.tolist(), u=s.u.tolist(), a=s.a.tolist(), y=s.y.tolist(), f_y=s.f_y.tolist(),
                   yg=s.yg.tolist(), best_fitness=s.best_fitness.tolist(), heading=s.heading.tolist())


def _sgn(v: float) -> float:
    return 1.0 if v > 0 else (-1.0 if v < 0 else 0.0)


def loop_step(sw: LoopSwarm, rngs: list[np.random.Generator], omega: float, c: tuple[float, float], dt: float,
              source: tuple[float, ...]) -> None:
    """One Adapted PSO (sgn) tick of every run, one robot and component at a time, in place.

    Cost f = |x − source| (minimised); pbest before velocity; attractors y − x and y_g − x.
    """
    c1, c2 = c
    for r, gen in enumerate(rngs):
        x, u, y, f_y = sw.x[r], sw.u[r], sw.y[r], sw.f_y[r]
        n, d = len(x), len(x[0])
        for i in range(n):  # [3.2] personal bests
            s = 0.0
            for j in range(d):
                diff = x[i][j] - source[j]
                s += diff * diff
            f = math.sqrt(s)
            if f < f_y[i]:
                y[i], f_y[i] = list(x[i]), f
        best = 0  # [3.3] global best: the first of the lowest
        for i in range(1, n):
            if f_y[i] < f_y[best]:
                best = i
        yg = list(y[best])
        sw.yg[r], sw.best_fitness[r] = yg, f_y[best]
        r1 = [[gen.random() for _ in range(d)] for _ in range(n)]  # draws in the engine's order:
        r2 = [[gen.random() for _ in range(d)] for _ in range(n)]  # term, robot, component
        for i in range(n):
            moving = False
            new = [0.0] * d
            for j in range(d):
                t1 = c1 * r1[i][j] * _sgn(y[i][j] - x[i][j])
                t2 = c2 * r2[i][j] * _sgn(yg[j] - x[i][j])
                new[j] = omega * u[i][j] + (t1 + t2)  # [3.11]
                moving = moving or new[j] != 0.0
            sw.a[r][i] = [(new[j] - u[i][j]) / dt for j in range(d)]  # [3.22]
            x[i] = [x[i][j] + dt * new[j] for j in range(d)]  # [3.10]
            u[i] = new
            if moving:
                sw.heading[r][i] = math.atan2(new[1], new[0]) if d >= 2 else (math.pi if new[0] < 0 else 0.0)


def engine_and_loop(robots: int, runs: int = 1, seed: int = 0):
    """A ``default``-preset engine swarm, its loop copy with copies of its generators, and
    the coefficients the loop needs."""
    from shoal.presets.build import build_simulation
    from shoal.presets.io import load

    sim = build_simulation(load("default", [f"sim.robots={robots}"]), runs=runs, seed=seed)
    omega, c = sim.policy.coefficients(sim.t, sim.dt, sim.d)
    loop = LoopSwarm.from_state(sim.state)
    rngs = copy.deepcopy(sim.rngs)
    source = tuple(float(v) for v in sim.objective.source[: sim.d])
    return sim, loop, rngs, (float(omega), tuple(float(v) for v in np.asarray(c)), sim.dt, source)


def check_same(sim, loop: LoopSwarm) -> None:
    """Raise AssertionError unless the loop and the engine hold the same numbers: bit for bit
    for positions, velocities, accelerations and bests; headings within 2 ulp (numpy's
    ``arctan2`` and ``math.atan2`` may round the last bit differently)."""
    s = sim.state
    for name in ("x", "u", "a", "y", "f_y", "yg", "best_fitness"):
        a, b = getattr(s, name), np.asarray(getattr(loop, name))
        assert np.array_equal(a, b), f"{name} differs: max |Δ| = {np.max(np.abs(a - b))}"
    np.testing.assert_array_max_ulp(s.heading, np.asarray(loop.heading), maxulp=2)


def compare_loop(sizes: tuple[int, ...], steps: int) -> list[list[str]]:
    """Median CPU ms per step of the loop and of the engine (``steps`` steps each, timed one by
    one), after checking that they agree before and after."""
    rows = []
    for n in sizes:
        sim, loop, rngs, args = engine_and_loop(n)
        for _ in range(3):  # the equality check, and a warm-up
            sim.step()
            loop_step(loop, rngs, *args)
        check_same(sim, loop)
        t_loop, t_vec = [], []
        for _ in range(steps):
            t0 = time.thread_time()
            loop_step(loop, rngs, *args)
            t_loop.append(time.thread_time() - t0)
        for _ in range(steps):
            t0 = time.thread_time()
            sim.step()
            t_vec.append(time.thread_time() - t0)
        check_same(sim, loop)
        lo, ve = float(np.median(t_loop)), float(np.median(t_vec))
        rows.append([str(n), fmt(lo * 1e3), fmt(ve * 1e3), f"{lo / ve:.1f}×", f"{n / lo / 1e6:.3g} M",
                     f"{n / ve / 1e6:.3g} M", "yes"])
    return rows


# ---------------------------------------------------------------------- (b) pyswarms
W, C1, C2 = 0.7298, 1.49618, 1.49618
HALF = 5.12  # start positions uniform in [−5.12, 5.12]^D


def shoal_standard(fn: str, dim: int, particles: int, iters: int, runs: int, seed: int):
    """Standard PSO with a global best in Shoal: (best fitness per run, seconds)."""
    from shoal.engine.core.objectives import Objective
    from shoal.engine.kinds.swarm import Simulation
    from shoal.engine.pso.coeffs import Constant
    from shoal.engine.pso.laws import Law

    sim = Simulation(robots=particles, d=dim, dt=1.0, law=Law("standard"), policy=Constant(W, (C1, C2)),
                     objective=Objective(fn, source=np.zeros(dim)), runs=runs, seed=seed,
                     init_center=np.zeros(dim), init_spread=2 * HALF, init_speed=0.0)
    x0 = sim.state.x.copy()
    t0 = time.thread_time()
    for _ in range(iters):
        sim.step()
    return sim.state.best_fitness.copy(), time.thread_time() - t0, x0


def pyswarms_standard(fn: str, dim: int, x0: np.ndarray, iters: int, seed: int) -> tuple[float, float]:
    """pyswarms ``GlobalBestPSO`` from ``x0`` with zero velocities: (best fitness, seconds)."""
    import logging

    from pyswarms.single import GlobalBestPSO

    from shoal.engine.core.objectives import Objective

    logging.getLogger("pyswarms").setLevel(logging.WARNING)
    objective = Objective(fn, source=np.zeros(dim))
    np.random.seed(seed)
    opt = GlobalBestPSO(n_particles=len(x0), dimensions=dim, options={"c1": C1, "c2": C2, "w": W},
                        init_pos=x0.copy())
    opt.swarm.velocity = np.zeros_like(opt.swarm.position)
    t0 = time.thread_time()
    cost, _ = opt.optimize(objective, iters=iters, verbose=False)
    return float(cost), time.thread_time() - t0


def check_functions(dim: int) -> None:
    """Shoal's Sphere and Rastrigin equal pyswarms' on in-bounds points."""
    from pyswarms.utils.functions import single_obj

    from shoal.engine.core.objectives import Objective

    pts = np.random.default_rng(1).uniform(-HALF, HALF, (50, dim))
    for fn in ("sphere", "rastrigin"):
        ours = Objective(fn, source=np.zeros(dim))(pts)
        assert np.allclose(ours, getattr(single_obj, fn)(pts), rtol=1e-12, atol=1e-12), fn


def compare_pyswarms(dim: int, particles: int, iters: int, seeds: int) -> list[list[str]]:
    check_functions(dim)
    rows = []
    for fn in ("sphere", "rastrigin"):
        ours, theirs = [], []
        for s in range(seeds):
            best, secs, x0 = shoal_standard(fn, dim, particles, iters, 1, s)
            ours.append((float(best[0]), secs))
            theirs.append(pyswarms_standard(fn, dim, x0[0], iters, s))
        best_b, secs_b, _ = shoal_standard(fn, dim, particles, iters, seeds, 0)
        for name, res in (("Shoal, one seed per call", ours), ("pyswarms GlobalBestPSO", theirs)):
            f = np.array([r[0] for r in res])
            t = np.array([r[1] for r in res]) / iters
            rows.append([fn, name, fmt(np.median(t) * 1e6), f"{np.median(f):.3g}", f"{f.min():.3g} – {f.max():.3g}"])
        rows.append([fn, f"Shoal, {seeds} seeds batched in one call", fmt(secs_b / iters / seeds * 1e6),
                     f"{np.median(best_b):.3g}", f"{best_b.min():.3g} – {best_b.max():.3g}"])
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer steps, iterations and seeds")
    ap.add_argument("--dim", type=int, default=10)
    ap.add_argument("--particles", type=int, default=30)
    args = ap.parse_args()
    steps, iters, seeds = (20, 200, 5) if args.quick else (200, 1000, 20)
    print(f"{load_note()}\n")
    print("(a) Adapted PSO step, plain Python loop vs vectorised engine (one run, default preset), CPU time\n")
    print(table(["robots", "loop ms/step", "engine ms/step", "speed-up", "loop robot-steps/s",
                 "engine robot-steps/s", "same numbers"], compare_loop((10, 100, 1000), steps)))
    try:
        import pyswarms  # noqa: F401
    except ImportError:
        print("\n(b) skipped: pyswarms is not installed (pip install -e '.[bench]')")
        return
    print(f"\n(b) standard PSO, D = {args.dim}, {args.particles} particles, {iters} iterations, "
          f"{seeds} seeds, ω = {W}, c1 = c2 = {C1}\n")
    print(table(["function", "implementation", "CPU µs per iteration (per seed)", "median best fitness",
                 "range over seeds"], compare_pyswarms(args.dim, args.particles, iters, seeds)))


if __name__ == "__main__":
    main()
