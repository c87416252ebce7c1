"""Fitness and cost functions (Rossides Alg. 1, p. 90; §3.5, p. 74; common PSO benchmarks).

Every objective returns a value per robot, shape ``(runs, robots)``, and says whether
it is maximised; the swarms compare values through ``engine/pso/bests.py``, where NaN and the
worst infinity are never bests (docs/readings.md, "Fitness or cost", "Bests that are NaN or
infinite"). :data:`OBJECTIVES` is their registry: a plug-in adds its
own vectorised function there.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Literal

import numpy as np

from .registry import Registry


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


Frame = Literal["x", "offset", "scaled"]  # f sees x itself, x − source, or (x − source)/scale


@dataclass(frozen=True)
class ObjectiveFunction:
    """One objective of :data:`OBJECTIVES`: a vectorised ``f`` of positions (..., d) → (...)
    (a numpy function, or a numba-compiled one), whether it is maximised, and the frame it sees.
    A plug-in's objective sees ``(x − source)/scale`` as the benchmarks do, so a preset's
    ``objective.source`` and ``objective.scale`` place and size it on the scene.

    ``name`` is the preset's ``objective.kind``, ``label`` what a panel shows; ``maximise``: the
    best is the largest value; ``frame``: what ``f`` sees, ``"scaled"`` (x − source)/scale,
    ``"offset"`` x − source or ``"x"`` the position itself."""

    name: str
    label: str
    f: Callable[[np.ndarray], np.ndarray]
    maximise: bool = False
    frame: Frame = "scaled"


def shape_message(name: str, given: tuple[int, ...], got: tuple[int, ...]) -> str:
    """Why objective ``name``'s values cannot be a fitness per robot: it mapped ``given`` to ``got``."""
    hint = (" (a function of one point? make it work on the last axis, e.g. np.sum(z**2, axis=-1))"
            if len(got) < len(given) - 1 or got == given[-1:] else "")
    return (f"objective {name!r}: f must map (..., d) to (...), one value per point: given an array of shape "
            f"{given} it returned shape {got}, not {given[:-1]}{hint}")


OBJECTIVES: Registry[ObjectiveFunction] = Registry(
    "objective",
    ObjectiveFunction("source-distance", "distance to the source", lambda z: np.linalg.norm(z, axis=-1),
                      frame="offset"),  # Alg. 1
    ObjectiveFunction("linear", "f = x1 (maximised)", linear, maximise=True, frame="x"),  # §3.5
    ObjectiveFunction("sphere", "sphere", sphere),
    ObjectiveFunction("rastrigin", "Rastrigin", rastrigin),
    ObjectiveFunction("ackley", "Ackley", ackley),
    ObjectiveFunction("rosenbrock", "Rosenbrock", rosenbrock),
    ObjectiveFunction("griewank", "Griewank", griewank),
)


@dataclass(eq=False)
class Objective:
    """A named objective of :data:`OBJECTIVES`; benchmark functions (and plug-ins') are
    evaluated at ``(x − source)/scale`` so that their optimum sits on the source and their
    features fit the arena. ``source`` has as many components as the swarm or more (the first
    d are used; missing ones are 0)."""

    name: str = "source-distance"
    source: np.ndarray = field(default_factory=lambda: np.zeros(2))
    scale: float = 1.0
    bounds: tuple[float, float] | None = None  # every component of f's argument in [lo, hi]; None: unbounded
    boundary: str = "periodic"  # how a swarm keeps to the bounds (engine/pso/bounds.py)

    def __post_init__(self) -> None:
        OBJECTIVES.pick(self.name)
        if self.bounds is not None and not self.bounds[0] < self.bounds[1]:
            raise ValueError(f"bounds: need lo < hi, got {self.bounds}")

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Objective) and (self.name, self.scale) == (other.name, other.scale)
                and np.array_equal(self.source, other.source)
                and (self.bounds, self.boundary) == (other.bounds, other.boundary))

    def box(self, d: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The bounds as positions, (d,) each: where f's argument is ``bounds`` in every component."""
        if self.bounds is None:
            return None
        frame = OBJECTIVES[self.name].frame
        origin = np.zeros(d) if frame == "x" else self._source(d)
        size = self.scale if frame == "scaled" else 1.0
        lo, hi = self.bounds
        return origin + size * lo, origin + size * hi

    @property
    def maximise(self) -> bool:
        return OBJECTIVES[self.name].maximise

    def _source(self, d: int) -> np.ndarray:
        src = self.source[:d]
        return src if src.shape[-1] == d else np.concatenate([src, np.zeros(d - src.shape[-1])])

    def __call__(self, x: np.ndarray) -> np.ndarray:
        entry = OBJECTIVES[self.name]
        if entry.frame == "x":
            out = entry.f(x)
        else:
            z = x - self._source(x.shape[-1])
            out = np.asarray(entry.f(z if entry.frame == "offset" else z / self.scale), dtype=float)
        if np.shape(out) != x.shape[:-1]:
            raise ValueError(shape_message(self.name, x.shape, np.shape(out)))
        return out

    def is_better(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """True where fitness ``a`` beats ``b`` (strictly)."""
        return a > b if self.maximise else a < b

    @property
    def worst(self) -> float:
        return -np.inf if self.maximise else np.inf
