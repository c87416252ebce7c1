"""Batched standard PSO on every core against its peers (issue 35, item 1): Shoal's
``Simulation.run`` on one thread and on every core, a plain vectorised numpy batch, evosax's
PSO under ``jax.vmap`` on the CPU, and another tree's Shoal (``--base``: a checkout of main).

Run: python benchmarks/bench_batch_peers.py [--base PATH] [--reps 5]   (evosax: pip install -e '.[bench]')

The problem of the issue: 20 seeds × 30 particles × D = 10, Sphere, 1,000 iterations, ω =
0.7298, c1 = c2 = 1.49618, starts uniform in [−5.12, 5.12]^D, zero start velocities. Wall
time of the whole batch (what a user waits for), each implementation in turn (A B C D …),
``--reps`` times after a warm-up of each (numba's and XLA's compiles); the table gives the
median and the range, the ratios are taken within each turn. evosax runs in float32 (JAX's
default) and draws r1, r2 once per particle (its PSO); the others draw per component in
float64. The median best fitness of the seeds says each one optimised.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_common import fmt, load_note, table  # noqa: E402

SEEDS, PARTICLES, D, ITERS = 20, 30, 10, 1000
W, C1, C2, HALF = 0.7298, 1.49618, 1.49618, 5.12


def shoal_batch(seed: int = 1) -> np.ndarray:
    """Shoal's batched run: one Simulation of SEEDS runs, ITERS ticks in one ``run`` call."""
    from shoal.engine.core.objectives import Objective
    from shoal.engine.kinds.swarm import Simulation
    from shoal.engine.pso.coeffs import Constant
    from shoal.engine.pso.laws import Law

    sim = Simulation(robots=PARTICLES, d=D, dt=1.0, law=Law("standard"), policy=Constant(W, (C1, C2)),
                     objective=Objective("sphere", source=np.zeros(D)), runs=SEEDS, seed=seed,
                     init_center=np.zeros(D), init_spread=2 * HALF, init_speed=0.0)
    sim.run(ITERS)
    return sim.state.best_fitness


def numpy_batch(seed: int = 1) -> np.ndarray:
    """The same standard PSO as a plain vectorised numpy batch (seeds × particles × D arrays)."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-HALF, HALF, (SEEDS, PARTICLES, D))
    v = np.zeros_like(x)
    f = (x * x).sum(-1)
    y, fy = x.copy(), f.copy()
    runs = np.arange(SEEDS)
    g = y[runs, fy.argmin(1)]
    for _ in range(ITERS):
        r = rng.random((2, SEEDS, PARTICLES, D))
        v = W * v + C1 * r[0] * (y - x) + C2 * r[1] * (g[:, None] - x)
        x = x + v
        f = (x * x).sum(-1)
        better = f < fy
        y[better], fy[better] = x[better], f[better]
        g = y[runs, fy.argmin(1)]
    return fy.min(1)


def evosax_batch():
    """evosax 0.3's PSO, ITERS generations by ``lax.scan``, vmapped over SEEDS keys, jitted."""
    import jax
    import jax.numpy as jnp
    from evosax.algorithms import PSO

    pso = PSO(population_size=PARTICLES, solution=jnp.zeros(D))
    params = pso.default_params.replace(inertia_coeff=W, cognitive_coeff=C1, social_coeff=C2)

    def one(key):
        k0, k1 = jax.random.split(key)
        x0 = jax.random.uniform(k0, (PARTICLES, D), minval=-HALF, maxval=HALF)
        state = pso.init(k1, x0, jnp.sum(x0 * x0, axis=-1), params)

        def gen(carry, _):
            state, key = carry
            key, ka, kt = jax.random.split(key, 3)
            x, state = pso.ask(ka, state, params)
            state, _ = pso.tell(kt, x, jnp.sum(x * x, axis=-1), state, params)  # (state, metrics)
            return (state, key), None

        (state, _), _ = jax.lax.scan(gen, (state, key), None, length=ITERS)
        return jnp.min(state.fitness_best)

    run = jax.jit(jax.vmap(one))
    keys = jax.random.split(jax.random.key(1), SEEDS)

    def call() -> np.ndarray:
        return np.asarray(run(keys).block_until_ready())

    return call


CHILD = r"""
import json, sys, time
sys.path.insert(0, sys.argv[1])
from bench_batch_peers import shoal_batch
shoal_batch()
for line in sys.stdin:
    t0 = time.perf_counter()
    best = shoal_batch()
    print(json.dumps([time.perf_counter() - t0, float(sorted(best)[len(best) // 2])]), flush=True)
"""


class Base:
    """Shoal's batch in another tree, in a child process."""

    def __init__(self, tree: Path) -> None:
        env = os.environ | {"PYTHONPATH": str(tree / "src")}
        self.proc = subprocess.Popen([sys.executable, "-c", CHILD, str(Path(__file__).resolve().parent)], env=env,
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)

    def __call__(self) -> tuple[float, float]:
        assert self.proc.stdin and self.proc.stdout
        self.proc.stdin.write("go\n")
        self.proc.stdin.flush()
        seconds, best = json.loads(self.proc.stdout.readline())
        return seconds, best

    def close(self) -> None:
        if self.proc.stdin:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


def timed(fn) -> tuple[float, float]:
    t0 = time.perf_counter()
    best = np.asarray(fn())
    return time.perf_counter() - t0, float(np.median(best))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--base", type=Path, help="another tree (its src/ is imported in a child process)")
    ap.add_argument("--reps", type=int, default=5)
    args = ap.parse_args()
    from shoal.engine.core import parallel

    cores = parallel.threads()

    def shoal_on(n: int):
        def call() -> np.ndarray:
            parallel.set_threads(n)
            try:
                return shoal_batch()
            finally:
                parallel.set_threads(None)
        return call

    impls: dict[str, object] = {"Shoal, 1 thread": shoal_on(1), f"Shoal, {cores} threads": shoal_on(cores),
                                "numpy batch": numpy_batch}
    try:
        impls["evosax (jax.vmap, CPU)"] = evosax_batch()
    except ImportError as err:
        print(f"# evosax not measured: {err}")
    base = Base(args.base) if args.base else None
    if base:
        impls["base tree's Shoal"] = base
    print(f"# {load_note()} (before)", flush=True)
    for fn in impls.values():  # warm-up: numba's and XLA's compiles
        timed(fn) if fn is not base else base()  # type: ignore[operator]
    got: dict[str, list[tuple[float, float]]] = {k: [] for k in impls}
    for _ in range(args.reps):
        for name, fn in impls.items():
            got[name].append(base() if fn is base else timed(fn))  # type: ignore[arg-type, operator]
    rows = []
    ref_np, ref_ev = got["numpy batch"], got.get("evosax (jax.vmap, CPU)")
    for name, vals in got.items():
        ms = sorted(v[0] * 1e3 for v in vals)
        vs_np = sorted(b[0] / v[0] for v, b in zip(vals, ref_np))
        vs_ev = sorted(b[0] / v[0] for v, b in zip(vals, ref_ev)) if ref_ev else []
        rows.append([name, f"{fmt(ms[len(ms) // 2])} ({fmt(ms[0])}–{fmt(ms[-1])})",
                     f"{vs_np[len(vs_np) // 2]:.2f}× ({vs_np[0]:.2f}–{vs_np[-1]:.2f})",
                     f"{vs_ev[len(vs_ev) // 2]:.2f}× ({vs_ev[0]:.2f}–{vs_ev[-1]:.2f})" if vs_ev else "–",
                     f"{vals[-1][1]:.2g}"])
    print(table(["implementation", "wall ms, 20 seeds × 1000 iterations", "speed vs numpy batch",
                 "speed vs evosax", "median best fitness"], rows))
    print(f"# {load_note()} (after)")
    if base:
        base.close()


if __name__ == "__main__":
    main()
