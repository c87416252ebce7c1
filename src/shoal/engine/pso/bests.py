"""Personal and global bests ([3.2], [3.3]) and the attractors they define."""

from __future__ import annotations

import numpy as np

from ..core.objectives import Objective


def update_personal(
    x: np.ndarray, f: np.ndarray, y: np.ndarray, f_y: np.ndarray, objective: Objective
) -> tuple[np.ndarray, np.ndarray]:
    """[3.2]: keep the best location each robot has visited. Shapes (R, N, d), (R, N)."""
    better = objective.is_better(f, f_y)
    return np.where(better[..., None], x, y), np.where(better, f, f_y)


def best_index(f_y: np.ndarray, objective: Objective) -> np.ndarray:
    """The robot holding the best personal best of each run (the first of equals), (R,)."""
    return np.argmax(f_y, axis=1) if objective.maximise else np.argmin(f_y, axis=1)


def global_best(y: np.ndarray, f_y: np.ndarray, objective: Objective) -> tuple[np.ndarray, np.ndarray]:
    """[3.3]: the best personal best of each run. Returns (R, d) and (R,)."""
    idx = best_index(f_y, objective)
    runs = np.arange(y.shape[0])
    return y[runs, idx], f_y[runs, idx]
