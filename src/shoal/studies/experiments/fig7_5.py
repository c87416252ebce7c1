"""Fig. 7-5: median time to convergence over (Q, U) at SNR_0 = 10 dB, D = λ_c/2 (Ch. 7.4.1).

As Fig. 7-4 (``fig7_4.sweep``) with the top speed U swept instead of D; the Adapted PSO
coefficients follow U (ω = 1 − β, ĉ = βU/√2 [4.15]). Default grid (ours; the thesis gives
none): Q ∈ {1, 1.5, 10, 50} and U ∈ {2, 4, 8, 12} m/s for all four algorithms, 20 runs per
point (the thesis: 100). Both splits of ĉ of fig7-2 run as cases; the preset's is judged
by the checks, the other is reported as information.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from . import chapter78 as ch
from . import verdict as vd
from .fig7_2 import SPLITS, split_label
from .fig7_4 import C1_SHARE, D0, HORIZON, Q0, U0, _readme, converges, est, final, heatmaps, med, sweep, unaffected
from .output import check, info

DEFAULT_RUNS = 20
Q_GRID = (1.0, 1.5, 10.0, 50.0)
U_GRID = (2.0, 4.0, 8.0, 12.0)


def run(out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
        steps: int = HORIZON, q: Sequence[float] = Q_GRID, u: Sequence[float] = U_GRID,
        mode: str = "waveform", shares: Sequence[float] = SPLITS) -> dict[str, Any]:
    q, u = tuple(sorted(q)), tuple(sorted(u))
    if Q0 not in q or U0 not in u:
        raise ValueError(f"the grid must contain the Fig. 7-2 setting Q = {Q0:g}, U = {U0:g} m/s")
    shares = tuple(dict.fromkeys((C1_SHARE, *shares)))  # the preset's split first
    points = {alg: [(x, D0, y) for x in q for y in u] for alg in ch.ALGORITHMS}
    res, cost = sweep(out_dir, "fig7-5", points, runs, workers, progress, steps, mode, shares)
    for sh in shares:
        name = "fig7-5.png" if sh == C1_SHARE else f"fig7-5-c1c2-{split_label(sh).replace(':', '-')}.png"

        def key(alg: str, x: float, y: float, sh: float = sh) -> tuple:
            return (alg, x, D0, y, sh)

        heatmaps(out_dir / name, res, points, q, u, key, "U (m/s)",
                 f"Fig. 7-5: median time to d_c at SNR0 = 10 dB, D = λ_c/2, c1:c2 = {split_label(sh)}, {runs} runs "
                 "per point", steps=steps)
    checks = _checks(res, q, u, steps, C1_SHARE)
    information = [info(f"[c1:c2 = {split_label(sh)}] {c['name']}", c["thesis"], c["measured"], c["pass"])
                   for sh in shares[1:] for c in _checks(res, q, u, steps, sh)]
    summary = {
        "checks": checks,
        "information": information,
        "mode": mode, "horizon": steps, "snr0_db": 10.0, "q_grid": list(q), "U_grid": list(u),
        "c1_share": C1_SHARE, "c1_shares": list(shares),
        "final_com_dist_m": {f"{alg} Q={x:g} U={y:g} c1:c2={split_label(sh)}": round(final(res, alg, x, D0, y, sh), 1)
                             for sh in shares for alg in ch.ALGORITHMS for x in q for y in u},
        "seed_rule": "every point uses child i of SeedSequence(seed) for run i, seed = the Fig. 7-2 seed of 10 dB",
        "cost": cost,
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    return _readme("Fig. 7-5", "fig7-5.png", "(Q, U)", summary["runs"], summary["horizon"], summary["mode"], summary)


def _checks(res: dict, q: Sequence[float], u: Sequence[float], steps: int, sh: float) -> list[dict[str, Any]]:
    """The thesis' claims about Fig. 7-5 for one split of ĉ."""
    qlo, qhi, ulo, uhi = q[0], q[-1], u[0], u[-1]
    m = lambda alg, x, y: med(res, alg, x, D0, y, sh)  # noqa: E731
    e = lambda alg, x, y: est(res, alg, x, D0, y, sh)  # noqa: E731
    checks = []
    for alg in ch.ALGORITHMS:
        a, b = m(alg, Q0, ulo), m(alg, Q0, uhi)
        ideal = uhi / ulo
        checks.append(check(f"{ch.LABELS[alg]}: time ∝ 1/U at Q = {Q0:g} (median time at U = {ulo:g} over U = {uhi:g}; "
                            f"pass: within ×1.5 of {ideal:g}; threshold ours)", f"time ∝ d_s/U, ratio {ideal:g}",
                            f"{ch.time_text(a, steps)} / {ch.time_text(b, steps)}" + (
                                f" = {a / b:.2f}" if np.isfinite(a) and np.isfinite(b) else ""),
                            bool(np.isfinite(a) and np.isfinite(b) and ideal / 1.5 <= a / b <= ideal * 1.5),
                            vd.all_of(converges(e(alg, Q0, ulo)), converges(e(alg, Q0, uhi)),
                                      vd.within(e(alg, Q0, ulo).ratio(e(alg, Q0, uhi)), ideal / 1.5, ideal * 1.5))))
    for alg in ("a-pso", "x-pso"):
        reached = [x for x in u if np.isfinite(m(alg, Q0, x))]
        if len(reached) >= 2 and reached[0] != ulo:
            a, b = m(alg, Q0, reached[0]), m(alg, Q0, reached[-1])
            ideal = reached[-1] / reached[0]
            checks.append(check(f"{ch.LABELS[alg]}: time ∝ 1/U over the speeds where it converges (U = {reached[0]:g} "
                                f"over U = {reached[-1]:g}; pass: within ×1.5 of {ideal:g}; check and threshold ours)",
                                "time ∝ d_s/U", f"{a:.0f} / {b:.0f} = {a / b:.2f}",
                                ideal / 1.5 <= a / b <= ideal * 1.5,
                                vd.all_of(converges(e(alg, Q0, reached[0])), converges(e(alg, Q0, reached[-1])),
                                          vd.within(e(alg, Q0, reached[0]).ratio(e(alg, Q0, reached[-1])),
                                                    ideal / 1.5, ideal * 1.5))))
        checks.append(unaffected(res, alg, [(qlo, D0, uhi), (qhi, D0, uhi)], f"Q at U = {uhi:g} m/s", steps, sh))
    both = [x for x in u if np.isfinite(m("a-pso", Q0, x)) and np.isfinite(m("x-pso", Q0, x))]
    checks.append(check(f"X-PSO faster than A-PSO wherever both converge (Q = {Q0:g}, median times)",
                        "3400 < 4500 at U = 2 m/s (Fig. 7-2)",
                        "; ".join(f"U {x:g}: X {m('x-pso', Q0, x):.0f} vs A {m('a-pso', Q0, x):.0f}"
                                  for x in both) or "neither converges at any U",
                        bool(both) and all(m("x-pso", Q0, x) < m("a-pso", Q0, x) for x in both),
                        vd.all_of(vd.less(e("x-pso", Q0, x), e("a-pso", Q0, x)) for x in both) if both else
                        vd.Verdict(vd.FAILS if all(vd.negate(converges(e(a, Q0, x))).outcome == vd.HOLDS
                                                   for a in ("a-pso", "x-pso") for x in u) else vd.UNDECIDED,
                                   e("a-pso", Q0, ulo).runs)))
    b_hi = [m("b-pso", qhi, x) for x in u]
    xb_hi = [m("xb-pso", qhi, x) for x in u]
    checks.append(check(f"B-PSO never converges at large U with Q = {qhi:g} "
                        f"(median not reached at U ≥ {u[len(u) // 2]:g})",
                        "B-PSO unable to converge however much U increases",
                        "; ".join(f"U {x:g}: {ch.time_text(t, steps)}" for x, t in zip(u, b_hi)),
                        not any(np.isfinite(t) for x, t in zip(u, b_hi) if x >= u[len(u) // 2]),
                        vd.all_of(vd.negate(converges(e("b-pso", qhi, x))) for x in u if x >= u[len(u) // 2])))
    checks.append(check(f"XB-PSO keeps improving with U at Q = {qhi:g} (median time falls with U and is reached at "
                        f"U = {uhi:g})", "XB-PSO's performance improves as U increases",
                        "; ".join(f"U {x:g}: {ch.time_text(t, steps)}" for x, t in zip(u, xb_hi)),
                        bool(np.isfinite(xb_hi[-1]) and all(b <= a for a, b in zip(xb_hi, xb_hi[1:]))),
                        vd.all_of(converges(e("xb-pso", qhi, uhi)),
                                  *(vd.at_most_of(e("xb-pso", qhi, y), e("xb-pso", qhi, x))
                                    for x, y in zip(u, u[1:])))))
    return checks
