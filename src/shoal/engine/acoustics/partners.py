"""Random communication partners: each robot hears one other robot per step (Rossides §7.2.2, p. 154;
docs/readings.md, "Initial state and partners").

Every run draws from its own generator, one U(0,1) number per robot per step whatever the
exclusion set, so a run's random stream does not depend on how many runs share the call.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

Rngs = np.random.Generator | Sequence[np.random.Generator]


def uniforms(rng: Rngs, shape: tuple[int, int]) -> np.ndarray:
    """(R, N) U(0,1) draws: one row per run from that run's generator (or all from one)."""
    R, N = shape
    if isinstance(rng, np.random.Generator):
        return rng.random((R, N))
    if len(rng) != R:
        raise ValueError(f"rng: {len(rng)} generators for {R} runs")
    return np.stack([g.random(N) for g in rng]) if R else np.zeros((0, N))


def pick_partner(allowed: np.ndarray, u: np.ndarray) -> np.ndarray:
    """(R, N) index of a partner drawn uniformly from ``allowed`` (R, N, N) with draws ``u``.

    Row i of ``allowed`` marks which robots i may hear. −1 where nobody is allowed.
    """
    count = allowed.sum(axis=-1)
    k = np.minimum(np.floor(u * count), np.maximum(count - 1, 0)).astype(int)
    rank = np.cumsum(allowed, axis=-1)  # 1-based rank of each allowed robot
    j = np.argmax(allowed & (rank == (k + 1)[..., None]), axis=-1)
    return np.where(count > 0, j, -1)


def random_partner(rng: Rngs, shape: tuple[int, int], exclude: np.ndarray | None = None) -> np.ndarray:
    """Alg. 5/6 step 2a: a partner j ≠ i per robot, uniform over the others, (R, N) int.

    ``exclude`` (R, N, N) bool removes further robots (GT-PSO drops i's own triangle).
    """
    R, N = shape
    allowed = np.broadcast_to(~np.eye(N, dtype=bool), (R, N, N))
    if exclude is not None:
        allowed = allowed & ~exclude
    return pick_partner(allowed, uniforms(rng, shape))
