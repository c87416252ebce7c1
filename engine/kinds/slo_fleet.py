"""The Chapter 4–5 fleet on SLO-estimated positions (spec §15): DVC, RPSO and the
non-omnidirectional controller steered by what the robots believe.

Only the two attractors use positions. Each robot steers towards its personal best, kept
relative to itself by odometry, and the fleet's global best, placed at x̂_i,owner + P_owner
(:class:`~.slo_host.BelievedBests`, as for the Chapter 3 swarm). Obstacle sensing stays
local (six range sectors need no positions), the cost is read at the true position, and a
collided robot stays in the swarm as a still robot: it is still ranged and still ranges the
others, and its personal best can still be the global one.

With the None error set and true initial beliefs a run equals the oracle :class:`Fleet` run
of the same seed up to floating-point error.
"""

from __future__ import annotations

import numpy as np

from ..slo.positions import SLOHost
from .fleet import Fleet


class SLOFleet(SLOHost, Fleet):
    """A :class:`Fleet` whose robots localise each other with SLO (``slo``: the
    :class:`~.slo_source.SLOPositionSource` keywords, e.g. ``errors``, ``unit``)."""

    def _update_bests(self) -> None:
        """Phase A: localise, carry the relative bests by odometry, score at the truth."""
        s = self.state
        self.bests.sense(s.x, s.k)
        before = s.f_y.copy()
        super()._update_bests()
        self.bests.keep(s.f_y != before)  # a new best is where the robot stands
        self._to_best = self._to_global()

    def _to_global(self) -> np.ndarray:
        return self.bests.to_owner(np.argmin(self.state.f_y, axis=1))

    def _attractors(self) -> tuple[np.ndarray, np.ndarray]:
        return self.bests.pbest, self._to_best


__all__ = ["SLOFleet"]
