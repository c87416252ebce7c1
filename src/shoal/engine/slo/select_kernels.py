"""The compiled RTS [3.8] and Akcan [3.9] selections (numba), edge by edge.

:func:`~.selection.rts` and :func:`~.selection.akcan` say the same in numpy, vectorised over
edges (and, for RTS, over the edges of one tail at a time); the kernels here walk the edges in
the same order with the same arithmetic, so their bits are the numpy ones
(``tests/test_slo_kernels.py``). numpy's ``min`` and ``argmin`` are repeated with their NaN
rules (a NaN wins; ``argmin`` gives the first NaN, else the first minimum), and a score is
summed over the common neighbours in ascending order from +0, as numpy sums along that axis.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.compiled import kernel
from .candidates import Kind

KINDS = np.array([Kind.X1, Kind.X2, Kind.X3], dtype=np.int8)
INF = np.inf


@kernel
def _min(a: float, b: float) -> float:
    """numpy's minimum: NaN wins."""
    if a != a:
        return a
    if b != b:
        return b
    return b if b < a else a


@kernel
def _argmin(v: np.ndarray) -> int:
    """numpy's argmin: the first NaN, else the first minimum."""
    best = 0
    for i in range(v.shape[0]):
        if v[i] != v[i]:
            return i
        if v[i] < v[best]:
            best = i
    return best


@kernel
def _triangle(adj: np.ndarray, r: int, a: int, b: int, c: int) -> bool:
    return c != a and c != b and adj[r, a, b] and adj[r, b, c] and adj[r, c, a]


@kernel
def _loop_errors(sets: np.ndarray, smask: np.ndarray, r: int, a: int, b: int, c: int, err: np.ndarray) -> None:
    """err[p] = min over q ∈ S_bc, s ∈ S_ca of ‖p + q + s‖ for the three p ∈ S_ab (absent → inf)."""
    for p in range(3):
        m = INF
        for q in range(3):
            for s in range(3):
                tx = sets[r, a, b, p, 0] + sets[r, b, c, q, 0] + sets[r, c, a, s, 0]
                ty = sets[r, a, b, p, 1] + sets[r, b, c, q, 1] + sets[r, c, a, s, 1]
                ok = smask[r, a, b, p] and smask[r, b, c, q] and smask[r, c, a, s]
                m = _min(m, math.sqrt(tx * tx + ty * ty) if ok else INF)
        err[p] = m


@kernel
def _rts(points: np.ndarray, mask: np.ndarray, adj: np.ndarray, best_loop: bool, prefer_geometric: bool,
         tolerance: float, est: np.ndarray, kind: np.ndarray, used: np.ndarray, e_used: np.ndarray) -> None:
    """:func:`~.selection.rts` on ``est``/``kind`` holding the fallback (CSS) choice."""
    R, n = adj.shape[0], adj.shape[1]
    sets, smask = points.copy(), mask.copy()  # S_e: the candidates (absent ones zero), later the resolved value
    for r in range(R):
        for a in range(n):
            for b in range(n):
                for p in range(3):
                    if not mask[r, a, b, p]:
                        sets[r, a, b, p, 0] = sets[r, a, b, p, 1] = 0.0
    resolved = np.zeros((n, n), np.bool_)
    err, err_c = np.empty(3), np.empty(3)
    ms = np.empty(n)
    for r in range(R):
        for a in range(n):
            for b in range(n):
                resolved[a, b] = adj[r, a, b] and (int(mask[r, a, b, 0]) + int(mask[r, a, b, 1])
                                                   + int(mask[r, a, b, 2])) == 1
                if resolved[a, b]:  # x3 alone
                    est[r, a, b, 0], est[r, a, b, 1] = points[r, a, b, 2, 0], points[r, a, b, 2, 1]
                    kind[r, a, b] = Kind.X3
        for a in range(n):
            for b in range(n):
                if not adj[r, a, b] or resolved[a, b]:
                    continue
                cc = -1
                for c in range(n):
                    if _triangle(adj, r, a, b, c):
                        cc = c
                        break
                if cc < 0:
                    continue  # no triangle: the fallback stays
                if best_loop:  # the c whose best loop error is lowest
                    for c in range(n):
                        if _triangle(adj, r, a, b, c):
                            _loop_errors(sets, smask, r, a, b, c, err_c)
                            ms[c] = _min(_min(err_c[0], err_c[1]), err_c[2])
                        else:
                            ms[c] = INF
                    cc = _argmin(ms)
                    if _triangle(adj, r, a, b, cc):
                        _loop_errors(sets, smask, r, a, b, cc, err)
                    else:
                        err[0] = err[1] = err[2] = INF
                else:
                    _loop_errors(sets, smask, r, a, b, cc, err)
                if prefer_geometric and _min(err[0], err[1]) < tolerance:
                    err[2] = INF
                p = _argmin(err)
                est[r, a, b, 0], est[r, a, b, 1], kind[r, a, b] = points[r, a, b, p, 0], points[r, a, b, p, 1], KINDS[p]
                used[r, a, b], e_used[r, a, b] = cc, err[p]
            for b in range(n):  # tail a resolved: its estimates are the sets its edges offer
                if adj[r, a, b] and not resolved[a, b]:
                    for p in range(3):
                        sets[r, a, b, p, 0], sets[r, a, b, p, 1] = est[r, a, b, 0], est[r, a, b, 1]
                        smask[r, a, b, p] = p == 2


def rts(points: np.ndarray, mask: np.ndarray, adjacency: np.ndarray, fallback: tuple[np.ndarray, np.ndarray],
        triangle: str = "first", prefer_geometric: bool = False, tolerance: float = 0.0,
        ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`~.selection.rts` compiled: the same estimates, kinds, closing vertices and e_r."""
    R, n = adjacency.shape[:2]
    est, kind = fallback[0].astype(float, copy=True), fallback[1].astype(np.int8, copy=True)
    used, e_used = np.full((R, n, n), -1), np.full((R, n, n), np.nan)
    _rts(np.ascontiguousarray(points, dtype=float), np.ascontiguousarray(mask, dtype=bool),
         np.ascontiguousarray(adjacency, dtype=bool), triangle == "best", bool(prefer_geometric), float(tolerance),
         est, kind, used, e_used)
    return est, kind, used, e_used


@kernel
def _akcan(points: np.ndarray, mask: np.ndarray, adj: np.ndarray, ranges: np.ndarray, est: np.ndarray,
           kind: np.ndarray) -> None:
    """:func:`~.selection.akcan` on ``est``/``kind`` holding the fallback (CSS) choice."""
    R, n = adj.shape[0], adj.shape[1]
    score = np.empty(3)
    for r in range(R):
        for a in range(n):
            for b in range(n):
                if not adj[r, a, b]:
                    continue
                use = False
                score[0] = score[1] = score[2] = 0.0
                for c in range(n):
                    common = adj[r, a, c] and adj[r, b, c] and ranges[r, b, c] > 0
                    use = use or common
                    for p in range(3):
                        if not common:
                            score[p] += 0.0
                            continue
                        px = points[r, a, b, p, 0] if mask[r, a, b, p] else 0.0
                        py = points[r, a, b, p, 1] if mask[r, a, b, p] else 0.0
                        m = INF
                        for q in range(3):
                            qx = points[r, a, c, q, 0] if mask[r, a, c, q] else 0.0
                            qy = points[r, a, c, q, 1] if mask[r, a, c, q] else 0.0
                            dx, dy = px - qx, py - qy
                            e = abs(math.sqrt(dx * dx + dy * dy) - ranges[r, b, c])
                            m = _min(m, e if mask[r, a, c, q] else INF)
                        score[p] += m
                if not use:
                    continue
                for p in range(3):
                    if not mask[r, a, b, p]:
                        score[p] = INF
                p = _argmin(score)
                est[r, a, b, 0], est[r, a, b, 1], kind[r, a, b] = points[r, a, b, p, 0], points[r, a, b, p, 1], KINDS[p]


def akcan(points: np.ndarray, mask: np.ndarray, adjacency: np.ndarray, ranges: np.ndarray,
          fallback: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~.selection.akcan` compiled: the same estimates and kinds."""
    est, kind = fallback[0].astype(float, copy=True), fallback[1].astype(np.int8, copy=True)
    _akcan(np.ascontiguousarray(points, dtype=float), np.ascontiguousarray(mask, dtype=bool),
           np.ascontiguousarray(adjacency, dtype=bool), np.ascontiguousarray(ranges, dtype=float), est, kind)
    return est, kind
