"""One run of a batch from step 0 with a seed of its own, while the others go on: how a vector
environment resets the environments whose episodes ended.

Run i restarts as run i of its new seed: the engine's snapshot (:mod:`shoal.engine.core.snapshot`)
takes, wherever it holds a value per run (an array whose first axis is the runs, a list of one
generator state per run), run 0 of a fresh one-run engine built for ``first_run = i`` and that
seed; the rest (the step count, the seed of a full reset, the world) stays the batch's. The
engine contract keeps every per-run value run-major, so this needs nothing of a kind but its
``snapshot`` and ``restore``. What a fresh engine has not computed yet (the last tick's hearing of
a run that has not listened) keeps the batch's value, and the environment does not show it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from shoal.api.scene import Scene


def splice(batch: Any, fresh: Any, run: int, runs: int) -> Any:
    """``batch`` (a snapshot tree of ``runs`` runs) with run ``run`` taken from ``fresh`` (of one run)."""
    if isinstance(batch, dict) and isinstance(fresh, dict):
        return {k: splice(v, fresh[k], run, runs) if k in fresh else v for k, v in batch.items()}
    if isinstance(batch, np.ndarray) and isinstance(fresh, np.ndarray):
        if batch.ndim and fresh.ndim == batch.ndim and batch.shape[0] == runs and fresh.shape[0] == 1 \
                and batch.shape[1:] == fresh.shape[1:]:
            out = batch.copy()
            out[run] = fresh[0]
            return out
        return batch
    if isinstance(batch, (list, tuple)) and isinstance(fresh, (list, tuple)):
        if len(batch) == runs and len(fresh) == 1:
            items = list(batch)
            items[run] = fresh[0]
            return tuple(items) if isinstance(batch, tuple) else items
        if len(batch) == len(fresh):
            return type(batch)(splice(b, f, run, runs) for b, f in zip(batch, fresh))
    return batch


def restart_runs(scene: Scene, runs: np.ndarray, seeds: np.ndarray) -> None:
    """Runs ``runs`` of ``scene`` from step 0, run ``runs[j]`` as run ``runs[j]`` of ``seeds[j]``."""
    engine: Any = scene.engine
    if not hasattr(engine, "snapshot") or not hasattr(engine, "restore"):
        raise ValueError(f"the {scene.kind.label} engine offers no snapshot(): its runs cannot restart one by one")
    if engine.runs < 2:
        raise ValueError("restart_runs: a scene of one run restarts with reset(seed)")
    data = engine.snapshot()
    for run, seed in zip(runs.tolist(), seeds.tolist()):
        fresh: Any = scene.kind.build(scene.scenario, runs=1, seed=int(seed), first_run=int(run))
        data = splice(data, fresh.snapshot(), int(run), engine.runs)
    engine.restore(data)
