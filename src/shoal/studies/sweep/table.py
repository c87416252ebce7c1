"""The finished cells of a sweep held in memory (the app's experiments write no files): the
tidy table, byte for byte the ``results.csv`` of ``shoal sweep`` over the same cells, and
per cell the median of an outcome with its 95 % confidence interval.

Cells arrive from one thread while others read: every access holds the table's lock.
"""

from __future__ import annotations

import io
import threading

import numpy as np

from .outcomes import CellBatch, median, median_interval
from .plan import SweepPlan
from .store import cell_rows, write_tidy, written


class CellTable:
    """Finished cells of ``plan`` by index, in memory."""

    def __init__(self, plan: SweepPlan) -> None:
        self.plan = plan
        self._cells: dict[int, CellBatch] = {}
        self._stats: dict[tuple[int, str], tuple[float, float, float]] = {}  # a finished cell's never change
        self._lock = threading.Lock()

    def add(self, index: int, batch: CellBatch) -> None:
        with self._lock:
            self._cells[index] = batch

    def finished(self) -> list[int]:
        """The indices of the finished cells, in grid order."""
        with self._lock:
            return sorted(self._cells)

    def __len__(self) -> int:
        with self._lock:
            return len(self._cells)

    def outcome_names(self) -> list[str]:
        """The outcome columns of the finished cells, in order of appearance."""
        with self._lock:
            names: list[str] = []
            for i in sorted(self._cells):
                names += [n for n in self._cells[i].columns if n not in names]
            return names

    def runs_of(self, index: int, name: str) -> np.ndarray:
        """Outcome ``name`` of every run of a finished cell, as the tidy table writes it
        (NaN where missing)."""
        with self._lock:
            batch = self._cells[index]
        col = batch.columns.get(name)
        return written(name, col) if col is not None else np.full(batch.runs, np.nan)

    def csv(self) -> str:
        """The tidy table of the finished cells (``results.csv``: one row per cell × run)."""
        with self._lock:
            cells = sorted(self._cells.items())
        columns: list[str] = []
        rows: list[dict[str, str]] = []
        for i, batch in cells:
            header, values = cell_rows(self.plan.prefix(i), batch.first_run, self.plan.scenario(i).sim.seed,
                                       batch.columns)
            columns += [c for c in header if c not in columns]
            rows += [dict(zip(header, r)) for r in values]
        buf = io.StringIO()
        write_tidy(buf, columns, rows)
        return buf.getvalue()

    def summary(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Median, low and high end of its 95 % interval, each of the grid's shape (one
        dimension per axis); NaN in cells not finished (or too few runs for an interval)."""
        shape = self.plan.shape
        out = [np.full(shape, np.nan) for _ in range(3)]
        for i in self.finished():
            stats = self._stats.get((i, name))
            if stats is None:
                v = self.runs_of(i, name)
                stats = self._stats[(i, name)] = (median(name, v), *median_interval(name, v))
            where = np.unravel_index(i, shape)
            out[0][where], out[1][where], out[2][where] = stats
        return out[0], out[1], out[2]
