"""SLO neighbourhoods (Mai §3.4, §4.5.3): which ordered pairs (i → j) are localised and
exchange PSO information, recomputed from TRUE positions every step.

Adjacency is boolean ``(R, N, N)`` with ``adj[r, i, j]`` = "j ∈ N_i"; the diagonal is False.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np

from . import kernels

NeighbourhoodKind = Literal["knn", "radius", "full", "random", "ring"]

DEFAULT_PARAM: dict[str, float] = {"knn": 5, "radius": 25.0, "full": 0, "random": 0.5, "ring": 2}
# the defaults: docs/readings.md, "Radius and ring size of the neighbourhoods"


def distances(x: np.ndarray) -> np.ndarray:
    """True distances ‖x_j − x_i‖ of every pair, (R, N, N), with +inf on the diagonal (compiled)."""
    return kernels.distances(np.ascontiguousarray(x, dtype=float))


def _no_self(adj: np.ndarray) -> np.ndarray:
    idx = np.arange(adj.shape[-1])
    adj[..., idx, idx] = False
    return adj


def full(runs: int, n: int) -> np.ndarray:
    """Every other particle."""
    return _no_self(np.ones((runs, n, n), dtype=bool))


def knn(dist: np.ndarray, k: int) -> np.ndarray:
    """The k closest particles, ties broken by index; directed (docs/readings.md,
    "Symmetric and directed neighbourhoods")."""
    n = dist.shape[-1]
    k = int(min(max(k, 0), n - 1))
    return _no_self(kernels.nearest(np.ascontiguousarray(dist, dtype=float), k))  # compiled stable argsort[:k]


def radius(dist: np.ndarray, r: float) -> np.ndarray:
    """All particles closer than r (symmetric)."""
    return _no_self(dist < r)


def ring(runs: int, n: int, width: int) -> np.ndarray:
    """X_i linked to X_{(i ± k) mod P} for 1 ≤ k ≤ width (static, symmetric)."""
    i = np.arange(n)
    offset = (i[None, :] - i[:, None]) % n
    ring_dist = np.minimum(offset, n - offset)
    adj = (ring_dist >= 1) & (ring_dist <= int(width))
    return np.broadcast_to(adj, (runs, n, n)).copy()


def random_links(uniforms: np.ndarray, p: float) -> np.ndarray:
    """Each unordered pair linked with probability p from ``uniforms`` (R, N, N); only the
    upper triangle is used, so links are symmetric (docs/readings.md,
    "Symmetric and directed neighbourhoods")."""
    upper = np.triu(uniforms < p, k=1)
    return upper | np.swapaxes(upper, -1, -2)


@dataclass(frozen=True)
class Neighbourhood:
    """A neighbourhood function and its parameter: k (knn), r (radius), n (ring), p (random)."""

    kind: NeighbourhoodKind = "knn"
    param: float | None = None

    @property
    def value(self) -> float:
        return DEFAULT_PARAM[self.kind] if self.param is None else float(self.param)

    def scaled(self, unit: float) -> "Neighbourhood":
        """The rule in an arena ``unit`` times the thesis' 100 × 100: only a radius is a length."""
        return Neighbourhood("radius", self.value * unit) if self.kind == "radius" else self

    def adjacency(self, x: np.ndarray, rngs: Sequence[np.random.Generator] | None = None) -> np.ndarray:
        """Adjacency (R, N, N) at true positions ``x`` (R, N, 2); ``rngs`` (one per run) feed
        the random topology, which is redrawn at every call."""
        R, n, _ = x.shape
        if self.kind == "full":
            return full(R, n)
        if self.kind == "ring":
            return ring(R, n, int(self.value))
        if self.kind == "random":
            if rngs is None:
                raise ValueError("the random neighbourhood needs one generator per run")
            return random_links(np.stack([g.random((n, n)) for g in rngs]), self.value)
        dist = distances(x)
        if self.kind == "knn":
            return knn(dist, int(self.value))
        if self.kind == "radius":
            return radius(dist, self.value)
        raise ValueError(f"neighbourhood: unknown kind {self.kind!r}")
