"""SLO-estimated positions for a host swarm (spec §15): the bests a robot can know without
an oracle, and a mixin that puts any Shoal swarm on them.

A robot on SLO positions knows its own displacement (odometry) and its estimates x̂_ij of
the vectors to the others, never a position. So it keeps its personal best *relative to
itself*, P_i ≈ y_i − x_i, shifted by the measured odometry every tick (gap A35) and reset to
the offset of a new best; and it places another robot's best at x̂_ij + P_j, P_j being
communicated (gap A36). :class:`BelievedBests` holds P and forms the two global bests of
the theses from it: the best robot's best (Chapters 3–5, A-/X-PSO) and the centroid of all
personal bests (B-/XB-/GT-PSO [7.11]). :class:`SLOHost` starts an
:class:`~.slo_source.SLOPositionSource` with the host's seed at every reset.

With the None error set and true initial beliefs the relative vectors equal the oracle's
y − x and y_g − x up to floating-point error.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # slo_source's SLOSimulation is itself an SLOHost
    from .slo_source import SLOPositionSource


class BelievedBests:
    """Personal bests kept relative to their robots, (R, N, 2), and the global best each
    robot believes, from the estimates of ``source``.

    ``pbest`` is P at the start (y − x, 0 for a fresh swarm); ``k`` the tick the source
    last localised at (its start).
    """

    def __init__(self, source: SLOPositionSource, pbest: np.ndarray, k: int = 0) -> None:
        self.source = source
        self.pbest = np.array(pbest, dtype=float)
        self.sensed_k = k

    def sense(self, x: np.ndarray, k: int) -> bool:
        """Localise at the true positions ``x`` once per tick ``k`` and carry every personal
        best along by the measured odometry: P_i ← P_i − v*_i ([3.13], measured, gap A35).
        False (nothing done) when tick ``k`` was sensed already."""
        if k == self.sensed_k:
            return False
        self.source.observe(x)
        self.pbest = self.pbest - self.source.odometry
        self.sensed_k = k
        return True

    def keep(self, improved: np.ndarray, offset: np.ndarray | float = 0.0) -> None:
        """Where ``improved`` (R, N), the personal best becomes the new best: the robot's own
        position (``offset`` 0) or a remote candidate at ``offset`` (R, N, 2) from it."""
        self.pbest = np.where(np.asarray(improved, bool)[..., None], offset, self.pbest)

    def estimates(self) -> np.ndarray:
        """x̂_ij of every ordered pair, (R, N, N, 2), exactly 0 for i = j."""
        est = self.source.beliefs.est
        n = est.shape[1]
        return np.where(np.eye(n, dtype=bool)[None, :, :, None], 0.0, est)

    def to_owner(self, owner: np.ndarray) -> np.ndarray:
        """Each robot's vector to the personal best of robot ``owner`` (R,): x̂_i,owner +
        P_owner (gap A36), (R, N, 2)."""
        own = np.take_along_axis(self.pbest, np.asarray(owner)[:, None, None], axis=1)  # (R, 1, 2)
        return self.source.relative(owner) + own

    def to_centroid(self) -> np.ndarray:
        """Each robot's vector to the centroid of all personal bests [7.11] as it places
        them, mean_j (x̂_ij + P_j), (R, N, 2)."""
        return (self.estimates() + self.pbest[:, None, :, :]).mean(axis=2)


class SLOHost:
    """Mixin: a host swarm (:class:`~.sim.Simulation`, :class:`~.fleet.Fleet`,
    :class:`~.sonar.AcousticSwarm`) whose robots localise each other with SLO.

    ``slo`` holds the :class:`SLOPositionSource` keywords (errors, selection, unit, …); the
    source is ``slo_source``. The host needs ``state.x``, ``state.y``, ``state.k``, ``seed``
    and ``first_run``, and calls ``self.bests`` where it would read positions.
    """

    slo_params: dict[str, Any]
    slo_source: SLOPositionSource  # not ``source``: a fleet's source is where it is going
    bests: BelievedBests

    def __init__(self, *args: Any, slo: dict[str, Any] | None = None, **kwargs: Any) -> None:
        self.slo_params = dict(slo or {})
        super().__init__(*args, **kwargs)

    def reset(self, seed: int | None = None) -> None:
        super().reset(seed)  # type: ignore[misc]
        self._start_source()

    def step(self) -> Any:
        """The host's tick, then localisation where the moves ended: the beliefs are current
        for drawing, and the next tick's sensing finds them done (same positions, same draws)."""
        info = super().step()  # type: ignore[misc]
        s = self.state  # type: ignore[attr-defined]
        self.bests.sense(s.x, s.k)
        return info

    def _to_global(self) -> np.ndarray:
        """Each robot's vector to the global best as it believes it, (R, N, 2)."""
        raise NotImplementedError

    def believed_gbest(self) -> np.ndarray:
        """(R, N, 2) where each robot believes the global best is, put at its true position."""
        return self.state.x + self._to_global()  # type: ignore[attr-defined]

    def _start_source(self) -> None:
        """Fresh beliefs (and sensor streams) at the current true positions."""
        from .slo_source import SLOPositionSource

        s = self.state  # type: ignore[attr-defined]
        if s.x.shape[-1] != 2:
            raise ValueError(f"SLO positions need d = 2, got {s.x.shape[-1]}")
        self.slo_source = SLOPositionSource(s.x, seed=self.seed, first_run=self.first_run,  # type: ignore[attr-defined]
                                            **self.slo_params)
        self.bests = BelievedBests(self.slo_source, s.y - s.x, s.k)

    def _retune_positions(self, slo: dict[str, Any]) -> None:
        """Change the SLO keywords (errors, selection, …) mid-run, beliefs kept (the host's
        ``retune(slo=...)``); see :meth:`SLOPositionSource.retune`."""
        merged = {**self.slo_params, **slo}
        self.slo_source.retune(**{k: merged[k] for k in slo if k != "unit"}, unit=merged.get("unit", 1.0),
                               **({"neighbourhood_param": merged.get("neighbourhood_param")}
                                  if "neighbourhood" in slo and "neighbourhood_param" not in slo else {}))
        self.slo_params = merged


__all__ = ["BelievedBests", "SLOHost"]
