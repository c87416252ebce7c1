"""Fig. 7-4: median time to convergence over (Q, D/λ_c) at SNR_0 = 10 dB (Ch. 7.4.1).

Chapter 7 set-up (preset ``sonar-xb-pso``, Adapted PSO, U = 2 m/s, 10 robots, horizon 6000)
with Q and the hydrophone separation D/λ_c swept. The thesis grids are not given; the
default grid here is ours, with 20 runs per point instead of 100 to keep the waveform-level
sweep to minutes (``--runs`` and the ``q``/``d`` options change both):

- B-PSO, XB-PSO: the full Q × D/λ_c grid;
- A-PSO: the Q axis only (one centre hydrophone: D does not enter the simulation at all, so
  its heatmap repeats the Q row across D/λ_c, as the thesis' does);
- X-PSO: the Q axis at D = λ_c/2 and the D axis at the highest Q.

Every point uses the Fig. 7-2 seed of SNR_0 = 10 dB, so the point (Q = 1.5, D = λ_c/2) repeats
Fig. 7-2's 10 dB runs exactly. Medians count never-converged runs as +∞ ("n.c." cells);
the median |CoM − source| at the horizon is recorded too, which still ranks points that
did not converge.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from shoal.presets.io import load
from shoal.presets.models import required

from . import chapter78 as ch
from . import verdict as vd
from .fig7_2 import PRESET, seed_for, split_label
from .output import check, checks_table, information_table, new_figure, num, save, write_csv
from .runner import run_jobs
from .verdict import Estimate

DEFAULT_RUNS = 20
HORIZON = 6000
SNR0 = 10.0
Q_GRID = (1.0, 1.5, 3.0, 10.0, 50.0)
D_GRID = (0.5, 1.0, 2.0, 5.0, 10.0)
U0, D0, Q0 = 2.0, 0.5, 1.5  # the Fig. 7-2 setting
RUNS_COLUMNS = ("case", "run", "seed", "Q", "d_over_lambda", "U", "c1_share", "converged", "steps_to_converge")
GRID_COLUMNS = ("case", "Q", "d_over_lambda", "U", "c1_share", "runs", "converged_fraction",
                "median_steps_to_converge", "mean_steps_converged_runs", "median_final_com_dist_m")
C1_SHARE = required(load(PRESET).acoustics, "acoustics").c1_share  # the preset's split of ĉ (fig7-2)

Point = tuple[float, float, float]  # (Q, D/λ_c, U)


def fig7_4_points(q: Sequence[float], d: Sequence[float]) -> dict[str, list[Point]]:
    full = [(x, y, U0) for x in q for y in d]
    x_pso = [(x, D0, U0) for x in q] + [(max(q), y, U0) for y in d if y != D0]
    return {"a-pso": [(x, D0, U0) for x in q], "x-pso": x_pso, "b-pso": full, "xb-pso": full}


def sweep(out_dir: Path, target: str, points: dict[str, list[Point]], runs: int, workers: int, progress: bool,
          steps: int, mode: str, shares: Sequence[float] = (C1_SHARE,),
          ) -> tuple[dict[tuple, ch.SonarBatch], dict[str, Any]]:
    """Simulate every (algorithm, point, split of ĉ), write ``runs.csv`` and ``grid.csv``;
    returns the batches by (algorithm, Q, D/λ_c, U, c1 share) and the cost record."""
    seed = seed_for(load(PRESET).sim.seed, SNR0)
    jobs = [ch.job((alg, *pt, sh), PRESET, (f"acoustics.algorithm={alg}", f"acoustics.snr0_db={SNR0:g}",
                                            f"acoustics.Q={pt[0]:g}", f"acoustics.d_over_lambda={pt[1]:g}",
                                            f"acoustics.U={pt[2]:g}", f"acoustics.c1_share={sh:g}",
                                            f"acoustics.mode={mode}", f"sim.steps={steps}"),
                   seed, runs, steps)
            for sh in shares for alg, pts in points.items() for pt in dict.fromkeys(pts)]
    t0 = time.perf_counter()
    res = run_jobs(jobs, workers=workers, progress=progress, desc=target, simulate=ch.simulate_sonar,
                   merge=ch.merge, chunk=runs)
    wall = time.perf_counter() - t0
    rows, grid = [], []
    for j in jobs:
        alg, q, d, u, sh = j.key
        b = res[j.key]
        rows += [[alg, str(r), str(b.seed), num(q), num(d), num(u), num(sh), str(int(c)), ch.steps_cell(f)]
                 for r, c, f in zip(b.run_index, b.converged, b.first_converged)]
        m = b.median_steps()
        conv = b.first_converged[b.converged]
        grid.append([alg, num(q), num(d), num(u), num(sh), str(b.runs), num(b.converged.mean()),
                     num(m) if np.isfinite(m) else "", num(conv.mean()) if conv.size else "",
                     num(np.median(b.com_dist[-1]))])
    write_csv(out_dir / "runs.csv", RUNS_COLUMNS, rows)
    write_csv(out_dir / "grid.csv", GRID_COLUMNS, grid)
    robot_steps = sum(b.robot_steps for b in res.values())
    cost = {"simulation_wall_s": round(wall, 1), "robot_steps": robot_steps,
            "wall_us_per_robot_step": round(wall / max(robot_steps, 1) * 1e6, 2), "workers": workers,
            "seed": seed, "command_example": jobs[0].command()}
    return res, cost


def heatmaps(path: Path, res: dict[tuple, ch.SonarBatch], points: dict[str, list[Point]], x: Sequence[float],
             y: Sequence[float], key: Callable[[str, float, float], tuple], ylabel: str, title: str,
             lines: Sequence[float] = (1.0, 10.0), mark: float = Q0, steps: int = HORIZON) -> None:
    """One heatmap per algorithm of the median time to d_c over (Q, y); blank = not
    simulated, grey 'n.c.' = median not reached within the horizon."""
    from matplotlib.colors import LogNorm

    algs = list(points)
    fig, axes = new_figure(1, len(algs), 3.6, 3.3)
    norm = LogNorm(vmin=50, vmax=steps)
    im = None
    for ax, alg in zip(axes, algs):
        Z = np.full((len(y), len(x)), np.nan)
        nc = np.zeros_like(Z, bool)
        for i, yy in enumerate(y):
            for k, xx in enumerate(x):
                b = res.get(key(alg, xx, yy))
                if b is None:
                    continue
                m = b.median_steps()
                Z[i, k], nc[i, k] = (m, False) if np.isfinite(m) else (np.nan, True)
        im = ax.imshow(Z, origin="lower", cmap="viridis_r", norm=norm, aspect="auto")
        ax.imshow(np.where(nc, 1.0, np.nan), origin="lower", cmap="Greys", vmin=0, vmax=2, aspect="auto")
        for i in range(len(y)):
            for k in range(len(x)):
                if nc[i, k] or np.isfinite(Z[i, k]):
                    ax.text(k, i, "n.c." if nc[i, k] else f"{Z[i, k]:.0f}", ha="center", va="center", fontsize=6,
                            color="black" if nc[i, k] else "white")
        for q in lines:
            if q in x:
                ax.axvline(list(x).index(q), color="red", lw=0.8)
        if mark in x:
            ax.axvline(list(x).index(mark), color="blue", lw=0.8)
        ax.set_xticks(range(len(x)), [f"{v:g}" for v in x])
        ax.set_yticks(range(len(y)), [f"{v:g}" for v in y])
        ax.set_xlabel("Q")
        ax.set_ylabel(ylabel)
        ax.set_title(ch.LABELS[alg], fontsize=10)
    fig.colorbar(im, ax=list(axes), shrink=0.8, label="median time to d_c (timesteps)")
    fig.suptitle(title, fontsize=10)
    save(fig, path)


def med(res: dict[tuple, ch.SonarBatch], alg: str, q: float, d: float = D0, u: float = U0,
        share: float = C1_SHARE) -> float:
    return res[(alg, q, d, u, share)].median_steps()


def est(res: dict[tuple, ch.SonarBatch], alg: str, q: float, d: float = D0, u: float = U0,
        share: float = C1_SHARE) -> Estimate:
    """:func:`med` with its interval."""
    return res[(alg, q, d, u, share)].steps()


def converges(e: Estimate) -> vd.Verdict:
    """The median time is reached (its interval is finite)."""
    return vd.below(e, np.inf)


def final(res: dict[tuple, ch.SonarBatch], alg: str, q: float, d: float = D0, u: float = U0,
          share: float = C1_SHARE) -> float:
    return float(np.median(res[(alg, q, d, u, share)].com_dist[-1]))


def unaffected(res, alg: str, pts: Sequence[Point], what: str, steps: int, share: float = C1_SHARE) -> dict[str, Any]:
    """Check that ``alg`` behaves alike at the points: median times within ×1.3 when all
    converge, else median final distances within ±20 % (thresholds ours)."""
    t = [res[(alg, *p, share)].median_steps() for p in pts]
    f = [float(np.median(res[(alg, *p, share)].com_dist[-1])) for p in pts]
    te = [res[(alg, *p, share)].steps() for p in pts]
    fe = [Estimate.median(res[(alg, *p, share)].com_dist[-1]) for p in pts]
    verdict = vd.any_of(vd.all_of(*(converges(e) for e in te), vd.ratio_at_most(te, 1.3)),
                        vd.all_of(*(vd.negate(converges(e)) for e in te), vd.ratio_at_most(fe, 1.2)))
    if all(np.isfinite(t)):
        shown, ok = ", ".join(f"{v:.0f}" for v in t) + " steps", max(t) <= 1.3 * min(t)
    else:
        shown = ", ".join(ch.time_text(v, steps) for v in t) + "; final |CoM − source| " + ", ".join(
            f"{v:.0f}" for v in f) + " m"
        ok = not any(np.isfinite(t)) and max(f) <= 1.2 * min(f)
    return check(f"{ch.LABELS[alg]} is not affected by {what} (median times within ×1.3, or if none converges the "
                 "median final distances within ±20 %; thresholds ours)", "no effect", shown, ok, verdict)


def run(out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
        steps: int = HORIZON, q: Sequence[float] = Q_GRID, d: Sequence[float] = D_GRID,
        mode: str = "waveform") -> dict[str, Any]:
    q, d = tuple(sorted(q)), tuple(sorted(d))
    if Q0 not in q or D0 not in d:
        raise ValueError(f"the grid must contain the Fig. 7-2 setting Q = {Q0:g}, D/λ_c = {D0:g}")
    points = fig7_4_points(q, d)
    res, cost = sweep(out_dir, "fig7-4", points, runs, workers, progress, steps, mode)
    heatmaps(out_dir / "fig7-4.png", res, points, q, d,
             lambda alg, x, y: (alg, x, D0 if alg == "a-pso" else y, U0, C1_SHARE), "D/λ_c",
             f"Fig. 7-4: median time to d_c at SNR0 = 10 dB, {runs} runs per point (A-PSO: one hydrophone, "
             "the D axis repeats its Q row; blank = not simulated)", steps=steps)
    qlo, qhi = q[0], q[-1]
    checks = [
        unaffected(res, "a-pso", [(qlo, D0, U0), (qhi, D0, U0)], f"Q ({qlo:g} vs {qhi:g})", steps),
        unaffected(res, "x-pso", [(qlo, D0, U0), (qhi, D0, U0)], f"Q ({qlo:g} vs {qhi:g})", steps),
        unaffected(res, "x-pso", [(qhi, D0, U0), (qhi, d[-1], U0)], f"D (D/λ_c {D0:g} vs {d[-1]:g} at Q = {qhi:g})",
                   steps),
    ]
    for alg in ("b-pso", "xb-pso"):
        checks.append(check(f"{ch.LABELS[alg]} slower as Q rises (D = λ_c/2: median time at Q = {qhi:g} above "
                            f"Q = {qlo:g})",
                            "performance decreases as Q increases",
                            f"{ch.time_text(med(res, alg, qhi), steps)} vs {ch.time_text(med(res, alg, qlo), steps)}",
                            med(res, alg, qhi) > med(res, alg, qlo), vd.less(est(res, alg, qlo), est(res, alg, qhi))))
    pairs = [(med(res, "xb-pso", x), med(res, "b-pso", x)) for x in q]
    checks.append(check("XB-PSO at least as fast as B-PSO at every Q (D = λ_c/2; pass: XB ≤ 1.05 × B; threshold ours)",
                        "XB-PSO slightly faster than B-PSO at every Q",
                        "; ".join(f"Q {x:g}: {ch.time_text(a, steps)} vs {ch.time_text(b, steps)}"
                                  for x, (a, b) in zip(q, pairs)),
                        all(a <= 1.05 * b for a, b in pairs),
                        vd.all_of(vd.at_most_of(est(res, "xb-pso", x), est(res, "b-pso", x).scaled(1.05)) for x in q)))
    for alg in ("b-pso", "xb-pso"):
        checks.append(unaffected(res, alg, [(qlo, y, U0) for y in d],
                                 f"D at low Q (Q = {qlo:g}, D/λ_c {d[0]:g}–{d[-1]:g})", steps))
        if 1.0 in d:
            t_half, t_one, t_far = med(res, alg, qhi, D0), med(res, alg, qhi, 1.0), med(res, alg, qhi, d[-1])
            checks.append(check(f"{ch.LABELS[alg]} at Q = {qhi:g}: worse as D → λ (median time at D = λ above D = λ/2)",
                                "worse as D approaches λ at high Q",
                                f"{ch.time_text(t_one, steps)} vs {ch.time_text(t_half, steps)}", t_one > t_half,
                                vd.less(est(res, alg, qhi, D0), est(res, alg, qhi, 1.0))))
            checks.append(check(f"{ch.LABELS[alg]} at Q = {qhi:g}: recovers toward D = {d[-1]:g}λ (median time "
                                f"at {d[-1]:g}λ below λ)", "convergence time reduced again toward 10λ",
                                f"{ch.time_text(t_far, steps)} vs {ch.time_text(t_one, steps)}", t_far < t_one,
                                vd.less(est(res, alg, qhi, d[-1]), est(res, alg, qhi, 1.0))))
    summary = {
        "checks": checks,
        "mode": mode, "horizon": steps, "snr0_db": SNR0, "q_grid": list(q), "d_over_lambda_grid": list(d),
        "points": {alg: [list(p) for p in dict.fromkeys(pts)] for alg, pts in points.items()},
        "seed_rule": "every point uses child i of SeedSequence(seed) for run i, seed = the Fig. 7-2 seed of 10 dB",
        "cost": cost,
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    return _readme("Fig. 7-4", "fig7-4.png", "(Q, D/λ_c)", summary["runs"], summary["horizon"], summary["mode"],
                   summary)


def _readme(fig: str, png: str, grid: str, runs: int, steps: int, mode: str, summary: dict[str, Any]) -> str:
    more = [sh for sh in summary.get("c1_shares", []) if sh != C1_SHARE]
    splits = "".join(f"; also {split_label(sh)}, reported as information" for sh in more)
    others = "".join(f"; the same for c1:c2 = {split_label(sh)} in "
                     f"`{png[:-4]}-c1c2-{split_label(sh).replace(':', '-')}.png`" for sh in more)
    return f"""# {fig} reproduction: median time to convergence over {grid}

Chapter 7 set-up (preset `{PRESET}`, c1:c2 = {split_label(C1_SHARE)}{splits}), SNR0 = 10 dB, {runs} seeded
runs per grid point, horizon {steps} timesteps, acoustics mode `{mode}`. Points per algorithm:
`summary.json` → `points`.

## Files

- `runs.csv`: `{",".join(RUNS_COLUMNS)}` (empty `steps_to_converge`: not within the horizon).
- `grid.csv`: `{",".join(GRID_COLUMNS)}` per algorithm, point and split (empty median: n.c.).
- `{png}`: heatmaps of the median time to d_c (grey "n.c.": median not reached){others}.

## Checks

{checks_table(summary["checks"])}

{information_table(summary.get("information", []))}
"""
