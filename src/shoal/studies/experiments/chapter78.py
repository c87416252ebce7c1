"""Shared machinery of the Chapter 7–8 acoustic reproductions (Figs. 7-2, 7-4, 7-5, 8-2,
8-4, 8-5).

A :class:`SonarJob` is one case: a shipped preset plus ``--set``-style overrides (so
``shoal run PRESET --set ...`` reproduces any run by hand, see :func:`command`), ``runs``
seeded runs of at most ``steps`` ticks. :func:`simulate_sonar` advances a chunk of its runs
in ONE :class:`~shoal.engine.kinds.sonar.AcousticSwarm` (runs axis), stopping each run once it
converged when the job asks so (the run is masked out, shapes are kept); :func:`merge`
glues chunks, so :func:`~shoal.studies.experiments.runner.run_jobs` can spread the runs
over processes with results that do not depend on the number of workers.

Run ``i`` of a job uses child ``i`` of ``SeedSequence(seed)``; jobs that should start from
the same layouts (e.g. every algorithm at one SNR_0) share ``seed``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, Sequence

import numpy as np

from shoal.engine.acoustics.strategies import STRATEGIES
from shoal.presets.builders.sonar import build_sonar
from shoal.presets.io import load
from shoal.presets.models import Scenario

from ..cost import run_cost
from .output import num, percentile_band, write_csv
from .runner import run_jobs
from .verdict import Estimate

ALGORITHMS = ("a-pso", "x-pso", "b-pso", "xb-pso")  # Chapter 7 order
LABELS = {name: strategy.label for name, strategy in STRATEGIES.items()}
COLOURS = {"a-pso": "tab:red", "x-pso": "tab:orange", "b-pso": "tab:blue", "xb-pso": "tab:green",
           "gt-pso": "tab:purple"}
NOT_CONVERGED = -1


@dataclass(frozen=True)
class SonarJob:
    """One case: ``runs`` runs of at most ``steps`` ticks. Picklable.

    ``window`` > 0 averages the escort metrics over ticks ``window … steps`` and, with
    ``cell`` > 0, accumulates the occupancy of robots relative to the true source in
    ``cell`` × ``cell`` m cells over the square of half-side ``extent`` (the fraction of
    robot-ticks per cell, our reading of Figs. 8-4 and 8-5). ``routes`` keeps the CoM route
    of every run in a frame that puts its source on the +x axis (Fig. 7-3).
    """

    key: tuple[Any, ...]
    preset: str
    overrides: tuple[str, ...]
    seed: int
    runs: int
    steps: int
    window: int = 0
    cell: float = 0.0
    extent: float = 0.0
    routes: bool = False

    @property
    def cost(self) -> float:
        """Estimated CPU seconds of one run (:func:`~shoal.studies.cost.run_cost`)."""
        return run_cost(self.scenario(), self.steps)

    def scenario(self) -> Scenario:
        return load(self.preset, list(self.overrides))

    def command(self) -> str:
        """The ``shoal run`` line that replays run 0 of this job (drop ``--runs`` for more)."""
        sets = " ".join(f"--set {o}" for o in self.overrides)
        return f"shoal run {self.preset} {sets} --seed {self.seed} --steps {self.steps}".strip()


def job(key: tuple[Any, ...], preset: str, overrides: Sequence[str], seed: int, runs: int, steps: int,
        stop: bool = True, **kw: Any) -> SonarJob:
    """A job of ``preset`` with ``overrides``; ``stop`` freezes converged runs."""
    extra = ("acoustics.stop_on_converge=true",) if stop else ()
    return SonarJob(key, preset, (*overrides, *extra), seed, runs, steps, **kw)


@dataclass
class SonarBatch:
    """Outcome of runs ``first_run …`` of one job (step axis first; index 0 = initial state)."""

    seed: int
    first_run: int
    robots: int
    dt: float
    dc: float
    r_trap: float
    r_ref: float
    com_dist: np.ndarray  # (K+1, R) float32, |CoM − x_src| (held after a run stops)
    first_converged: np.ndarray  # (R,) first tick with |CoM − x_src| ≤ d_c, −1 if never
    robot_steps: int  # robot-ticks actually simulated
    mean_dist: np.ndarray | None = None  # (K+1, R) float32 mean robot–source distance (escort jobs)
    frac_inside: np.ndarray | None = None  # (K+1, R) float32 fraction inside r_trap of the source
    occupancy: np.ndarray | None = None  # (R, C, C) int64 robot-ticks per cell in the window
    com: np.ndarray | None = None  # (K+1, R, 2) float32 CoM, source on +x (held after a run stops)
    extent: float = 0.0
    cell: float = 0.0
    window: int = 0

    @property
    def runs(self) -> int:
        return self.com_dist.shape[1]

    @property
    def run_index(self) -> np.ndarray:
        return np.arange(self.first_run, self.first_run + self.runs)

    @property
    def converged(self) -> np.ndarray:
        return self.first_converged >= 0

    def median_steps(self) -> float:
        """Median ticks to converge over all runs, a never-converged run counting as +∞
        (the thesis' "on average" read as the median its figures plot); ``inf`` when fewer
        than half converged."""
        return median_time(self.first_converged)

    def steps(self) -> "Estimate":
        """:meth:`median_steps` with its interval (a never-converged run as +∞)."""
        first = np.where(self.first_converged >= 0, self.first_converged.astype(float), np.inf)
        return Estimate.median(first, first_passage=True)

    def window_mean(self, values: np.ndarray) -> np.ndarray:
        """(R,) mean of a per-tick series over the window, ticks ``window …`` K."""
        return values[self.window:].astype(float).mean(axis=0)

    def kept(self, name: Literal["mean_dist", "frac_inside", "occupancy", "com"]) -> np.ndarray:
        """A series only some jobs keep (the escort metrics and occupancy of a job with a
        ``window``, the routes of one with ``routes``); a ``ValueError`` if this one did not."""
        values: np.ndarray | None = getattr(self, name)
        if values is None:
            raise ValueError(f"this batch did not keep {name} (see SonarJob)")
        return values


def median_time(first: np.ndarray) -> float:
    """Median of first-passage ticks with −1 read as +∞."""
    t = np.where(np.asarray(first) >= 0, np.asarray(first, dtype=float), np.inf)
    return float(np.median(t)) if t.size else float("inf")


def simulate_sonar(job: SonarJob, first_run: int, runs: int) -> SonarBatch:
    """Runs ``first_run … first_run + runs − 1`` of ``job`` (``simulate`` for ``run_jobs``)."""
    scenario = job.scenario()
    sw = build_sonar(scenario, runs=runs, seed=job.seed, first_run=first_run)
    K, N, p = job.steps, sw.robots, sw.params
    escort = job.window > 0
    com = np.empty((K + 1, runs), np.float32)
    md = np.empty((K + 1, runs), np.float32) if escort else None
    fr = np.empty((K + 1, runs), np.float32) if escort else None
    C = int(round(2 * job.extent / job.cell)) if job.cell > 0 else 0
    occ = np.zeros(runs * C * C, np.int64) if C else None
    route = np.empty((K + 1, runs, 2), np.float32) if job.routes else None
    if route is not None:  # rotate each run so that its source lies on +x
        angle = np.arctan2(sw.source0[:, 1], sw.source0[:, 0])
        turn = np.stack([np.stack([np.cos(angle), np.sin(angle)], -1),
                         np.stack([-np.sin(angle), np.cos(angle)], -1)], axis=1)  # (R, 2, 2) = R(−angle)
    info = sw.info()
    for k in range(K + 1):
        if k > 0:
            if not sw.running.any():  # every run stopped: hold the last values
                for a in (com, md, fr, route):
                    if a is not None:
                        a[k:] = a[k - 1]
                break
            info = sw.step()
        com[k] = info.com_dist
        if route is not None:
            route[k] = np.einsum("rij,rj->ri", turn, info.com)
        if md is not None and fr is not None:  # an escort job
            md[k], fr[k] = info.mean_dist_to_source, info.frac_inside_ring
            if occ is not None and k >= job.window:
                # source-centred frame: docs/readings.md, "Occupancy maps of Figures 8-4 and 8-5"
                rel = sw.state.x - sw.state.source[:, None, :]
                ij = np.floor((rel + job.extent) / job.cell).astype(np.int64)
                ok = np.all((ij >= 0) & (ij < C), axis=-1)
                flat = (np.arange(runs)[:, None] * C + ij[..., 0]) * C + ij[..., 1]
                occ += np.bincount(flat[ok], minlength=occ.size)
    return SonarBatch(
        seed=job.seed, first_run=first_run, robots=N, dt=p.dt, dc=p.dc, r_trap=p.r_trap, r_ref=p.r_ref,
        com_dist=com, first_converged=sw.state.first_converged.copy(), robot_steps=int(sw.state.steps.sum()) * N,
        mean_dist=md, frac_inside=fr, occupancy=None if occ is None else occ.reshape(runs, C, C),
        com=route, extent=job.extent, cell=job.cell, window=job.window,
    )


def merge(parts: Sequence[SonarBatch]) -> SonarBatch:
    """Glue chunks of consecutive runs (in any order) into one batch."""
    parts = sorted(parts, key=lambda b: b.first_run)
    first, expected = parts[0], parts[0].first_run
    for b in parts:
        if b.first_run != expected or b.seed != first.seed or b.com_dist.shape[0] != first.com_dist.shape[0]:
            raise ValueError("chunks must be consecutive runs of the same seed and length")
        expected += b.runs

    def cat(name: str, axis: int) -> np.ndarray:
        return np.concatenate([getattr(b, name) for b in parts], axis=axis)

    def cat_kept(name: str, axis: int) -> np.ndarray | None:  # a series only some jobs keep
        arrays = [getattr(b, name) for b in parts]
        return None if arrays[0] is None else np.concatenate(arrays, axis=axis)

    return SonarBatch(
        seed=first.seed, first_run=first.first_run, robots=first.robots, dt=first.dt, dc=first.dc,
        r_trap=first.r_trap, r_ref=first.r_ref, com_dist=cat("com_dist", 1),
        first_converged=cat("first_converged", 0), robot_steps=sum(b.robot_steps for b in parts),
        mean_dist=cat_kept("mean_dist", 1), frac_inside=cat_kept("frac_inside", 1),
        occupancy=cat_kept("occupancy", 0), com=cat_kept("com", 1), extent=first.extent, cell=first.cell,
        window=first.window,
    )


# ---------------------------------------------------------------------- outputs
def steps_cell(first: int) -> str:
    """A ``steps_to_converge`` cell: the tick, or empty when the run never converged."""
    return str(int(first)) if first >= 0 else ""


def time_text(t: float, horizon: int) -> str:
    """A median time for a check: the number of ticks, or 'n.c. (> horizon)'."""
    return f"{t:.0f}" if np.isfinite(t) else f"n.c. (> {horizon})"


def series_rows(prefix: Sequence[str], b: SonarBatch, every: int) -> list[list[str]]:
    """Median and 5/25/75/95th percentiles of |CoM − x_src| (m) every ``every`` ticks."""
    d = b.com_dist.astype(float)
    med, p05, p95 = percentile_band(d, axis=1)
    p25, p75 = np.percentile(d, [25, 75], axis=1)
    idx = np.unique(np.r_[np.arange(0, d.shape[0], every), d.shape[0] - 1])
    return [[*prefix, str(k), num(k * b.dt), num(med[k]), num(p05[k]), num(p25[k]), num(p75[k]), num(p95[k])]
            for k in idx]


SERIES_TAIL = ("step", "t", "median_m", "p05_m", "p25_m", "p75_m", "p95_m")


def band_panel(ax: Any, batches: dict[str, SonarBatch], title: str, dc: float, r_ref: float,
               thesis: dict[str, float] | None = None, inner: bool = False) -> None:
    """Median |CoM − x_src| (spatial steps, R_ref) over time per algorithm with its 5–95 %
    band (and the 25–75 % band with ``inner``), the d_c line and thesis median times."""
    for alg, b in batches.items():
        d = b.com_dist.astype(float) / r_ref
        t = np.arange(d.shape[0]) * b.dt
        med, p05, p95 = percentile_band(d, axis=1)
        col = COLOURS.get(alg, "black")
        ax.fill_between(t, p05, p95, color=col, alpha=0.12, linewidth=0)
        if inner:
            p25, p75 = np.percentile(d, [25, 75], axis=1)
            ax.fill_between(t, p25, p75, color=col, alpha=0.25, linewidth=0)
        ax.plot(t, med, color=col, lw=1.4, label=LABELS.get(alg, alg))
        if thesis and np.isfinite(thesis.get(alg, np.nan)):
            ax.plot([thesis[alg]], [dc / r_ref], marker="v", color=col, ms=8, ls="none")
    ax.axhline(dc / r_ref, color="black", ls="--", lw=0.8)
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("time (timesteps)")
    ax.set_ylabel("|CoM − source| (spatial steps)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)


# ---------------------------------------------------------------------- escorting (Figs. 8-4, 8-5)
ESCORT_COLUMNS = ("case", "run", "seed", "n_robots", "r", "v_n", "psd_s", "frac_inside_ring", "mean_dist_to_source")
ESCORT_SERIES = ("case", "step", "t", "median_mean_dist_m", "median_com_dist_m", "median_frac_inside_ring")


@dataclass(frozen=True)
class EscortCase:
    """One panel: robots, ring radius r (m), source speed v_n [8.8] and source PSD (dB)."""

    name: str
    robots: int
    r: float
    v_n: float = 0.0
    psd_s: float = 120.0
    start: str = "origin"

    def overrides(self, steps: int) -> tuple[str, ...]:
        return (f"sim.robots={self.robots}", f"acoustics.r={self.r:g}", f"acoustics.v_n={self.v_n:g}",
                f"acoustics.psd_s={self.psd_s:g}", f"acoustics.start={self.start}", f"sim.steps={steps}")


def escort_jobs(cases: Sequence[EscortCase], preset: str, runs: int, steps: int, extent: float,
                cell: float = 5.0, mode: str = "waveform") -> list[SonarJob]:
    """One job per panel; metrics averaged and occupancy accumulated over the second half."""
    seed = load(preset).sim.seed
    return [job((c.name,), preset, (*c.overrides(steps), f"acoustics.mode={mode}"), seed, runs, steps, stop=False,
                window=steps // 2, cell=cell, extent=extent) for c in cases]


def escort_rows(case: EscortCase, b: SonarBatch) -> list[list[str]]:
    """``ESCORT_COLUMNS`` rows: per run, window means of the ring fraction and distance."""
    frac, dist = b.window_mean(b.kept("frac_inside")), b.window_mean(b.kept("mean_dist"))
    return [[case.name, str(r), str(b.seed), str(case.robots), num(case.r), num(case.v_n), num(case.psd_s),
             num(f), num(d)] for r, f, d in zip(b.run_index, frac, dist)]


def escort_series(case: EscortCase, b: SonarBatch, every: int = 10) -> list[list[str]]:
    K = b.com_dist.shape[0]
    idx = np.unique(np.r_[np.arange(0, K, every), K - 1])
    md, cd, fr = (np.median(a.astype(float), axis=1) for a in (b.kept("mean_dist"), b.com_dist, b.kept("frac_inside")))
    return [[case.name, str(k), num(k * b.dt), num(md[k]), num(cd[k]), num(fr[k])] for k in idx]


def occupancy_probability(b: SonarBatch) -> np.ndarray:
    """(C, C) fraction of all robot-ticks of all runs in each cell; rows = x cells."""
    occ = b.kept("occupancy").sum(axis=0).astype(float)
    window = b.com_dist.shape[0] - b.window  # ticks window … K
    return occ / max(b.robots * b.runs * window, 1)  # robots outside the mapped square count too


def escort_estimates(b: SonarBatch) -> dict[str, Estimate]:
    """Medians over runs with their intervals: the window means of the fraction inside the
    ring (``frac``), the mean robot–source distance (``dist``) and |CoM − source| (``com``),
    and the mean robot–source distance at the end (``final``)."""
    dist = b.kept("mean_dist")
    return {"frac": Estimate.median(b.window_mean(b.kept("frac_inside"))), "dist": Estimate.median(b.window_mean(dist)),
            "com": Estimate.median(b.window_mean(b.com_dist)), "final": Estimate.median(dist[-1])}


def inside_peak(b: SonarBatch, r: float) -> Estimate:
    """The highest occupancy of a cell lying wholly inside the ring r (all runs pooled, as
    the maps), as the mean over runs of that cell's per-run occupancy, with its interval."""
    p = occupancy_probability(b)
    centres = -b.extent + (np.arange(p.shape[0]) + 0.5) * b.cell
    inside = np.hypot(*np.meshgrid(centres, centres, indexing="ij")) + b.cell / np.sqrt(2) < r
    if not inside.any():
        return Estimate.exact(0.0)
    i, j = np.unravel_index(np.argmax(np.where(inside, p, -1.0)), p.shape)
    window = b.com_dist.shape[0] - b.window
    return Estimate.mean(b.kept("occupancy")[:, i, j] / max(b.robots * window, 1))


def occupancy_rows(case: EscortCase, b: SonarBatch) -> list[list[str]]:
    """Non-empty cells: centre (m, source frame) and probability."""
    p = occupancy_probability(b)
    i, j = np.nonzero(p)
    centre = lambda k: -b.extent + (k + 0.5) * b.cell  # noqa: E731
    return [[case.name, num(centre(a)), num(centre(c)), num(p[a, c])] for a, c in zip(i, j)]


def occupancy_panel(ax: Any, b: SonarBatch, title: str, r: float, level: float) -> None:
    """Occupancy probability (log colour) round the source with the r ring and a ``level`` contour."""
    from matplotlib.colors import LogNorm

    p = occupancy_probability(b)
    e = b.extent
    shown = np.where(p > 0, p, np.nan).T  # imshow rows are y
    vmax = float(np.nanmax(shown)) if np.isfinite(shown).any() else 1.0
    ax.imshow(shown, origin="lower", extent=(-e, e, -e, e), cmap="viridis",
              norm=LogNorm(vmin=max(vmax * 1e-3, 1e-7), vmax=vmax), interpolation="nearest")
    centres = -e + (np.arange(p.shape[0]) + 0.5) * b.cell
    if (p >= level).any() and (p < level).any():
        ax.contour(centres, centres, p.T, levels=[level], colors="white", linewidths=0.8)
    t = np.linspace(0, 2 * np.pi, 200)
    ax.plot(r * np.cos(t), r * np.sin(t), color="red", lw=0.8, ls="--")
    ax.plot([0], [0], marker="*", color="red", ms=8)
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x − x_src (m)")
    ax.set_ylabel("y − y_src (m)")
    ax.set_aspect("equal")


def convergence_sweep(
    jobs: Sequence[Any], runs: int, out_dir: Path, runs_columns: Sequence[str], series_every: int,
    workers: int, progress: bool, desc: str,
) -> tuple[dict[Any, Any], float]:
    """Run convergence jobs keyed (algorithm, SNR_0, …), write runs.csv and series.csv
    (columns: case, run, seed, one per further key entry, converged, steps_to_converge);
    return the results and the wall time."""
    t0 = time.perf_counter()
    res = run_jobs(jobs, workers=workers, progress=progress, desc=desc, simulate=simulate_sonar, merge=merge,
                   chunk=runs)
    wall = time.perf_counter() - t0
    rows, series = [], []
    for j in jobs:
        alg, *rest = j.key
        cells = [f"{v:g}" for v in rest]
        b = res[j.key]
        rows += [[alg, str(r), str(b.seed), *cells, str(int(c)), steps_cell(f)]
                 for r, c, f in zip(b.run_index, b.converged, b.first_converged)]
        series += series_rows((alg, *cells), b, series_every)
    write_csv(out_dir / "runs.csv", runs_columns, rows)
    write_csv(out_dir / "series.csv", ("case", *runs_columns[3:-2], *SERIES_TAIL), series)
    return res, wall
