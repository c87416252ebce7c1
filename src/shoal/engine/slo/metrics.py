"""SLO metrics (Mai §4.1, p. 35; Tab. 4.2, p. 39): localisation errors over neighbour pairs,
inter-particle distances over all unordered pairs (docs/readings.md, "Pairs behind the
metrics"), dead-reckoning share,
round-trip error, and the per-run summaries (best, end, first generation meeting T).

Every statistic is per run, shape (R,); mean, std, SEM (both: docs/readings.md, "Standard
deviation or standard error") and median;
NaN when a run has no pair.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..core.compiled import f64
from ..core.portable import LIBM_KERNELS, arctan2
from ..core.vectors import norm
from . import metric_kernels
from .selection import Kind, first_triangle


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angle in (−π, π]."""
    return np.pi - np.mod(np.pi - angle, 2.0 * np.pi)


def _truth(x: np.ndarray) -> np.ndarray:
    return x[:, None, :, :] - x[:, :, None, :]


def distance_errors(x: np.ndarray, est: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """e_abs and e_rel of every ordered pair (R, N, N), NaN outside ``valid``; e_rel is also
    NaN for coincident particles (compiled, :func:`~.metric_kernels.distance_errors`)."""
    return metric_kernels.distance_errors(f64(x), f64(est), np.ascontiguousarray(valid, dtype=bool))


def angular_errors(x: np.ndarray, est: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """e_ang of every ordered pair (R, N, N), NaN outside ``valid``; the C library's atan2, not
    numpy's AVX-512 loop (engine/core/portable.py): the median of errors near 1e-15 rad shows its
    last bits. Compiled (:func:`~.metric_kernels.angle_differences`) unless numba would vectorise
    atan2 with SVML."""
    if LIBM_KERNELS:
        ang = metric_kernels.angle_differences(f64(x), f64(est), np.ascontiguousarray(valid, dtype=bool))
    else:
        truth = _truth(x)
        ang = arctan2(est[..., 1], est[..., 0]) - arctan2(truth[..., 1], truth[..., 0])
    return np.where(valid, np.abs(_wrap(ang)), np.nan)


def pair_errors(x: np.ndarray, est: np.ndarray, valid: np.ndarray) -> dict[str, np.ndarray]:
    """e_abs, e_rel and e_ang of every ordered pair (R, N, N), NaN outside ``valid``;
    e_rel is also NaN for coincident particles."""
    e_abs, e_rel = distance_errors(x, est, valid)
    return {"abs": e_abs, "rel": e_rel, "ang": angular_errors(x, est, valid)}


STATS = ("mean", "std", "sem", "median", "count")


def stats(values: np.ndarray, keys: Sequence[str] = STATS) -> dict[str, np.ndarray]:
    """Mean, std, SEM, median and count per run over all trailing axes, ignoring NaN; only
    the ``keys`` asked for are worked out (compiled, :func:`~.metric_kernels.stats`: numpy's
    pairwise sums and order statistics, so numpy's bits)."""
    return metric_kernels.stats(values.reshape(values.shape[0], -1), keys)


def pair_distances(x: np.ndarray) -> np.ndarray:
    """‖x_j − x_i‖ over all unordered pairs i < j, (R, N(N−1)/2) (compiled)."""
    return metric_kernels.pair_distances(f64(x))


def dead_reckoning_share(kind: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Share of this step's estimates that are pure dead reckoning x3, (R,) (compiled)."""
    return metric_kernels.dead_reckoning_share(np.ascontiguousarray(kind, dtype=np.int8),
                                               np.ascontiguousarray(valid, dtype=bool), int(Kind.X3))


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
    return np.where(c >= 0, norm(loop), np.nan)


def first_met(best: np.ndarray, threshold: float) -> np.ndarray:
    """First generation whose best fitness is ≤ T, per run; inf if never. ``best`` (T, R)."""
    met = best <= threshold
    return np.where(met.any(axis=0), np.argmax(met, axis=0).astype(float), np.inf)


def run_summary(best: np.ndarray, threshold: float) -> dict[str, np.ndarray]:
    """Per-run values of Tab. 4.4 from the best-fitness history ``best`` (T, R): the best of
    the run, the best in the last generation and the first generation meeting T."""
    return {"fit": best.min(axis=0), "end": best[-1].copy(), "gen": first_met(best, threshold)}


def median_over_runs(values: np.ndarray) -> tuple[float, int]:
    """Median across repetitions, inf ranking above every finite value, and the count used
    (docs/readings.md, "Medians with runs that never reach")."""
    v = np.asarray(values, dtype=float)
    v = v[~np.isnan(v)]
    return (float(np.median(v)) if v.size else float("nan")), int(v.size)
