"""The thesis law as the baseline: :func:`baseline` gives the action the scene's own law would take.

The scene is stepped one tick ahead by its own law and put back (``engine.snapshot()`` and
``restore``: the same bits), and what the law did is read off that tick:

* ``"velocity"``: each robot's command. Steered with it, the engine makes the law's draws and moves
  the robots as the law does, to the bit, so an episode driven by the baseline writes the metrics
  ``shoal run`` writes for the same preset and seed;
* ``"waypoint"``: where the law's tick takes each robot (the same path, up to rounding);
* ``"pso-params"``: the law's ω, c1 and c2 for the tick (the mean over the robots where the law
  tunes each robot itself, as DVC does; NaN where the kind does not say).
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from .batch import Batch


def ahead(batch: Batch, read: Callable[[Batch], Any]) -> Any:
    """``read(batch)`` after one tick of the law, with the scene put back as it was."""
    engine = batch.engine
    if not hasattr(engine, "snapshot") or not hasattr(engine, "restore"):
        raise ValueError(f"the {batch.scene.kind.label} engine offers no snapshot(): no look-ahead for a baseline")
    data = engine.snapshot()
    try:
        engine.steering = None
        engine.step()
        return read(batch)
    finally:
        engine.restore(data)


def _read(batch: Batch) -> np.ndarray:
    """What the law did in the tick just done, as the control mode's action (R, N, m) or (R, m)."""
    mode = batch.control.name
    if mode == "velocity":
        return batch.spec.commanded(batch.scene)
    if mode == "waypoint":
        return batch.scene.state.x.copy()
    assert batch.coefficients is not None
    own = np.asarray(batch.coefficients.own(batch.scene), dtype=float)  # (3, R, N)
    return np.moveaxis(own.mean(axis=2), 0, -1)


def batch_of(env: Any) -> Batch:
    """The :class:`Batch` under a Shoal environment (through any wrappers)."""
    for candidate in (env, getattr(env, "unwrapped", None), getattr(env, "env", None)):
        got = getattr(candidate, "batch", None)
        if isinstance(got, Batch):
            return got
    raise TypeError(f"baseline: {type(env).__name__} is not a Shoal environment (shoal.rl's Gymnasium, vector or "
                    "PettingZoo env)")


def baseline(env: Any) -> Any:
    """The action the scene's own law would take now, in the shape ``env.step`` takes: (N, m) or (m,)
    for a Gymnasium env, (num_envs, …) for a vector env, ``{agent: (m,)}`` for a PettingZoo env."""
    from .parallel import ShoalParallelEnv
    from .vector import ShoalVectorEnv

    batch = batch_of(env)
    action = np.asarray(ahead(batch, _read), dtype=float)
    unwrapped = getattr(env, "unwrapped", env)
    if isinstance(unwrapped, ShoalParallelEnv):
        per_robot = action if action.ndim == 3 else np.broadcast_to(action[:, None], (1, batch.robots, 3))
        return {a: per_robot[0, int(a.rsplit("_", 1)[1])].copy() for a in unwrapped.agents}
    if isinstance(unwrapped, ShoalVectorEnv):
        return action
    return action[0]
