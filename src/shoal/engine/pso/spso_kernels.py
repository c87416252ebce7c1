"""The robot-centred SPSO 2011 update [3.10]–[3.11] compiled (numba): the same arithmetic, in
the same order, as :meth:`~.spso2011.SPSO2011.local_velocity` (the numpy reference;
``tests/test_slo_kernels.py`` compares them bit for bit), without its dozen small arrays a
generation."""

from __future__ import annotations

import math

import numpy as np

from ..core.compiled import f64, kernel
from .spso2011 import SPSO2011, SPSODraws


@kernel
def _local_velocity(v: np.ndarray, p: np.ndarray, l: np.ndarray, u1: np.ndarray, u2: np.ndarray, normal: np.ndarray,
                    rho: np.ndarray, self_best: np.ndarray, inertia: float, c1: float, c2: float, c3: float, c4: float,
                    uniform_area: bool, halving: bool) -> np.ndarray:
    R, n = v.shape[0], v.shape[1]
    out = np.empty((R, n, 2))
    for r in range(R):
        for i in range(n):
            cog0, cog1 = c1 * u1[r, i, 0] * p[r, i, 0], c1 * u1[r, i, 1] * p[r, i, 1]
            if halving and self_best[r, i]:  # SPSO's own-best rule
                g0, g1 = cog0 / 2.0, cog1 / 2.0
            else:  # [3.10]
                g0, g1 = (cog0 + c2 * u2[r, i, 0] * l[r, i, 0]) / 3.0, (cog1 + c2 * u2[r, i, 1] * l[r, i, 1]) / 3.0
            radius = c3 * math.sqrt(g0 * g0 + g1 * g1) + c4
            if not (radius >= 0.0 or radius != radius):  # numpy's maximum(radius, 0)
                radius = 0.0
            n0, n1 = normal[r, i, 0], normal[r, i, 1]
            length = math.sqrt(n0 * n0 + n1 * n1)
            d0, d1 = (n0 / length, n1 / length) if length > 0.0 else (0.0, 0.0)
            step = radius * (math.sqrt(rho[r, i]) if uniform_area else rho[r, i])
            out[r, i, 0] = inertia * v[r, i, 0] + (g0 + step * d0)  # [3.11]
            out[r, i, 1] = inertia * v[r, i, 1] + (g1 + step * d1)
    return out


def local_velocity(law: SPSO2011, v: np.ndarray, p: np.ndarray, l: np.ndarray, d: SPSODraws,
                   self_best: np.ndarray | None = None) -> np.ndarray:
    """:meth:`SPSO2011.local_velocity` compiled: V' = ω·V + H(G, c3·‖G‖ + c4), (R, N, 2)."""
    own = np.zeros(v.shape[:2], bool) if self_best is None else np.ascontiguousarray(self_best, dtype=bool)
    return _local_velocity(f64(v), f64(p), f64(l), f64(d.u1), f64(d.u2), f64(d.normal), f64(d.rho), own,
                           float(law.inertia), float(law.c1), float(law.c2), float(law.c3), float(law.c4),
                           law.radial == "uniform_area", bool(law.spso_self_best_halving and self_best is not None))
