"""Many seeded runs at once, in memory: :func:`run` (one preset, ``shoal run``'s numbers) and
:func:`sweep` (a grid of preset fields, ``shoal sweep``'s numbers)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, NamedTuple, Sequence

from shoal.presets.models import Scenario

from .scene import Scene, scenario_of
from .tables import as_table


class Tables(NamedTuple):
    """What :func:`run` returns with ``trajectories=True``: both of ``shoal run``'s tables."""

    metrics: Any
    trajectories: Any


def run(preset: str | Path | Mapping[str, Any] | Scenario = "default", overrides: Sequence[str] = (), *,
        pandas: bool | None = None, trajectories: bool = False, **sections: Any) -> Any:
    """Run ``preset`` (with overrides, as :func:`~shoal.api.scene.make` takes them) for its
    ``sim.steps`` and return every step's metrics: the rows ``shoal run`` writes to
    ``metrics.csv``, as a table. With ``trajectories=True``, :class:`Tables` of the metrics and
    of every robot at every step (``trajectories.csv``'s rows)."""
    scene = Scene(scenario_of(preset, overrides, **sections), trajectories=trajectories)
    scene.run()
    if trajectories:
        return Tables(scene.metrics(pandas=pandas), scene.trajectories(pandas=pandas))
    return scene.metrics(pandas=pandas)


def sweep(preset: str | Path | Mapping[str, Any] | Scenario = "default",
          grid: Mapping[str, Sequence[Any]] | Sequence[str] = (), *, runs: int | None = None,
          seed: int | None = None, steps: int | None = None, overrides: Sequence[str] = (), workers: int = 1,
          pandas: bool | None = None) -> Any:
    """Seeded runs of ``preset`` over a grid of preset fields, in memory: one row per cell and
    run with the grid's values, ``run``, ``seed`` and each run's outcomes (its last metric row,
    the peak speed, …): the numbers ``shoal sweep`` writes to ``results.csv``.

    >>> table = sweep("course-dvc", {"controller.alpha": [0.5, 0.9]}, runs=4, steps=50)
    """
    from shoal.studies.sweep.run import plan_sweep, sweep_rows  # (every kind's outcomes: loaded by a sweep only)

    raw = preset.model_dump(mode="json") if isinstance(preset, Scenario) else \
        dict(preset) if isinstance(preset, Mapping) else preset
    plan = plan_sweep(raw, grid, runs=runs, seed=seed, steps=steps, sets=overrides)
    return as_table(sweep_rows(plan, workers=workers), pandas=pandas)
