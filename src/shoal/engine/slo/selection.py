"""Choosing each neighbour's estimate among its candidates (Mai §3.5.3): Closest Solution
Selection (CSS) [3.7], Round Trip Selection (RTS) [3.8] and Akcan's criterion [3.9], and their
registry :data:`SELECTIONS`.

Arrays: candidates ``(R, N, N, 3, 2)`` for the ordered pairs (a → b), masks ``(R, N, N, 3)``,
adjacency ``(R, N, N)``; outputs are the estimate ``(R, N, N, 2)`` and the :class:`Kind` of
what was selected, ``(R, N, N)``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Literal, Protocol

import numpy as np

from ..core.registry import Registry, shape
from . import select_kernels
from .candidates import Candidates, Kind

RTSTriangle = Literal["first", "best"]


def css(
    c: Candidates, prediction_weight: float = 0.5, entry: np.ndarray | None = None,
    coin: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """[3.7] read as in docs/readings.md, "x_c in [3.7]": x̂ = w·x3 + (1 − w)·x_c, x_c the
    geometric candidate closest to x3; x3 alone when there is no geometric pair.

    ``entry`` marks newly arrived neighbours; there ``coin`` (True → x1) picks x1 or x2
    unblended (entry policy "geometric_random"; docs/readings.md, "Estimates of robots
    outside the neighbourhood (SLO)")."""
    x1, x2, x3 = c.points[..., 0, :], c.points[..., 1, :], c.x3
    pick1 = np.linalg.norm(x1 - x3, axis=-1) <= np.linalg.norm(x2 - x3, axis=-1)
    if entry is not None and coin is not None:
        pick1 = np.where(entry, coin, pick1)
    xc = np.where(pick1[..., None], x1, x2)
    w = float(prediction_weight)
    blended = w * x3 + (1.0 - w) * xc
    if entry is not None:
        blended = np.where(entry[..., None], xc, blended)
    geo = c.geometric
    est = np.where(geo[..., None], blended, x3)
    kind = np.where(geo, np.where(pick1, Kind.X1, Kind.X2), Kind.X3).astype(np.int8)
    return est, kind


def _masked_points(c: Candidates) -> np.ndarray:
    """Candidate points with absent ones zeroed (masks exclude them; keeps arithmetic finite)."""
    return np.where(c.mask[..., None], c.points, 0.0)


def akcan(
    c: Candidates, adjacency: np.ndarray, ranges: np.ndarray, fallback: tuple[np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """[3.9], aggregated as in docs/readings.md, "Aggregating Akcan's criterion":
    score(p) = Σ_{C ∈ N_A ∩ N_B} min_{q ∈ C_AC} |‖p − q‖ − d*_BC|
    with d*_BC measured by B; x̂_AB = argmin score; no common neighbour → ``fallback`` (CSS)."""
    pts, mask = _masked_points(c), c.mask
    r, a, b = np.nonzero(adjacency)  # the edges (a → b) of every run
    # common[e, c]: c ∈ N_a ∩ N_b (so c ∉ {a, b}) and B measured C
    common = adjacency[r, a] & adjacency[r, b] & (ranges[r, b] > 0)
    diff = pts[r, a, b][:, None, :, None, :] - pts[r, a][:, :, None, :, :]  # (E, c, p, q, 2)
    gap = np.sqrt(np.sum(diff * diff, axis=-1))
    err = np.abs(gap - ranges[r, b][:, :, None, None])
    err = np.where(mask[r, a][:, :, None, :], err, np.inf).min(axis=-1)  # (E, c, p)
    score = np.where(common[..., None], err, 0.0).sum(axis=1)
    score = np.where(mask[r, a, b], score, np.inf)
    choice = np.argmin(score, axis=-1)
    use = common.any(axis=1)
    est, kind = fallback[0].copy(), fallback[1].copy()
    est[r[use], a[use], b[use]] = c.points[r, a, b][use, choice[use]]
    kind[r[use], a[use], b[use]] = np.array([Kind.X1, Kind.X2, Kind.X3], dtype=np.int8)[choice[use]]
    return est, kind


@dataclass(frozen=True)
class RTSResult:
    """Estimates plus, per edge, the closing vertex c (−1: none, CSS used) and its e_r."""

    est: np.ndarray  # (R, N, N, 2)
    kind: np.ndarray  # (R, N, N)
    triangle: np.ndarray  # (R, N, N) int
    round_trip: np.ndarray  # (R, N, N), NaN where no triangle was used


def first_triangle(adjacency: np.ndarray) -> np.ndarray:
    """For each edge (a → b), the first c (ascending) with edges b → c and c → a, or −1."""
    tri = triangles(adjacency)
    first = np.argmax(tri, axis=-1)
    return np.where(tri.any(axis=-1), first, -1)


def triangles(adjacency: np.ndarray) -> np.ndarray:
    """tri[r, a, b, c]: edges a → b, b → c and c → a exist, c ∉ {a, b}."""
    n = adjacency.shape[-1]
    tri = adjacency[:, :, :, None] & adjacency[:, None, :, :] & np.swapaxes(adjacency, -1, -2)[:, :, None, :]
    idx = np.arange(n)
    tri[:, idx, :, idx] = False
    tri[:, :, idx, idx] = False
    return tri


def _loop_error(p: np.ndarray, q: np.ndarray, s: np.ndarray, mp: np.ndarray, mq: np.ndarray,
                ms: np.ndarray) -> np.ndarray:
    """min over q, s of ‖p + q + s‖ for each of the 3 p, absent combinations → inf.
    p, q, s (..., 3, 2); masks (..., 3); returns (..., 3)."""
    total = p[..., :, None, None, :] + q[..., None, :, None, :] + s[..., None, None, :, :]
    err = np.sqrt(np.sum(total * total, axis=-1))
    ok = mp[..., :, None, None] & mq[..., None, :, None] & ms[..., None, None, :]
    return np.where(ok, err, np.inf).min(axis=(-2, -1))


def rts(
    c: Candidates,
    adjacency: np.ndarray,
    fallback: tuple[np.ndarray, np.ndarray],
    triangle: RTSTriangle = "first",
    prefer_geometric: bool = False,
    tolerance: float = 0.0,
) -> RTSResult:
    """Greedy RTS [3.8] in ascending (a, b) order, e_r = ‖x̂_ab + x̂_bc + x̂_ca‖ (docs/readings.md, "Order
    of Round Trip Selection").

    An edge with one candidate is resolved at once. An open edge (a → b) takes the candidate
    p minimising e_r over S_bc × S_ca, where S is the resolved value or the candidate set;
    only (a → b) is fixed. ``triangle`` = "first" uses the first closing c (thesis), "best"
    the c with the lowest e_r. No triangle → ``fallback`` (CSS). Output is unblended
    (docs/readings.md, "No blending after RTS or Akcan").

    ``prefer_geometric`` admits x3 only when no geometric candidate closes a loop with
    e_r < ``tolerance`` (an optional runaway remedy).

    Edge (a → b) only reads edges with tails b and c ≠ a, so all edges of one tail are resolved
    together, exactly as the sequential order would; the loop runs over tails because each
    may read the resolutions of the smaller ones.
    """
    R, n = adjacency.shape[:2]
    sets = _masked_points(c).copy()  # S_e: candidates, or the resolved value at index 2
    smask = c.mask.copy()
    tri = triangles(adjacency)
    has = np.asarray(tri.any(axis=-1))
    cfirst = np.argmax(tri, axis=-1)
    resolved = adjacency & (c.mask.sum(axis=-1) == 1)
    est = np.where(resolved[..., None], c.x3, fallback[0])
    kind = np.where(resolved, Kind.X3, fallback[1]).astype(np.int8)
    used = np.full((R, n, n), -1)
    e_used = np.full((R, n, n), np.nan)
    kinds = np.array([Kind.X1, Kind.X2, Kind.X3], dtype=np.int8)
    single = np.array([False, False, True])
    rr = np.arange(R)[:, None]
    for a in range(n):
        open_ = adjacency[:, a, :] & ~resolved[:, a, :]  # (R, b)
        if not open_.any():
            continue
        do = open_ & has[:, a]
        bs = np.nonzero(do.any(axis=0))[0]
        if bs.size:
            p_ab, m_ab = sets[:, a, bs], smask[:, a, bs]  # (R, B, 3, 2)
            if triangle == "first":
                cc = cfirst[:, a, bs]  # (R, B)
                bb = bs[None, :]
                err = _loop_error(p_ab, sets[rr, bb, cc], sets[rr, cc, a], m_ab, smask[rr, bb, cc], smask[rr, cc, a])
            else:
                q, mq = sets[:, bs], smask[:, bs]  # (R, B, C, 3, 2)
                s_, ms = sets[:, None, :, a], smask[:, None, :, a]
                err_all = _loop_error(p_ab[:, :, None], q, s_, m_ab[:, :, None], mq, ms)  # (R, B, C, 3)
                err_all = np.where(tri[:, a, bs, :, None], err_all, np.inf)
                cc = np.argmin(err_all.min(axis=-1), axis=-1)
                err = np.take_along_axis(err_all, cc[..., None, None], axis=2)[:, :, 0]
            if prefer_geometric:
                geo_ok = err[..., :2].min(axis=-1, keepdims=True) < tolerance
                err = np.where(geo_ok & single, np.inf, err)
            choice = np.argmin(err, axis=-1)  # (R, B)
            chosen = np.take_along_axis(c.points[:, a, bs], choice[..., None, None], axis=-2)[..., 0, :]
            sel = do[:, bs]
            est[:, a, bs] = np.where(sel[..., None], chosen, est[:, a, bs])
            kind[:, a, bs] = np.where(sel, kinds[choice], kind[:, a, bs])
            used[:, a, bs] = np.where(sel, cc, -1)
            e_used[:, a, bs] = np.where(sel, np.take_along_axis(err, choice[..., None], axis=-1)[..., 0], np.nan)
        sets[:, a] = np.where(open_[..., None, None], est[:, a, :, None, :], sets[:, a])
        smask[:, a] = np.where(open_[..., None], single, smask[:, a])
        resolved[:, a] |= open_
    return RTSResult(est=est, kind=kind, triangle=used, round_trip=e_used)


# --------------------------------------------------------------------------- the registry


class RTSOptions(Protocol):
    """The localisation choices a selection may read (:class:`~.beliefs.LocaliserParams`)."""

    @property
    def rts_triangle(self) -> RTSTriangle: ...

    @property
    def rts_prefer_geometric(self) -> bool: ...

    @property
    def rts_tolerance(self) -> float: ...


Chosen = tuple[np.ndarray, np.ndarray, "np.ndarray | None", "np.ndarray | None"]  # est, kind, triangle, e_r


@dataclass(frozen=True)
class SelectionRule:
    """One candidate selection: (candidates, adjacency, measured ranges d*(t), the CSS choice it
    falls back on, options) → estimate, kind, and for RTS the closing vertex and its e_r."""

    name: str
    label: str
    select: Callable[[Candidates, np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray], RTSOptions], Chosen]
    reads_candidates: bool = True  # needs the candidate sets, not only the CSS choice


def _css(c: Candidates, adjacency: np.ndarray, ranges: np.ndarray, base: tuple[np.ndarray, np.ndarray],
         options: RTSOptions) -> Chosen:
    return base[0], base[1], None, None


# RTS and Akcan run compiled (select_kernels); rts() and akcan() above are their numpy references


def _rts(c: Candidates, adjacency: np.ndarray, ranges: np.ndarray, base: tuple[np.ndarray, np.ndarray],
         options: RTSOptions) -> Chosen:
    return select_kernels.rts(c.points, c.mask, adjacency, base, options.rts_triangle, options.rts_prefer_geometric,
                              options.rts_tolerance)


def _akcan(c: Candidates, adjacency: np.ndarray, ranges: np.ndarray, base: tuple[np.ndarray, np.ndarray],
           options: RTSOptions) -> Chosen:
    est, kind = select_kernels.akcan(c.points, c.mask, adjacency, ranges, base)
    return est, kind, None, None


SELECTIONS: Registry[SelectionRule] = Registry(
    "selection",
    SelectionRule("css", "CSS (closest solution)", _css, reads_candidates=False),  # [3.7]
    SelectionRule("rts", "RTS (round trip)", _rts),  # [3.8]
    SelectionRule("akcan", "Akcan (GDL)", _akcan),  # [3.9]
    check=shape("select", reads_candidates=bool),
)
