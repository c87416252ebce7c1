"""What the arena draws, copied under the session's lock: one :class:`Snapshot` for every
scene kind; what only one kind draws travels in ``extras``."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from shoal.presets.models import Scenario

from .beliefs import Ghosts
from .history import Trails


@dataclass(frozen=True)
class Snapshot:
    """Run 0 at step ``k``: robots, trails, bests and the kind's own drawing data.

    A recorded frame (scrubbed or replayed, ``live`` False) has robots, trails, swarm B and the
    scene parts of its step (the driver's ``recorded``: obstacles, a source); bests, beliefs and
    whatever the kind blanks in ``extras`` are not recorded.
    """

    scenario: Scenario  # the scene it belongs to (static drawing: arena, objective)
    k: int
    t: float
    x: np.ndarray  # (N, d)
    heading: np.ndarray  # (N,)
    status: np.ndarray  # (N,) 0 active
    trails: Trails  # (M, L, d ≤ 3) oldest first, M ≤ N, with the step of each point
    revision: int
    selected: int  # the robot the panels and the view single out
    y: np.ndarray | None = None  # (N, d) personal bests
    yg: np.ndarray | None = None  # (d,) global best
    ghosts: Ghosts | None = None  # the selected robot's beliefs (SLO positions)
    twin: tuple[np.ndarray, Trails] | None = None  # swarm B's robots (N, d) and trails at this step
    live: bool = True
    extras: dict[str, Any] = field(default_factory=dict)  # kind-specific drawing data
