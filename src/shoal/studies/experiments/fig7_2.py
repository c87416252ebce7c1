"""Fig. 7-2: convergence of A-, X-, B- and XB-PSO against the initial SNR (Ch. 7.4).

Table 7.1 set-up (preset ``sonar-xb-pso``): 10 USVs, Adapted PSO [3.11] with U = 2 m/s,
Δt = 1 s, β = 0.9 (as in Chs. 4–5), waveform-level signals (Q = 1.5, TBP = 100, D = λ_c/2,
fs = 48 kHz), forgetting a = 1, d_0 = d_c = 50 m, horizon 6000 timesteps, the source at
d_s = R_ref·10^(−SNR_0/20) [7.16] on a random bearing. The split of ĉ into c1 and c2 is not
stated; both 1:3 (the preset's) and 1:1 run as cases. Every algorithm and split at one
SNR_0 uses the same seed, so run i starts from the same layout and source for all.

A run stops at its first tick with |CoM − x_src| ≤ d_c (its distance is held from then on
in the series and the figure); the median time counts a run that never converged as +∞.
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
from .output import check, checks_table, info, information_table, new_figure, r3, save

PRESET = "sonar-xb-pso"
DEFAULT_RUNS = 100
HORIZON = 6000
SNRS = (10.0, 4.0, 0.0)
# thesis median times (timesteps) to reach d_c; None = did not converge in 6000 (Section 7.4, p. 162)
THESIS: dict[float, dict[str, float | None]] = {
    10.0: {"a-pso": 4500, "x-pso": 3400, "b-pso": 1200, "xb-pso": 1100},
    4.0: {"a-pso": None, "x-pso": None, "b-pso": 2700, "xb-pso": 2600},
    0.0: {"a-pso": None, "x-pso": None, "b-pso": 4400, "xb-pso": 4400},
}
RUNS_COLUMNS = ("case", "run", "seed", "snr0_db", "c1_share", "converged", "steps_to_converge")
SERIES_EVERY = 10
# c1/(c1 + c2), which Ch. 7 does not state: both are run; the preset's (1:3) reproduces the
# thesis' A-PSO and X-PSO times, 1:1 leaves them unconverged (docs/readings.md)
SPLITS = (0.25, 0.5)
ROUTES_SNR = 10.0  # Fig. 7-3 studies the 10 dB runs
ROUTES, ROUTE_EVERY = "routes.npz", 5


def seed_for(base: int, snr0_db: float) -> int:
    """One seed per SNR_0, shared by the algorithms: 10000·base + 5000 + 10·SNR_0."""
    return 10_000 * base + 5_000 + int(round(10 * snr0_db))


def make_jobs(runs: int, steps: int, snrs: Sequence[float], algorithms: Sequence[str], mode: str,
              preset: str = PRESET, extra: Sequence[str] = (), shares: Sequence[float] | None = None,
              routes: bool = False) -> list[ch.SonarJob]:
    """One job per (SNR_0, algorithm), keyed (algorithm, SNR_0); with ``shares`` one per
    c1/(c1 + c2) as well, keyed (algorithm, SNR_0, share). ``routes`` keeps the CoM routes
    of the 10 dB jobs of the preset's own split (Fig. 7-3)."""
    base = load(preset).sim.seed
    own = required(load(preset).acoustics, "acoustics").c1_share
    jobs = []
    for share in (None,) if shares is None else shares:
        for snr in snrs:
            for alg in algorithms:
                key = (alg, float(snr)) if share is None else (alg, float(snr), float(share))
                split = () if share is None or share == own else (f"acoustics.c1_share={share:g}",)
                jobs.append(ch.job(key, preset, (f"acoustics.algorithm={alg}", f"acoustics.snr0_db={snr:g}",
                                                 f"acoustics.mode={mode}", f"sim.steps={steps}", *split, *extra),
                                   seed_for(base, snr), runs, steps,
                                   routes=routes and snr == ROUTES_SNR and share in (None, own)))
    return jobs


def split_label(share: float) -> str:
    """c1:c2 of a c1/(c1 + c2) share, e.g. 0.25 → "1:3"."""
    return "1:1" if share == 0.5 else f"1:{(1 - share) / share:g}" if share > 0 else "0:1"


def run(
    out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
    steps: int = HORIZON, snrs: Sequence[float] = SNRS, algorithms: Sequence[str] = ch.ALGORITHMS,
    mode: str = "waveform", shares: Sequence[float] = SPLITS,
) -> dict[str, Any]:
    own = required(load(PRESET).acoustics, "acoustics").c1_share
    shares = tuple(dict.fromkeys((own, *shares)))  # the preset's split first
    jobs = make_jobs(runs, steps, snrs, algorithms, mode, shares=shares, routes=True)
    res, wall = ch.convergence_sweep(jobs, runs, out_dir, RUNS_COLUMNS, SERIES_EVERY, workers, progress, "fig7-2")
    if ROUTES_SNR in snrs:
        write_routes(out_dir / ROUTES, {a: res[(a, ROUTES_SNR, own)] for a in algorithms}, runs, steps)

    med = {j.key: res[j.key].median_steps() for j in jobs}
    frac = {j.key: float(res[j.key].converged.mean()) for j in jobs}
    p = sonar_params_for(required(jobs[0].scenario().acoustics, "acoustics"))
    r_ref, dc, U = p.r_ref, p.dc, p.U
    _figure(out_dir / "fig7-2.png", res, snrs, algorithms, shares, r_ref, dc, runs, steps)
    def of(d: dict, sh: float) -> dict:
        return {k[:2]: v for k, v in d.items() if k[2] == sh}

    by_share = {sh: (of(med, sh), of(frac, sh), of(res, sh)) for sh in shares}
    checks = _checks(*by_share[own], snrs, algorithms, steps, r_ref, dc, U)
    information = [info(f"[c1:c2 = {split_label(sh)}] {c['name']}", c["thesis"], c["measured"], c["pass"])
                   for sh in shares[1:] for c in _checks(*by_share[sh], snrs, algorithms, steps, r_ref, dc, U)]
    information += [_nearer(by_share[sh][2], steps, sh) for sh in shares if 10.0 in snrs and all(
        (a, 10.0) in by_share[sh][0] and not np.isfinite(by_share[sh][0][(a, 10.0)]) for a in ("a-pso", "x-pso"))]
    score = {sh: _within_two(by_share[sh][0], snrs, algorithms) for sh in shares}
    robot_steps = sum(b.robot_steps for b in res.values())
    summary = {
        "checks": checks,
        "information": information,
        "mode": mode,
        "horizon": steps,
        "snr0_db": list(snrs),
        "dc_m": dc,
        "series_every": SERIES_EVERY,
        "route_every": ROUTE_EVERY,
        "c1_share": own,
        "c1_share_evidence": {split_label(sh): f"{score[sh][0]} of {score[sh][1]} thesis median times matched within ×2"
                              for sh in shares},
        "cases": {f"{alg} @ {snr:g} dB, c1:c2 = {split_label(sh)}": {
            "median_steps_to_converge": None if not np.isfinite(med[(alg, snr, sh)]) else med[(alg, snr, sh)],
            "converged_fraction": r3(frac[(alg, snr, sh)]),
            "mean_steps_converged_runs": _mean_converged(res[(alg, snr, sh)]),
            "mean_com_speed_m_s": _speed(res[(alg, snr, sh)], r_ref, snr, dc),
            "thesis_median": THESIS.get(snr, {}).get(alg, "not reported"),
            "command": next(j.command() for j in jobs if j.key == (alg, snr, sh)),
        } for sh in shares for snr in snrs for alg in algorithms},
        "seeds": {f"{snr:g} dB": seed_for(load(PRESET).sim.seed, snr) for snr in snrs},
        "seed_rule": "run i of every algorithm and split at one SNR_0 uses child i of SeedSequence(seed), "
                     "seed = 10000·preset seed + 5000 + 10·SNR_0",
        "cost": {"simulation_wall_s": round(wall, 1), "robot_steps": robot_steps,
                 "wall_us_per_robot_step": round(wall / max(robot_steps, 1) * 1e6, 2), "workers": workers},
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    return _readme(summary["runs"], summary["horizon"], summary["mode"], summary)


def _within_two(med: dict, snrs: Sequence[float], algorithms: Sequence[str]) -> tuple[int, int]:
    """How many thesis median times (n.c. included) a split reproduces within ×2."""
    hits = total = 0
    for snr in snrs:
        for a in algorithms:
            if a not in THESIS.get(snr, {}):
                continue
            th = THESIS[snr][a]
            total += 1
            m = med[(a, snr)]
            hits += (not np.isfinite(m)) if th is None else bool(np.isfinite(m) and th / 2 <= m <= 2 * th)
    return hits, total


def _speed(b: ch.SonarBatch, r_ref: float, snr: float, dc: float) -> float | None:
    """Mean CoM approach speed (d_s − d_c)/t_c over the runs that converged, m/s."""
    f = b.first_converged[b.converged]
    d_s = r_ref * 10 ** (-snr / 20)
    return round(float(np.mean((d_s - dc) / (f * b.dt))), 3) if f.size else None


def write_routes(path: Path, batches: dict[str, ch.SonarBatch], runs: int, steps: int) -> None:
    """The 10 dB CoM routes (source on +x, every ``ROUTE_EVERY`` steps) for fig7-3."""
    b0 = next(iter(batches.values()))
    contents: dict[str, Any] = dict(runs=runs, steps=steps, every=ROUTE_EVERY, r_ref=b0.r_ref, dc=b0.dc, dt=b0.dt,
                                    seed=b0.seed)  # (numbers and arrays, in this order)
    contents.update({f"com_{a}": b.com[::ROUTE_EVERY] for a, b in batches.items() if b.com is not None})
    contents.update({f"first_{a}": b.first_converged for a, b in batches.items()})
    np.savez_compressed(path, **contents)


def _nearer(res: dict, steps: int, share: float) -> dict[str, Any]:
    """X-PSO against A-PSO by the median distance at the horizon (a converged run holds d_c):
    meaningful where neither converges (ours)."""
    dX, dA = (float(np.median(res[(a, 10.0)].com_dist[-1])) for a in ("x-pso", "a-pso"))
    return info(f"[c1:c2 = {split_label(share)}] X-PSO ends nearer the source than A-PSO at 10 dB "
                f"(median |CoM − source| after {steps} steps, a converged run held at its first distance ≤ d_c; ours)",
                "X-PSO is less sensitive to noise", f"X {dX:.0f} m vs A {dA:.0f} m", dX < dA)


def _mean_converged(b: ch.SonarBatch) -> float | None:
    f = b.first_converged[b.converged]
    return round(float(f.mean()), 1) if f.size else None


def _checks(med, frac, res, snrs, algorithms, steps, r_ref, dc, U) -> list[dict[str, Any]]:
    txt = lambda alg, snr: f"{ch.time_text(med[(alg, snr)], steps)} ({frac[(alg, snr)]:.0%} of runs converged)"  # noqa: E731
    est = {k: b.steps() for k, b in res.items()}
    converges = lambda k: vd.below(est[k], np.inf)  # noqa: E731 (a median time that is reached)
    checks = []
    have = lambda *algs: all((a, s) in med for a in algs for s in snrs)  # noqa: E731
    if 10.0 in snrs and have(*ch.ALGORITHMS):
        conv = {a: np.isfinite(med[(a, 10.0)]) for a in ch.ALGORITHMS}
        checks.append(check(
            f"at SNR0 = 10 dB all four algorithms converge (median time to d_c within {steps} steps)",
            "A 4500, X 3400, B 1200, XB 1100",
            "; ".join(f"{ch.LABELS[a]} {txt(a, 10.0)}" for a in ch.ALGORITHMS), all(conv.values()),
            vd.all_of(converges((a, 10.0)) for a in ch.ALGORITHMS)))
        for a in ("b-pso", "xb-pso"):
            ratio = med[("a-pso", 10.0)] / med[(a, 10.0)]
            lower = not np.isfinite(med[("a-pso", 10.0)])
            shown = f"> {steps / med[(a, 10.0)]:.1f}× (A-PSO median not reached)" if lower else f"{ratio:.2f}×"
            checks.append(check(
                f"{ch.LABELS[a]} ≈ 4× faster than A-PSO at 10 dB (ratio of median times; pass: 2.5×–6×; "
                "threshold ours)",
                "3.75× (B) / 4.09× (XB); text: 'more than 4 times'", shown,
                (not lower) and 2.5 <= ratio <= 6.0, vd.within(est[("a-pso", 10.0)].ratio(est[(a, 10.0)]), 2.5, 6.0)))
        checks.append(check(
            "X-PSO faster than A-PSO at 10 dB (median time to d_c)", "3400 < 4500",
            f"X {txt('x-pso', 10.0)} vs A {txt('a-pso', 10.0)}",
            bool(np.isfinite(med[("x-pso", 10.0)]) and med[("x-pso", 10.0)] < med[("a-pso", 10.0)]),
            vd.all_of(converges(("x-pso", 10.0)), vd.less(est[("x-pso", 10.0)], est[("a-pso", 10.0)]))))
    for snr in (s for s in snrs if s < 10.0 and s in THESIS):
        if have(*ch.ALGORITHMS):
            ok = all(np.isfinite(med[(a, snr)]) for a in ("b-pso", "xb-pso")) and not any(
                np.isfinite(med[(a, snr)]) for a in ("a-pso", "x-pso"))
            checks.append(check(
                f"at SNR0 = {snr:g} dB only B-PSO and XB-PSO converge (median within {steps} steps)",
                f"A n.c., X n.c., B {THESIS[snr]['b-pso']}, XB {THESIS[snr]['xb-pso']}",
                "; ".join(f"{ch.LABELS[a]} {txt(a, snr)}" for a in ch.ALGORITHMS), ok,
                vd.all_of([converges((a, snr)) for a in ("b-pso", "xb-pso")]
                          + [vd.negate(converges((a, snr))) for a in ("a-pso", "x-pso")])))
    for snr in snrs:
        for a in algorithms:
            if a not in THESIS.get(snr, {}):
                continue
            th = THESIS[snr][a]
            m = med[(a, snr)]
            if th is None:
                checks.append(check(f"{ch.LABELS[a]} at {snr:g} dB: median time to d_c (pass: n.c.)", "n.c.",
                                    txt(a, snr), not np.isfinite(m), vd.negate(converges((a, snr)))))
            else:
                checks.append(check(f"{ch.LABELS[a]} at {snr:g} dB: median time to d_c (pass: within ×2 of the "
                                    "thesis; threshold ours)",
                                    th, txt(a, snr), bool(np.isfinite(m) and th / 2 <= m <= 2 * th),
                                    vd.within(est[(a, snr)], th / 2, 2 * th)))
        if ("b-pso", snr) in med and ("xb-pso", snr) in med:
            mb, mx = med[("b-pso", snr)], med[("xb-pso", snr)]
            checks.append(check(f"XB-PSO at least as fast as B-PSO at {snr:g} dB (median; pass: XB ≤ 1.05 × B; "
                                "threshold ours)",
                                "XB ≤ B at every SNR0", f"XB {ch.time_text(mx, steps)} vs B {ch.time_text(mb, steps)}",
                                bool(np.isfinite(mx) and mx <= 1.05 * mb),
                                vd.all_of(converges(("xb-pso", snr)),
                                          vd.at_most_of(est[("xb-pso", snr)], est[("b-pso", snr)].scaled(1.05)))))
    floor = {snr: max(r_ref * 10 ** (-snr / 20) - dc, 0) / U for snr in snrs}
    fastest = min((float(res[(a, s)].first_converged[res[(a, s)].converged].min()) - floor[s]
                   for a in algorithms for s in snrs if res[(a, s)].converged.any()), default=np.inf)
    checks.append(check("no run beats the straight line (d_s − d_c)/U (sanity)",
                        "straight line at U from d_s [7.16] to d_c (Table 7.1)",
                        f"smallest margin {fastest:.1f} steps" if np.isfinite(fastest) else "no run converged",
                        fastest >= 0, vd.exact(fastest >= 0)))
    return checks


def _figure(path: Path, res, snrs, algorithms, shares, r_ref: float, dc: float, runs: int, steps: int) -> None:
    fig, axes = new_figure(len(shares), len(snrs), 4.6, 3.8)
    axes = axes.reshape(len(shares), len(snrs))
    for row, sh in zip(axes, shares):
        for ax, snr in zip(row, snrs):
            ds = r_ref * 10 ** (-snr / 20) / r_ref
            thesis = {a: float(v) for a, v in THESIS.get(snr, {}).items() if v is not None}
            ch.band_panel(ax, {a: res[(a, snr, sh)] for a in algorithms},
                          f"SNR0 = {snr:g} dB (d_s = {ds:.3f} R), c1:c2 = {split_label(sh)}", dc, r_ref, thesis)
            ax.set_xlim(0, steps)
    axes[0, 0].legend(fontsize=8, loc="upper right")
    fig.suptitle(f"Fig. 7-2: median |CoM − source| and 5–95 % band, {runs} runs per case; top row the preset's "
                 f"c1:c2 = {split_label(shares[0])} (▼ = thesis median time to d_c)", fontsize=10)
    save(fig, path)


def _readme(runs: int, steps: int, mode: str, summary: dict[str, Any]) -> str:
    own = split_label(summary["c1_share"])
    evidence = "; ".join(f"c1:c2 = {k}: {v}" for k, v in summary["c1_share_evidence"].items())
    return f"""# Fig. 7-2 reproduction: convergence against the initial SNR

A-, X-, B- and XB-PSO with the Adapted PSO controller (Table 7.1), {runs} seeded runs per
algorithm, SNR0 and split of ĉ = c1 + c2, horizon {steps} timesteps, acoustics mode `{mode}`.
Every case is the preset `sonar-xb-pso` with `--set` overrides (see `summary.json` →
`cases.*.command`). Chapter 7 gives U = 2 m/s but neither β nor the split c1:c2; β is read as
in Chapters 4–5 (docs/readings.md, "β in Chapter 7"). Both splits run as cases; the preset's
c1:c2 = {own} is judged by the checks, the other is reported as information ({evidence}).

## Files

- `runs.csv`: `{",".join(RUNS_COLUMNS)}`. `steps_to_converge` is the first timestep with
  |CoM − source| ≤ d_c = {summary['dc_m']:g} m, empty when the run never got there within the horizon.
  Run `run` uses child `run` of `SeedSequence(seed)`; all algorithms and splits at one SNR0
  share `seed`.
- `series.csv`: per case, SNR0 and split, every {summary['series_every']} steps, the median and the
  percentiles of |CoM − source| that its columns name, in metres (a run is stopped when it converges
  and its distance is held from then on).
- `{ROUTES}`: the CoM routes of the 10 dB runs of the preset's split, every {summary['route_every']} steps,
  in a frame with the source on +x (target fig7-3 draws Fig. 7-3 from them).
- `fig7-2.png`: median |CoM − source| in spatial steps (R_ref = 1000 m) with percentile bands,
  one panel per SNR0, one row per split; ▼ marks the thesis median time at d_c.
- `summary.json`: checks, per-case median and mean times, mean CoM speeds, converged
  fractions, seeds and cost.

## Checks

{checks_table(summary["checks"])}

{information_table(summary["information"])}
"""
