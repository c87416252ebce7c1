"""Truth against belief in any arena: the selected robot's ghosts (:mod:`.session.beliefs`),
each joined to the true robot by an error segment coloured from green (no error) to red
(``scale`` and beyond). :class:`GhostLayer` draws them in any view built on ``_points``
helpers, a ``scene`` and a ``nodes`` dict.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .session.beliefs import Ghosts

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
