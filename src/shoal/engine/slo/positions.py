"""The positions a host swarm acts on (SLO, Mai Ch. 3, p. 21): a collaborator each scene kind
with robots in the plane (the Chapter 3 swarm, the fleet, the acoustic swarm) asks wherever its controller
reads a position.

* :class:`Oracle`: every robot knows every true position, as in the theses (the default).
* :class:`Estimated`: each robot localises the others with SLO (a :class:`~.tracker.BeliefTracker`)
  and knows only its own displacement (odometry) and its estimates x̂_ij of the vectors to the
  others, never a position. So it keeps its personal best *relative to itself*, P_i ≈ y_i − x_i,
  shifted by the measured odometry every tick and reset to the offset of a new best; and it
  places another robot's best at x̂_ij + P_j, P_j being communicated (docs/readings.md,
  "Shifting the personal best [3.13]", "Local best from positions or personal bests").

The vectors a kind asks for are the two attractors of the theses: to a robot's own best, to the
best robot's best (Chapters 3–5, A-/X-PSO) or to the centroid of all personal bests
(B-/XB-/GT-PSO [7.11]). With the None error set and true initial beliefs :class:`Estimated`
gives :class:`Oracle`'s vectors up to floating-point error.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core.positions import Oracle, PositionSource
from ..core.snapshot import SnapshotError, arrays, integer, part
from .beliefs import Beliefs
from .tracker import BeliefTracker

__all__ = ["Estimated", "Oracle", "PositionSource"]  # (the protocol and the truth: engine/core/positions.py)


class Estimated:
    """Positions each robot estimates with SLO. The keywords are the :class:`~.tracker.BeliefTracker`
    ones (errors, selection, neighbourhood, …) with lengths in thesis units, ``unit`` metres each."""

    exact = False

    def __init__(self, *, unit: float = 1.0, **slo: Any) -> None:
        self.params: dict[str, Any] = {**slo, "unit": float(unit)}
        self.tracker: BeliefTracker
        self.pbest: np.ndarray  # (R, N, 2) P: each personal best relative to its robot
        self.sensed_k = 0  # the tick the tracker last localised at

    @property
    def unit(self) -> float:
        """Metres per thesis length unit."""
        return self.params["unit"]

    @property
    def beliefs(self) -> Beliefs:
        return self.tracker.beliefs

    def start(self, x: np.ndarray, y: np.ndarray, k: int, seed: int, first_run: int) -> None:
        """Fresh beliefs (and sensor streams, from ``seed``) at the true positions ``x``."""
        if x.shape[-1] != 2:
            raise ValueError(f"SLO positions need d = 2, got {x.shape[-1]}")
        self.tracker = BeliefTracker(x, seed=seed, first_run=first_run, **self.params)
        self.pbest = np.array(y - x, dtype=float)
        self.sensed_k = k

    def observe(self, x: np.ndarray, k: int) -> bool:
        """Localise at ``x`` and carry every personal best along by the measured odometry:
        P_i ← P_i − v*_i ([3.13], measured; docs/readings.md, "Shifting the personal best
        [3.13]")."""
        if k == self.sensed_k:
            return False
        self.tracker.observe(x)
        self.pbest = self.pbest - self.tracker.odometry
        self.sensed_k = k
        return True

    def keep(self, improved: np.ndarray, offset: np.ndarray | float = 0.0) -> None:
        """The new best is the robot's own position (``offset`` 0) or a remote candidate at
        ``offset`` (R, N, 2) from it."""
        self.pbest = np.where(np.asarray(improved, bool)[..., None], offset, self.pbest)

    def estimates(self) -> np.ndarray:
        """x̂_ij of every ordered pair, (R, N, N, 2), exactly 0 for i = j."""
        est = self.tracker.beliefs.est
        n = est.shape[1]
        return np.where(np.eye(n, dtype=bool)[None, :, :, None], 0.0, est)

    def to_personal(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return self.pbest

    def to_owner(self, x: np.ndarray, y: np.ndarray, owner: np.ndarray) -> np.ndarray:
        """x̂_i,owner + P_owner (docs/readings.md, "Local best from positions or personal bests")."""
        own = np.take_along_axis(self.pbest, np.asarray(owner)[:, None, None], axis=1)  # (R, 1, 2)
        return self.tracker.relative(owner) + own

    def to_centroid(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """mean_j (x̂_ij + P_j): the centroid of the personal bests as robot i places them."""
        return (self.estimates() + self.pbest[:, None, :, :]).mean(axis=2)

    def placed(self, x: np.ndarray) -> np.ndarray:
        """x_i + x̂_ij."""
        return x[:, :, None, :] + self.estimates()

    def resize(self, x: np.ndarray, k: int) -> None:
        """Kept robots keep their beliefs, calibration and relative bests; a new robot's best is
        where it stands (:meth:`~.tracker.BeliefTracker.resize`)."""
        m = min(x.shape[1], self.pbest.shape[1])
        self.tracker.resize(x)
        fresh = np.zeros_like(x, dtype=float)
        fresh[:, :m] = self.pbest[:, :m]
        self.pbest, self.sensed_k = fresh, k

    def retune(self, **slo: Any) -> None:
        """New SLO keywords mid-run, beliefs kept (:meth:`~.tracker.BeliefTracker.retune`); a new
        neighbourhood without its parameter keeps the one set before."""
        merged = {**self.params, **slo}
        keep_param = "neighbourhood" in slo and "neighbourhood_param" not in slo
        self.tracker.retune(**{k: merged[k] for k in slo if k != "unit"}, unit=merged["unit"],
                            **({"neighbourhood_param": merged.get("neighbourhood_param")} if keep_param else {}))
        self.params = merged

    def snapshot(self) -> dict[str, Any]:
        return {"source": "estimated", "pbest": self.pbest.copy(), "sensed_k": self.sensed_k,
                "tracker": self.tracker.snapshot()}

    def restore(self, data: Any, x: np.ndarray) -> None:
        if part(data, "source", "positions") != "estimated":
            raise SnapshotError("positions: the snapshot is of a swarm on true positions, this one acts on SLO ones")
        pbest = arrays(part(data, "pbest", "positions"), "positions.pbest", dtype=np.floating)
        if pbest.shape != x.shape:
            raise SnapshotError(f"positions.pbest: expected shape {x.shape}, got {pbest.shape}")
        sensed_k = integer(part(data, "sensed_k", "positions"), "positions.sensed_k")
        self.tracker.restore(part(data, "tracker", "positions"))
        if self.tracker.x.shape != x.shape:
            raise SnapshotError(f"positions.tracker.x: expected shape {x.shape}, got {self.tracker.x.shape}")
        self.pbest, self.sensed_k = pbest, sensed_k
