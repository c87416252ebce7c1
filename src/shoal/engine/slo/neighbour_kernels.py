"""Each robot's neighbours without the N × N distance matrix (numba): the k nearest through a
k-d tree's proposals (scipy), those within a radius through a uniform grid of the run's
positions, the ring from its indices.

The lists are :func:`~.neighbourhoods.knn`, :func:`~.neighbourhoods.radius` and
:func:`~.neighbourhoods.ring` row by row, as slots: ``nb[r, i, s]`` the s-th neighbour of i in
ascending index order, −1 past the last. The distances are :func:`~.kernels.distances`' (the
same bits) and the k nearest are its stable order (ties to the lower index, NaN last); a run
with a position that is not finite is searched by brute force. A grid cell is a radius wide,
so a robot's search costs what its neighbours do, not O(N) (``tests/test_slo_ranging.py``
compares the lists with the dense neighbourhoods).
"""

from __future__ import annotations

import math

import numpy as np

from ..core.compiled import kernel
from .kernels import _before

MAX_CELLS = 1 << 22  # cells of one run's grid at most
MARGIN = 1e-9  # relative slack of the grid's bounds: a search looks a little further, never less far


@kernel
def _dist(xr: np.ndarray, i: int, j: int) -> float:
    dx, dy = xr[j, 0] - xr[i, 0], xr[j, 1] - xr[i, 1]
    return math.sqrt(dx * dx + dy * dy)


@kernel
def _grid(xr: np.ndarray, h: float) -> tuple:
    """Robots of one run in cells of side ≥ ``h`` over their bounding box: (x0, y0, h, nx, ny,
    start, items), the robots of cell c being items[start[c] : start[c + 1]] in index order.
    nx = 0 when a position is not finite (no grid)."""
    n = xr.shape[0]
    x0 = y0 = np.inf
    x1 = y1 = -np.inf
    for i in range(n):
        a, b = xr[i, 0], xr[i, 1]
        if not (math.isfinite(a) and math.isfinite(b)):
            return 0.0, 0.0, 1.0, 0, 0, np.zeros(1, np.int64), np.zeros(0, np.int64)
        x0, y0, x1, y1 = min(x0, a), min(y0, b), max(x1, a), max(y1, b)
    span = max(x1 - x0, y1 - y0)
    h = max(h, span * 1e-12, 1e-300)
    while ((x1 - x0) / h + 1.0) * ((y1 - y0) / h + 1.0) > MAX_CELLS:
        h *= 2.0
    nx, ny = int((x1 - x0) / h) + 1, int((y1 - y0) / h) + 1
    start = np.zeros(nx * ny + 1, np.int64)
    cell = np.empty(n, np.int64)
    for i in range(n):
        cx = min(nx - 1, int((xr[i, 0] - x0) / h))
        cy = min(ny - 1, int((xr[i, 1] - y0) / h))
        cell[i] = cy * nx + cx
        start[cell[i] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    items = np.empty(n, np.int64)
    for i in range(n):
        items[fill[cell[i]]] = i
        fill[cell[i]] += 1
    return x0, y0, h, nx, ny, start, items


@kernel
def _insert(row_d: float, j: int, m: int, k: int, best: np.ndarray, best_d: np.ndarray) -> int:
    """Insert (row_d, j) into the k first so far (best, best_d: m of them, in stable order); returns the new m."""
    if m == k and not _before(row_d, j, best_d[k - 1], best[k - 1]):
        return m
    p = m if m < k else k - 1
    while p > 0 and _before(row_d, j, best_d[p - 1], best[p - 1]):
        best[p], best_d[p] = best[p - 1], best_d[p - 1]
        p -= 1
    best[p], best_d[p] = j, row_d
    return min(m + 1, k)


@kernel
def _sorted_into(out: np.ndarray, best: np.ndarray, m: int) -> None:
    """best[:m] in ascending index order into out, −1 after."""
    for q in range(m):
        out[q] = best[q]
    for a in range(1, m):
        v = out[a]
        b = a - 1
        while b >= 0 and out[b] > v:
            out[b + 1] = out[b]
            b -= 1
        out[b + 1] = v
    for q in range(m, out.shape[0]):
        out[q] = -1


@kernel
def _brute_row(i: int, xr: np.ndarray, k: int, best: np.ndarray, best_d: np.ndarray) -> int:
    """The k first of row i in stable order, robot i itself at +inf as in the dense matrix (it
    can be among them only when others are infinitely far or NaN; the caller drops it)."""
    m = 0
    for j in range(xr.shape[0]):
        m = _insert(_dist(xr, i, j) if j != i else np.inf, j, m, k, best, best_d)
    return m


@kernel
def _without(out: np.ndarray, best: np.ndarray, m: int, i: int) -> None:
    """best[:m] but i, ascending, into out (−1 after)."""
    c = 0
    for q in range(m):
        if best[q] != i:
            best[c] = best[q]
            c += 1
    _sorted_into(out, best, c)


@kernel
def knn_rows(xr: np.ndarray, k: int, idx: np.ndarray, tree_d: np.ndarray, out: np.ndarray) -> None:
    """The k nearest of every robot of one run into ``out`` (N, k), from a k-d tree's m ≥ k + 1
    nearest (``idx``, ``tree_d``; scipy's cKDTree.query). The tree only proposes: the order is
    :func:`_insert`'s on this module's distances, and a row whose k-th is not clearly nearer than
    the farthest the tree returned (a tie at the edge, a rounding apart) is searched by brute force."""
    n, m = idx.shape
    best_d, best_i = np.empty(k), np.empty(k, np.int64)
    for i in range(n):
        c = _insert(np.inf, i, 0, k, best_i, best_d)  # itself, as the dense matrix's diagonal
        for q in range(m):
            j = idx[i, q]
            if j != i and j < n:
                c = _insert(_dist(xr, i, j), j, c, k, best_i, best_d)
        edge = tree_d[i, m - 1]
        sure = m >= n or (c == k and best_d[k - 1] < edge * (1.0 - MARGIN))
        if not sure:
            c = _brute_row(i, xr, k, best_i, best_d)
        _without(out[i], best_i, c, i)


@kernel
def brute_knn(xr: np.ndarray, k: int, out: np.ndarray) -> None:
    """:func:`knn_rows` without a tree (a run with a position that is not finite)."""
    best, best_d = np.empty(max(k, 1), np.int64), np.empty(max(k, 1))
    for i in range(xr.shape[0]):
        _without(out[i], best, _brute_row(i, xr, k, best, best_d), i)


def knn_slots(x: np.ndarray, k: int) -> np.ndarray:
    """The k nearest of every robot of every run, (R, N, k) slots (as :func:`~.neighbourhoods.knn`):
    candidates from scipy's k-d tree, O(N log N) a run, chosen and ordered here."""
    from scipy.spatial import cKDTree

    R, n = x.shape[0], x.shape[1]
    k = int(min(max(k, 0), n - 1))
    nb = np.full((R, n, k), -1, np.int64)
    if k == 0:
        return nb
    for r in range(R):
        xr = np.ascontiguousarray(x[r], dtype=float)
        if not np.isfinite(xr).all():
            brute_knn(xr, k, nb[r])
            continue
        m = min(k + 2, n)
        tree = cKDTree(xr, balanced_tree=False, compact_nodes=False)  # a sliding-midpoint tree builds faster
        order = tree.indices  # the robots in the tree's order: queried in it, neighbours are near in memory
        tree_d, idx = tree.query(xr[order], k=m)
        found, dist = np.empty((n, m), np.int64), np.empty((n, m))
        found[order], dist[order] = idx, tree_d
        knn_rows(xr, k, found, dist, nb[r])
    return nb


@kernel
def _radius_row(i: int, xr: np.ndarray, g: tuple, radius: float, out: np.ndarray) -> int:
    """The robots closer than ``radius`` to robot i, in ascending index order into ``out`` (if
    it has room); how many."""
    x0, y0, h, nx, ny, start, items = g
    n = xr.shape[0]
    m = 0
    if nx == 0:
        for j in range(n):
            if j != i and _dist(xr, i, j) < radius:
                if m < out.shape[0]:
                    out[m] = j
                m += 1
        return m
    cx, cy = min(nx - 1, int((xr[i, 0] - x0) / h)), min(ny - 1, int((xr[i, 1] - y0) / h))
    reach = int(math.ceil(radius / h)) if radius < np.inf else max(nx, ny)
    for qy in range(max(0, cy - reach), min(ny - 1, cy + reach) + 1):
        for qx in range(max(0, cx - reach), min(nx - 1, cx + reach) + 1):
            c = qy * nx + qx
            for s in range(start[c], start[c + 1]):
                j = items[s]
                if j != i and _dist(xr, i, j) < radius:
                    if m < out.shape[0]:
                        out[m] = j
                    m += 1
    if m <= out.shape[0]:
        _sorted_into(out, out.copy(), m)
    return m


@kernel
def radius_slots(x: np.ndarray, radius: float) -> np.ndarray:
    """Every robot closer than ``radius``, (R, N, K) slots with K the most any robot has (as
    :func:`~.neighbourhoods.radius`)."""
    R, n = x.shape[0], x.shape[1]
    grids = []
    most = 0
    none = np.empty(0, np.int64)
    h = radius * (1.0 + MARGIN) if radius > 0 else 1.0
    for r in range(R):
        g = _grid(x[r], h if math.isfinite(h) else 1.0)
        grids.append(g)
        for i in range(n):
            most = max(most, _radius_row(i, x[r], g, radius, none))
    nb = np.full((R, n, most), -1, np.int64)
    for r in range(R):
        for i in range(n):
            _radius_row(i, x[r], grids[r], radius, nb[r, i])
    return nb


@kernel
def ring_slots(runs: int, n: int, width: int) -> np.ndarray:
    """X_{(i ± k) mod n} for 1 ≤ k ≤ width, (R, N, K) slots (as :func:`~.neighbourhoods.ring`)."""
    mark = np.zeros(n, np.bool_)
    count = 0
    for k in range(1, width + 1):  # which offsets o = j − i (mod n) are links
        for o in (k % n, (n - k) % n):
            if o != 0 and not mark[o]:
                mark[o] = True
                count += 1
    nb = np.full((runs, n, count), -1, np.int64)
    row = np.empty(count, np.int64)
    for i in range(n):
        m = 0
        for j in range(n):
            if mark[(j - i) % n]:
                row[m] = j
                m += 1
        for r in range(runs):
            nb[r, i, :] = row
    return nb
