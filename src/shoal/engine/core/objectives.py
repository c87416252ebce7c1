"""Fitness and cost functions (Rossides Alg. 1, p. 90; §3.5, p. 74; common PSO benchmarks).

Every objective returns a value per robot, shape ``(runs, robots)``, and says whether
it is maximised; :meth:`Objective.is_better` is the single comparison the swarm uses
(docs/readings.md, "Fitness or cost").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Literal

import numpy as np

ObjectiveName = Literal[
    "source-distance", "linear", "sphere", "rastrigin", "ackley", "rosenbrock", "griewank"
]


def source_distance(x: np.ndarray, source: np.ndarray) -> np.ndarray:
    """Cost of Algorithm 1: f = |x − x_source| (minimised)."""
    return np.linalg.norm(x - source, axis=-1)


def linear(x: np.ndarray) -> np.ndarray:
    """f(x) = x_1 of Rossides §3.5, p. 74 (maximised: the swarm drifts in +x_1 for ever)."""
    return x[..., 0].copy()


def line(x: np.ndarray) -> np.ndarray:
    """Mai's "line" objective, undefined in the thesis: x_0², minimum 0 on the line x_0 = 0
    (docs/readings.md, "The line objective")."""
    return x[..., 0] ** 2


def sphere(x: np.ndarray) -> np.ndarray:
    return np.sum(x**2, axis=-1)


def rastrigin(x: np.ndarray) -> np.ndarray:
    return 10.0 * x.shape[-1] + np.sum(x**2 - 10.0 * np.cos(2 * np.pi * x), axis=-1)


def ackley(x: np.ndarray) -> np.ndarray:
    d = x.shape[-1]
    a = -20.0 * np.exp(-0.2 * np.sqrt(np.sum(x**2, axis=-1) / d))
    b = -np.exp(np.sum(np.cos(2 * np.pi * x), axis=-1) / d)
    return a + b + 20.0 + np.e


def rosenbrock(x: np.ndarray) -> np.ndarray:
    if x.shape[-1] < 2:
        return (1.0 - x[..., 0]) ** 2
    return np.sum(100.0 * (x[..., 1:] - x[..., :-1] ** 2) ** 2 + (1.0 - x[..., :-1]) ** 2, axis=-1)


def griewank(x: np.ndarray) -> np.ndarray:
    i = np.arange(1, x.shape[-1] + 1)
    return 1.0 + np.sum(x**2, axis=-1) / 4000.0 - np.prod(np.cos(x / np.sqrt(i)), axis=-1)


_BENCHMARKS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "sphere": sphere,
    "rastrigin": rastrigin,
    "ackley": ackley,
    "rosenbrock": rosenbrock,
    "griewank": griewank,
}


@dataclass(eq=False)
class Objective:
    """A named objective; benchmark functions are evaluated at ``(x − source)/scale``
    so that their optimum sits on the source and their features fit the arena."""

    name: ObjectiveName = "source-distance"
    source: np.ndarray = field(default_factory=lambda: np.zeros(2))
    scale: float = 1.0

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Objective) and (self.name, self.scale) == (other.name, other.scale)
                and np.array_equal(self.source, other.source))

    @property
    def maximise(self) -> bool:
        return self.name == "linear"

    def __call__(self, x: np.ndarray) -> np.ndarray:
        if self.name == "source-distance":
            return source_distance(x, self.source[: x.shape[-1]])
        if self.name == "linear":
            return linear(x)
        z = (x - self.source[: x.shape[-1]]) / self.scale
        return _BENCHMARKS[self.name](z)

    def is_better(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """True where fitness ``a`` beats ``b`` (strictly)."""
        return a > b if self.maximise else a < b

    @property
    def worst(self) -> float:
        return -np.inf if self.maximise else np.inf
