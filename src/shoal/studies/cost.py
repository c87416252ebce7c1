"""What a run costs: the one place that turns steps × robots × runs × kind into CPU seconds.

Batches of runs are sized by it (:func:`~.experiments.runner.iter_jobs`), and the app checks
every path a page can ask for work through it (a live scene, a sweep of any field, a replay,
a Share page, ``shoal export-replay``; ``shoal.app.limits``).

CPU seconds on one core for one run of a scenario over ``steps`` ticks, from the per-tick
costs the benchmarks measure (``benchmarks/bench_costs.py``, ``benchmarks/README.md``): a
per-run share of each tick (the numpy calls and generator draws of a batched tick), and a
share for every term that scales the work: robots, robots × ``sim.d`` (the Chapter 3 swarm),
ordered pairs of robots where each is ranged and localised (SLO), the world's obstacles, and
a waveform sonar's band bins and lags; plus laying out the world (a forest of 17,000 trees
takes seconds), once per engine. It only has to rank, split and bound work sensibly; it is
never a promise, and results never depend on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shoal.presets.kinds import kind_for
from shoal.presets.models import Scenario

# The quantities a tick's work scales with, each priced by one constant of a kind's row.
TERMS = ("run", "robot", "pair", "robot_dim", "obstacle", "bin", "bin_lag", "fft")


@dataclass(frozen=True)
class TickCost:
    """CPU seconds of one tick of one run: ``run`` once, ``robot`` per robot, ``pair`` per
    ordered pair of robots, ``robot_dim`` per robot and dimension of ``sim.d`` (the Chapter 3
    swarm's arrays are robots × d), ``obstacle`` per obstacle of the world (the fleet's
    sensing), and for waveform acoustics ``bin`` per robot and band bin (its spectra),
    ``bin_lag`` per robot, bin and lag searched (the cross-correlation, K × L) and ``fft`` per
    robot and n·log2(n) of the full-lag inverse FFT of n points."""

    run: float
    robot: float
    pair: float = 0.0
    robot_dim: float = 0.0
    obstacle: float = 0.0
    bin: float = 0.0
    bin_lag: float = 0.0
    fft: float = 0.0


# The built-in kinds' constants, in one table: engine kind, or kind/variant where a setting
# changes the cost. A kind not in it (a plug-in's) is priced by its registry entry's ``cost``
# (presets/kinds.py: CPU s per run and tick, per robot and tick). Fitted to the cases of
# ``benchmarks/bench_costs.py --fit`` (measured against estimated: benchmarks/README.md).
# (Rounded up where the fit is low for the largest cases: a price bounds work.)
TICK_COSTS: dict[str, TickCost] = {
    "swarm": TickCost(run=20e-6, robot=0.02e-6, robot_dim=40e-9),  # arrays of robots × d
    "fleet": TickCost(run=100e-6, robot=5e-6, obstacle=5e-9),
    "fleet/physics": TickCost(run=1e-3, robot=15e-6, obstacle=5e-9),  # ten pymunk substeps a tick
    "sonar": TickCost(run=800e-6, robot=7e-6, bin=90e-9, bin_lag=0.5e-9, fft=2e-9),  # waveforms: spectra, lags
    "sonar/surrogate": TickCost(run=400e-6, robot=35e-6),
    "slo_swarm": TickCost(run=50e-6, robot=10e-6, pair=15e-9),
}
SLO_HOST = TickCost(run=80e-6, robot=10e-6, pair=15e-9)  # what a swarm, fleet or sonar on SLO positions adds

# Laying out a world, once per engine built (a live scene, each cell of a sweep): a forest
# draws trees until it covers its density (at most FOREST_TRIES draws), each checked against
# the trees so far; a course or an empty arena costs next to nothing.
WORLD_SECONDS = 2e-3
TREE_SECONDS = 250e-6  # per tree a forest is expected to hold
FOREST_TRIES = 20_000  # world.forest's max_tries
MEAN_TREE_AREA = 1.016  # m²: π E[r²] for r ~ U(0.3, 0.8) m, world.forest's radii


def variant(scenario: Scenario) -> str:
    """The key of ``scenario``'s row in :data:`TICK_COSTS` (a plug-in kind: its name)."""
    kind = kind_for(scenario).name
    if kind == "fleet" and scenario.robot.motion == "physics":
        return "fleet/physics"
    if kind == "sonar" and scenario.acoustics is not None and scenario.acoustics.mode != "waveform":
        return "sonar/surrogate"
    return kind


def forest_trees(scenario: Scenario) -> float:
    """About how many trees ``scenario``'s forest holds (0: no forest)."""
    w = scenario.world
    if w is None or w.kind != "forest":
        return 0.0
    return float(min(w.density * w.width * w.width / MEAN_TREE_AREA, FOREST_TRIES))


def obstacles(scenario: Scenario) -> float:
    """About how many obstacles ``scenario``'s world holds (its own list, or its forest's trees)."""
    w = scenario.world
    if w is None:
        return 0.0
    return float(len(w.obstacles)) if w.obstacles is not None else forest_trees(scenario)


def _waveform(scenario: Scenario) -> tuple[float, float, float]:
    """(band bins K, K × lags searched, n·log2 n of the full-lag FFT) of a waveform sonar scene."""
    a = scenario.acoustics
    if a is None or a.mode != "waveform":
        return 0.0, 0.0, 0.0
    from shoal.engine.acoustics.band import Band
    from shoal.engine.acoustics.receiver import _fft_size, lag_samples
    from shoal.engine.acoustics.strategies import STRATEGIES

    try:
        band = Band(f_c=a.f_c, Q=a.Q, tbp=a.tbp, c=a.c, fs=a.fs)
        k = float(band.K)
        two = a.algorithm in STRATEGIES and STRATEGIES[a.algorithm].hydrophones == 2
        if not two:
            return k, 0.0, 0.0
        if a.full_lag:
            n = float(_fft_size(band))
            return k, 0.0, n * math.log2(max(n, 2.0))
        lags = float(lag_samples(band, a.d_over_lambda * a.c / a.f_c).size)
        return k, k * lags, 0.0
    except (ValueError, ArithmeticError):  # (a band the engine refuses: it is refused when built)
        return 0.0, 0.0, 0.0


def quantities(scenario: Scenario, robots: int | None = None) -> dict[str, float]:
    """How much of each of :data:`TERMS` one tick of one run of ``scenario`` holds."""
    n = float(scenario.sim.robots if robots is None else robots)
    k, k_lags, fft = _waveform(scenario)
    return {"run": 1.0, "robot": n, "pair": n * n, "robot_dim": n * scenario.sim.d, "obstacle": obstacles(scenario),
            "bin": n * k, "bin_lag": n * k_lags, "fft": n * fft}


def shares(scenario: Scenario, robots: int | None = None) -> dict[str, float]:
    """Estimated CPU seconds of one tick of one run of ``scenario``, term by term (:data:`TERMS`)."""
    key = variant(scenario)
    row = TICK_COSTS.get(key) or TickCost(*kind_for(scenario).cost[:2])
    if scenario.slo is not None and key != "slo_swarm":
        row = TickCost(*(getattr(row, t) + getattr(SLO_HOST, t) for t in TERMS))
    q = quantities(scenario, robots)
    return {term: getattr(row, term) * q[term] for term in TERMS}


# The preset fields that set each term, for a refusal to name (the largest share's).
FIELDS = {"run": "sim.robots", "robot": "sim.robots", "pair": "sim.robots", "robot_dim": "sim.d",
          "obstacle": "world.obstacles", "bin": "acoustics.tbp", "bin_lag": "acoustics.tbp",
          "fft": "acoustics.full_lag"}


def costliest_field(scenario: Scenario) -> str:
    """The preset field behind the largest share of ``scenario``'s tick."""
    parts = shares(scenario)
    return FIELDS[max(parts, key=lambda term: parts[term])]


def tick_cost(scenario: Scenario, robots: int | None = None) -> float:
    """Estimated CPU seconds of one tick of one run of ``scenario`` (with ``robots`` robots:
    by default its ``sim.robots``)."""
    return sum(shares(scenario, robots).values())


def world_cost(scenario: Scenario) -> float:
    """Estimated CPU seconds of laying out ``scenario``'s world, once per engine built (0: none)."""
    if scenario.world is None:
        return 0.0
    return WORLD_SECONDS + TREE_SECONDS * forest_trees(scenario)


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
    world: float = 0.0  # of ``seconds``: laying out its world
    d: int = 2

    def describe(self) -> str:
        dims = f" in {self.d:,} dimensions" if self.d > 2 else ""
        world = f", {_duration(self.world)} of it to lay out its world" if self.world >= 0.05 * self.seconds > 0 else ""
        return (f"{self.steps:,} steps × {self.robots:,} robots × {self.runs:,} runs of a {self.variant} scene{dims}: "
                f"an estimated {_duration(self.seconds)} of CPU{world}")


def cost(scenario: Scenario, *, steps: int | None = None, runs: int | None = None) -> Cost:
    """The cost of ``runs`` runs (default ``sim.runs``) of ``steps`` ticks (default ``sim.steps``),
    their world laid out once (one engine runs them, batched)."""
    steps = scenario.sim.steps if steps is None else int(steps)
    runs = scenario.sim.runs if runs is None else int(runs)
    world = world_cost(scenario)
    return Cost(variant(scenario), scenario.sim.robots, steps, runs, runs * run_cost(scenario, steps) + world, world,
                scenario.sim.d)


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    return f"{seconds / 3600:.3g} h"
