"""What a run costs: the one place that turns steps × robots × runs × kind into CPU seconds.

Batches of runs are sized by it (:func:`~.experiments.runner.iter_jobs`), and the app checks
every path a page can ask for work through it (a live scene, a sweep of any field, a replay,
a Share page, ``shoal export-replay``; ``shoal.app.limits``).

CPU seconds on one core for one run of a scenario over ``steps`` ticks, from the per-tick
costs the benchmarks measure (``benchmarks/README.md``): a per-run share of each tick (the
numpy calls and generator draws of a batched tick), a per-robot share and, where every
ordered pair of robots is ranged and localised (SLO), a per-pair share. It only has to rank,
split and bound work sensibly; it is never a promise, and results never depend on it.
"""

from __future__ import annotations

from dataclasses import dataclass

from shoal.presets.kinds import kind_for
from shoal.presets.models import Scenario


@dataclass(frozen=True)
class TickCost:
    """CPU seconds of one tick of one run: ``run`` once, ``robot`` per robot, ``pair`` per
    ordered pair of robots."""

    run: float
    robot: float
    pair: float = 0.0


# The built-in kinds' constants, in one table: engine kind, or kind/variant where a setting
# changes the cost. A kind not in it (a plug-in's) is priced by its registry entry's ``cost``
# (presets/kinds.py: CPU s per run and tick, per robot and tick).
TICK_COSTS: dict[str, TickCost] = {
    "swarm": TickCost(run=2e-6, robot=0.1e-6),
    "fleet": TickCost(run=30e-6, robot=3e-6),
    "fleet/physics": TickCost(run=30e-6, robot=15e-6),  # ten pymunk substeps a tick, every space read in one call
    "sonar": TickCost(run=30e-6, robot=10e-6),  # waveforms: each robot's hydrophone spectra
    "sonar/surrogate": TickCost(run=30e-6, robot=1e-6),
    "slo_swarm": TickCost(run=40e-6, robot=0.0, pair=0.1e-6),
}
SLO_HOST = TickCost(run=0.0, robot=0.0, pair=0.1e-6)  # a swarm, fleet or sonar on SLO positions adds its pairs


def variant(scenario: Scenario) -> str:
    """The key of ``scenario``'s row in :data:`TICK_COSTS` (a plug-in kind: its name)."""
    kind = kind_for(scenario).name
    if kind == "fleet" and scenario.robot.motion == "physics":
        return "fleet/physics"
    if kind == "sonar" and scenario.acoustics is not None and scenario.acoustics.mode != "waveform":
        return "sonar/surrogate"
    return kind


def tick_cost(scenario: Scenario, robots: int | None = None) -> float:
    """Estimated CPU seconds of one tick of one run of ``scenario`` (with ``robots`` robots:
    by default its ``sim.robots``)."""
    n = scenario.sim.robots if robots is None else robots
    key = variant(scenario)
    row = TICK_COSTS.get(key) or TickCost(*kind_for(scenario).cost)
    pair = row.pair or (SLO_HOST.pair if scenario.slo is not None else 0.0)
    return row.run + n * row.robot + n * n * pair


def run_cost(scenario: Scenario, steps: int) -> float:
    """Estimated CPU seconds of one run of ``scenario`` for ``steps`` ticks."""
    return max(steps, 1) * tick_cost(scenario)


@dataclass(frozen=True)
class Cost:
    """``runs`` runs of ``steps`` ticks of ``robots`` robots of one kind (``variant``), and
    their estimated CPU ``seconds``."""

    variant: str
    robots: int
    steps: int
    runs: int
    seconds: float

    def describe(self) -> str:
        return (f"{self.steps:,} steps × {self.robots:,} robots × {self.runs:,} runs of a {self.variant} scene: "
                f"an estimated {_duration(self.seconds)} of CPU")


def cost(scenario: Scenario, *, steps: int | None = None, runs: int | None = None) -> Cost:
    """The cost of ``runs`` runs (default ``sim.runs``) of ``steps`` ticks (default ``sim.steps``)."""
    steps = scenario.sim.steps if steps is None else int(steps)
    runs = scenario.sim.runs if runs is None else int(runs)
    return Cost(variant(scenario), scenario.sim.robots, steps, runs, runs * run_cost(scenario, steps))


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"
