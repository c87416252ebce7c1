"""The folder of a sweep: ``sweep.json``, one CSV per finished cell, ``results.csv``.

A cell's file is written atomically the moment the cell finishes, so an interrupted sweep
keeps every finished cell and a rerun with the same arguments skips them. ``sweep.json``
holds the sweep's identity (preset, grid, runs, seed, ...): a different sweep is refused
rather than mixed into the folder.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any, Iterable, Iterator, Sequence

import numpy as np

from ...core.atomic import atomic_text_writer, atomic_write_text
from .grid import SweepError
from .outcomes import INTEGER

MANIFEST = "sweep.json"
RESULTS = "results.csv"
MEDIANS = "medians.csv"


def cell_id(index: int) -> str:
    """File stem of cell ``index`` (its place in the grid, first axis slowest)."""
    return f"cell-{index:05d}"


def fmt(name: str, v: float) -> str:
    """A CSV cell: integers as such, floats to 12 significant digits, NaN empty, ``inf``."""
    v = float(v)
    if np.isnan(v):
        return ""
    if np.isinf(v):
        return "inf" if v > 0 else "-inf"
    if name in INTEGER and v == int(v):
        return str(int(v))
    return f"{v + 0.0:.12g}"


def _canonical(obj: Any) -> Any:
    return json.loads(json.dumps(obj))


class SweepDir:
    """``out/sweep.json``, ``out/cells/<cell-id>.csv`` and the assembled tables."""

    def __init__(self, out: Path | str) -> None:
        self.out = Path(out)
        self.cells = self.out / "cells"

    def open(self, identity: dict[str, Any], meta: dict[str, Any]) -> None:
        """Start or resume: refuse a folder holding anything but the same sweep."""
        identity = _canonical(identity)
        path = self.out / MANIFEST
        if self.out.exists() and not self.out.is_dir():
            raise SweepError([f"--out {self.out}: exists and is not a folder"])
        if path.is_file():
            old = json.loads(path.read_text(encoding="utf-8")).get("identity")
            if old != identity:
                differ = sorted(k for k in set(identity) | set(old or {}) if (old or {}).get(k) != identity.get(k))
                raise SweepError([f"--out {self.out}: holds a different sweep (differs in: {', '.join(differ)}); "
                                  "rerun with the same arguments to resume, or choose another --out"])
        elif self.out.is_dir() and any(self.out.iterdir()):
            raise SweepError([f"--out {self.out}: is not empty and holds no {MANIFEST}; choose another --out"])
        self.write_manifest({"identity": identity, **meta})
        for stale in self.cells.glob(".*.partial-*"):  # a cell being written when the sweep was killed
            stale.unlink(missing_ok=True)

    def write_manifest(self, data: dict[str, Any]) -> None:
        atomic_write_text(self.out / MANIFEST, json.dumps(data, indent=2, ensure_ascii=False) + "\n")

    def manifest(self) -> dict[str, Any]:
        return json.loads((self.out / MANIFEST).read_text(encoding="utf-8"))

    def path(self, index: int) -> Path:
        return self.cells / f"{cell_id(index)}.csv"

    def finished(self, index: int) -> bool:
        return self.path(index).is_file()

    def write_cell(self, index: int, prefix: dict[str, str], first_run: int, seed: int,
                   columns: dict[str, np.ndarray]) -> None:
        """One row per run: the cell's grid values, ``run``, ``seed``, then the outcomes."""
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([*prefix, "run", "seed", *columns])
        runs = len(next(iter(columns.values())))
        for r in range(runs):
            w.writerow([*prefix.values(), str(first_run + r), str(seed), *(fmt(k, v[r]) for k, v in columns.items())])
        atomic_write_text(self.path(index), buf.getvalue())

    def read_cell(self, index: int) -> tuple[list[str], Iterator[dict[str, str]]]:
        with open(self.path(index), newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
        header = list(rows[0]) if rows else []
        return header, iter(rows)

    def assemble(self, indices: Sequence[int]) -> list[str]:
        """Concatenate the cells' files into ``results.csv`` (the union of their columns,
        in order of appearance), streaming; returns the columns."""
        columns: list[str] = []
        for i in indices:
            with open(self.path(i), newline="", encoding="utf-8") as fh:
                for name in next(csv.reader(fh)):
                    if name not in columns:
                        columns.append(name)
        with atomic_text_writer(self.out / RESULTS) as fh:
            w = csv.DictWriter(fh, columns, restval="", lineterminator="\n")
            w.writeheader()
            for i in indices:
                w.writerows(self.read_cell(i)[1])
        return columns

    def write_table(self, name: str, header: Sequence[str], rows: Iterable[Sequence[str]]) -> None:
        with atomic_text_writer(self.out / name) as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(header)
            w.writerows(rows)
