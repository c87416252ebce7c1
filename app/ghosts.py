"""Truth against belief in any arena (spec §15.2 item 1): the selected robot's ghosts.

For an observer robot i on SLO positions, a ghost at x_i + x̂_ij stands for every robot j it
localised at its last step, joined to the true x_j by an error segment coloured from green
(no error) to red (``scale`` and beyond); a host swarm adds where i believes the global best
is. :func:`ghosts_of` reads them from an engine's beliefs; :class:`GhostLayer` draws them in
any view built on ``_points`` helpers, a ``scene`` and a ``nodes`` dict (the SLO, Chapter 3,
fleet and acoustic views).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

GHOST = (60, 110, 230)
GHOST_BEST = (30, 80, 220)
ERR_LOW = np.array([40, 170, 70], float)
ERR_HIGH = np.array([230, 40, 40], float)
GHOST_NODES = ("ghost_errors", "ghosts", "ghost_best", "ghost_best_error")


def error_colors(err: np.ndarray, scale: float) -> np.ndarray:
    """(G, 2, 3) uint8: green for no error to red at ``scale`` and beyond."""
    f = np.clip(np.asarray(err, dtype=float) / max(scale, 1e-12), 0.0, 1.0)[:, None]
    rgb = (ERR_LOW + (ERR_HIGH - ERR_LOW) * f).astype(np.uint8)
    return np.repeat(rgb[:, None, :], 2, axis=1)


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
    """Observer ``i``'s ghosts (run 0) from :class:`~shoal.engine.slo.beliefs.Beliefs` and
    the true positions ``x`` (N, 2): every neighbour it localised at its last step."""
    of = np.flatnonzero(beliefs.valid[0, i])
    points = x[i] + beliefs.est[0, i, of]
    truth = x[of]
    err = np.hypot(*(points - truth).T) if len(of) else np.zeros(0)
    return Ghosts(observer=i, points=points, of=of, truth=truth, error=err, scale=float(scale), best=best,
                  true_best=true_best)


def host_ghosts(sim: Any, i: int, true_best: np.ndarray) -> Ghosts | None:
    """The ghosts of observer ``i`` of a host swarm (Chapter 3 swarm, fleet, acoustic swarm) on
    SLO positions, or None on true positions. Errors show fully red at 10 thesis units."""
    positions = sim.positions
    if positions.exact:
        return None
    return ghosts_of(positions.beliefs, sim.state.x[0], i, 10.0 * positions.unit,
                     best=sim.believed_gbest()[0, i].copy(), true_best=np.asarray(true_best, dtype=float))


class GhostLayer:
    """``draw_ghosts`` for views with ``_points``, ``_name``, ``to_view``, ``scene``, ``nodes``
    and the robot marker size ``_twin_size()``."""

    nodes: dict[str, Any]
    GHOST_Z = (0.004, 0.008)  # heights of the error segments and the ghosts

    def _colored_lines(self: Any, key: str, segs: np.ndarray, colors: np.ndarray, px: float, z: float) -> None:
        segs = np.asarray(segs, dtype=float).reshape(-1, 2, 2)
        pts = self.to_view(segs, z) if len(segs) else np.zeros((1, 2, 3), np.float32)
        cols = colors if len(segs) else np.zeros((1, 2, 3), np.uint8)
        node = self.nodes.get(key)
        if node is None:
            self.nodes[key] = self.scene.add_line_segments(self._name(key), pts, colors=cols, thickness=px,
                                                           thickness_units="screen")
        else:
            node.points, node.colors = pts, cols
        self.nodes[key].visible = bool(len(segs))

    def draw_ghosts(self: Any, ghosts: Ghosts | None) -> None:
        """Draw the observer's ghosts and error segments, or hide them (None: nothing believed)."""
        if ghosts is None:
            for key in GHOST_NODES:
                if key in self.nodes:
                    self.nodes[key].visible = False
            return
        z_err, z_ghost = self.GHOST_Z
        size = self._twin_size()
        errs = np.stack([ghosts.points, ghosts.truth], axis=1) if len(ghosts.of) else np.zeros((0, 2, 2))
        self._colored_lines("ghost_errors", errs, error_colors(ghosts.error, ghosts.scale), 2.0, z_err)
        self._points("ghosts", ghosts.points, GHOST, 0.8 * size, "diamond", z_ghost)
        if ghosts.best is None or ghosts.true_best is None:
            if "ghost_best" in self.nodes:
                self.nodes["ghost_best"].visible = self.nodes["ghost_best_error"].visible = False
            return
        err = float(np.hypot(*(ghosts.best - ghosts.true_best)))
        self._colored_lines("ghost_best_error", np.stack([ghosts.best, ghosts.true_best])[None],
                            error_colors(np.array([err]), ghosts.scale), 1.5, z_err)
        self._points("ghost_best", ghosts.best[None], GHOST_BEST, 1.2 * size, "diamond", z_ghost)
