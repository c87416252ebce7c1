"""``shoal sweep``: seeded runs of a preset over a grid of field values, resumable.

Every cell of the grid runs the same ``runs`` seeded runs (run i = child i of
``SeedSequence(seed)``, as everywhere in Shoal, so cells share their random draws) on a
local process pool or a Dask cluster. Each finished cell is saved at once; at the end the
cells are assembled into ``results.csv`` (one row per cell and run), ``medians.csv`` (one
row per cell) and pictures of the medians.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from shoal import __version__
from shoal.presets.io import PresetError, apply_overrides, read_raw, validate

from ..experiments.runner import Simulate, iter_jobs
from ..experiments.schedulers import Scheduler
from . import outcomes
from .grid import Axis, SweepError, cells, check_axes, parse_axes
from .plan import SweepPlan
from .plots import plot_medians
from .store import MEDIANS, RESULTS, SweepDir, cell_id, fmt

NOT_MEDIANS = frozenset({"run", "seed", "step", "t"})


@dataclass
class SweepReport:
    out: Path
    cells: int
    computed: int  # cells simulated by this call (the others were already in the folder)
    runs: int
    columns: list[str]
    plots: list[str]


def _fixed(sets: Sequence[str], runs: int | None, seed: int | None, steps: int | None) -> list[str]:
    extra = [f"{k}={v}" for k, v in (("sim.runs", runs), ("sim.seed", seed), ("sim.steps", steps)) if v is not None]
    return [*sets, *extra]


def _key(override: str) -> str:
    return override.partition("=")[0].strip()


def _medians(store: SweepDir, axes: Sequence[Axis], n_cells: int) -> tuple[list[str], dict[str, np.ndarray]]:
    """Median over runs of every outcome, per cell, read back from the cell files."""
    shape = tuple(len(a.values) for a in axes)
    keys = {a.key for a in axes}
    names: list[str] = []
    medians: dict[str, np.ndarray] = {}
    for i in range(n_cells):
        header, cell = store.read_cell(i)
        rows = list(cell)
        for name in header:
            if name in keys or name in NOT_MEDIANS:
                continue
            if name not in medians:
                names.append(name)
                medians[name] = np.full(shape, np.nan)
            v = np.array([float(r[name]) if r[name] not in ("", None) else np.nan for r in rows])
            medians[name][np.unravel_index(i, shape)] = outcomes.median(name, v)
    return names, medians


def plan_sweep(preset: str | Path | Mapping[str, Any], grid: Sequence[str] | Mapping[str, Sequence[Any]], *,
               runs: int | None = None, seed: int | None = None, steps: int | None = None,
               sets: Sequence[str] = ()) -> SweepPlan:
    """The validated cells of a sweep: ``preset`` (a name, a file or a raw preset dict) with
    ``sets`` and the ``runs``/``seed``/``steps`` given, over ``grid`` (``--grid`` strings, or
    dotted key → values). :class:`SweepError` names every bad argument or field."""
    fixed = _fixed(sets, runs, seed, steps)
    try:
        raw = dict(preset) if isinstance(preset, Mapping) else read_raw(preset)
        base_raw = apply_overrides(raw, fixed)
        validate(base_raw)  # a bad preset is named before the grid
    except PresetError as err:
        raise SweepError(err.messages) from None
    if isinstance(grid, Mapping):
        axes = check_axes([Axis(str(k), tuple(v)) for k, v in grid.items()], [_key(f) for f in fixed])
    else:
        axes = parse_axes(grid, [_key(f) for f in fixed])
    return SweepPlan.resolve(base_raw, axes)


def sweep_rows(plan: SweepPlan, *, workers: int = 1, scheduler: Scheduler | None = None,
               simulate: Simulate = outcomes.simulate_cell) -> dict[str, list[Any]]:
    """Every cell of ``plan`` simulated in memory, as the columns of ``results.csv``: the grid
    values (as given), ``run``, ``seed``, then the outcomes (full precision; the file holds them to
    12 significant digits), a cell without an outcome another has: NaN."""
    batches: dict[int, outcomes.CellBatch] = dict(iter_jobs(
        [plan.job(i) for i in range(len(plan))], workers=workers, scheduler=scheduler, simulate=simulate,
        merge=outcomes.merge, desc="sweep"))
    names: list[str] = []
    for i in range(len(plan)):
        names += [n for n in batches[i].columns if n not in names]
    table: dict[str, list[Any]] = {k: [] for k in (*plan.keys, "run", "seed", *names)}
    for i, values in enumerate(cells(plan.axes)):
        batch, sc = batches[i], plan.scenario(i)
        for r in range(batch.runs):
            for key, v in zip(plan.keys, values):
                table[key].append(v)
            table["run"].append(batch.first_run + r)
            table["seed"].append(sc.sim.seed)
            for n in names:
                col = batch.columns.get(n)
                table[n].append(float(col[r]) if col is not None else float("nan"))
    return table


def run_sweep(
    preset: str | Path,
    grid: Sequence[str],
    out: Path | str,
    *,
    runs: int | None = None,
    seed: int | None = None,
    steps: int | None = None,
    sets: Sequence[str] = (),
    workers: int = 1,
    scheduler: Scheduler | None = None,
    progress: bool = True,
    simulate: Simulate = outcomes.simulate_cell,
) -> SweepReport:
    """Sweep ``preset`` over the ``--grid`` axes ``grid`` into ``out``.

    ``runs``/``seed``/``steps`` default to the preset's ``sim`` fields; ``sets`` are
    ``--set`` overrides of every cell. Every argument and every cell is validated before
    anything runs (:class:`SweepError` names the bad field). A folder holding the same
    sweep is resumed: finished cells are kept, not recomputed. ``simulate`` (picklable,
    ``simulate(job, first_run, runs) -> CellBatch``) is for tests."""
    t0 = time.perf_counter()
    if workers < 1:
        raise SweepError([f"--workers must be >= 1, got {workers}"])
    plan = plan_sweep(preset, grid, runs=runs, seed=seed, steps=steps, sets=sets)
    base, scenarios, runs, axes = plan.base, plan.scenarios, plan.runs, plan.axes
    store = SweepDir(out)
    values = plan.labels
    identity = {
        "preset": base.model_dump(mode="json"),
        "grid": [[a.key, list(a.labels)] for a in axes],
        "runs": runs,
        "seed": base.sim.seed,
        "steps": base.sim.steps,
    }
    meta = {
        "preset_name": str(preset), "grid": {a.key: list(a.labels) for a in axes}, "runs": runs,
        "seed": base.sim.seed, "steps": base.sim.steps, "set": list(sets), "shoal_version": __version__,
        "seed_rule": "run i of every cell uses child i of SeedSequence(seed) (the cell's sim.seed if gridded)",
        "cells": [{"id": cell_id(i), **dict(zip((a.key for a in axes), vs))} for i, vs in enumerate(values)],
        "status": "running",
    }
    with store.locked():  # a second sweep into ``out`` meanwhile is refused
        store.open(identity, meta)
        pending = [i for i in range(len(scenarios)) if not store.finished(i)]
        jobs = [plan.job(i) for i in pending]
        from tqdm import tqdm

        with tqdm(total=len(scenarios) * runs, initial=(len(scenarios) - len(pending)) * runs, desc="sweep",
                  unit="run", disable=not progress) as bar:
            for key, batch in iter_jobs(jobs, workers=workers, scheduler=scheduler, progress=bar.update,
                                        simulate=simulate, merge=outcomes.merge, desc="sweep"):
                i = key  # (a cell's key is its index)
                store.write_cell(i, plan.prefix(i), batch.first_run, plan.scenario(i).sim.seed, batch.columns)
        indices = list(range(len(scenarios)))
        columns = store.assemble(indices)
        names, medians = _medians(store, axes, len(scenarios))
        store.write_table(MEDIANS, [*(a.key for a in axes), "runs", *names],
                          ([*values[i], str(runs), *(fmt(n, medians[n][np.unravel_index(i, medians[n].shape)])
                                                     for n in names)] for i in indices))
        plots, note = plot_medians(store.out, axes, medians, runs)
        elapsed = time.perf_counter() - t0
        store.write_manifest({
            **store.manifest(), "status": "finished", "files": [RESULTS, MEDIANS, *plots], "plots_note": note,
            "last_call": {"cells_computed": len(pending), "elapsed_s": round(elapsed, 3), "scheduler":
                          scheduler.describe() if scheduler is not None else f"local, {workers} worker(s)"},
        })
        return SweepReport(store.out, len(scenarios), len(pending), runs, columns, plots)
