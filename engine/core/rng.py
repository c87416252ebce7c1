"""The seeding scheme of every engine: run i of ``seed`` draws from child i of
``SeedSequence(seed)``, so a run is the same whether it is simulated alone (``first_run=i,
runs=1``), in a batch or in another process.

An SLO run splits its draws further: component k draws from child k of run
i's sequence, spawn key (i, k), so each component (motion, sensors, PSO, …) keeps its own
stream whatever the others consume.
"""

from __future__ import annotations

import numpy as np


def run_generators(seed: int, first_run: int, runs: int) -> list[np.random.Generator]:
    """One generator per run: run i draws from child i of ``SeedSequence(seed)``."""
    children = range(first_run, first_run + runs)
    return [np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(i,)))) for i in children]


COMPONENTS = ("init", "permanent", "range", "odometry", "topology", "entry", "pso", "motion", "fitness")

Streams = dict[str, list[np.random.Generator]]


def component_generators(seed: int, first_run: int, runs: int, offset: int = 0) -> Streams:
    """One generator per run for every component; ``offset`` shifts the component keys
    (an SLO layer inside another simulation uses its own block of children)."""
    out: Streams = {}
    for k, name in enumerate(COMPONENTS):
        out[name] = [
            np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(i, offset + k))))
            for i in range(first_run, first_run + runs)
        ]
    return out
