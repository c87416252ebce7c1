"""Per-run outcome of one sweep cell: the final row of the metric table plus a few
whole-run summaries, for every scene kind (Chapter 3 swarm, fleet, acoustic swarm, SLO).

A :class:`CellJob` carries its fully resolved scenario (JSON), so a worker on another
machine needs neither the preset file nor the ``--grid`` arguments. Only (runs,) arrays
leave the worker: a cell never holds trajectories.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from shoal.engine.core.recorder import metric_table
from shoal.engine.core.schema import Column, Schema
from shoal.presets.build import build
from shoal.presets.kinds import integer_columns
from shoal.presets.models import Scenario

from ..cost import run_cost
from ..experiments.schedulers import check_interrupt
from ..medians import FIRST_PASSAGE, MEDIAN_LEVEL, median, median_interval  # noqa: F401 (the Sweep tab's names)

# The per-run outcomes a cell adds to its kind's last metric row.
SWEEP_COLUMNS: Schema = (
    Column("peak_speed", "m/s", "float", "highest speed of any robot over the run"),
    Column("time_to_converge_s", "s", "float", "an acoustic swarm's steps_to_converge × Δt (empty if it never did)"),
)


def integer_outcomes() -> frozenset[str]:
    """The outcomes that are whole numbers: the int metric columns of every kind (their schemas,
    :mod:`shoal.presets.kinds`) but ``run``, which a cell file writes itself."""
    return _integer_outcomes(integer_columns())


@functools.lru_cache(maxsize=4)
def _integer_outcomes(columns: frozenset[str]) -> frozenset[str]:
    return columns - {"run"}


@dataclass(frozen=True)
class CellJob:
    """``runs`` seeded runs (run i = child i of ``SeedSequence(seed)``) of one cell. Picklable."""

    key: int  # the cell's index in the grid
    scenario: str  # resolved Scenario as JSON
    seed: int
    runs: int
    steps: int

    @property
    def cost(self) -> float:
        """Estimated CPU seconds of one run (:func:`~shoal.studies.cost.run_cost`)."""
        return run_cost(Scenario.model_validate_json(self.scenario), self.steps)


@dataclass
class CellBatch:
    """Outcome columns, each (runs,), of runs ``first_run …`` of one cell."""

    first_run: int
    columns: dict[str, np.ndarray]

    @property
    def runs(self) -> int:
        return len(next(iter(self.columns.values())))


def simulate_cell(job: CellJob, first_run: int, runs: int) -> CellBatch:
    """Advance runs ``first_run … first_run + runs − 1`` of a cell for ``job.steps`` ticks
    (an acoustic swarm whose runs all stopped at convergence ends early) and keep, per
    run: the last metric row, the highest speed of any robot over the run (``peak_speed``)
    and, for an acoustic swarm, the time to convergence in seconds (``time_to_converge_s``,
    empty if none)."""
    scenario = Scenario.model_validate_json(job.scenario)
    sim = build(scenario, runs=runs, seed=job.seed, first_run=first_run)

    def speed() -> np.ndarray:
        return np.linalg.norm(sim.state.u, axis=-1).max(axis=1)

    peak = speed()
    info = sim.info()
    running = getattr(sim, "running", None)  # (an acoustic swarm's runs stop at convergence)
    for _ in range(job.steps):
        if running is not None and not np.any(sim.running):  # type: ignore[attr-defined]
            break
        check_interrupt()  # a cancelled experiment stops here, within a fraction of a second
        info = sim.step()
        peak = np.maximum(peak, speed())
    table = metric_table(sim.state, info, sim.t)
    table.pop("run")
    cols = {"step": table.pop("step"), "t": table.pop("t"), "peak_speed": peak, **table}
    if "steps_to_converge" in cols:
        first = np.asarray(cols["steps_to_converge"], dtype=float)
        first[first < 0] = np.nan
        cols["steps_to_converge"] = first
        cols["time_to_converge_s"] = first * sim.dt
    return CellBatch(first_run, {k: np.asarray(v, dtype=float).copy() for k, v in cols.items()})


def merge(parts: Sequence[CellBatch]) -> CellBatch:
    """Glue chunks of consecutive runs (in any order) into one batch."""
    parts = sorted(parts, key=lambda b: b.first_run)
    expected = parts[0].first_run
    for b in parts:
        if b.first_run != expected or list(b.columns) != list(parts[0].columns):
            raise ValueError("chunks must be consecutive runs of one cell")
        expected += b.runs
    names = list(parts[0].columns)
    return CellBatch(parts[0].first_run, {k: np.concatenate([b.columns[k] for b in parts]) for k in names})
