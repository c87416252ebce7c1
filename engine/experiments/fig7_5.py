"""Fig. 7-5: median time to convergence over (Q, U) at SNR_0 = 10 dB, D = λ_c/2 (spec §8.1,
§9.2).

As Fig. 7-4 (``fig7_4.sweep``) with the top speed U swept instead of D; the Adapted PSO
coefficients follow U (ω = 1 − β, ĉ = βU/√2). Default grid: Q ∈ {1, 1.5, 10, 50} and
U ∈ {2, 4, 8, 12} m/s for all four algorithms, 20 runs per point (the thesis: 100, grid not
given, spec A24).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from . import chapter78 as ch
from .fig7_4 import D0, HORIZON, Q0, U0, _readme, final, heatmaps, med, sweep, unaffected
from .output import check

DEFAULT_RUNS = 20
Q_GRID = (1.0, 1.5, 10.0, 50.0)
U_GRID = (2.0, 4.0, 8.0, 12.0)


def run(out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
        steps: int = HORIZON, q: Sequence[float] = Q_GRID, u: Sequence[float] = U_GRID,
        mode: str = "waveform") -> dict[str, Any]:
    q, u = tuple(sorted(q)), tuple(sorted(u))
    if Q0 not in q or U0 not in u:
        raise ValueError(f"the grid must contain the Fig. 7-2 setting Q = {Q0:g}, U = {U0:g} m/s")
    points = {alg: [(x, D0, y) for x in q for y in u] for alg in ch.ALGORITHMS}
    res, cost = sweep(out_dir, "fig7-5", points, runs, workers, progress, steps, mode)
    heatmaps(out_dir / "fig7-5.png", res, points, q, u, lambda alg, x, y: (alg, x, D0, y), "U (m/s)",
             f"Fig. 7-5: median time to d_c at SNR0 = 10 dB, D = λ_c/2, {runs} runs per point", steps=steps)
    qlo, qhi, ulo, uhi = q[0], q[-1], u[0], u[-1]
    checks = []
    for alg in ch.ALGORITHMS:
        a, b = med(res, alg, Q0, D0, ulo), med(res, alg, Q0, D0, uhi)
        ideal = uhi / ulo
        checks.append(check(f"{ch.LABELS[alg]}: time ∝ 1/U at Q = {Q0:g} (median time at U = {ulo:g} over U = {uhi:g}; "
                            f"pass: within ×1.5 of {ideal:g}; threshold ours)", f"time ∝ d_s/U, ratio {ideal:g}",
                            f"{ch.time_text(a, steps)} / {ch.time_text(b, steps)}" + (
                                f" = {a / b:.2f}" if np.isfinite(a) and np.isfinite(b) else ""),
                            bool(np.isfinite(a) and np.isfinite(b) and ideal / 1.5 <= a / b <= ideal * 1.5)))
    for alg in ("a-pso", "x-pso"):
        reached = [x for x in u if np.isfinite(med(res, alg, Q0, D0, x))]
        if len(reached) >= 2 and reached[0] != ulo:
            a, b = med(res, alg, Q0, D0, reached[0]), med(res, alg, Q0, D0, reached[-1])
            ideal = reached[-1] / reached[0]
            checks.append(check(f"{ch.LABELS[alg]}: time ∝ 1/U over the speeds where it converges (U = {reached[0]:g} "
                                f"over U = {reached[-1]:g}; pass: within ×1.5 of {ideal:g}; check and threshold ours)", "time ∝ d_s/U",
                                f"{a:.0f} / {b:.0f} = {a / b:.2f}", ideal / 1.5 <= a / b <= ideal * 1.5))
        checks.append(unaffected(res, alg, [(qlo, D0, uhi), (qhi, D0, uhi)], f"Q at U = {uhi:g} m/s", steps))
    both = [x for x in u if np.isfinite(med(res, "a-pso", Q0, D0, x)) and np.isfinite(med(res, "x-pso", Q0, D0, x))]
    checks.append(check(f"X-PSO faster than A-PSO wherever both converge (Q = {Q0:g}, median times)",
                        "3400 < 4500 at U = 2 m/s (Fig. 7-2)",
                        "; ".join(f"U {x:g}: X {med(res, 'x-pso', Q0, D0, x):.0f} vs A {med(res, 'a-pso', Q0, D0, x):.0f}"
                                  for x in both) or "neither converges at any U",
                        bool(both) and all(med(res, "x-pso", Q0, D0, x) < med(res, "a-pso", Q0, D0, x) for x in both)))
    b_hi = [med(res, "b-pso", qhi, D0, x) for x in u]
    xb_hi = [med(res, "xb-pso", qhi, D0, x) for x in u]
    checks.append(check(f"B-PSO never converges at large U with Q = {qhi:g} (median not reached at U ≥ {u[len(u) // 2]:g})",
                        "B-PSO unable to converge however much U increases",
                        "; ".join(f"U {x:g}: {ch.time_text(t, steps)}" for x, t in zip(u, b_hi)),
                        not any(np.isfinite(t) for x, t in zip(u, b_hi) if x >= u[len(u) // 2])))
    checks.append(check(f"XB-PSO keeps improving with U at Q = {qhi:g} (median time falls with U and is reached at "
                        f"U = {uhi:g})", "XB-PSO's performance improves as U increases",
                        "; ".join(f"U {x:g}: {ch.time_text(t, steps)}" for x, t in zip(u, xb_hi)),
                        bool(np.isfinite(xb_hi[-1]) and all(b <= a for a, b in zip(xb_hi, xb_hi[1:])))))
    summary = {
        "checks": checks,
        "mode": mode, "horizon": steps, "snr0_db": 10.0, "q_grid": list(q), "U_grid": list(u),
        "final_com_dist_m": {f"{alg} Q={x:g} U={y:g}": round(final(res, alg, x, D0, y), 1)
                             for alg in ch.ALGORITHMS for x in q for y in u},
        "seed_rule": "every point uses child i of SeedSequence(seed) for run i, seed = the Fig. 7-2 seed of 10 dB",
        "cost": cost,
    }
    (out_dir / "README.md").write_text(_readme("Fig. 7-5", "fig7-5.png", "(Q, U)", runs, steps, mode, summary),
                                       encoding="utf-8")
    return summary
