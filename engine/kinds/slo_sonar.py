"""The acoustic swarm of Chapters 7–8 on SLO-estimated positions (spec §15).

The strategies (A/X/B/XB/GT-PSO) place bearing rays and intensity triangles at the robots'
positions. On SLO positions robot i knows only its own pose and x_i + x̂_ij for the others,
so it runs the best-location step **in its own believed frame** (our reading; the theses do
not combine the two):

1. listen: unchanged, at the true positions (the acoustics are physics);
2. candidates: every robot i gets a copy of the swarm placed where it believes the others
   are, anchored at its true position (x̂_ii = 0). The (run, robot) pairs are handed to the
   strategy as runs of their own, and robot i keeps only its own row: its candidate (own
   position, or the intersection of its rays with its partner's rays placed at
   x_i + x̂_i,partner; for GT-PSO the triangles of its believed neighbours), fitness and
   validity. The strategy's random partner draws are shared by the frames of one run, so
   they are the oracle run's draws;
3. memory: the personal best is kept relative to the robot (P_i, carried by odometry) with
   the forgetting rule [7.2]/[7.9]/[8.6] on the candidate's offset from the robot;
4. global best as each robot believes it (:class:`~.slo_host.BelievedBests`): the best
   robot's x̂_i,owner + P_owner (A/X-PSO), or the centroid of x̂_ij + P_j over all robots
   (B/XB/GT-PSO [7.11]), communicated P_j being exact (gap A16);
5. the velocity law and the escort ring use these vectors; robots still sense each other
   locally (six sectors, no positions needed).

``state.y`` holds x_i + P_i (where robot i's remembered best lies, as it believes, put at
its true position), ``state.y_g`` the swarm's version of the global best (the owner's
x + P, or the centroid of x + P) and :meth:`believed_gbest` (R, N, 2) each robot's own.
``state.loc`` is robot i's own decision in its frame (intersections around its true
position). With the None error set and true initial beliefs a run equals the oracle
:class:`AcousticSwarm` run of the same seed up to floating-point error.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..acoustics.forgetting import forget_update, improves
from ..acoustics.strategies import LocInfo, Sensed
from ..acoustics.triangulation import Triangles
from ..slo.positions import SLOHost
from .sonar import AcousticSwarm, Decision


class SharedDraws:
    """One run's generator as seen by one robot's frame: the n-th ``random`` call of every
    frame of the run returns the same numbers, drawn from the run's generator at the first
    of those calls (the strategies draw only ``random(size)``)."""

    def __init__(self, gen: np.random.Generator, log: list[Any]) -> None:
        self.gen, self.log, self.calls = gen, log, 0

    def random(self, size: Any = None) -> Any:
        if self.calls == len(self.log):
            self.log.append(self.gen.random(size))
        out = self.log[self.calls]
        self.calls += 1
        return out


def frame_draws(rngs: list[np.random.Generator], robots: int) -> list[SharedDraws]:
    """``robots`` frames per run, run-major, sharing their run's draws."""
    out: list[SharedDraws] = []
    for gen in rngs:
        log: list[Any] = []
        out += [SharedDraws(gen, log) for _ in range(robots)]
    return out


def own_rows(a: np.ndarray | None, runs: int, robots: int) -> np.ndarray | None:
    """Robot i's row of frame (r, i): (runs·robots, robots, …) → (runs, robots, …)."""
    if a is None:
        return None
    i = np.arange(robots)
    return a.reshape((runs, robots, robots) + a.shape[2:])[:, i, i]


def own_decision(info: LocInfo, runs: int, robots: int) -> dict[str, Any]:
    """The LocInfo fields of every robot's own row (f_g and improved left to the caller)."""
    out = {k: own_rows(getattr(info, k), runs, robots)
           for k in ("candidate", "fitness", "valid", "partner", "points", "forward", "kept", "selected")}
    t = info.triangles
    out["triangles"] = None if t is None else Triangles(
        *(own_rows(getattr(t, k), runs, robots) for k in ("members", "centroid", "direction", "normal", "valid")))
    return out


class SLOAcousticSwarm(SLOHost, AcousticSwarm):
    """An :class:`AcousticSwarm` whose robots localise each other with SLO (``slo``: the
    :class:`~.slo_source.SLOPositionSource` keywords, e.g. ``errors``, ``unit``)."""

    def _to_global(self, f_hat: np.ndarray | None = None) -> np.ndarray:
        """From the memory ``f_hat`` (R, N) (default: the state's)."""
        if self.strategy.global_best == "best":  # Alg. 3/4: the best robot's personal best
            f = self.state.f_hat if f_hat is None else f_hat
            return self.bests.to_owner(np.argmax(f, axis=1))
        return self.bests.to_centroid()  # [7.11]: the centroid of the personal bests

    def _bests(self, idx: np.ndarray, x: np.ndarray, sensed: Sensed, rngs: list) -> Decision:
        s, strat = self.state, self.strategy
        self.bests.sense(s.x, s.k - 1)  # done at the end of the last tick (the counter moved on since)
        R, N = x.shape[:2]
        frames = (x[:, :, None, :] + self.bests.estimates()[idx]).reshape(R * N, N, 2)

        def rep(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else np.repeat(a, N, axis=0)

        per_frame = Sensed(intensity=rep(sensed.intensity), rho=rep(sensed.rho), rays=rep(sensed.rays))
        _, _, _, info = strat.update(rep(s.f_hat[idx]), frames, frames, per_frame, frame_draws(rngs, N))
        mine = own_decision(info, R, N)
        offset = mine["candidate"] - x  # the candidate as seen from the robot
        f_old, p_old = s.f_hat[idx], self.bests.pbest[idx]
        better = improves(f_old, mine["fitness"], offset, mine["valid"])
        f_hat, pbest = forget_update(f_old, p_old, mine["fitness"], offset, mine["valid"], strat.a)
        self.bests.pbest[idx] = pbest
        y = x + pbest
        f_all = s.f_hat.copy()
        f_all[idx] = f_hat
        to_g = self._to_global(f_all)[idx]
        f_g = None
        if strat.global_best == "best":
            owner = np.argmax(f_hat, axis=1)
            y_g, f_g = y[np.arange(R), owner], f_hat[np.arange(R), owner]
        else:
            y_g = y.mean(axis=1)
        loc = LocInfo(improved=better, f_g=f_g, **mine)
        return Decision(f_hat, y, y_g, loc, np.stack([pbest, to_g]), x + to_g)


__all__ = ["SLOAcousticSwarm", "frame_draws", "own_rows"]
