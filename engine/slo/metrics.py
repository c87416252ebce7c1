"""SLO metrics (Mai §4.1, Tab. 4.2, spec §11): localisation errors over neighbour pairs,
inter-particle distances over all unordered pairs (gap A30), dead-reckoning share,
round-trip error, and the per-run summaries (best, end, first generation meeting T).

Every statistic is per run, shape (R,); mean, std, SEM (gap A31: both) and median;
NaN when a run has no pair.
"""

from __future__ import annotations

import numpy as np

from .selection import Kind, first_triangle


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angle in (−π, π]."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def pair_errors(x: np.ndarray, est: np.ndarray, valid: np.ndarray) -> dict[str, np.ndarray]:
    """e_abs, e_rel and e_ang of every ordered pair (R, N, N), NaN outside ``valid``;
    e_rel is also NaN for coincident particles."""
    truth = x[:, None, :, :] - x[:, :, None, :]
    e_abs = np.linalg.norm(est - truth, axis=-1)
    dist = np.linalg.norm(truth, axis=-1)
    e_rel = np.divide(e_abs, dist, out=np.full_like(e_abs, np.nan), where=dist > 0)
    ang = np.arctan2(est[..., 1], est[..., 0]) - np.arctan2(truth[..., 1], truth[..., 0])
    e_ang = np.abs(_wrap(ang))
    return {k: np.where(valid, v, np.nan) for k, v in (("abs", e_abs), ("rel", e_rel), ("ang", e_ang))}


def stats(values: np.ndarray) -> dict[str, np.ndarray]:
    """Mean, std, SEM, median and count per run over all trailing axes, ignoring NaN."""
    flat = values.reshape(values.shape[0], -1)
    good = np.isfinite(flat)
    n = good.sum(axis=1)
    safe = np.where(good, flat, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = safe.sum(axis=1) / n
        var = np.where(good, (safe - mean[:, None]) ** 2, 0.0).sum(axis=1) / n
        std = np.sqrt(var)
        sem = std / np.sqrt(n)
    ordered = np.sort(np.where(good, flat, np.inf), axis=1)
    lo, hi = np.maximum((n - 1) // 2, 0), np.maximum(n // 2, 0)
    rows = np.arange(flat.shape[0])
    median = np.where(n > 0, 0.5 * (ordered[rows, lo] + ordered[rows, hi]), np.nan)
    empty = n == 0
    return {"mean": np.where(empty, np.nan, mean), "std": np.where(empty, np.nan, std),
            "sem": np.where(empty, np.nan, sem), "median": median, "count": n}


def pair_distances(x: np.ndarray) -> np.ndarray:
    """‖x_j − x_i‖ over all unordered pairs i < j, (R, N(N−1)/2)."""
    i, j = np.triu_indices(x.shape[1], k=1)
    return np.linalg.norm(x[:, j] - x[:, i], axis=-1)


def dead_reckoning_share(kind: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Share of this step's estimates that are pure dead reckoning x3, (R,)."""
    n = valid.sum(axis=(1, 2))
    dr = (valid & (kind == Kind.X3)).sum(axis=(1, 2))
    return np.divide(dr, n, out=np.full(n.shape, np.nan), where=n > 0)


def round_trip_errors(est: np.ndarray, adjacency: np.ndarray) -> np.ndarray:
    """e_r = ‖x̂_ab + x̂_bc + x̂_ca‖ [3.8] of the final estimates over each edge's first
    closing triangle, (R, N, N), NaN where the edge has none."""
    c = first_triangle(adjacency)
    R, n = adjacency.shape[:2]
    r = np.arange(R)[:, None, None]
    a = np.arange(n)[None, :, None]
    b = np.arange(n)[None, None, :]
    cc = np.maximum(c, 0)
    loop = est + est[r, b, cc] + est[r, cc, a]
    return np.where(c >= 0, np.linalg.norm(loop, axis=-1), np.nan)


def first_met(best: np.ndarray, threshold: float) -> np.ndarray:
    """First generation whose best fitness is ≤ T, per run; inf if never. ``best`` (T, R)."""
    met = best <= threshold
    return np.where(met.any(axis=0), np.argmax(met, axis=0).astype(float), np.inf)


def run_summary(best: np.ndarray, threshold: float) -> dict[str, np.ndarray]:
    """Per-run values of Tab. 4.4 from the best-fitness history ``best`` (T, R): the best of
    the run, the best in the last generation and the first generation meeting T."""
    return {"fit": best.min(axis=0), "end": best[-1].copy(), "gen": first_met(best, threshold)}


def median_over_runs(values: np.ndarray) -> tuple[float, int]:
    """Median across repetitions, inf ranking above every finite value (gap A34), and the
    count used."""
    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    return (float(np.median(v)) if v.size else float("nan")), int(v.size)
