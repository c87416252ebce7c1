"""A validated sweep: the base scenario, the axes, one resolved scenario per cell, and the
seeded jobs that simulate them.

``shoal sweep`` and the app's Experiment tab both build their cells here, so the same grid
gives the same jobs (resolved scenario, seed, runs, steps) and so the same per-run outcomes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

from shoal.presets.io import PresetError, validate
from shoal.presets.models import Scenario

from .grid import Axis, SweepError, cell_problems, cells, check_cells, label
from .outcomes import CellJob


@dataclass(frozen=True)
class SweepPlan:
    """Every cell of a grid, validated; cell ``i`` is the ``i``-th of :func:`~.grid.cells`
    (first axis slowest). The runs per cell are the base's ``sim.runs``; a cell's seed and
    steps are its own ``sim.seed`` and ``sim.steps`` (the base's unless gridded). A plan
    resolved with ``skip_invalid`` leaves out the cells the model refuses (``scenarios[i]``
    None, ``skipped[i]`` why); it runs the others."""

    base: Scenario
    axes: tuple[Axis, ...]
    scenarios: tuple[Scenario | None, ...]
    labels: tuple[tuple[str, ...], ...] = field(repr=False)  # per cell, the label of each axis' value
    skipped: dict[int, tuple[str, ...]] = field(default_factory=dict)  # cell → the model's messages

    @classmethod
    def resolve(cls, base_raw: dict[str, Any], axes: Sequence[Axis], where: str = "--grid cell",
                skip_invalid: bool = False) -> SweepPlan:
        """Validate the base and every cell (:class:`SweepError` names each bad field and the
        first cell it occurs in, after ``where``; with ``skip_invalid`` only when no cell is left)."""
        try:
            base = validate(base_raw)
        except PresetError as err:
            raise SweepError(err.messages) from None
        checked = check_cells(base_raw, axes)
        problems = cell_problems(axes, checked, where)
        valid = [sc if isinstance(sc, Scenario) else None for sc in checked]
        if problems and (not skip_invalid or all(sc is None for sc in valid)):
            raise SweepError(problems)
        skipped = {i: tuple(r.messages) for i, r in enumerate(checked) if isinstance(r, PresetError)}
        labels = tuple(tuple(label(v) for v in values) for values in cells(axes))
        return cls(base, tuple(axes), tuple(valid), labels, skipped)

    @property
    def runnable(self) -> tuple[int, ...]:
        """The cells that run (all but the skipped ones), in grid order."""
        return tuple(i for i, sc in enumerate(self.scenarios) if sc is not None)

    def scenario(self, index: int) -> Scenario:
        """Cell ``index``'s scenario (:class:`SweepError` for a skipped cell)."""
        sc = self.scenarios[index]
        if sc is None:
            raise SweepError([f"cell {index + 1} was skipped: " + "; ".join(self.skipped.get(index, ()))])
        return sc

    @property
    def runs(self) -> int:
        return self.base.sim.runs

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a.values) for a in self.axes)

    @property
    def keys(self) -> tuple[str, ...]:
        return tuple(a.key for a in self.axes)

    def __len__(self) -> int:
        return len(self.scenarios)

    def prefix(self, index: int) -> dict[str, str]:
        """The grid values of cell ``index`` by key, as the tidy table writes them."""
        return dict(zip(self.keys, self.labels[index]))

    def job(self, index: int) -> CellJob:
        """The seeded runs of cell ``index`` (run i = child i of ``SeedSequence(seed)``)."""
        sc = self.scenario(index)
        return CellJob(index, sc.model_dump_json(), sc.sim.seed, self.runs, sc.sim.steps)
