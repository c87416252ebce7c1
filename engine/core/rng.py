"""Independent random streams of an SLO run (spec §15.4 item 6): run i of ``seed`` draws
component k from child k of ``SeedSequence(seed, spawn_key=(i,))``, i.e. spawn key (i, k),
so a run is identical alone or in a batch and each component (motion, sensors, PSO, …)
keeps its own stream whatever the others consume."""

from __future__ import annotations

import numpy as np

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
