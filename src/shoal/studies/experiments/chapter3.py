"""Shared machinery of the Chapter 3 velocity experiments (Figs. 3-4 and 3-5).

1-D swarms maximise f = x1 for 100 s; what is recorded is the swarm's highest speed. The
thesis samples "the maximum velocity at every second" without saying whether that is a
snapshot or the maximum over the second (not stated): the series keep both, the
figures and checks use the snapshot at whole seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from shoal.presets.io import load
from shoal.presets.models import Scenario

from .output import check, r3, save, write_csv  # noqa: F401 (used as c3.check etc.)
from .output import num as _num
from .runner import BatchResult, Job, run_jobs

SIZES = (10, 100, 1000)
DURATION = 100.0  # s of simulated time
RUNS_COLUMNS = ("case", "run", "seed", "swarm_size", "U", "A_plus", "dt", "beta", "max_speed")
SERIES_COLUMNS = (
    "case", "swarm_size", "t", "max_snapshot_median", "max_snapshot_p05", "max_snapshot_p95",
    "max_window_median", "particle_u", "U", "A_plus_dt",
)
SAMPLING = (
    "swarm maximum |u| sampled as a snapshot at each whole second t = 0, 1, ..., 100 s "
    "(max_snapshot_*: median and 5th/95th percentiles over runs); max_window_median is the "
    "median over runs of the maximum over all iterations in (t - 1 s, t]"
)


@dataclass(frozen=True)
class Case:
    """One panel of a figure under one reading of the attractors."""

    name: str  # e.g. "3-4a/ahead"
    preset: str  # shipped preset, e.g. "fig3-4a"
    attractors: str  # "ahead" or "literal"

    @property
    def panel(self) -> str:
        return self.name.split("/")[0]

    def scenario(self, size: int) -> Scenario:
        return load(self.preset, list(self.overrides(size)))

    def overrides(self, size: int) -> tuple[str, ...]:
        return (f"sim.robots={size}", f"bests.attractors={self.attractors}")


def seed_for(base: int, size: int) -> int:
    """Root seed of every case with ``size`` particles: the preset seed + the swarm size.

    All cases of a figure share it (common random numbers), so cases whose per-iteration
    law is the same (equal ω and ĉ) draw the same numbers and can be compared exactly.
    """
    return base + size


def track_for(seed: int, size: int) -> int:
    """The "one random particle" whose velocity is drawn: fixed by the seed."""
    return int(np.random.default_rng([seed, size, 3]).integers(size))


def steps_for(scenario: Scenario, duration: float) -> int:
    dt = scenario.controller.dt
    per_second = round(1.0 / dt)
    if per_second < 1 or abs(per_second * dt - 1.0) > 1e-9:
        raise ValueError(f"dt = {dt} s does not divide one second; whole-second snapshots need it to")
    return int(round(duration * per_second))


def make_jobs(cases: Sequence[Case], sizes: Sequence[int], runs: int, duration: float) -> list[Job]:
    jobs = []
    for case in cases:
        for size in sizes:
            scenario = case.scenario(size)
            seed = seed_for(scenario.sim.seed, size)
            jobs.append(Job(
                key=(case.name, size), preset=case.preset, overrides=case.overrides(size), seed=seed, runs=runs,
                steps=steps_for(scenario, duration), track=track_for(seed, size),
            ))
    return jobs


def limits(scenario: Scenario) -> tuple[list[float], list[float]]:
    """U and A+ of each interval of the controller schedule (one item when constant)."""
    c = scenario.controller
    return [c.U] + [s.U for s in c.schedule], [c.A_plus] + [s.A_plus for s in c.schedule]


def runs_rows(case: Case, size: int, res: BatchResult, scenario: Scenario) -> list[list[str]]:
    """Rows of runs.csv; with a schedule, U, A_plus and beta are ``;``-joined per interval."""
    Us, As = limits(scenario)
    dt = scenario.controller.dt
    betas = [a * dt / u for u, a in zip(Us, As)]
    U, A, beta = (";".join(_num(v) for v in vals) for vals in (Us, As, betas))
    return [
        [case.name, str(i), str(res.seed), str(size), U, A, _num(dt), beta, _num(m)]
        for i, m in zip(res.run_index, res.run_max)
    ]


@dataclass
class Series:
    """Whole-second samples of one (case, swarm size)."""

    t: np.ndarray  # (S,) 0, 1, …, duration
    snapshot: np.ndarray  # (S, R) swarm max at t
    window: np.ndarray  # (S, R) swarm max over (t − 1, t]
    particle: np.ndarray  # (S,) tracked particle's velocity in run 0 (signed in 1-D, |u| otherwise)
    U: np.ndarray  # (S,) top speed in force at t
    A_plus_dt: np.ndarray  # (S,) A+·Δt = ĉ√d in force at t

    @property
    def median(self) -> np.ndarray:
        return np.median(self.snapshot, axis=1)


def series(res: BatchResult) -> Series:
    per_second = round(1.0 / res.dt)
    n = res.steps // per_second
    idx = np.arange(n + 1) * per_second
    window = np.empty((n + 1, res.runs))
    window[0] = res.max_speed[0]
    for s in range(1, n + 1):
        window[s] = res.max_speed[idx[s - 1] + 1 : idx[s] + 1].max(axis=0)
    u = res.tracked[idx, 0]
    particle = u[:, 0] if res.d == 1 else np.linalg.norm(u, axis=-1)
    return Series(
        t=res.t[idx], snapshot=res.max_speed[idx], window=window, particle=particle, U=res.U[idx],
        A_plus_dt=res.c_hat[idx] * math.sqrt(res.d),
    )


def series_rows(case: Case, size: int, s: Series) -> list[list[str]]:
    med = s.median
    p05, p95 = np.percentile(s.snapshot, [5, 95], axis=1)
    wmed = np.median(s.window, axis=1)
    return [
        [case.name, str(size), _num(s.t[i]), _num(med[i]), _num(p05[i]), _num(p95[i]), _num(wmed[i]),
         _num(s.particle[i]), _num(s.U[i]), _num(s.A_plus_dt[i])]
        for i in range(len(s.t))
    ]


# ---------------------------------------------------------------------- figures
def greens(n: int) -> list[Any]:
    """Dark (smallest swarm) to light (largest swarm)."""
    import matplotlib

    cmap = matplotlib.colormaps["Greens"]
    return [cmap(v) for v in np.linspace(0.9, 0.35, n)] if n > 1 else [cmap(0.7)]


def draw_panel(ax: Any, title: str, per_size: dict[int, Series], particle_size: int, ymax: float) -> None:
    """Bands: median over runs of the per-second swarm max, one per swarm size (dark →
    light green), U(t) blue, A+Δt(t) red dashed, one particle yellow."""
    sizes = sorted(per_size)
    colours = greens(len(sizes))
    for size, colour in reversed(list(zip(sizes, colours))):  # largest (highest) first
        s = per_size[size]
        ax.fill_between(s.t, 0.0, s.median, color=colour, linewidth=0, label=f"max, {size} particles")
    ref = per_size[sizes[-1]]
    ax.step(ref.t, ref.U, where="post", color="tab:blue", lw=1.6, label="U")
    ax.step(ref.t, ref.A_plus_dt, where="post", color="tab:red", lw=1.4, ls="--", label="A+·Δt")
    one = per_size[particle_size]
    ax.plot(one.t, one.particle, color="#f5c400", lw=1.0, label=f"one particle ({particle_size})")
    ax.set_title(title, fontsize=10)
    ax.set_xlim(ref.t[0], ref.t[-1])
    ax.set_ylim(0.0, ymax)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("velocity (m/s)")
    ax.grid(alpha=0.3, lw=0.5)


def save_figure(path: Path, panels: Sequence[tuple[str, dict[int, Series]]], ncols: int, suptitle: str) -> None:
    from matplotlib.figure import Figure  # no pyplot: rendered by the Agg canvas, no display needed

    nrows = math.ceil(len(panels) / ncols)
    fig = Figure(figsize=(5.2 * ncols, 3.6 * nrows), layout="constrained")
    axes = np.atleast_1d(fig.subplots(nrows, ncols)).ravel()
    ymax = 1.08 * max(float(np.max(s.U)) for _, per in panels for s in per.values())
    for ax, (title, per_size) in zip(axes, panels):
        draw_panel(ax, title, per_size, max(per_size), ymax)
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    handles, labels = axes[0].get_legend_handles_labels()
    n_bands = len(panels[0][1])  # bands were drawn largest first; list them smallest first
    handles = handles[:n_bands][::-1] + handles[n_bands:]
    labels = labels[:n_bands][::-1] + labels[n_bands:]
    fig.legend(handles, labels, loc="outside lower center", ncols=min(6, len(labels)), fontsize=8, frameon=False)
    fig.suptitle(suptitle, fontsize=11)
    save(fig, path)


def median_range(values: np.ndarray) -> str:
    v = np.asarray(values, dtype=float)
    return f"median {np.median(v):.3f} (min {v.min():.3f}, max {v.max():.3f})"


def simulate_cases(
    cases: Sequence[Case], sizes: Sequence[int], runs: int, duration: float, out_dir: Path,
    workers: int, progress: bool, desc: str,
) -> tuple[dict[Any, BatchResult], dict[str, dict[int, Series]]]:
    """Run every case × swarm size, write runs.csv and series.csv, and return the results
    and the per-second series of each case and size."""
    results = run_jobs(make_jobs(cases, sizes, runs, duration), workers=workers, progress=progress, desc=desc)
    rows, srows = [], []
    ser: dict[str, dict[int, Series]] = {}
    for case in cases:
        ser[case.name] = {}
        for size in sizes:
            res = results[(case.name, size)]
            rows += runs_rows(case, size, res, case.scenario(size))
            ser[case.name][size] = s = series(res)
            srows += series_rows(case, size, s)
    write_csv(out_dir / "runs.csv", RUNS_COLUMNS, rows)
    write_csv(out_dir / "series.csv", SERIES_COLUMNS, srows)
    return results, ser
