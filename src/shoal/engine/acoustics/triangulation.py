"""GT-PSO's position–intensity plane (Rossides §8.1, p. 174; Alg. 7; Fig. 8-1, p. 175; [8.2]–[8.4]).

Each robot and its two nearest neighbours give three points q = (x1, x2, I) [8.2]. The plane
through them tilts toward the stronger intensity; the horizontal part of its normal,
signed by n_z, is the estimated gradient, which becomes a ray from the triangle's centroid.
No ray (``valid`` False) when the triangle is degenerate: fewer than three robots,
coincident or collinear robots (n_z ≈ 0), or equal intensities (n_xy ≈ 0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

COLLINEAR = 1e-9  # |sin| of the triangle's angle at robot i below which it is collinear
FLAT = 1e-12  # relative intensity change across the triangle below which the plane is flat


@dataclass(frozen=True)
class Triangles:
    """Each robot's triplet and the ray it defines (all arrays finite)."""

    members: np.ndarray  # (R, N, 3) int: i, nearest j, second-nearest h (−1 if N < 3)
    centroid: np.ndarray  # (R, N, 2) m^{i,j,h} [8.3]
    direction: np.ndarray  # (R, N, 2) unit ray direction d^i (0 where invalid)
    normal: np.ndarray  # (R, N, 3) n^{i,j,h} [8.4]
    valid: np.ndarray  # (R, N) bool


def nearest_two(x: np.ndarray) -> np.ndarray:
    """(R, N, 2) indices of each robot's nearest and second-nearest other robot.

    Ties go to the lower index. Needs N ≥ 3.
    """
    N = x.shape[1]
    d = np.linalg.norm(x[:, :, None, :] - x[:, None, :, :], axis=-1)
    d[:, np.arange(N), np.arange(N)] = np.inf
    return np.argsort(d, axis=-1, kind="stable")[..., :2]


def plane_normal(q_i: np.ndarray, q_j: np.ndarray, q_h: np.ndarray) -> np.ndarray:
    """[8.4]: n = (q^i − q^j) × (q^i − q^h), shapes (…, 3)."""
    return np.cross(q_i - q_j, q_i - q_h)


def triangles(x: np.ndarray, intensity: np.ndarray, maximise: bool = True) -> Triangles:
    """Alg. 7 step 2 for every robot: triplet, centroid [8.3], normal [8.4] and ray direction.

    ``x`` (R, N, 2), ``intensity`` (R, N). The direction is −sgn(n_z)·n_xy normalised
    (Alg. 7 line 8), i.e. up the estimated gradient; ``maximise=False`` flips it for a cost.
    """
    x = np.asarray(x, dtype=float)
    I = np.asarray(intensity, dtype=float)
    R, N = I.shape
    if N < 3:
        z2, z3 = np.zeros((R, N, 2)), np.zeros((R, N, 3))
        return Triangles(np.full((R, N, 3), -1), x.copy(), z2, z3, np.zeros((R, N), bool))
    nb = nearest_two(x)
    runs = np.arange(R)[:, None, None]
    members = np.concatenate([np.broadcast_to(np.arange(N), (R, N))[..., None], nb], axis=-1)
    q = np.concatenate([x, I[..., None]], axis=-1)[runs, members]  # (R, N, 3, 3) [8.2]
    centroid = q[..., :2].mean(axis=-2)  # [8.3]
    finite = np.all(np.isfinite(q), axis=(-2, -1))
    q = np.where(finite[..., None, None], q, 0.0)
    n = plane_normal(q[..., 0, :], q[..., 1, :], q[..., 2, :])  # [8.4]
    e1, e2 = q[..., 0, :2] - q[..., 1, :2], q[..., 0, :2] - q[..., 2, :2]
    span = np.linalg.norm(e1, axis=-1) * np.linalg.norm(e2, axis=-1)
    flat_tri = np.abs(n[..., 2]) <= COLLINEAR * span  # coincident or collinear robots
    dI = np.maximum(np.abs(q[..., 0, 2] - q[..., 1, 2]), np.abs(q[..., 0, 2] - q[..., 2, 2]))
    flat_field = dI <= FLAT * np.abs(q[..., :, 2]).max(axis=-1)  # equal intensities
    g = -np.sign(n[..., 2])[..., None] * n[..., :2]  # Alg. 7 line 8: ∝ estimated gradient
    norm = np.linalg.norm(g, axis=-1)
    valid = finite & ~flat_tri & ~flat_field & (norm > 0)
    d = np.where(valid[..., None], g / np.where(valid, norm, 1.0)[..., None], 0.0)
    if not maximise:
        d = -d
    return Triangles(members, centroid, d, np.where(valid[..., None], n, 0.0), valid)
