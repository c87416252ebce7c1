"""Shared machinery of the SLO reproductions (Mai, Chapter 4: Figs. 4.1–4.13, Table 4.4).

A *case* is a shipped SLO preset plus ``--set`` overrides (``slo-walk`` for the random-walk
experiments of Mai §4.5, ``slo-pso-sphere`` for the PSO experiment of §4.6), so every case can
be run by hand with ``shoal run``. An :class:`SLOJob` is one case for ``runs`` seeded runs;
:func:`simulate_slo` advances a chunk of its runs and keeps per-generation series, and
:func:`merge` glues chunks back together, so
:func:`shoal.studies.experiments.runner.run_jobs` spreads runs over processes with results
that do not depend on the number of workers.

Run ``i`` of every case uses the streams of run ``i`` of the preset seed: the same start
positions in every case (common random numbers).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Iterable, Sequence

import numpy as np

from shoal.engine.kinds.slo_swarm import SLOSwarm
from shoal.presets.build import build_slo
from shoal.presets.io import load

from ..cost import run_cost
from .output import num

WALK = "slo-walk"
PSO = "slo-pso-sphere"
KEPT = ("e_abs_mean", "e_rel_median", "distance_median", "best_fitness", "quality_met_at", "dead_reckoning")


@dataclass(frozen=True)
class Case:
    """A named SLO preset with overrides."""

    name: str
    preset: str
    overrides: tuple[str, ...] = ()

    def command(self, generations: int) -> str:
        sets = " ".join(f"--set {o}" for o in self.overrides)
        return f"shoal run {self.preset} {sets} --steps {generations}".replace("  ", " ")


def walk(name: str, *overrides: str) -> Case:
    return Case(name, WALK, tuple(overrides))


@dataclass(frozen=True)
class SLOJob:
    """One case for ``runs`` runs of ``generations`` generations. Picklable."""

    key: str
    preset: str
    overrides: tuple[str, ...]
    seed: int
    runs: int
    generations: int

    @property
    def cost(self) -> float:
        """Estimated CPU seconds of one run (:func:`~shoal.studies.cost.run_cost`)."""
        return run_cost(load(self.preset, list(self.overrides)), self.generations)


def jobs_for(cases: Iterable[Case], runs: int, generations: int | dict[str, int]) -> list[SLOJob]:
    out = []
    for c in cases:
        g = generations if isinstance(generations, int) else generations[c.name]
        seed = load(c.preset, list(c.overrides)).sim.seed
        out.append(SLOJob(c.name, c.preset, c.overrides, seed, runs, g))
    return out


@dataclass
class SLOBatch:
    """Per-generation series (G+1, R) of runs ``first_run …`` (index 0 = generation 0)."""

    seed: int
    first_run: int
    series: dict[str, np.ndarray]

    @property
    def runs(self) -> int:
        return next(iter(self.series.values())).shape[1]

    @property
    def generations(self) -> int:
        return next(iter(self.series.values())).shape[0] - 1

    @property
    def run_index(self) -> np.ndarray:
        return np.arange(self.first_run, self.first_run + self.runs)

    def median(self, column: str) -> np.ndarray:
        """Median over runs per generation (NaN-aware), (G+1,)."""
        v = self.series[column]
        with np.errstate(all="ignore"):
            return np.array([np.nanmedian(r) if np.isfinite(r).any() or np.isinf(r).any() else np.nan for r in v])

    def final(self, column: str) -> np.ndarray:
        return self.series[column][-1]

    def average(self, column: str, start: int = 1) -> np.ndarray:
        """Mean over generations ``start`` … G per run, (R,)."""
        return np.nanmean(self.series[column][start:], axis=0)


def slo_swarm(job: SLOJob, first_run: int, runs: int) -> SLOSwarm:
    """Mai's SLO swarm of ``job`` (its preset says ``[slo] swarm = "slo"``), runs ``first_run …``."""
    swarm = build_slo(load(job.preset, list(job.overrides)), runs=runs, seed=job.seed, first_run=first_run)
    if not isinstance(swarm, SLOSwarm):
        raise ValueError(f"{job.preset}: this SLO study needs [slo] swarm = \"slo\", not a host swarm")
    return swarm


def simulate_slo(job: SLOJob, first_run: int, runs: int) -> SLOBatch:
    """Runs ``first_run … first_run + runs − 1`` of ``job`` (``simulate`` for ``run_jobs``)."""
    swarm = slo_swarm(job, first_run, runs)
    hist = swarm.run(job.generations, KEPT)  # only the kept series
    return SLOBatch(job.seed, first_run, {k: hist[k] for k in KEPT})


def simulate_entry(job: SLOJob, first_run: int, runs: int) -> SLOBatch:
    """Runs of ``job`` recording, per generation, the mean absolute error of the neighbour
    pairs that have just entered the neighbourhood (``e_abs_entering``) and of those that were
    neighbours the generation before too (``e_abs_staying``); NaN when a run has none."""
    swarm = slo_swarm(job, first_run, runs)
    before = swarm.state.adjacency.copy()
    eye = np.eye(before.shape[-1], dtype=bool)
    rows: dict[str, list[np.ndarray]] = {"e_abs_entering": [], "e_abs_staying": []}
    for _ in range(job.generations):
        swarm.step()
        s = swarm.state
        err = np.linalg.norm(s.est - (s.x[:, None] - s.x[:, :, None]), axis=-1)
        now = s.adjacency & ~eye
        for name, mask in (("e_abs_entering", now & ~before), ("e_abs_staying", now & before)):
            count = mask.sum(axis=(1, 2))
            total = np.where(mask, err, 0.0).sum(axis=(1, 2))
            with np.errstate(invalid="ignore", divide="ignore"):
                rows[name].append(np.where(count > 0, total / np.maximum(count, 1), np.nan))
        before = s.adjacency.copy()
    return SLOBatch(job.seed, first_run, {k: np.array(v) for k, v in rows.items()})


def merge(parts: Sequence[SLOBatch]) -> SLOBatch:
    """Glue chunks of consecutive runs (in any order) into one batch (``merge`` for ``run_jobs``)."""
    parts = sorted(parts, key=lambda p: p.first_run)
    expected = parts[0].first_run
    for p in parts:
        if p.first_run != expected or p.seed != parts[0].seed or p.generations != parts[0].generations:
            raise ValueError("chunks must be consecutive runs of the same seed and length")
        expected += p.runs
    series = {k: np.concatenate([p.series[k] for p in parts], axis=1) for k in parts[0].series}
    return SLOBatch(parts[0].seed, parts[0].first_run, series)


# ---------------------------------------------------------------------- rows and numbers
WALK_RUNS_COLUMNS = ("case", "run", "seed", "e_abs_final", "e_abs_avg", "e_rel_final", "dead_reckoning_final")
SERIES_COLUMNS = ("case", "generation", "e_abs_mean_median", "e_rel_median_median", "distance_median_median",
                  "best_fitness_median")


def walk_runs_rows(case: str, b: SLOBatch) -> list[list[str]]:
    """runs.csv rows of a random-walk case: mean e_abs at the last generation and averaged over
    generations 1…G, median e_rel at the last generation, dead-reckoning share at the end."""
    fin, avg = b.final("e_abs_mean"), b.average("e_abs_mean")
    rel, dr = b.final("e_rel_median"), b.final("dead_reckoning")
    return [[case, str(i), str(b.seed), num(fin[j]), num(avg[j]), num(rel[j]), num(dr[j])]
            for j, i in enumerate(b.run_index)]


def series_rows(case: str, b: SLOBatch) -> list[list[str]]:
    cols = [b.median(c) for c in ("e_abs_mean", "e_rel_median", "distance_median", "best_fitness")]
    return [[case, str(g)] + [num(c[g]) for c in cols] for g in range(b.generations + 1)]


def med(values: np.ndarray) -> float:
    """Median over runs (NaN ignored, inf ranks above every finite value)."""
    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    return float(np.median(v)) if v.size else float("nan")


def g3(v: float) -> float:
    """Three significant digits (for summaries)."""
    return float(f"{float(v):.3g}")


# ---------------------------------------------------------------------- figures
def plot_curves(ax: Any, curves: dict[str, np.ndarray], *, title: str, ylabel: str, log: bool = False,
                start: int = 0) -> None:
    """Median-over-runs curves against the generation."""
    for label, y in curves.items():
        g = np.arange(len(y))
        ax.plot(g[start:], y[start:], lw=1.4, label=label)
    if log:
        ax.set_yscale("log")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("generation")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.25, lw=0.5)
    ax.legend(fontsize=7, frameon=False)


def cases_section(cases: Sequence[Case], generations: int | dict[str, int]) -> dict[str, str]:
    return {c.name: c.command(generations if isinstance(generations, int) else generations[c.name]) for c in cases}
