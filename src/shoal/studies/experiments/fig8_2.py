"""Fig. 8-2: Generalised Triangulation PSO against XB-PSO (Rossides §8.1.1, p. 179; Fig. 8-2, p. 181).

Both drive the non-omnidirectional controller [8.7] with DVC (Table 8.1: α = β = 0.9,
U = 2 m/s, Δt = 1 s), 10 robots sensing each other in six sectors (R_sense = 10 m,
robots as 1 m-radius discs; collisions not enforced, contacts counted), waveform-level
signals (Q = 1.5, TBP = 100; D = 0.75 m for XB-PSO, one centre hydrophone for GT-PSO),
a = 1, d_0 = d_c = 50 m, horizon 2000 timesteps (preset ``sonar-gt-pso``). The thesis
names only SNR_0 = 10 and 6 dB; 4 and 0 dB stand for its unlisted lower values (docs/readings.md, "Unstated settings of
Chapter 8").
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from shoal.presets.builders.sonar import sonar_params_for
from shoal.presets.io import load
from shoal.presets.models import required

from . import chapter78 as ch
from . import verdict as vd
from .fig7_2 import SERIES_EVERY, make_jobs, seed_for
from .output import check, checks_table, new_figure, r3, save

PRESET = "sonar-gt-pso"
DEFAULT_RUNS = 100
HORIZON = 2000
SNRS = (10.0, 6.0, 4.0, 0.0)
ALGORITHMS = ("gt-pso", "xb-pso")
RUNS_COLUMNS = ("case", "run", "seed", "snr0_db", "converged", "steps_to_converge")
GT_CONVERGES = (10.0, 6.0)  # thesis: GT-PSO converges only there within 2000 steps


def run(
    out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
    steps: int = HORIZON, snrs: Sequence[float] = SNRS, mode: str = "waveform",
) -> dict[str, Any]:
    jobs = make_jobs(runs, steps, snrs, ALGORITHMS, mode, preset=PRESET)
    res, wall = ch.convergence_sweep(jobs, runs, out_dir, RUNS_COLUMNS, SERIES_EVERY, workers, progress, "fig8-2")
    acoustics = required(jobs[0].scenario().acoustics, "acoustics")
    p = sonar_params_for(acoustics)
    med = {j.key: res[j.key].median_steps() for j in jobs}
    frac = {j.key: float(res[j.key].converged.mean()) for j in jobs}

    fig, axes = new_figure(1, len(snrs), 4.2, 3.6)
    for ax, snr in zip(axes, snrs):
        ch.band_panel(ax, {a: res[(a, snr)] for a in ALGORITHMS}, f"SNR0 = {snr:g} dB", p.dc, p.r_ref, inner=True)
        ax.set_xlim(0, steps)
    axes[0].legend(fontsize=8, loc="upper right")
    fig.suptitle(f"Fig. 8-2: median |CoM − source|, 25–75 % and 5–95 % bands, {runs} runs, non-omni controller",
                 fontsize=10)
    save(fig, out_dir / "fig8-2.png")

    txt = lambda a, s: f"{ch.time_text(med[(a, s)], steps)} ({frac[(a, s)]:.0%} converged)"  # noqa: E731
    conv = lambda a, s: bool(np.isfinite(med[(a, s)]))  # noqa: E731
    est = {k: b.steps() for k, b in res.items()}
    converges = lambda a, s: vd.below(est[(a, s)], np.inf)  # noqa: E731
    checks = []
    high = [s for s in snrs if s in GT_CONVERGES]
    low = [s for s in snrs if s not in GT_CONVERGES]
    if high:
        checks.append(check(f"GT-PSO converges at SNR0 = {', '.join(f'{s:g}' for s in high)} dB within {steps} steps "
                            "(median)", "converges at 10 and 6 dB",
                            "; ".join(f"{s:g} dB: {txt('gt-pso', s)}" for s in high),
                            all(conv("gt-pso", s) for s in high), vd.all_of(converges("gt-pso", s) for s in high)))
    if low:
        checks.append(check(f"GT-PSO does not converge at the lower SNR0 ({', '.join(f'{s:g}' for s in low)} dB) "
                            f"within {steps} steps (median)", "no convergence below 6 dB in 2000 steps",
                            "; ".join(f"{s:g} dB: {txt('gt-pso', s)}" for s in low),
                            not any(conv("gt-pso", s) for s in low),
                            vd.all_of(vd.negate(converges("gt-pso", s)) for s in low)))
    checks.append(check(f"XB-PSO converges at every SNR0 within {steps} steps (median)", "fast convergence at all SNR0",
                        "; ".join(f"{s:g} dB: {txt('xb-pso', s)}" for s in snrs), all(conv("xb-pso", s) for s in snrs),
                        vd.all_of(converges("xb-pso", s) for s in snrs)))
    checks.append(check("XB-PSO faster than GT-PSO at every SNR0 (median time)", "XB-PSO converges fast",
                        "; ".join(f"{s:g} dB: XB {ch.time_text(med[('xb-pso', s)], steps)} vs GT "
                                  f"{ch.time_text(med[('gt-pso', s)], steps)}" for s in snrs),
                        all(med[("xb-pso", s)] < med[("gt-pso", s)] for s in snrs),
                        vd.all_of(vd.less(est[("xb-pso", s)], est[("gt-pso", s)]) for s in snrs)))
    robot_steps = sum(b.robot_steps for b in res.values())
    summary = {
        "checks": checks,
        "mode": mode,
        "horizon": steps,
        "snr0_db": list(snrs),
        "receiver": {"lag_peak": acoustics.lag_peak, "fs": acoustics.fs},
        "percentiles": [5, 25, 75, 95],
        "series_every": SERIES_EVERY,
        "cases": {f"{a} @ {s:g} dB": {
            "median_steps_to_converge": med[(a, s)] if conv(a, s) else None,
            "converged_fraction": r3(frac[(a, s)]),
            "command": next(j.command() for j in jobs if j.key == (a, s)),
        } for s in snrs for a in ALGORITHMS},
        "seeds": {f"{s:g} dB": seed_for(load(PRESET).sim.seed, s) for s in snrs},
        "seed_rule": "run i of both algorithms at one SNR_0 uses child i of SeedSequence(seed), "
                     "seed = 10000·preset seed + 5000 + 10·SNR_0",
        "cost": {"simulation_wall_s": round(wall, 1), "robot_steps": robot_steps,
                 "wall_us_per_robot_step": round(wall / max(robot_steps, 1) * 1e6, 2), "workers": workers},
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    runs, steps, mode = summary["runs"], summary["horizon"], summary["mode"]
    return f"""# Fig. 8-2 reproduction: GT-PSO against XB-PSO

Non-omnidirectional controller with DVC (Table 8.1), 10 robots, {runs} seeded runs per algorithm
and SNR0, horizon {steps} timesteps, acoustics mode `{mode}`; preset `sonar-gt-pso` with `--set`
overrides (`summary.json` → `cases.*.command`). XB-PSO hears with the Chapter 7 receiver (the
sample lag at {summary["receiver"]["fs"]:g} Hz). Robots sense each other in six sectors but
collisions are not enforced.

## Files

- `runs.csv`: `{",".join(RUNS_COLUMNS)}` (empty `steps_to_converge`: not within the horizon).
- `series.csv`: median and {"/".join(f"{q:g}" for q in summary["percentiles"])}th percentiles of |CoM − source| (m)
  every {summary["series_every"]} steps.
- `fig8-2.png`: median with 25–75 % and 5–95 % bands, one panel per SNR0.

## Checks

{checks_table(summary["checks"])}
"""
