"""Personal and global bests ([3.2], [3.3]) and the attractors they define.

A best is honest: NaN is never one, nor the worst infinity (+inf when minimising, −inf when
maximising). A value that is neither is *admissible*; an admissible value beats one that is not,
so a robot that started where the objective is NaN takes its first admissible value as its best
(docs/readings.md, "Bests that are NaN or infinite"). Where no value is admissible the first
robot's stands, whatever it is. With admissible values only, these are the plain comparisons."""

from __future__ import annotations

import warnings

import numpy as np

from ..core.objectives import Objective


def admissible(f: np.ndarray, maximise: bool) -> np.ndarray:
    """True where ``f`` may be a best: not NaN, and not the worst infinity."""
    return ~np.isnan(f) & (f != (-np.inf if maximise else np.inf))


def improves(a: np.ndarray, b: np.ndarray, maximise: bool) -> np.ndarray:
    """True where ``a`` replaces the best ``b``: ``a`` is admissible and beats ``b`` strictly, or
    ``b`` is not admissible."""
    ok = admissible(a, maximise)
    return ok & ((a > b if maximise else a < b) | ~admissible(b, maximise))


def best_of(f: np.ndarray, maximise: bool, axis: int = -1) -> np.ndarray:
    """The index of the best admissible value along ``axis`` (the first of equals; the first
    value where none is admissible)."""
    worst = -np.inf if maximise else np.inf
    masked = np.where(admissible(f, maximise), f, worst)
    return np.argmax(masked, axis=axis) if maximise else np.argmin(masked, axis=axis)


def update_personal(
    x: np.ndarray, f: np.ndarray, y: np.ndarray, f_y: np.ndarray, objective: Objective
) -> tuple[np.ndarray, np.ndarray]:
    """[3.2]: keep the best location each robot has visited. Shapes (R, N, d), (R, N)."""
    better = improves(f, f_y, objective.maximise)
    return np.where(better[..., None], x, y), np.where(better, f, f_y)


def best_index(f_y: np.ndarray, objective: Objective) -> np.ndarray:
    """The robot holding the best personal best of each run (the first of equals), (R,)."""
    return best_of(f_y, objective.maximise, axis=1)


def global_best(y: np.ndarray, f_y: np.ndarray, objective: Objective) -> tuple[np.ndarray, np.ndarray]:
    """[3.3]: the best personal best of each run. Returns (R, d) and (R,)."""
    idx = best_index(f_y, objective)
    runs = np.arange(y.shape[0])
    return y[runs, idx], f_y[runs, idx]


def warn_unfound(best: np.ndarray, maximise: bool, objective: str, warned: bool) -> bool:
    """Say once (a ``RuntimeWarning`` naming ``objective``) that some run has no admissible best:
    every value it met was NaN or the worst infinity. Returns whether it has been said."""
    if warned or admissible(best, maximise).all():
        return warned
    runs = np.flatnonzero(~admissible(best, maximise))
    warnings.warn(f"objective {objective!r}: every value run(s) {', '.join(map(str, runs[:5]))}"
                  f"{' …' if runs.size > 5 else ''} met is NaN or {'-' if maximise else '+'}inf, so there is no "
                  "best yet (NaN is never a best)", RuntimeWarning, stacklevel=3)
    return True
