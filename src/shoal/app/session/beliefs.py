"""Truth against belief: what one observer robot on SLO positions believes (its "ghosts").

For an observer robot i, a ghost at x_i + x̂_ij stands for every robot j it localised at its
last step; a host swarm (the Chapter 3 swarm, a fleet, an acoustic swarm on SLO positions)
adds where i believes the global best is. The views draw them; the panels read them out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Ghosts:
    """What one observer robot believes, in world coordinates anchored at its true position."""

    observer: int
    points: np.ndarray  # (G, 2) x_i + x̂_ij
    of: np.ndarray  # (G,) the robot j each ghost stands for
    truth: np.ndarray  # (G, 2) x_j
    error: np.ndarray  # (G,) |ghost − x_j|
    scale: float  # error drawn fully red
    best: np.ndarray | None = None  # (2,) where i believes the global best is
    true_best: np.ndarray | None = None  # (2,) the global best it stands for

    @property
    def mean_error(self) -> float:
        return float(self.error.mean()) if len(self.error) else float("nan")


def ghosts_of(beliefs: Any, x: np.ndarray, i: int, scale: float, *, best: np.ndarray | None = None,
              true_best: np.ndarray | None = None) -> Ghosts:
    """Observer ``i``'s ghosts (run 0) from :class:`~shoal.engine.slo.beliefs.Beliefs` and the
    true positions ``x`` (N, 2): every neighbour it localised at its last step."""
    of = np.flatnonzero(beliefs.valid[0, i])
    points = x[i] + beliefs.est[0, i, of]
    truth = x[of]
    err = np.hypot(*(points - truth).T) if len(of) else np.zeros(0)
    return Ghosts(observer=i, points=points, of=of, truth=truth, error=err, scale=float(scale), best=best,
                  true_best=true_best)


def host_ghosts(sim: Any, i: int, true_best: np.ndarray) -> Ghosts | None:
    """The ghosts of observer ``i`` of a host swarm (Chapter 3 swarm, fleet, acoustic swarm) on
    SLO positions (its ``positions`` source), or None on true positions. Errors show fully red
    at 10 thesis units."""
    positions = sim.positions
    if positions.exact:
        return None
    return ghosts_of(positions.beliefs, sim.state.x[0], i, 10.0 * positions.unit,
                     best=sim.believed_gbest()[0, i].copy(), true_best=np.asarray(true_best, dtype=float))
