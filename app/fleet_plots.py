"""uPlot series for a fleet: pure functions of numbers, no viser.

* swarm fitness [4.17] (the CoM's x) vs time, with a dotted line at each obstacle layer
  (Figs. 4-6, 5-5);
* operational and collided robots vs time (the time view of Fig. 4-7).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .plots import speed_scales

LAYER_STROKE = "rgba(120, 120, 120, 0.9)"


def _padded(t: np.ndarray, *ys: np.ndarray) -> tuple[np.ndarray, ...]:
    """uPlot needs two x values to draw an axis: repeat a lone point."""
    t = np.asarray(t, dtype=float)
    ys = tuple(np.asarray(y, dtype=float) for y in ys)
    if len(t) >= 2:
        return (t, *ys)
    t0 = float(t[0]) if len(t) else 0.0
    return (np.array([t0, t0 + 1e-6]), *(np.repeat(y[:1], 2) if len(y) else np.zeros(2) for y in ys))


def com_series(layers: np.ndarray) -> tuple[dict[str, Any], ...]:
    """Series options for :func:`com_data`: time, the CoM and one dotted line per layer."""
    lines = tuple({"label": f"layer {i + 1}", "stroke": LAYER_STROKE, "width": 1, "dash": (3.0, 4.0)}
                  for i in range(len(layers)))
    return ({"label": "t [s]"}, {"label": "CoM x [m]", "stroke": "rgb(220,50,50)", "width": 2}) + lines


def com_data(t: np.ndarray, com: np.ndarray, layers: np.ndarray) -> tuple[np.ndarray, ...]:
    """(t, CoM x, layer 1 x, …): each layer is a constant series, i.e. a horizontal line."""
    t, com = _padded(t, com)
    return (t, com) + tuple(np.full(len(t), float(x)) for x in layers)


def com_scales(t: np.ndarray, bounds: tuple[float, float, float, float]) -> dict[str, Any]:
    """Numeric x axis over the data; y spans the world along x, so every layer line shows."""
    return {"x": speed_scales(t)["x"], "y": {"range": (float(bounds[0]), float(bounds[2]))}}


def robots_series() -> tuple[dict[str, Any], ...]:
    return (
        {"label": "t [s]"},
        {"label": "operational", "stroke": "rgb(30,140,70)", "width": 2},
        {"label": "collided", "stroke": "rgb(150,150,150)", "width": 2, "dash": (6.0, 4.0)},
    )


def robots_data(t: np.ndarray, operational: np.ndarray, collided: np.ndarray) -> tuple[np.ndarray, ...]:
    return _padded(t, operational, collided)


def robots_scales(t: np.ndarray, robots: int) -> dict[str, Any]:
    return {"x": speed_scales(t)["x"], "y": {"range": (0.0, float(max(robots, 1)) + 0.5)}}
