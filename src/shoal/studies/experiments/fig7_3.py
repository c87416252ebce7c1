"""Fig. 7-3: the routes of the CoM of the 10 dB swarms of Fig. 7-2 and where they passed.

The thesis draws, per algorithm, the CoM routes of its 100 swarms at SNR_0 = 10 dB over a
map of how many swarms passed each place, with three random swarms picked out, and reads
them: A-PSO and X-PSO zig-zag and spread, B-PSO and XB-PSO run fairly straight; locations
that more than half of the swarms pass appear only from about 0.25 spatial steps for A/X
but from about 0.1 for B/XB (Ch. 7.4).

The routes are those of fig7-2 (same preset, seeds and split of ĉ): the target reads the
``routes.npz`` a fig7-2 run beside it wrote, or simulates the same 10 dB jobs when there is
none with the same runs and horizon. Every route is turned so that its source lies on +x
(at d_s = 0.316 spatial steps, R_ref = 1000 m) and ends where the run converged (or at the
horizon).

Measures (ours; the thesis states no numbers but 0.25 and 0.1):

- straightness: progress toward the source over path length, per run;
- spread: root-mean-square distance of the route from the origin–source line, per run;
- density: the fraction of swarms whose route passes each cell of ``CELL`` spatial steps;
  ``x50`` is the distance from the origin beyond which, up to the convergence circle, every
  column of cells holds a cell passed by more than half of the swarms.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Sequence

import numpy as np

from shoal.presets.builders.sonar import sonar_params_for
from shoal.presets.models import required

from . import chapter78 as ch
from . import verdict as vd
from .fig7_2 import DEFAULT_RUNS, HORIZON, PRESET, ROUTES, ROUTES_SNR, make_jobs, split_label, write_routes
from .output import check, checks_table, info, information_table, new_figure, num, r3, save, write_csv
from .runner import run_jobs
from .verdict import LEVEL, Estimate

CELL = 0.02  # spatial steps (20 m) per side of a density cell
EXAMPLES = 3  # randomly chosen swarms drawn over the map, as in the thesis
EXAMPLE_SEED = 73
THESIS_X50 = {"a-pso": 0.25, "x-pso": 0.25, "b-pso": 0.1, "xb-pso": 0.1}
RUNS_COLUMNS = ("case", "run", "seed", "converged", "steps_to_converge", "path_length", "straightness", "spread")
SOURCE_NOTE = {"fig7-2": "read from the fig7-2 run beside this one", "simulated": "simulated by this target"}


def load_routes(path: Path, runs: int, steps: int) -> dict[str, Any] | None:
    """The routes a fig7-2 run wrote, if they exist and match ``runs`` and ``steps``."""
    if not path.is_file():
        return None
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    if int(data["runs"]) != runs or int(data["steps"]) != steps:
        return None
    return data


def simulate_routes(out_dir: Path, runs: int, steps: int, workers: int, progress: bool, mode: str) -> dict[str, Any]:
    """The 10 dB jobs of fig7-2 (preset split) with routes, written to ``out_dir/routes.npz``."""
    jobs = [j for j in make_jobs(runs, steps, (ROUTES_SNR,), ch.ALGORITHMS, mode, routes=True)]
    res = run_jobs(jobs, workers=workers, progress=progress, desc="fig7-3", simulate=ch.simulate_sonar,
                   merge=ch.merge, chunk=runs)
    write_routes(out_dir / ROUTES, {j.key[0]: res[j.key] for j in jobs}, runs, steps)
    routes = load_routes(out_dir / ROUTES, runs, steps)
    if routes is None:  # (just written for these runs and steps)
        raise RuntimeError(f"{out_dir / ROUTES}: the routes just written do not read back")
    return routes


def route_of(com: np.ndarray, first: int, every: int) -> np.ndarray:
    """One run's CoM route (K', 2) up to its convergence sample (the whole route if it never converged)."""
    end = com.shape[0] if first < 0 else min(com.shape[0], first // every + 2)
    return com[:end].astype(float)


def densify(route: np.ndarray, step: float) -> np.ndarray:
    """Points along the route no farther apart than ``step`` (linear between samples)."""
    seg = np.diff(route, axis=0)
    n = np.maximum(1, np.ceil(np.linalg.norm(seg, axis=-1) / step).astype(int))
    t = np.concatenate([np.arange(k) / k for k in n])
    start = np.repeat(route[:-1], n, axis=0)
    return np.vstack([start + t[:, None] * np.repeat(seg, n, axis=0), route[-1:]])


def route_stats(route: np.ndarray) -> tuple[float, float, float]:
    """Path length, straightness (progress along +x over path length) and RMS distance from
    the x axis, all in the route's units."""
    length = float(np.linalg.norm(np.diff(route, axis=0), axis=-1).sum())
    progress = float(route[-1, 0] - route[0, 0])
    return length, progress / length if length > 0 else 0.0, float(np.sqrt(np.mean(route[:, 1] ** 2)))


def half_floors(runs: int) -> tuple[float, float]:
    """The fractions of ``runs`` swarms from which more than half of all swarms may pass a
    cell, and from which they surely do (the 95 % interval of the proportion, as the
    interval of a median of 0/1 values, lies partly / wholly above 0.5); inf: never."""
    from scipy.stats import binomtest

    def first(ok) -> float:
        k = next((k for k in range(runs + 1) if ok(binomtest(k, runs).proportion_ci(LEVEL))), None)
        return np.inf if k is None else k / runs

    return first(lambda ci: ci.high > 0.5), first(lambda ci: ci.low > 0.5)


def density(routes: list[np.ndarray], lo: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """(nx, ny) fraction of routes that pass each cell of side ``CELL`` from corner ``lo``."""
    count = np.zeros(shape, np.int64)
    for r in routes:
        ij = np.floor((densify(r, CELL / 2) - lo) / CELL).astype(np.int64)
        ok = np.all((ij >= 0) & (ij < np.array(shape)), axis=-1)
        cells = np.unique(ij[ok, 0] * shape[1] + ij[ok, 1])
        count.ravel()[cells] += 1
    return count / max(len(routes), 1)


def x50(dens: np.ndarray, xs: np.ndarray, x0: float, x1: float, floor: float | None = None) -> float:
    """Smallest x in [x0, x1] from which every column up to x1 has a cell above 50 % (with
    ``floor``: a cell of at least that fraction)."""
    cols = np.flatnonzero((xs >= x0) & (xs <= x1))
    high = dens[cols].max(axis=1) > 0.5 if floor is None else dens[cols].max(axis=1) >= floor - 1e-12
    if not high.size or not high[-1]:
        return float("nan")
    last_low = np.flatnonzero(~high)
    start = cols[last_low[-1] + 1] if last_low.size else cols[0]
    return float(xs[start])


def _reach_verdict(dens: dict, xs: np.ndarray, x0: float, x1: float, runs: int, near: Sequence[str],
                   far: Sequence[str]) -> vd.Verdict:
    """x50 of B/XB-PSO (``far``) reached and nearer the origin than A/X-PSO's (``near``; never
    reached counts as farthest), judged on x50 with the cells that more than half of all
    swarms may pass (earliest) and surely pass (latest)."""
    may, sure = half_floors(runs)
    early = {a: x50(dens[a], xs, x0, x1, may) for a in dens}  # nan: never
    late = {a: x50(dens[a], xs, x0, x1, sure) for a in dens}
    inf = lambda v: np.inf if np.isnan(v) else v  # noqa: E731
    holds = all(np.isfinite(late[f]) for f in far) and all(inf(early[n]) > max(late[f] for f in far) for n in near)
    fails = any(np.isnan(early[f]) for f in far) or any(
        np.isfinite(late[n]) and late[n] <= max(inf(early[f]) for f in far) for n in near)
    return vd.Verdict(vd.HOLDS if holds else vd.FAILS if fails else vd.UNDECIDED, runs)


def run(out_dir: Path, runs: int = DEFAULT_RUNS, workers: int = 1, progress: bool = True, *,
        steps: int = HORIZON, mode: str = "waveform") -> dict[str, Any]:
    data = load_routes(out_dir.parent / "fig7-2" / ROUTES, runs, steps)
    origin = "fig7-2"
    if data is None:
        data, origin = simulate_routes(out_dir, runs, steps, workers, progress, mode), "simulated"
    jobs = make_jobs(runs, steps, (ROUTES_SNR,), ch.ALGORITHMS, mode)
    p = sonar_params_for(required(jobs[0].scenario().acoustics, "acoustics"))
    R, every = float(data["r_ref"]), int(data["every"])
    d_s, dc, d0 = p.d_s / R, p.dc / R, p.d0 / R
    routes = {a: [route_of(data[f"com_{a}"][:, i] / R, int(data[f"first_{a}"][i]), every) for i in range(runs)]
              for a in ch.ALGORITHMS}
    lo = np.array([-0.1, -0.15])  # the mapped window, spatial steps: x to d_s + 0.1, y ± 0.15
    shape = (int(round((d_s + 0.2) / CELL)), int(round(0.3 / CELL)))
    xs = lo[0] + (np.arange(shape[0]) + 0.5) * CELL
    dens = {a: density(r, lo, shape) for a, r in routes.items()}
    stats = {a: np.array([route_stats(r) for r in rs]) for a, rs in routes.items()}  # (runs, 3)
    reach = {a: x50(dens[a], xs, d0, d_s - dc) for a in ch.ALGORITHMS}
    corridor = {a: _corridor(dens[a], xs, d0, d_s - dc) for a in ch.ALGORITHMS}
    rows = []
    for a in ch.ALGORITHMS:
        first = data[f"first_{a}"]
        rows += [[a, str(i), str(int(data["seed"])), str(int(first[i] >= 0)), ch.steps_cell(int(first[i])),
                  num(stats[a][i, 0]), num(stats[a][i, 1]), num(stats[a][i, 2])] for i in range(runs)]
    write_csv(out_dir / "runs.csv", RUNS_COLUMNS, rows)
    write_csv(out_dir / "density.csv", ("case", "x", "y", "fraction_of_swarms"),
              [[a, num(xs[i]), num(lo[1] + (j + 0.5) * CELL), num(dens[a][i, j])]
               for a in ch.ALGORITHMS for i, j in zip(*np.nonzero(dens[a]))])
    pick = np.random.default_rng(EXAMPLE_SEED).choice(runs, size=min(EXAMPLES, runs), replace=False)
    _figure(out_dir / "fig7-3.png", routes, dens, lo, shape, pick, d_s, dc, every, runs)

    med = {a: np.median(stats[a], axis=0) for a in ch.ALGORITHMS}
    straight, spread = ({a: r3(med[a][k]) for a in ch.ALGORITHMS} for k in (1, 2))
    near, far = ("a-pso", "x-pso"), ("b-pso", "xb-pso")
    checks = [
        check("B-PSO and XB-PSO run straighter than A-PSO and X-PSO (median over runs of progress toward the source "
              "over path length; measure ours)", "A/X-PSO zig-zag, B/XB-PSO fairly straight routes",
              ", ".join(f"{ch.LABELS[a]} {straight[a]}" for a in ch.ALGORITHMS),
              min(straight[a] for a in far) > max(straight[a] for a in near),
              vd.all_of(vd.less(Estimate.median(stats[n][:, 1]), Estimate.median(stats[f][:, 1]))
                        for n in near for f in far)),
        check("A-PSO and X-PSO spread more (median over runs of the RMS distance of the route from the origin–source "
              "line, spatial steps; measure ours)", "A/X-PSO spread more in the area",
              ", ".join(f"{ch.LABELS[a]} {spread[a]}" for a in ch.ALGORITHMS),
              min(spread[a] for a in near) > max(spread[a] for a in far),
              vd.all_of(vd.less(Estimate.median(stats[f][:, 2]), Estimate.median(stats[n][:, 2]))
                        for n in near for f in far)),
        check(f"places passed by more than half of the swarms begin nearer the origin for B/XB-PSO than for A/X-PSO "
              f"(x50 in spatial steps, {CELL:g} cells; measure ours)",
              "A/X from ≈ 0.25, B/XB from ≈ 0.1 spatial steps",
              ", ".join(f"{ch.LABELS[a]} {_x(reach[a])}" for a in ch.ALGORITHMS),
              all(np.isfinite(reach[a]) for a in far) and all(
                  not np.isfinite(reach[n]) or reach[n] > max(reach[a] for a in far) for n in near),
              _reach_verdict(dens, xs, d0, d_s - dc, runs, near, far)),
    ]
    information = [info(f"{ch.LABELS[a]}: x50 near the thesis' value (within 0.05 spatial steps)",
                        f"≈ {THESIS_X50[a]:g}", _x(reach[a]),
                        bool(np.isfinite(reach[a]) and abs(reach[a] - THESIS_X50[a]) <= 0.05)) for a in ch.ALGORITHMS]
    information.append(info("share of the way from the deployment disc to the convergence circle over which some "
                            "cell is passed by more than half of the swarms",
                            "B/XB-PSO most of the way, A/X-PSO little",
                            ", ".join(f"{ch.LABELS[a]} {corridor[a]:.2f}" for a in ch.ALGORITHMS),
                            min(corridor[a] for a in far) > max(corridor[a] for a in near)))
    summary = {
        "checks": checks,
        "information": information,
        "snr0_db": ROUTES_SNR,
        "c1_share": float(p.c1_share),
        "c1_c2": split_label(float(p.c1_share)),
        "routes_from": SOURCE_NOTE[origin],
        "horizon": steps,
        "cell_spatial_steps": CELL,
        "examples": [int(i) for i in pick],
        "x50": {a: None if not np.isfinite(v) else r3(v) for a, v in reach.items()},
        "median": {a: {"path_length": r3(med[a][0]), "straightness": r3(med[a][1]), "spread": r3(med[a][2])}
                   for a in ch.ALGORITHMS},
        "commands": {a: j.command() for a, j in zip(ch.ALGORITHMS, jobs)},
    }
    return summary


def readme(summary: dict[str, Any]) -> str:
    """README.md from the summary alone (``shoal reproduce --report`` renders it again)."""
    return _readme(summary, summary["runs"], summary["horizon"])


def _x(v: float) -> str:
    return f"{v:.2f}" if np.isfinite(v) else "none"


def _corridor(dens: np.ndarray, xs: np.ndarray, x0: float, x1: float) -> float:
    cols = (xs >= x0) & (xs <= x1)
    return float(np.mean(dens[cols].max(axis=1) > 0.5)) if cols.any() else 0.0


def _figure(path: Path, routes, dens, lo, shape, pick, d_s: float, dc: float, every: int, runs: int) -> None:
    from matplotlib.colors import LogNorm

    fig, axes = new_figure(2, 4, 3.7, 3.3)
    top, bottom = axes[:4], axes[4:]
    extent = (lo[0], lo[0] + shape[0] * CELL, lo[1], lo[1] + shape[1] * CELL)
    colours = ("tab:red", "tab:green", "tab:blue")
    xs = lo[0] + (np.arange(shape[0]) + 0.5) * CELL
    ys = lo[1] + (np.arange(shape[1]) + 0.5) * CELL
    im = None
    for ax, low, a in zip(top, bottom, ch.ALGORITHMS):
        d = np.where(dens[a] > 0, dens[a], np.nan).T
        im = ax.imshow(d, origin="lower", extent=extent, cmap="viridis", norm=LogNorm(vmin=1.0 / runs, vmax=1.0),
                       interpolation="nearest", aspect="auto")
        if (dens[a] > 0.5).any():
            ax.contour(xs, ys, dens[a].T, levels=[0.5], colors="white", linewidths=0.8)
        for c, i in zip(colours, pick):
            r = routes[a][i]
            ax.plot(r[:, 0], r[:, 1], color=c, lw=0.9)
            low.plot(np.arange(len(r)) * every, r[:, 0], color=c, lw=0.9, ls="--")
        t = np.linspace(0, 2 * np.pi, 100)
        ax.plot(d_s + dc * np.cos(t), dc * np.sin(t), color="white", lw=0.6, ls=":")
        ax.plot([d_s], [0.0], marker="*", color="red", ms=9, mec="k")
        ax.set_title(ch.LABELS[a], fontsize=10)
        ax.set_xlabel("spatial steps toward the source")
        ax.set_ylabel("spatial steps across")
        low.axhline(d_s - dc, color="black", lw=0.6, ls=":")
        low.set_xlabel("time (timesteps)")
        low.set_ylabel("spatial steps toward the source")
        low.grid(alpha=0.3)
    fig.colorbar(im, ax=list(top), shrink=0.8, label="fraction of swarms that passed")
    fig.suptitle(f"Fig. 7-3: CoM routes of {runs} swarms per algorithm at SNR0 = 10 dB (white line: 50 % of the "
                 f"swarms; three random swarms drawn; bottom: their progress in time)", fontsize=10)
    save(fig, path)


def _readme(summary: dict[str, Any], runs: int, steps: int) -> str:
    return f"""# Fig. 7-3 reproduction: CoM routes at SNR0 = 10 dB

The {runs} seeded swarms per algorithm of fig7-2 at SNR0 = 10 dB (preset `{PRESET}`,
c1:c2 = {summary['c1_c2']}, horizon {steps} timesteps; routes {summary['routes_from']}).
Each route is turned so that the source lies on +x and ends where the swarm converged.

## Files

- `runs.csv`: `{",".join(RUNS_COLUMNS)}`; path length and spread in spatial steps
  (R_ref = 1000 m); straightness = progress toward the source / path length.
- `density.csv`: per algorithm, every cell of {CELL:g} × {CELL:g} spatial steps that some route
  passed, with the fraction of swarms that passed it.
- `fig7-3.png`: top, the fraction of swarms that passed each cell (log colour), the half
  contour (white), three random swarms (red, green, blue), the source (star) and the
  convergence circle; bottom, the same swarms' progress toward the source in time.
- `summary.json`: checks, medians of the measures, x50 per algorithm, the example runs.

## Checks

{checks_table(summary['checks'])}

{information_table(summary['information'])}
"""
