"""The compiled SLO pair step: candidates [3.1]–[3.6] and Closest Solution Selection [3.7] of
every ordered pair of every run in one pass (numba).

:func:`~.candidates.candidates` and :func:`~.selection.css` say the same in numpy, vectorised
over pairs; for a swarm of 20 that is some sixty array operations on small arrays, mostly
call overhead. :func:`localise` does the same arithmetic in the same order per pair, so its
bits are theirs (``tests/test_slo_kernels.py`` compares them on random and singular pairs and
on whole runs); the numpy pair stays the readable reference.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..core.compiled import f64, kernel
from .candidates import Candidates, Flag
from .selection import Kind

# Kind and Flag as plain ints, as a compiled function returns them
X1, X2, X3 = int(Kind.X1), int(Kind.X2), int(Kind.X3)
GEOMETRIC, FALLBACK, MITIGATED_V, MITIGATED_COS = (int(Flag.GEOMETRIC), int(Flag.FALLBACK), int(Flag.MITIGATED_V),
                                                   int(Flag.MITIGATED_COS))


@kernel
def css_pair(vx: float, vy: float, a: float, b: float, px: float, py: float, delta_cos: float, delta_v: float,
             literal: bool, w: float, new: bool, use_coin: bool, coin: bool) -> tuple:
    """Candidates [3.1]–[3.6] and the CSS choice [3.7] of one ordered pair from its relative
    displacement (vx, vy) = v*_j − v*_i, its ranges ``a`` = d*(t−1) and ``b`` = d*(t) and its
    previous estimate (px, py); ``new``: a neighbour arriving under a geometric entry policy
    (its candidate unblended; by ``coin`` with ``use_coin``). Returns the candidates
    (x1x, x1y, x2x, x2y, x3x, x3y), ok, geometric, cos α, the thinness, the estimate (ex, ey),
    its Kind and the set's Flag."""
    x3x, x3y = px + vx, py + vy  # [3.4]
    speed = math.sqrt(vx * vx + vy * vy)
    ok = (a > 0.0 and b > 0.0 and speed > 0.0 and math.isfinite(a) and math.isfinite(b)
          and math.isfinite(speed) and math.isfinite(x3x) and math.isfinite(x3y))
    s0, s1, sv = (a, b, speed) if ok else (1.0, 1.0, 1.0)
    t0, t1 = sv / s0, sv / s1
    thin = t0 if (t0 <= t1 or t0 != t0) else t1
    thin_ok = not thin <= delta_v  # [3.6]
    c = (s1 * s1 + sv * sv - s0 * s0) / (2.0 * sv * (s0 if literal else s1))  # [3.1]
    if not math.isfinite(c):
        c = 2.0
    cos_ok = not 1.0 - abs(c) <= delta_cos  # [3.5]
    geometric = ok and thin_ok and cos_ok
    if geometric:  # [3.2], [3.3]
        cc = min(max(c, -1.0), 1.0)
        sn = math.sqrt(1.0 - cc * cc)
        ux, uy = vx / sv, vy / sv
        ax, ay = (s1 * cc) * ux, (s1 * cc) * uy
        bx, by = (s1 * sn) * uy, (s1 * sn) * -ux
        x1x, x1y, x2x, x2y = ax + bx, ay + by, ax - bx, ay - by
    else:
        x1x, x1y, x2x, x2y = x3x, x3y, x3x, x3y
    if not ok:
        flag = FALLBACK
    elif not thin_ok:
        flag = MITIGATED_V
    elif geometric:
        flag = GEOMETRIC
    else:
        flag = MITIGATED_COS
    if not geometric:
        ex, ey, kind = x3x, x3y, X3
    else:
        # [3.7]: the geometric candidate closest to x3, blended with it by w; ‖e1‖ ≤ ‖e2‖ compared
        # as numpy's square roots (a root is monotone: they are needed only when e1² > e2²)
        e1x, e1y, e2x, e2y = x1x - x3x, x1y - x3y, x2x - x3x, x2y - x3y
        q1, q2 = e1x * e1x + e1y * e1y, e2x * e2x + e2y * e2y
        pick1 = q1 <= q2 or math.sqrt(q1) <= math.sqrt(q2)
        if new and use_coin:
            pick1 = coin
        xcx, xcy = (x1x, x1y) if pick1 else (x2x, x2y)
        if new:
            ex, ey = xcx, xcy
        else:
            ex, ey = w * x3x + (1.0 - w) * xcx, w * x3y + (1.0 - w) * xcy
        kind = X1 if pick1 else X2
    return x1x, x1y, x2x, x2y, x3x, x3y, ok, geometric, c, thin, ex, ey, kind, flag


@kernel
def _pairs(d0: np.ndarray, d1: np.ndarray, v: np.ndarray, prev: np.ndarray, delta_cos: float, delta_v: float,
           literal: bool, w: float, entry: np.ndarray, coin: np.ndarray, use_entry: bool, use_coin: bool, full: bool,
           points: np.ndarray, mask: np.ndarray, flag: np.ndarray, cos_alpha: np.ndarray, thinness: np.ndarray,
           est: np.ndarray, kind: np.ndarray) -> None:
    R, n = d0.shape[0], d0.shape[1]
    for r in range(R):
        for i in range(n):
            for j in range(n):
                vx, vy = v[r, j, 0] - v[r, i, 0], v[r, j, 1] - v[r, i, 1]  # v*_j − v*_i
                new = use_entry and entry[r, i, j]
                x1x, x1y, x2x, x2y, x3x, x3y, ok, geometric, c, thin, ex, ey, k, f = css_pair(
                    vx, vy, d0[r, i, j], d1[r, i, j], prev[r, i, j, 0], prev[r, i, j, 1], delta_cos, delta_v, literal,
                    w, new, use_coin, coin[r, i, j] if new and use_coin else False)
                if full:
                    p = points[r, i, j]
                    p[0, 0], p[0, 1], p[1, 0], p[1, 1], p[2, 0], p[2, 1] = x1x, x1y, x2x, x2y, x3x, x3y
                    mask[r, i, j, 0] = mask[r, i, j, 1] = geometric
                    mask[r, i, j, 2] = True
                    cos_alpha[r, i, j] = c if ok else np.nan
                    thinness[r, i, j] = thin if ok else np.nan
                flag[r, i, j] = f
                est[r, i, j, 0], est[r, i, j, 1], kind[r, i, j] = ex, ey, k


class Localised(NamedTuple):
    """One localisation step of every ordered pair: the CSS choice, why the candidate set is
    what it is, and (when asked for) the candidate sets themselves."""

    est: np.ndarray  # (R, N, N, 2) [3.7]
    kind: np.ndarray  # (R, N, N) int8 Kind
    flag: np.ndarray  # (R, N, N) int8 Flag
    candidates: Candidates | None


def localise(d0: np.ndarray, d1: np.ndarray, v: np.ndarray, prev: np.ndarray, *, delta_cos: float, delta_v: float,
             literal_eq_3_1: bool, prediction_weight: float = 0.5, entry: np.ndarray | None = None,
             coin: np.ndarray | None = None, candidates: bool = True) -> Localised:
    """Candidates of every ordered pair (i, j) from the ranges d*(t−1) ``d0`` and d*(t) ``d1``
    (R, N, N), the measured displacements ``v`` (R, N, 2) (the pair's relative one is
    v*_j − v*_i) and the previous estimates ``prev`` (R, N, N, 2), and their CSS choice;
    ``entry``/``coin`` as for :func:`~.selection.css`. The same as
    ``candidates(d0, d1, v_rel, prev, …)`` and ``css(…)``; the candidate sets (a megabyte for
    31 swarms of 20) only with ``candidates``."""
    R, n = d0.shape[:2]
    shape = (R, n, n) if candidates else (1, 1, 1)
    points, mask = np.empty(shape + (3, 2)), np.empty(shape + (3,), bool)
    cos_alpha, thinness = np.empty(shape), np.empty(shape)
    flag, kind, est = np.empty((R, n, n), np.int8), np.empty((R, n, n), np.int8), np.empty((R, n, n, 2))
    use_entry, use_coin = entry is not None, coin is not None
    e = np.ascontiguousarray(entry if use_entry else np.zeros((1, 1, 1)), dtype=bool)
    k = np.ascontiguousarray(coin if use_entry and use_coin else np.zeros((1, 1, 1)), dtype=bool)
    _pairs(f64(d0), f64(d1), f64(v), f64(prev), float(delta_cos), float(delta_v), bool(literal_eq_3_1),
           float(prediction_weight), e, k, use_entry, use_entry and use_coin, candidates, points, mask, flag,
           cos_alpha, thinness, est, kind)
    return Localised(est, kind, flag, Candidates(points, mask, flag, cos_alpha, thinness) if candidates else None)


def pair_candidates(d0: np.ndarray, d1: np.ndarray, v: np.ndarray, prev: np.ndarray, delta_cos: float,
                    delta_v: float, literal_eq_3_1: bool) -> Candidates:
    """Only the candidate sets of :func:`localise` (for a step that did not keep them)."""
    return localise(d0, d1, v, prev, delta_cos=delta_cos, delta_v=delta_v,  # type: ignore[return-value]
                    literal_eq_3_1=literal_eq_3_1).candidates


@kernel
def distances(x: np.ndarray) -> np.ndarray:
    """‖x_j − x_i‖ of every ordered pair of every run, (R, N, N), +inf on the diagonal
    (the bits of ``np.linalg.norm`` of the differences)."""
    R, n = x.shape[0], x.shape[1]
    d = np.empty((R, n, n))
    for r in range(R):
        for i in range(n):
            for j in range(n):
                dx, dy = x[r, j, 0] - x[r, i, 0], x[r, j, 1] - x[r, i, 1]
                d[r, i, j] = math.sqrt(dx * dx + dy * dy) if i != j else np.inf
    return d


@kernel
def _before(a: float, ia: int, b: float, ib: int) -> bool:
    """(a, ia) comes first in a stable ascending sort with NaN last."""
    if a != a:
        return b != b and ia < ib
    if b != b:
        return True
    return a < b or (a == b and ia < ib)


@kernel
def nearest(dist: np.ndarray, k: int) -> np.ndarray:
    """adj[r, i, j]: j is among the k first of row i of ``dist`` in a stable ascending order
    (``np.argsort(dist, kind="stable")[..., :k]``), (R, N, N) bool."""
    R, n = dist.shape[0], dist.shape[1]
    adj = np.zeros((R, n, n), np.bool_)
    if k <= 0:
        return adj
    best = np.empty(k, np.int64)
    for r in range(R):
        for i in range(n):
            row = dist[r, i]
            m = 0
            for j in range(n):  # insertion into the k first so far
                if m == k and not _before(row[j], j, row[best[k - 1]], best[k - 1]):
                    continue
                p = m if m < k else k - 1
                while p > 0 and _before(row[j], j, row[best[p - 1]], best[p - 1]):
                    best[p] = best[p - 1]
                    p -= 1
                best[p] = j
                m = min(m + 1, k)
            for q in range(m):
                adj[r, i, best[q]] = True
    return adj


@kernel
def _carry(adjacency: np.ndarray, new: np.ndarray, kind: np.ndarray, prev: np.ndarray, v: np.ndarray,
           dead_reckoning: bool, est: np.ndarray, kind_out: np.ndarray) -> None:
    R, n = adjacency.shape[0], adjacency.shape[1]
    for r in range(R):
        for i in range(n):
            for j in range(n):
                if adjacency[r, i, j]:
                    est[r, i, j, 0], est[r, i, j, 1] = new[r, i, j, 0], new[r, i, j, 1]
                    kind_out[r, i, j] = kind[r, i, j]
                    continue
                kind_out[r, i, j] = Kind.NONE
                if dead_reckoning:  # [3.4]
                    est[r, i, j, 0] = prev[r, i, j, 0] + (v[r, j, 0] - v[r, i, 0])
                    est[r, i, j, 1] = prev[r, i, j, 1] + (v[r, j, 1] - v[r, i, 1])
                else:
                    est[r, i, j, 0], est[r, i, j, 1] = prev[r, i, j, 0], prev[r, i, j, 1]


def carry(adjacency: np.ndarray, new: np.ndarray, kind: np.ndarray, prev: np.ndarray, v: np.ndarray,
          dead_reckoning: bool) -> tuple[np.ndarray, np.ndarray]:
    """The step's beliefs: the selected estimate ``new`` and its ``kind`` for a neighbour; for
    any other pair the previous estimate ``prev``, dead-reckoned by v*_j − v*_i [3.4] or kept,
    and kind NONE. (R, N, N, 2) and (R, N, N) int8."""
    est, kind_out = np.empty(new.shape), np.empty(adjacency.shape, np.int8)
    _carry(np.ascontiguousarray(adjacency, dtype=bool), f64(new), np.ascontiguousarray(kind, dtype=np.int8),
           f64(prev), f64(v), bool(dead_reckoning), est, kind_out)
    return est, kind_out


@kernel
def _local_best(f: np.ndarray, fP: np.ndarray, P: np.ndarray, adjacency: np.ndarray, est: np.ndarray,
                pbest: bool, P_out: np.ndarray, fP_out: np.ndarray, self_best: np.ndarray, L: np.ndarray) -> None:
    R, n = f.shape[0], f.shape[1]
    for r in range(R):
        for i in range(n):  # step 2: the pbest moves to the particle itself
            better = f[r, i] < fP[r, i]
            P_out[r, i, 0], P_out[r, i, 1] = (0.0, 0.0) if better else (P[r, i, 0], P[r, i, 1])
            fP_out[r, i] = f[r, i] if better else fP[r, i]
        score = fP_out[r] if pbest else f[r]
        for i in range(n):  # step 3: numpy's min and argmin over the informants (NaN first)
            best, low = 0, score[0] if (adjacency[r, i, 0] or i == 0) else np.inf
            for j in range(1, n):
                if low != low:
                    break
                v = score[j] if (adjacency[r, i, j] or i == j) else np.inf
                if v != v or v < low:
                    best, low = j, v
            own = score[i] <= low  # ties go to the particle itself
            self_best[r, i] = own
            jj = i if own else best
            if pbest:  # x̂_ij* + P_j*, or the own P
                if own:
                    L[r, i, 0], L[r, i, 1] = P_out[r, i, 0], P_out[r, i, 1]
                else:
                    L[r, i, 0], L[r, i, 1] = est[r, i, jj, 0] + P_out[r, jj, 0], est[r, i, jj, 1] + P_out[r, jj, 1]
            elif own:
                L[r, i, 0], L[r, i, 1] = 0.0, 0.0
            else:
                L[r, i, 0], L[r, i, 1] = est[r, i, jj, 0], est[r, i, jj, 1]


def local_best(f: np.ndarray, fP: np.ndarray, P: np.ndarray, adjacency: np.ndarray, est: np.ndarray,
               pbest: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Steps 2–4 of Alg. 1 for every particle of every run: the personal bests moved to the
    particles that sense a better fitness ``f`` (R, N) than ``fP``, then each particle's best
    informant (its neighbours and itself; ties to itself) by ``f``, or by the personal bests
    with ``pbest``, and the local best L relative to the particle: 0 (own P with ``pbest``)
    when it is its own best, else x̂_ij* (+ P_j*). Returns P, fP, self_best, L."""
    R, n = f.shape
    P_out, fP_out, self_best, L = np.empty((R, n, 2)), np.empty((R, n)), np.empty((R, n), np.bool_), np.empty((R, n, 2))
    _local_best(f64(f), f64(fP), f64(P), np.ascontiguousarray(adjacency, dtype=bool), f64(est), bool(pbest), P_out,
                fP_out, self_best, L)
    return P_out, fP_out, self_best, L
