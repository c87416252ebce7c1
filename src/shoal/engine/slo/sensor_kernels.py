"""The compiled SLO sensor models (numba): ranges [4.1]–[4.3] and odometry [4.4] from the
draws of :mod:`~.sensors`, in the arithmetic order of the numpy expressions they replace
(``tests/test_slo_kernels.py`` keeps those as references and compares them bit for bit).

The rotation's cos θ and sin θ stay numpy's (a compiled cos may differ from numpy's in the
last bit), so they come in worked out.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.compiled import kernel


@kernel
def reading(dd: float, fail: float, z_m: float, z_a: float, sigma_m: float, sigma_a: float, perm_m: float,
            perm_a: float, p_fail: float, max_range: float) -> float:
    """One range d* [4.1]–[4.3] from the true distance ``dd``, the failure draw ``fail`` and the
    normals ``z_m``, ``z_a``, with the observer's permanent ``perm_m``, ``perm_a``: 0 for a
    failure, beyond ``max_range`` or a non-finite distance; a negative reading clamped to 0."""
    finite = math.isfinite(dd) and dd <= max_range
    d = dd if finite else 0.0
    e_m = 1.0 + sigma_m * z_m + perm_m  # [4.2]
    e_a = sigma_a * z_a + perm_a  # [4.3]
    value = d * e_m + e_a  # [4.1]; docs/readings.md, "Negative ranges"
    if not (value >= 0.0 or value != value):  # numpy's maximum(reading, 0)
        value = 0.0
    return 0.0 if fail < p_fail or not finite else value


@kernel
def ranges(dist: np.ndarray, fail: np.ndarray, z: np.ndarray, sigma_m: float, sigma_a: float, perm_m: np.ndarray,
           perm_a: np.ndarray, p_fail: float, max_range: float) -> np.ndarray:
    """d*_ij (R, N, N) from the true distances, the U(0,1) failure draws ``fail`` (R, N, N), the
    normals ``z`` (R, 2, N, N) and observer i's permanent P_m, P_a (R, N); 0 on the diagonal,
    for a failure and beyond ``max_range``; negative readings clamped to 0."""
    R, n = dist.shape[0], dist.shape[1]
    out = np.empty((R, n, n))
    for r in range(R):
        for i in range(n):
            for j in range(n):
                value = reading(dist[r, i, j], fail[r, i, j], z[r, 0, i, j], z[r, 1, i, j], sigma_m, sigma_a,
                                perm_m[r, i], perm_a[r, i], p_fail, max_range)
                out[r, i, j] = 0.0 if i == j else value
    return out


@kernel
def odometry(v: np.ndarray, fail: np.ndarray, z: np.ndarray, sigma_m: float, sigma_a: float, perm_m: np.ndarray,
             perm_a: np.ndarray, cos_t: np.ndarray, sin_t: np.ndarray, p_fail: float) -> np.ndarray:
    """v*_i (R, N, 2) from the true displacements ``v``: per-axis E_m, E_a from the normals ``z``
    (R, 5, N) and the permanent P_m, P_a (R, N, 2), then the rotation by θ given as its cos and
    sin (R, N) [4.4]; (0, 0) where ``fail`` (R, N) < p_fail."""
    R, n = v.shape[0], v.shape[1]
    out = np.empty((R, n, 2))
    for r in range(R):
        for i in range(n):
            w0 = v[r, i, 0] * (1.0 + sigma_m * z[r, 0, i] + perm_m[r, i, 0]) + (sigma_a * z[r, 2, i] + perm_a[r, i, 0])
            w1 = v[r, i, 1] * (1.0 + sigma_m * z[r, 1, i] + perm_m[r, i, 1]) + (sigma_a * z[r, 3, i] + perm_a[r, i, 1])
            c, s = cos_t[r, i], sin_t[r, i]
            if fail[r, i] < p_fail:
                out[r, i, 0] = out[r, i, 1] = 0.0
            else:
                out[r, i, 0], out[r, i, 1] = c * w0 - s * w1, s * w0 + c * w1
    return out
