"""Fig. 8-4: escorting a stationary source with 10 and 40 robots at r = 25, 50, 75 m
(Rossides §8.2, p. 182; Fig. 8-4, p. 185).

GT-PSO finds the source; its global best y_g is a ring obstacle of radius r in the
six-sector reading of the non-omnidirectional DVC controller (Table 8.1), so the robots
bounce off the ring (preset ``escort-stationary``). Robots start as in Chapter 7 (disc of
50 m round the origin, source at SNR_0 = 10 dB, random bearing); 2000 steps (docs/readings.md, "Unstated
settings of Chapter 8"). Metrics and occupancy are taken over the second half (steps 1000–2000), relative
to the true source, in 5 × 5 m cells (docs/readings.md, "Occupancy maps of Figures 8-4 and
8-5"). Collisions are not enforced.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from . import chapter78 as ch
from . import verdict as vd
from .output import check, checks_table, new_figure, r3, save, write_csv
from .runner import run_jobs
from .verdict import Estimate

PRESET = "escort-stationary"
DEFAULT_RUNS = 20
HORIZON = 2000
EXTENT = 150.0  # m, half-side of the occupancy map
LEVEL = 0.001  # 0.1 % contour (Fig. 8-4)
CASES = tuple(ch.EscortCase(f"n{n}-r{r:g}", n, r) for n in (10, 40) for r in (25.0, 50.0, 75.0))


def run(out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
        steps: int = HORIZON, cases: Sequence[ch.EscortCase] = CASES, mode: str = "waveform") -> dict[str, Any]:
    return run_escort(out_dir, "fig8-4", PRESET, cases, runs, workers, progress, steps, EXTENT, LEVEL, mode,
                      _checks, "Fig. 8-4: stationary source, occupancy over steps {w}–{K} (0.1 % contour white, "
                      "ring r red)")


def run_escort(out_dir: Path, target: str, preset: str, cases: Sequence[ch.EscortCase], runs: int, workers: int,
               progress: bool, steps: int, extent: float, level: float, mode: str, make_checks, title: str,
               ) -> dict[str, Any]:
    """Shared by Figs. 8-4 and 8-5: simulate, write runs/series/occupancy CSVs, the map and README."""
    jobs = ch.escort_jobs(cases, preset, runs, steps, extent, mode=mode)
    t0 = time.perf_counter()
    res = run_jobs(jobs, workers=workers, progress=progress, desc=target, simulate=ch.simulate_sonar,
                   merge=ch.merge, chunk=runs)
    wall = time.perf_counter() - t0
    b = {c.name: res[(c.name,)] for c in cases}
    rows, series, occ = [], [], []
    for c in cases:
        rows += ch.escort_rows(c, b[c.name])
        series += ch.escort_series(c, b[c.name])
        occ += ch.occupancy_rows(c, b[c.name])
    write_csv(out_dir / "runs.csv", ch.ESCORT_COLUMNS, rows)
    write_csv(out_dir / "series.csv", ch.ESCORT_SERIES, series)
    write_csv(out_dir / "occupancy.csv", ("case", "x_m", "y_m", "probability"), occ)
    ncols = 3
    fig, axes = new_figure(int(np.ceil(len(cases) / ncols)), ncols, 3.6, 3.4)
    for ax, c in zip(axes, cases):
        label = f"N = {c.robots}, r = {c.r:g} m" + (f", v_n = {c.v_n:g}" if c.v_n else "") + (
            f", {c.psd_s:g} dB" if c.psd_s != 120.0 else "")
        ch.occupancy_panel(ax, b[c.name], f"{c.name.split('-')[0]}: {label}", c.r, level)
    for ax in axes[len(cases):]:
        ax.set_visible(False)
    w = jobs[0].window
    fig.suptitle(title.format(w=w, K=steps) + f", {runs} runs per panel", fontsize=10)
    save(fig, out_dir / f"{target}.png")
    stats = {c.name: _stats(c, b[c.name]) for c in cases}
    checks = make_checks(stats, cases, {c.name: ch.escort_estimates(b[c.name]) for c in cases}, b)
    robot_steps = sum(x.robot_steps for x in res.values())
    summary = {
        "checks": checks,
        "preset": preset,
        "mode": mode,
        "horizon": steps,
        "window": [w, steps],
        "cell_m": jobs[0].cell,
        "series_every": 10,
        "cases": {c.name: {**stats[c.name], "command": j.command()} for c, j in zip(cases, jobs)},
        "seed_rule": "run i of every panel uses child i of SeedSequence(seed), seed = the preset seed",
        "cost": {"simulation_wall_s": round(wall, 1), "robot_steps": robot_steps,
                 "wall_us_per_robot_step": round(wall / max(robot_steps, 1) * 1e6, 2), "workers": workers},
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    runs, steps, mode, preset, target = (summary[k] for k in ("runs", "horizon", "mode", "preset", "target"))
    w, cell = summary["window"][0], summary["cell_m"]
    return f"""# {target} reproduction: source escorting

GT-PSO with the non-omnidirectional DVC controller; y_g is a ring obstacle of radius r (Rossides §8.2, p. 182).
{runs} seeded runs per panel, {steps} steps, acoustics mode `{mode}`; preset `{preset}` with `--set`
overrides (`summary.json` → `cases.*.command`). Window for all averages and maps: steps {w}–{steps}.
Collisions are not enforced (robots may overlap; `summary.json` does not count them as failures).

## Files

- `runs.csv`: `{",".join(ch.ESCORT_COLUMNS)}`. `frac_inside_ring` is the fraction of robots closer
  than r to the true source, `mean_dist_to_source` the mean robot–source distance (m), both
  averaged over the window.
- `series.csv`: per panel every {summary["series_every"]} steps, medians over runs of the mean robot–source distance,
  |CoM − source| and the fraction inside the ring.
- `occupancy.csv`: non-empty {cell:g} × {cell:g} m cells (centre, source frame) with the fraction of all
  robot-steps of the window (all runs) in the cell.
- `{target}.png`: the occupancy maps (log colour), the ring r (red dashed) and the contour.

## Checks

{checks_table(summary["checks"])}
"""


def _stats(c: ch.EscortCase, b: ch.SonarBatch) -> dict[str, Any]:
    frac, dist = b.window_mean(b.kept("frac_inside")), b.window_mean(b.kept("mean_dist"))
    com = b.window_mean(b.com_dist)
    return {
        "robots": c.robots, "r": c.r, "v_n": c.v_n, "psd_s": c.psd_s,
        "median_frac_inside_ring": r3(np.median(frac)), "median_mean_dist_to_source": r3(np.median(dist)),
        "median_com_dist": r3(np.median(com)),
        "median_final_mean_dist": r3(np.median(b.kept("mean_dist")[-1])),
        "max_occupancy_inside_ring": r3(_inside_peak(b, c.r) * 1e3) / 1e3,
    }


def _inside_peak(b: ch.SonarBatch, r: float) -> float:
    """Highest occupancy probability of a cell lying wholly inside the ring."""
    p = ch.occupancy_probability(b)
    centres = -b.extent + (np.arange(p.shape[0]) + 0.5) * b.cell
    far = np.hypot(*np.meshgrid(centres, centres, indexing="ij")) + b.cell / np.sqrt(2) < r
    return float(p[far].max()) if far.any() else 0.0


def _checks(stats: dict[str, dict[str, Any]], cases: Sequence[ch.EscortCase], est: dict[str, dict[str, Estimate]],
            batches: dict[str, ch.SonarBatch]) -> list[dict[str, Any]]:
    s = lambda n, r, k: stats[f"n{n}-r{r:g}"][k]  # noqa: E731
    e = lambda n, r, k: est[f"n{n}-r{r:g}"][k]  # noqa: E731
    have = {c.name for c in cases}
    checks = []
    radii = [r for r in (25.0, 50.0, 75.0) if f"n10-r{r:g}" in have]
    if radii:
        peaks = {r: ch.inside_peak(batches[f"n10-r{r:g}"], r) for r in radii}
        checks.append(check("10 robots sometimes cross the ring: some cell wholly inside r has occupancy ≥ 0.1 %",
                            "0.1 % contour inside the ring for every r", "; ".join(
                                f"r = {r:g}: peak inside {100 * v.value:.2f} %" for r, v in peaks.items()),
                            all(v.value >= LEVEL for v in peaks.values()),
                            vd.all_of(vd.at_least(v, LEVEL) for v in peaks.values())))
    for r in (50.0, 75.0):
        if {f"n10-r{r:g}", f"n40-r{r:g}"} <= have:
            f10, f40 = s(10, r, "median_frac_inside_ring"), s(40, r, "median_frac_inside_ring")
            checks.append(check(f"40 robots hold r = {r:g} m better than 10: median fraction of robots inside the ring",
                                "40 robots hold the distance well, 10 robots cross the ring",
                                f"40: {f40:.3f} vs 10: {f10:.3f}", f40 < f10,
                                vd.less(e(40, r, "frac"), e(10, r, "frac"))))
    if {"n40-r25", "n40-r50", "n40-r75"} <= have:
        f = {r: s(40, r, "median_frac_inside_ring") for r in (25.0, 50.0, 75.0)}
        checks.append(check("40 robots hold r = 25 m worse than 50 and 75 m (median fraction inside the ring)",
                            "r = 25 m is not held (near-field curvature); 50 and 75 m are held well",
                            "; ".join(f"r = {r:g}: {v:.3f}" for r, v in f.items()), f[25.0] > max(f[50.0], f[75.0]),
                            vd.all_of(vd.less(e(40, r, "frac"), e(40, 25.0, "frac")) for r in (50.0, 75.0))))
    for c in cases:
        d = stats[c.name]["median_mean_dist_to_source"]
        checks.append(check(f"{c.name}: the swarm stays at the ring (median mean robot–source distance within "
                            "r ± 50 %; threshold ours)", f"robots keep r = {c.r:g} m", f"{d:.1f} m",
                            0.5 * c.r <= d <= 1.5 * c.r, vd.within(est[c.name]["dist"], 0.5 * c.r, 1.5 * c.r)))
    return checks
