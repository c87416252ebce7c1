"""How swarm B (the compare twin) looks in the arena: pale teal dots drawn just under A's
robots, and pale teal trails; in the plots a dashed teal curve. One extra point cloud and one
segment list per view, whatever the kind of scene.
"""

from __future__ import annotations

from typing import Any

import numpy as np

TWIN = (20, 170, 180)  # B's robots
TWIN_TRAIL = (150, 215, 220)  # B's trails
TWIN_STROKE = "rgb(20,170,180)"  # B's curve in the plots
TWIN_DASH = (5.0, 4.0)


def trail_segments(trails: np.ndarray) -> np.ndarray:
    """(M, L, d) trails → (S, 2, 2) segments in the ground plane (empty for no trail)."""
    tr = np.asarray(trails, dtype=float)
    if tr.ndim != 3 or not tr.shape[0] or tr.shape[1] < 2:
        return np.zeros((0, 2, 2))
    xy = np.zeros(tr.shape[:2] + (2,))
    d = min(tr.shape[2], 2)
    xy[..., :d] = tr[..., :d]
    return np.stack([xy[:, :-1], xy[:, 1:]], axis=2).reshape(-1, 2, 2)


def twin_series(label: str) -> dict[str, Any]:
    """uPlot series options of B's curve."""
    return {"label": f"B: {label}", "stroke": TWIN_STROKE, "width": 2, "dash": TWIN_DASH}


class TwinLayer:
    """``draw_twin`` for views built on ``_points``/``_lines`` helpers and a ``root`` node."""

    nodes: dict[str, Any]
    TWIN_Z = (0.009, -0.006)  # heights of B's robots and trails (just under A's)

    def _twin_size(self) -> float:
        """The ``size`` argument of ``_points`` for one of B's robots."""
        raise NotImplementedError

    def draw_twin(self: Any, view: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Draw B's robots and trails, or hide them (``view`` None: no B)."""
        if "root" not in self.nodes:
            return
        if view is None:
            for key in ("twin", "twin_trails"):
                if key in self.nodes:
                    self.nodes[key].visible = False
            return
        x, trails = view
        xy = np.zeros((len(x), 2))
        xy[:, : min(x.shape[1], 2)] = x[:, :2]
        self._points("twin", xy, TWIN, self._twin_size(), "circle", self.TWIN_Z[0])
        self._lines("twin_trails", trail_segments(trails), TWIN_TRAIL, 1.2, self.TWIN_Z[1])
