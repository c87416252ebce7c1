"""The Gymnasium spaces of a batch: the observation (a ``Dict`` of ``Box`` es, one per part) and the
action (a ``Box``), for the swarm as one agent or for one robot."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from .batch import OBS_DTYPE, Batch


def observation_space(batch: Batch, robot: bool = False) -> spaces.Dict:
    """The swarm's observation: every robot's parts (N, *shape) and the swarm's; ``robot``: one
    robot's own parts (*shape) and the swarm's."""
    n = batch.robots
    boxes: dict[str, spaces.Space] = {}
    for p in batch.parts:
        shape = p.shape if robot or p.per == "swarm" else (n, *p.shape)
        boxes[p.name] = spaces.Box(low=p.low, high=p.high, shape=shape, dtype=OBS_DTYPE)
    return spaces.Dict(boxes)


def action_space(batch: Batch, robot: bool = False) -> spaces.Box:
    """One action of the swarm ((N, m), or (m,) for a mode set for the whole swarm), or of one robot (m,).
    float64, the engine's own precision: the baseline's commands pass to the bit."""
    low, high = batch.low, batch.high
    if robot or batch.control.per == "swarm":
        return spaces.Box(low=low, high=high, dtype=np.float64)
    n = batch.robots
    return spaces.Box(low=np.tile(low, (n, 1)), high=np.tile(high, (n, 1)), dtype=np.float64)
