"""The folder of a sweep: ``sweep.json``, one CSV per finished cell, ``results.csv``.

A cell's file is written atomically the moment the cell finishes, so an interrupted sweep
keeps every finished cell and a rerun with the same arguments skips them. ``sweep.json``
holds the sweep's identity (preset, grid, runs, seed, ...): a different sweep is refused
rather than mixed into the folder, and a second sweep into a folder one is writing is
refused by its lock file (``.lock``).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
from pathlib import Path
from typing import IO, Any, Iterable, Iterator, Sequence

import numpy as np
from filelock import FileLock, Timeout

from shoal.engine.core.atomic import atomic_text_writer, atomic_write_text

from .grid import SweepError
from .outcomes import integer_outcomes

MANIFEST = "sweep.json"
RESULTS = "results.csv"
MEDIANS = "medians.csv"
LOCK = ".lock"


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
    if v == int(v) and name in integer_outcomes():
        return str(int(v))
    return f"{v + 0.0:.12g}"


def written(name: str, values: np.ndarray) -> np.ndarray:
    """``values`` as a cell file holds them (:func:`fmt`, read back): what medians are taken of."""
    return np.array([float(s) if s else np.nan for s in (fmt(name, v) for v in np.asarray(values).ravel())])


def cell_rows(prefix: dict[str, str], first_run: int, seed: int,
              columns: dict[str, np.ndarray]) -> tuple[list[str], list[list[str]]]:
    """The header and rows of one cell: its grid values, ``run``, ``seed``, then the outcomes."""
    runs = len(next(iter(columns.values())))
    rows = [[*prefix.values(), str(first_run + r), str(seed), *(fmt(k, v[r]) for k, v in columns.items())]
            for r in range(runs)]
    return [*prefix, "run", "seed", *columns], rows


def write_tidy(fh: IO[str], columns: Sequence[str], rows: Iterable[dict[str, str]]) -> None:
    """The tidy table (``results.csv``): ``columns`` as header, a missing value left empty."""
    w = csv.DictWriter(fh, columns, restval="", lineterminator="\n")
    w.writeheader()
    w.writerows(rows)


def _canonical(obj: Any) -> Any:
    return json.loads(json.dumps(obj))


class SweepDir:
    """``out/sweep.json``, ``out/cells/<cell-id>.csv`` and the assembled tables."""

    def __init__(self, out: Path | str) -> None:
        self.out = Path(out)
        self.cells = self.out / "cells"

    @contextlib.contextmanager
    def locked(self) -> Iterator[None]:
        """Hold the folder's lock file (creating the folder; removed again if nothing else was
        written): another sweep into the folder is refused meanwhile."""
        if self.out.exists() and not self.out.is_dir():
            raise SweepError([f"--out {self.out}: exists and is not a folder"])
        created = not self.out.exists()
        self.out.mkdir(parents=True, exist_ok=True)
        try:
            with FileLock(self.out / LOCK, timeout=0):
                yield
        except Timeout:
            raise SweepError([f"--out {self.out}: another shoal sweep is writing into it; wait for it to finish "
                              "(then rerun to resume) or choose another --out"]) from None
        finally:
            if created and all(p.name == LOCK for p in self.out.iterdir()):  # nothing written: leave no folder
                (self.out / LOCK).unlink(missing_ok=True)
                self.out.rmdir()

    def open(self, identity: dict[str, Any], meta: dict[str, Any]) -> None:
        """Start or resume: refuse a folder holding anything but the same sweep (call it under :meth:`locked`)."""
        identity = _canonical(identity)
        path = self.out / MANIFEST
        if path.is_file():
            old = json.loads(path.read_text(encoding="utf-8")).get("identity")
            if old != identity:
                differ = sorted(k for k in set(identity) | set(old or {}) if (old or {}).get(k) != identity.get(k))
                raise SweepError([f"--out {self.out}: holds a different sweep (differs in: {', '.join(differ)}); "
                                  "rerun with the same arguments to resume, or choose another --out"])
        elif self.out.is_dir() and any(p.name != LOCK for p in self.out.iterdir()):
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
        header, rows = cell_rows(prefix, first_run, seed, columns)
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(header)
        w.writerows(rows)
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
            write_tidy(fh, columns, (row for i in indices for row in self.read_cell(i)[1]))
        return columns

    def write_table(self, name: str, header: Sequence[str], rows: Iterable[Sequence[str]]) -> None:
        with atomic_text_writer(self.out / name) as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(header)
            w.writerows(rows)
