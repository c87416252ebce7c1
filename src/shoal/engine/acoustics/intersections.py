"""Ray–ray intersections for triangulation PSO (Fig. 7-1, p. 154; Alg. 5–7; Rossides §7.2.2–7.2.3, pp. 154, 157).

A ray starts at a point P and runs along a unit direction d. Two rays meet where
P_a + t·d_a = P_b + s·d_b; the meeting counts only ahead of both origins (t, s > ``eps``).
Parallel, anti-parallel and collinear rays, rays from one point (coincident robots), and
meetings behind or at an origin give no intersection. Non-finite inputs give none either.
Invalid slots hold the first ray's origin, so every array stays finite.
"""

from __future__ import annotations

import numpy as np

PARALLEL = 1e-12  # |sin| between two unit directions below which they are parallel
EPS = 1e-9  # m: a meeting must lie at least this far ahead of both origins

# robot i's ray index, partner's ray index for the four B-PSO pairings (+,+), (+,−), (−,+), (−,−)
PAIRS_I = np.array([0, 0, 1, 1])
PAIRS_J = np.array([0, 1, 0, 1])


def cross2(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """z-component of the 2-D cross product u_x v_y − u_y v_x over the last axis."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def intersect(
    pa: np.ndarray, da: np.ndarray, pb: np.ndarray, db: np.ndarray, eps: float = EPS
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Forward intersection of rays (pa, da) and (pb, db), broadcast over leading axes.

    Returns ``point`` (…, 2), ``t`` and ``s`` (distances along each unit ray) and ``valid``.
    """
    pa, da, pb, db = (np.asarray(v, dtype=float) for v in (pa, da, pb, db))
    finite = np.all(np.isfinite(pa) & np.isfinite(da) & np.isfinite(pb) & np.isfinite(db), axis=-1)
    with np.errstate(invalid="ignore", over="ignore"):
        w = pb - pa
        den = cross2(da, db)
        scale = np.linalg.norm(da, axis=-1) * np.linalg.norm(db, axis=-1)
        ok = finite & (np.abs(den) > PARALLEL * np.where(finite, scale, 0.0))
        safe = np.where(ok, den, 1.0)
        t = np.where(ok, cross2(w, db) / safe, 0.0)
        s = np.where(ok, cross2(w, da) / safe, 0.0)
        point = pa + t[..., None] * da
    valid = ok & (t > eps) & (s > eps) & np.all(np.isfinite(point), axis=-1)
    t, s = np.where(valid, t, 0.0), np.where(valid, s, 0.0)
    point = np.where(valid[..., None], point, np.where(np.isfinite(pa), pa, 0.0))
    return point, t, s, valid


def pair_intersections(
    x: np.ndarray, rays: np.ndarray, partner: np.ndarray, eps: float = EPS
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Alg. 5 step 2b: robot i's two rays against its partner's two rays (up to 4 points).

    ``x`` (R, N, 2), ``rays`` (R, N, 2, 2) = [r_+, r_−] [7.7], ``partner`` (R, N) (−1: none).
    Returns ``points`` (R, N, 4, 2), ``d_i`` and ``d_j`` (R, N, 4) (distance from robot i
    and from its partner) and ``valid`` (R, N, 4), in the order of ``PAIRS_I``/``PAIRS_J``.
    """
    R = x.shape[0]
    has = partner >= 0
    j = np.where(has, partner, np.arange(x.shape[1]))  # self where no partner: masked below
    xj = x[np.arange(R)[:, None], j]  # (R, N, 2)
    rj = rays[np.arange(R)[:, None], j]  # (R, N, 2, 2)
    pa = x[:, :, None, :]
    da = rays[:, :, PAIRS_I, :]
    pb = xj[:, :, None, :]
    db = rj[:, :, PAIRS_J, :]
    points, _, _, valid = intersect(pa, da, pb, db, eps)
    valid = valid & has[..., None]
    d_i = np.where(valid, np.linalg.norm(points - pa, axis=-1), 0.0)
    d_j = np.where(valid, np.linalg.norm(points - pb, axis=-1), 0.0)
    return points, d_i, d_j, valid


def furthest(points: np.ndarray, dist: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Alg. 5 step 2d: the valid point furthest from the robot, p_s = argmax |x^i − p|.

    Returns ``selected`` (…, 2), its ``index`` (−1: none) and its distance (0: none).
    """
    k = np.argmax(np.where(valid, dist, -np.inf), axis=-1)
    any_ = valid.any(axis=-1)
    sel = np.take_along_axis(points, k[..., None, None], axis=-2)[..., 0, :]
    d = np.take_along_axis(dist, k[..., None], axis=-1)[..., 0]
    return sel, np.where(any_, k, -1), np.where(any_, d, 0.0)


def rho_consistent(d_i: np.ndarray, d_j: np.ndarray, rho_i: np.ndarray, rho_j: np.ndarray) -> np.ndarray:
    """[7.12]: a point is kept iff it lies nearer the robot that hears the stronger ρ.

    Strict inequalities, so ties in distance or in ρ are dropped (docs/readings.md, "Ties in the cell deletion").
    Shapes broadcast: ``d_*`` (R, N, K), ``rho_*`` (R, N, 1) or (R, N, K).
    """
    return ((d_i < d_j) & (rho_i > rho_j)) | ((d_i > d_j) & (rho_i < rho_j))
