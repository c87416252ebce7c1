"""The compiled SLO metrics (numba): the pair errors and distances of Tab. 4.2 (Mai p. 39) and
their per-run statistics, in numpy's arithmetic.

The numpy versions (``tests/test_slo_kernels.py`` keeps them as references) spend most of a
generation's metric time in call overhead on small arrays. Here a sum is numpy's pairwise
summation (``core/sums.py``, added to the reduction's initial +0), and a median the mean of the two
middle order statistics of the finite values, found by selection instead of a full sort: the
same values, so the same bits.
"""

from __future__ import annotations

import math
from typing import Collection

import numpy as np

from ..core.compiled import f64, kernel
from ..core.sums import pairwise_stack, pairwise_sum_in


@kernel
def _select(buf: np.ndarray, m: int, k: int) -> float:
    """The k-th smallest of buf[:m] (no NaN), reordering buf so that every value after
    position k is at least it: quickselect with branch-free partitions (the values below the
    pivot to the front, then those equal to it), so unpredictable data costs no mispredictions."""
    lo, hi = 0, m
    while hi - lo > 1:
        a, b, c = buf[lo], buf[(lo + hi) // 2], buf[hi - 1]
        pivot = max(min(a, b), min(max(a, b), c))  # median of three
        s = lo
        for q in range(lo, hi):
            v = buf[q]
            buf[q] = buf[s]
            buf[s] = v
            s += v < pivot
        if k < s:
            hi = s
            continue
        e = s
        for q in range(s, hi):
            v = buf[q]
            buf[q] = buf[e]
            buf[e] = v
            e += v == pivot
        if k < e:
            return pivot
        lo = e
    return buf[lo]


@kernel
def _sum(a: np.ndarray, n: int, pairwise: bool, stack: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> float:
    """numpy's sum of a[:n] along a reduced axis: pairwise when the axis is the contiguous one, else
    one value after another (numpy then runs its loop along the other axis)."""
    if pairwise:
        return 0.0 + pairwise_sum_in(a, 0, n, stack)
    res = 0.0
    for i in range(n):
        res += a[i]
    return res


@kernel
def _stats(flat: np.ndarray, pairwise: bool, moments: int, median: bool, count: np.ndarray, mean: np.ndarray,
           std: np.ndarray, sem: np.ndarray, med: np.ndarray) -> None:
    """``moments`` 1: the mean, 2: also std and SEM."""
    R, m = flat.shape[0], flat.shape[1]
    safe, buf, stack = np.empty(m), np.empty(m), pairwise_stack()
    for r in range(R):
        n = 0
        for q in range(m):  # branch-free: which values are finite is not predictable
            v = flat[r, q]
            finite = math.isfinite(v)
            safe[q] = v if finite else 0.0
            buf[n] = v
            n += finite
        count[r] = n
        if moments:
            if n == 0:
                mean[r] = std[r] = sem[r] = np.nan
            else:
                mean[r] = mu = _sum(safe, m, pairwise, stack) / n
                if moments > 1:
                    for q in range(m):
                        dv = safe[q] - mu
                        safe[q] = dv * dv if math.isfinite(flat[r, q]) else 0.0
                    sd = math.sqrt(_sum(safe, m, pairwise, stack) / n)
                    std[r], sem[r] = sd, sd / math.sqrt(n)
        if median:
            if n == 0:
                med[r] = np.nan
            else:
                a = _select(buf, n, (n - 1) // 2)
                if n % 2:
                    med[r] = 0.5 * (a + a)
                else:  # the next order statistic: the least of those after the lower middle
                    b = np.inf
                    for q in range((n - 1) // 2 + 1, n):
                        b = min(b, buf[q])
                    med[r] = 0.5 * (a + b)


def stats(flat: np.ndarray, keys: Collection[str]) -> dict[str, np.ndarray]:
    """The ``keys`` among count, mean, std, sem and median of each row of ``flat`` (R, M) over
    its finite values; NaN for a row with none. The sums are numpy's for
    ``flat``'s memory layout: pairwise along contiguous rows, one value after another when the
    runs are the faster axis (as in an array gathered pair by pair, :func:`pair_distances`)."""
    R, m = flat.shape
    pairwise = R == 1 or m == 1 or abs(flat.strides[1]) <= abs(flat.strides[0])
    count = np.empty(R, np.int64)
    mean, std, sem, med = np.empty(R), np.empty(R), np.empty(R), np.empty(R)
    moments = 2 if {"std", "sem"} & set(keys) else int("mean" in keys)
    _stats(f64(flat), pairwise, moments, "median" in keys, count, mean, std, sem, med)
    out = {"count": count, "mean": mean, "std": std, "sem": sem, "median": med}
    return {k: out[k] for k in keys}


@kernel
def distance_errors(x: np.ndarray, est: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """e_abs = ‖x̂_ij − (x_j − x_i)‖ and e_rel = e_abs / ‖x_j − x_i‖ of every ordered pair,
    (R, N, N) each, NaN outside ``valid`` (e_rel also for coincident particles)."""
    R, n = x.shape[0], x.shape[1]
    e_abs, e_rel = np.empty((R, n, n)), np.empty((R, n, n))
    for r in range(R):
        for i in range(n):
            for j in range(n):
                tx, ty = x[r, j, 0] - x[r, i, 0], x[r, j, 1] - x[r, i, 1]
                dx, dy = est[r, i, j, 0] - tx, est[r, i, j, 1] - ty
                ea = math.sqrt(dx * dx + dy * dy)
                dist = math.sqrt(tx * tx + ty * ty)
                if valid[r, i, j]:
                    e_abs[r, i, j] = ea
                    e_rel[r, i, j] = ea / dist if dist > 0.0 else np.nan
                else:
                    e_abs[r, i, j] = e_rel[r, i, j] = np.nan
    return e_abs, e_rel


@kernel
def angle_differences(x: np.ndarray, est: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """atan2 of x̂_ij minus atan2 of x_j − x_i for every ordered pair in ``valid``, NaN elsewhere,
    (R, N, N): the C library's atan2 (engine/core/portable.py), only where it is read."""
    R, n = x.shape[0], x.shape[1]
    ang = np.empty((R, n, n))
    for r in range(R):
        for i in range(n):
            for j in range(n):
                if valid[r, i, j]:
                    tx, ty = x[r, j, 0] - x[r, i, 0], x[r, j, 1] - x[r, i, 1]
                    ang[r, i, j] = math.atan2(est[r, i, j, 1], est[r, i, j, 0]) - math.atan2(ty, tx)
                else:
                    ang[r, i, j] = np.nan
    return ang


@kernel
def pair_distances(x: np.ndarray) -> np.ndarray:
    """‖x_j − x_i‖ over the unordered pairs i < j in ``np.triu_indices`` order, (R, N(N−1)/2),
    laid out pair-major as numpy gathers ``x[:, j] − x[:, i]`` (so :func:`stats` sums as it did)."""
    R, n = x.shape[0], x.shape[1]
    d = np.empty((n * (n - 1) // 2, R)).T
    for r in range(R):
        q = 0
        for i in range(n):
            for j in range(i + 1, n):
                dx, dy = x[r, j, 0] - x[r, i, 0], x[r, j, 1] - x[r, i, 1]
                d[r, q] = math.sqrt(dx * dx + dy * dy)
                q += 1
    return d


@kernel
def dead_reckoning_share(kind: np.ndarray, valid: np.ndarray, x3: int) -> np.ndarray:
    """Share of the valid estimates of each run whose kind is ``x3``, (R,); NaN for none."""
    R = kind.shape[0]
    out = np.empty(R)
    for r in range(R):
        n, dr = 0, 0
        for q in range(kind[r].size):
            ok = valid[r].flat[q]
            n += ok
            dr += ok and kind[r].flat[q] == x3
        out[r] = dr / n if n > 0 else np.nan
    return out
