"""A strategy run in every robot's own believed frame (the acoustic swarm on SLO positions).

On SLO positions robot i knows only its own pose and x_i + x̂_ij for the others, so it runs the
best-location step in its own frame: a copy of the swarm placed where it believes the others
are, anchored at its true position (our reading; the theses do not combine the two). The
(run, robot) frames are handed to the strategy as runs of their own, and robot i keeps only its
own row. The strategy's random partner draws are shared by the frames of one run, so they are
the draws of the run on true positions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .partners import Rngs
from .strategies import LocInfo, Sensed, Strategy
from .triangulation import Triangles


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
    fields = ("candidate", "fitness", "valid", "partner", "points", "forward", "kept", "selected")
    out: dict[str, Any] = {k: own_rows(getattr(info, k), runs, robots) for k in fields}
    t = info.triangles
    rows = [own_rows(getattr(t, k), runs, robots) for k in ("members", "centroid", "direction", "normal", "valid")] \
        if t is not None else []
    out["triangles"] = None if t is None else Triangles(*rows)  # type: ignore[arg-type]  # (each row set: t's are)
    return out


def in_own_frames(strategy: Strategy, f_hat: np.ndarray, frames: np.ndarray, sensed: Sensed,
                  rngs: Rngs) -> dict[str, Any]:
    """Every robot's own decision of ``strategy``: ``frames`` (R, N, N, 2) holds where robot i
    places robot j (itself at its true position), ``f_hat`` (R, N) the memory and ``sensed``
    what the robots heard; returns the LocInfo fields of each robot's own row (:func:`own_decision`)."""
    R, N = f_hat.shape

    def rep(a: np.ndarray | None) -> np.ndarray | None:
        return None if a is None else np.repeat(a, N, axis=0)

    per_frame = Sensed(intensity=rep(sensed.intensity), rho=rep(sensed.rho), rays=rep(sensed.rays))
    flat = frames.reshape(R * N, N, 2)
    draws: Any = frame_draws(rngs, N)  # type: ignore[arg-type]  # (one generator per run)
    _, _, _, info = strategy.update(np.repeat(f_hat, N, axis=0), flat, flat, per_frame, draws)
    return own_decision(info, R, N)
