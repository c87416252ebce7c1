"""Beliefs of a swarm's robots about each other, followed step by step from the swarm's true
positions (Mai §3, p. 21): each robot localises the others from noisy ranges and odometry
(:class:`~.beliefs.Localiser`) with the SLO settings of a preset. :class:`BeliefTracker` is what
:class:`~.positions.Estimated` positions of a host swarm (the Chapter 3 swarm, the fleet, the
acoustic swarm) are made of.

With the None error set and true initial beliefs the believed vectors equal the true ones up to
floating-point error.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Literal

import numpy as np

from ..core.rng import component_generators
from ..core.snapshot import SnapshotError, arrays, part
from .beliefs import (
    Beliefs,
    Localiser,
    LocaliserParams,
    beliefs_data,
    beliefs_from,
    random_estimates,
    relative_truth,
    restore_streams,
    streams_data,
)
from .neighbourhoods import Neighbourhood, NeighbourhoodKind
from .sensors import ErrorModel, error_model

# Component keys of an SLO layer inside another simulation: children (i, 100 + k) of run i,
# clear of anything the host draws.
SOURCE_STREAM_OFFSET = 100


class BeliefTracker:
    """Beliefs of N robots about each other, updated from the swarm's true positions.

    ``x0`` (R, N, 2) are the true starting positions. ``errors`` is a preset name (none, low,
    high) or an :class:`ErrorModel` in thesis units, rescaled by ``unit`` (arena width / 100).
    ``initial_estimates`` "truth" starts from correct beliefs (a calibrated deployment);
    "random" uses differences of points in ``init_area`` (docs/readings.md, "Initial estimates x̂(−1)").
    Other keywords are
    :class:`LocaliserParams` fields (``selection``, ``prediction_weight``, ``delta_cos``, …).
    """

    def __init__(
        self,
        x0: np.ndarray,
        *,
        seed: int = 0,
        first_run: int = 0,
        errors: str | ErrorModel = "none",
        neighbourhood: NeighbourhoodKind = "full",
        neighbourhood_param: float | None = None,
        initial_estimates: Literal["truth", "random"] = "truth",
        init_area: tuple[float, float] = (-50.0, 50.0),
        unit: float = 1.0,
        **localiser: Any,
    ) -> None:
        x0 = np.asarray(x0, dtype=float)
        if x0.ndim != 3 or x0.shape[-1] != 2:
            raise ValueError(f"SLO needs 2-D positions (R, N, 2), got {x0.shape}")
        R, n, _ = x0.shape
        self.streams = component_generators(seed, first_run, R, offset=SOURCE_STREAM_OFFSET)
        self.errors = error_model(errors).scaled(unit)
        if "max_range" in localiser:
            localiser["max_range"] = float(localiser["max_range"]) * unit
        self.params = LocaliserParams(**localiser)
        self.rule = Neighbourhood(neighbourhood, neighbourhood_param).scaled(unit)
        self.localiser = Localiser(self.params, self.errors, self.streams, n)
        self.initial_estimates = initial_estimates
        self.init_area = (init_area[0] * unit, init_area[1] * unit)
        self.x = x0.copy()
        self.beliefs: Beliefs = self.localiser.start(x0, self.rule.adjacency(x0, self.streams["topology"]),
                                                     self._initial(x0))

    def snapshot(self) -> dict[str, Any]:
        """The beliefs, the positions they were last updated at, the calibration and every stream's state."""
        return {"x": self.x.copy(), "beliefs": beliefs_data(self.beliefs), "localiser": self.localiser.snapshot(),
                "streams": streams_data(self.streams)}

    def restore(self, data: Any) -> None:
        """Continue from :meth:`snapshot`'s ``data`` (a tracker made with the same settings and runs)."""
        x = arrays(part(data, "x", "tracker"), "tracker.x", ndim=3, dtype=np.floating)
        beliefs = beliefs_from(part(data, "beliefs", "tracker"), "tracker.beliefs")
        if x.shape[0] != self.x.shape[0] or x.shape[-1] != 2 or beliefs.est.shape[:2] != x.shape[:2]:
            raise SnapshotError(f"tracker.x: expected ({self.x.shape[0]}, N, 2) beside beliefs of N robots, got "
                                f"{x.shape} and {beliefs.est.shape}")
        self.localiser.restore(part(data, "localiser", "tracker"))
        restore_streams(self.streams, part(data, "streams", "tracker"), "tracker.streams")
        self.x, self.beliefs = x, beliefs

    def _initial(self, x: np.ndarray) -> np.ndarray:
        """x̂(−1) of a swarm deployed at ``x`` (R, N, 2): the truth or random vectors
        (docs/readings.md, "Initial estimates x̂(−1)")."""
        if self.initial_estimates == "truth":
            return relative_truth(x)
        return random_estimates(self.streams["init"], x.shape[1], *self.init_area)

    def resize(self, x: np.ndarray) -> Beliefs:
        """The swarm grew or shrank to the robots at ``x`` (R, N', 2), the first ones kept.

        Kept robots keep their beliefs of each other and their calibration offsets; a pair
        with a new robot starts as at a deployment (``initial_estimates``); every robot then
        measures its ranges afresh at ``x`` (no localisation, as at t = 0). The sensor streams
        run on, so no noise is drawn twice."""
        x = np.asarray(x, dtype=float)
        n, m = x.shape[1], min(x.shape[1], self.x.shape[1])
        self.localiser.resize(n)
        est = self._initial(x) if n > m else np.zeros(x.shape[:2] + x.shape[1:])
        est[:, :m, :m] = self.beliefs.est[:, :m, :m]
        self.x = x.copy()
        self.beliefs = self.localiser.start(x, self.rule.adjacency(x, self.streams["topology"]), est)
        return self.beliefs

    def retune(self, *, errors: str | ErrorModel | None = None, neighbourhood: NeighbourhoodKind | None = None,
               neighbourhood_param: float | None = None, unit: float = 1.0, **localiser: Any) -> None:
        """Change the sensor errors, the neighbourhood or the localisation choices mid-run,
        keeping the beliefs (and each robot's calibration offsets, rescaled)."""
        if "max_range" in localiser:
            localiser["max_range"] = float(localiser["max_range"]) * unit
        params = replace(self.params, **localiser) if localiser else None
        new_errors = error_model(errors).scaled(unit) if errors is not None else None
        if neighbourhood is not None:
            self.rule = Neighbourhood(neighbourhood, neighbourhood_param).scaled(unit)
        if params is not None:
            self.params = params
        if new_errors is not None:
            self.errors = new_errors
        self.localiser.retune(params, new_errors)

    def observe(self, x: np.ndarray, displacement: np.ndarray | None = None) -> Beliefs:
        """One sensing and localisation step at the new true positions ``x`` (R, N, 2).

        Odometry reads ``displacement`` (e.g. Δt·velocity) if given, else the change of ``x``."""
        x = np.asarray(x, dtype=float)
        before = self.x if displacement is None else x - np.asarray(displacement, dtype=float)
        adjacency = self.rule.adjacency(x, self.streams["topology"])
        self.beliefs = self.localiser.update(self.beliefs, before, x, adjacency)
        self.x = x.copy()
        return self.beliefs

    @property
    def odometry(self) -> np.ndarray:
        """Each robot's measured displacement of the last step v*_i, (R, N, 2)."""
        return self.beliefs.odometry

    def relative(self, target: np.ndarray) -> np.ndarray:
        """Each robot's belief of the vector to robot ``target`` (per run (R,) or per robot
        (R, N)), (R, N, 2); zero for the target itself."""
        est = self.beliefs.est
        R, n = est.shape[:2]
        t = np.broadcast_to(np.asarray(target).reshape(R, -1), (R, n))
        out = np.take_along_axis(est, t[:, :, None, None], axis=2)[:, :, 0, :]
        return np.where((t == np.arange(n))[..., None], 0.0, out)

    def believed_positions(self, x_self: np.ndarray | None = None) -> np.ndarray:
        """(R, N, N, 2): where robot i believes robot j is, anchored at i's own position
        ``x_self`` (default: the true one) — the ghost overlay."""
        anchor = self.x if x_self is None else x_self
        return anchor[:, :, None, :] + self.beliefs.est
