"""What one run costs, roughly, so batches of runs can be sized by cost rather than by count
(:func:`~.experiments.runner.iter_jobs`).

CPU seconds on one core for one run of a scenario over ``steps`` ticks, from the per-tick
costs the benchmarks measure (``benchmarks/README.md``): a per-run share of each tick (the
numpy calls and generator draws of a batched tick) plus a per-robot share. It only has to
rank and split work sensibly; it is never a promise, and results never depend on it.
"""

from __future__ import annotations

from shoal.presets.kinds import kind_for
from shoal.presets.models import Scenario

RUN_TICK = {"swarm": 2e-6, "fleet": 30e-6, "sonar": 30e-6, "slo_swarm": 40e-6}  # s per run and tick
ROBOT_TICK = {"swarm": 0.1e-6, "fleet": 3e-6, "sonar": 10e-6}  # s per robot and tick
PHYSICS_ROBOT_TICK = 15e-6  # a pymunk fleet: ten substeps a tick, every space read and written in one call each
SURROGATE_ROBOT_TICK = 1e-6  # the acoustic surrogate instead of waveforms
PAIR_TICK = 0.1e-6  # SLO: every ordered pair is ranged and localised each tick


def run_cost(scenario: Scenario, steps: int) -> float:
    """Estimated CPU seconds of one run of ``scenario`` for ``steps`` ticks."""
    entry = kind_for(scenario)  # a kind not priced here (a plug-in's): its registry entry's price
    kind = entry.name
    n = scenario.sim.robots
    per_robot = ROBOT_TICK.get(kind, 0.0 if kind in RUN_TICK else entry.cost[1])
    if kind == "fleet" and scenario.robot.motion == "physics":
        per_robot = PHYSICS_ROBOT_TICK
    if kind == "sonar" and scenario.acoustics is not None and scenario.acoustics.mode != "waveform":
        per_robot = SURROGATE_ROBOT_TICK
    pairs = n * n * PAIR_TICK if scenario.slo is not None else 0.0  # the SLO swarm, or a host on SLO positions
    return max(steps, 1) * (RUN_TICK.get(kind, entry.cost[0]) + n * per_robot + pairs)
