"""Personal-best memory with forgetting and the two global-best forms of Chapters 7–8.

The forgetting rule ([7.2], [7.9], [8.6]; Rossides §7.1.1, p. 149) lets a remembered fitness fade by
e^(−a) every step it is not beaten, so a noisy or moving source keeps refreshing the memory.
"""

from __future__ import annotations

import numpy as np


def improves(f_hat: np.ndarray, f_new: np.ndarray, candidate: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """(R, N) bool: the candidate is valid, finite and strictly beats the memory [7.2]."""
    f_new = np.asarray(f_new, dtype=float)
    ok = np.asarray(valid, bool) & np.isfinite(f_new) & np.all(np.isfinite(candidate), axis=-1)
    return ok & (np.where(ok, f_new, -np.inf) > f_hat)


def forget_update(
    f_hat: np.ndarray,
    y: np.ndarray,
    f_new: np.ndarray,
    candidate: np.ndarray,
    valid: np.ndarray,
    a: float,
) -> tuple[np.ndarray, np.ndarray]:
    """One forgetting step for every robot: shapes (R, N), (R, N, 2), (R, N), (R, N, 2), (R, N).

    A valid candidate whose fitness beats the memory replaces it; every other robot (no
    candidate, or no improvement) keeps its location and its fitness decays by e^(−a).
    A candidate with a non-finite fitness or location counts as invalid.
    Returns the new ``(f_hat, y)``.
    """
    f_hat = np.asarray(f_hat, dtype=float)
    better = improves(f_hat, f_new, candidate, valid)
    f_out = np.where(better, f_new, f_hat * np.exp(-a))  # [7.2], [7.9], [8.6]
    y_out = np.where(better[..., None], candidate, y)
    return f_out, y_out


def best_of(f_hat: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Alg. 3/4 lines 8–13: the personal best of the robot with the largest f̂, per run.

    Ties (including an all-zero memory at the start) go to the lowest robot index.
    Returns ``y_g`` (R, 2) and ``f_g`` (R,).
    """
    idx = np.argmax(f_hat, axis=1)
    runs = np.arange(f_hat.shape[0])
    return y[runs, idx], f_hat[runs, idx]


def centroid_of(y: np.ndarray) -> np.ndarray:
    """[7.11]: the mean of the personal bests of each run, (R, N, 2) → (R, 2)."""
    return np.mean(y, axis=1)
