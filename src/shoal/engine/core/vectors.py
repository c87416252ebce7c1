"""Small vector helpers shared by the engine."""

from __future__ import annotations

import numpy as np


def norm(v: np.ndarray) -> np.ndarray:
    """Length of 2-vectors (..., 2): the same bits as ``np.linalg.norm(v, axis=-1)``
    (√(v₀² + v₁²), summed in that order) at a fraction of its cost on short rows."""
    return np.sqrt(v[..., 0] * v[..., 0] + v[..., 1] * v[..., 1])
