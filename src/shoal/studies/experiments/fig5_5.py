"""Fig. 5-5: omnidirectional vs non-omnidirectional DVC on the Chapter 4 course (Section 5.3.1, p. 123).

Same course, six robots, 3 m sensing in six sectors and Table 5.1 parameters as in
Chapter 4, kinematic motion (the thesis uses MATLAB here). Cases:

- ``adapted-dvc``: Adapted RPSO + DVC (Algorithm 1), the Chapter 4 curve (preset ``course-dvc``);
- ``nonomni-dvc``: differential drive, non-omni controller [5.13] + DVC (Algorithm 2), with
  the DVC inertia guard (ours; preset ``course-nonomni``);
- ``nonomni-dvc-noguard``: the same, Algorithm 2 exactly as written.

The thesis plots the median CoM fitness with 5th–95th percentile bands; it reports that the
non-omni controller gets through faster and that its spread is wider.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from . import chapter45 as ch
from . import verdict as vd
from .output import check, checks_table, info, information_table, new_figure, r3, save, write_csv
from .runner import run_jobs
from .verdict import Estimate

DEFAULT_RUNS = 100
DURATION = 600.0  # s, as fig4-6
MODE = "kinematic"
CASES = (ch.CH4_CASES[-1], ch.NONOMNI, ch.NONOMNI_NO_GUARD)
OMNI, NONOMNI, NOGUARD = (c.name for c in CASES)


def run(
    out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
    duration: float = DURATION,
) -> dict[str, Any]:
    jobs = [ch.fleet_job(c, MODE, runs, duration) for c in CASES]
    res = run_jobs(jobs, workers=workers, progress=progress, desc="fig5-5", simulate=ch.simulate_fleet,
                   merge=ch.merge)
    b = {c.name: res[(c.name, MODE)] for c in CASES}
    rows, series = [], []
    for c in CASES:
        rows += ch.runs_rows(c.name, MODE, b[c.name])
        series += ch.series_rows(c.name, MODE, b[c.name])
    write_csv(out_dir / "runs.csv", ch.RUNS_COLUMNS, rows)
    write_csv(out_dir / "series.csv", ch.SERIES_COLUMNS, series)
    layer_x = b[OMNI].layer_x
    _figure(out_dir / "fig5-5.png", b, layer_x, runs)

    out = {n: ch.outcome(v) for n, v in b.items()}
    mid = ch.at_time(b[OMNI], duration / 2)
    med = {n: np.median(v.com, axis=1) for n, v in b.items()}
    spread = {n: np.percentile(v.com, 95, axis=1) - np.percentile(v.com, 5, axis=1) for n, v in b.items()}
    checks, information = [], []
    for n in (NONOMNI, NOGUARD):
        tag = "guard on, ours" if n == NONOMNI else "guard off, Algorithm 2 as written"
        checks += [
            check(f"{n} ({tag}) ends ahead of {OMNI}: median CoM fitness at t = {duration:g} s",
                  "the non-omni controller gets through the course faster",
                  f"{r3(med[n][-1])} m vs {r3(med[OMNI][-1])} m", med[n][-1] > med[OMNI][-1],
                  vd.less(Estimate.median(b[OMNI].com[-1]), Estimate.median(b[n].com[-1]))),
            check(f"{n} ({tag}) is ahead of {OMNI} at mid-run: median CoM fitness at t = {b[OMNI].t[mid]:g} s",
                  "the non-omni controller gets through the course faster",
                  f"{r3(med[n][mid])} m vs {r3(med[OMNI][mid])} m", med[n][mid] > med[OMNI][mid],
                  vd.less(Estimate.median(b[OMNI].com[mid]), Estimate.median(b[n].com[mid]))),
            check(f"{n} ({tag}) has the wider spread: 5th-95th percentile width of the CoM fitness, averaged "
                  "over time", "noisier curves, wider percentile spread",
                  f"{r3(spread[n].mean())} m vs {r3(spread[OMNI].mean())} m (at the end {r3(spread[n][-1])} vs "
                  f"{r3(spread[OMNI][-1])} m)", spread[n].mean() > spread[OMNI].mean(),
                  vd.less(Estimate.spread(b[OMNI].com), Estimate.spread(b[n].com))),
        ]
    for n, thesis in ((OMNI, "Adapted RPSO + DVC is collision-free (Ch. 4)"),
                      (NONOMNI, "DVC limits v so that collisions are avoided whatever w is (Section 5.2.2)"),
                      (NOGUARD, "DVC limits v so that collisions are avoided whatever w is (Section 5.2.2)")):
        o = out[n]
        checks.append(check(
            f"{n}: no robot collided at the end of the median run (the thesis' measure in Fig. 4-7)", thesis,
            f"{o.collided_median_run} collided, {o.stalled_median_run} stalled", o.collided_median_run == 0,
            vd.over_choices(lambda c: c == 0, b[n].collided[-1][vd.median_runs(b[n].com[-1])], runs=o.runs)))
        information.append(info(
            f"{n}: no robot collided in any run", thesis,
            f"{o.collided_total} robots collided, in {o.runs_with_collision} of {o.runs} runs (mean per run "
            f"{r3(o.collided_mean)})", o.collided_total == 0))
    summary = {
        "checks": checks,
        "information": information,
        "contacts": ch.CONTACTS,
        "duration_s": duration,
        "mode": MODE,
        "seed": b[OMNI].seed,
        "seed_rule": "run i of every case uses child i of SeedSequence(seed), seed = the preset seed",
        "cases": {c.name: c.command(ch.MODE_OVERRIDES[MODE]) + f" --steps {int(duration)}" for c in CASES},
        "outcomes": {n: o.as_dict() for n, o in out.items()},
        "median_com_m": {n: {"mid": r3(med[n][mid]), "end": r3(med[n][-1])} for n in med},
        "layer_x_m": [r3(v) for v in layer_x],
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    return _readme(summary, summary["runs"])


STYLE = {OMNI: ("#238b45", "omni: Adapted RPSO + DVC"), NONOMNI: ("#6a3d9a", "non-omni DVC, guard on (ours)"),
         NOGUARD: ("#e08214", "non-omni DVC as written (no guard)")}


def _figure(path: Path, b: dict, layer_x: np.ndarray, runs: int) -> None:
    fig, axes = new_figure(1, 2, 5.6, 4.4)
    top = max(float(np.percentile(v.com, 95, axis=1).max()) for v in b.values())
    for ax, pair in zip(axes, ((OMNI, NONOMNI), (OMNI, NOGUARD))):
        for n in pair:
            v = b[n]
            colour, label = STYLE[n]
            med, p05, p95 = ch.band(v.com)
            ax.fill_between(v.t, p05, p95, color=colour, alpha=0.18, lw=0, label=f"{label}, 5th-95th pct")
            ax.plot(v.t, med, color=colour, lw=1.8, label=f"{label}, median")
        ax.set_xlim(0, v.t[-1])
        ax.set_ylim(0, max(top, float(layer_x[-1]) if len(layer_x) else 0.0) + 3.0)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("CoM fitness: mean x of all robots (m)")
        ax.set_title(f"{STYLE[pair[0]][1]} vs {STYLE[pair[1]][1]}", fontsize=9)
        ax.legend(loc="upper left", fontsize=7, frameon=False)
        ax.grid(alpha=0.25, lw=0.5)
        ch.draw_layers(ax, layer_x)
    fig.suptitle(f"Fig. 5-5 reproduction: CoM fitness over time, {runs} runs each (dotted: obstacle layers)",
                 fontsize=11)
    save(fig, path)


def _readme(summary: dict[str, Any], runs: int) -> str:
    cmds = "\n".join(f"- `{k}`: `{v}`" for k, v in summary["cases"].items())
    return f"""# Fig. 5-5 reproduction: omni vs non-omni DVC on the obstacle course

The Chapter 4 course and robots (fig4-6), {summary['duration_s']:g} s, kinematic motion,
{runs} seeded runs per case:

{cmds}

## Files

- `runs.csv`: one row per (case, run): `{','.join(ch.RUNS_COLUMNS)}`.
- `series.csv`: per case and second: median, 5th and 95th percentile of the CoM fitness
  over runs, mean collided robots, median layers passed, mean stalled robots.
- Contacts: {summary['contacts']}
- `fig5-5.png`: median CoM fitness with 5th-95th percentile bands; left the omni
  controller against the non-omni one with our guard, right against Algorithm 2 as written.
- `summary.json`: the checks below and per-case outcomes.

## Checks

{checks_table(summary['checks'])}

{information_table(summary['information'])}

## Differences from the thesis

- The thesis gives no numbers for this figure, so the checks are its qualitative claims.
- `nonomni-dvc` adds our DVC inertia guard (the forward speed is capped at α·sf_1/Δt after
  the update; docs/readings.md, "The DVC guard"); `nonomni-dvc-noguard` is the thesis algorithm.
"""
