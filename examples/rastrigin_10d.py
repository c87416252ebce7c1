"""Your own objective on a 10-D Rastrigin, beside pyswarms (when it is installed): the same
swarm size, coefficients and iterations, and the same vectorised function of positions.

    python examples/rastrigin_10d.py
"""

from __future__ import annotations

import sys

import numpy as np

import shoal

D, PARTICLES, ITERS = 10, 30, 500
W, C1, C2 = 0.729, 1.49, 1.49  # Clerc's constriction values as inertia and coefficients


def my_rastrigin(x: np.ndarray) -> np.ndarray:
    """Vectorised over any leading axes: (..., D) → (...); minimum 0 at the origin."""
    return 10.0 * x.shape[-1] + np.sum(x**2 - 10.0 * np.cos(2.0 * np.pi * x), axis=-1)


def with_shoal(seed: int = 0) -> float:
    scene = shoal.make("default", d=D, robots=PARTICLES, seed=seed,
                       objective={"kind": my_rastrigin, "source": [0.0, 0.0]},
                       controller={"law": "standard", "mode": "raw", "omega": W, "c1": C1, "c2": C2},
                       init={"center": [0.0, 0.0], "spread": 10.24})
    table = scene.run(ITERS)
    return float(table["best_fitness"].iloc[-1])


def with_pyswarms(seed: int = 0) -> float | None:
    try:
        import pyswarms as ps
    except ImportError:
        return None
    np.random.seed(seed)
    bounds = (np.full(D, -5.12), np.full(D, 5.12))
    optimizer = ps.single.GlobalBestPSO(n_particles=PARTICLES, dimensions=D, options={"c1": C1, "c2": C2, "w": W},
                                        bounds=bounds)
    cost, _ = optimizer.optimize(my_rastrigin, iters=ITERS, verbose=False)
    return float(cost)


def main() -> int:
    ours = with_shoal()
    print(f"Shoal, standard PSO, {D}-D Rastrigin, {PARTICLES} particles, {ITERS} iterations: best f = {ours:.4g}")
    theirs = with_pyswarms()
    print("pyswarms: not installed" if theirs is None
          else f"pyswarms GlobalBestPSO, same settings: best f = {theirs:.4g}")
    assert np.isfinite(ours) and ours < my_rastrigin(np.full(D, 2.5)), "the swarm improved on a random start"
    return 0


if __name__ == "__main__":
    sys.exit(main())
