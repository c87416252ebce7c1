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


class BlockDraws:
    """U(0,1) draws of ``ticks`` ticks of every run taken in one call a run: run r's block holds
    what ``ticks`` calls of ``rngs[r].random(shape)`` would give one after another (a generator
    fills doubles in stream order), so the stream is the same as one call a tick.

    The generators run ahead of the draws used: :meth:`settle` puts each back where one call a
    tick would have left it, before anything else draws from it. It steps PCG64 back by the
    unused draws (one 64-bit output a double), so the generators must draw doubles only (a
    32-bit draw's buffered half would be dropped)."""

    def __init__(self, rngs: list[np.random.Generator], shape: tuple[int, ...], ticks: int) -> None:
        self.rngs, self.shape, self.ticks, self.used = rngs, shape, ticks, 0
        self.draws = np.empty((len(rngs), ticks) + shape)  # (R, ticks, *shape)
        for g, out in zip(rngs, self.draws):
            g.random(out=out)

    def take(self) -> int:
        """The index (into axis 1 of :attr:`draws`) of the next tick's draws."""
        self.used += 1
        return self.used - 1

    @property
    def spent(self) -> bool:
        return self.used == self.ticks

    def settle(self) -> None:
        """Step every generator back over the unused draws (whoever draws next gets them)."""
        unused = (self.ticks - self.used) * int(np.prod(self.shape))
        if unused:
            for g in self.rngs:
                g.bit_generator.advance(-unused)  # type: ignore[attr-defined]  # (PCG64's; numpy's stubs lack it)
        self.used = self.ticks
