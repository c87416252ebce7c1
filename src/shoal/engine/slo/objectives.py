"""Benchmarks of the SLO PSO experiment (Mai §4.6): DEAP's 2-D definitions, all minimised,
with the quality thresholds T of the "first generation with best ≤ T" metric."""

from __future__ import annotations

from typing import Callable, Literal

import numpy as np

from ..core.objectives import ackley, griewank, line, linear, rastrigin, rosenbrock, sphere

SLOObjectiveName = Literal["ackley", "griewank", "line", "plane", "rastrigin", "rosenbrock", "sphere"]
Fitness = Callable[[np.ndarray], np.ndarray]

# DEAP forms in 2-D; ``plane`` is f = x_0 minimised (the Chapter 3 "linear" maximises it).
SLO_OBJECTIVES: dict[str, Fitness] = {
    "ackley": ackley,
    "griewank": griewank,
    "line": line,  # x_0²; see docs/readings.md, "The line objective"
    "plane": linear,
    "rastrigin": rastrigin,
    "rosenbrock": rosenbrock,
    "sphere": sphere,
}

# Thresholds inside the bounds implied by Tab. 4.4 (Mai p. 55); docs/readings.md, "Quality thresholds".
QUALITY_THRESHOLDS: dict[str, float] = {
    "ackley": 0.1,
    "griewank": 0.01,
    "line": 1e-3,
    "plane": -1000.0,
    "rastrigin": 0.01,
    "rosenbrock": 50.0,
    "sphere": 1e-4,
}


def slo_objective(objective: str | Fitness) -> Fitness:
    """A fitness callable ``(..., 2) -> (...)`` by name, or ``objective`` itself."""
    if callable(objective):
        return objective
    if objective not in SLO_OBJECTIVES:
        raise ValueError(f"objective: unknown {objective!r}, expected one of {sorted(SLO_OBJECTIVES)}")
    return SLO_OBJECTIVES[objective]
