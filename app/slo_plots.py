"""uPlot series for an SLO scene: pure functions of numbers, no viser (spec §15.2, item 3).

* localisation error per step: mean and median absolute error, median relative error;
* median distance between robots (the swarm contracting, Fig. 4.11);
* best fitness on a log scale, plotted as log10 |f| (uPlot's own log axis rejects values ≤ 0
  and Sphere runs reach 1e-140; Fig. 4.13).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .fleet_plots import _padded

TINY = 1e-300


def x_label(generations: bool) -> str:
    return "generation" if generations else "t [s]"


def _x_scale(t: np.ndarray) -> dict[str, Any]:
    t0, t1 = (float(t[0]), float(t[-1])) if len(t) else (0.0, 1.0)
    return {"time": False, "range": (t0, max(t1, t0 + 1e-6))}


def error_series(generations: bool) -> tuple[dict[str, Any], ...]:
    return (
        {"label": x_label(generations)},
        {"label": "mean e_abs", "stroke": "rgb(220,50,50)", "width": 2},
        {"label": "median e_abs", "stroke": "rgb(240,150,30)", "width": 2, "dash": (6.0, 4.0)},
        {"label": "median e_rel", "stroke": "rgb(60,110,230)", "width": 1, "scale": "rel"},
    )


def error_data(t: np.ndarray, mean: np.ndarray, median: np.ndarray, rel: np.ndarray) -> tuple[np.ndarray, ...]:
    return tuple(np.nan_to_num(a, nan=0.0) for a in _padded(t, mean, median, rel))


def error_scales(t: np.ndarray) -> dict[str, Any]:
    return {"x": _x_scale(t), "y": {"range": (0.0, None)}, "rel": {"range": (0.0, None)}}


def distance_series(generations: bool) -> tuple[dict[str, Any], ...]:
    return ({"label": x_label(generations)},
            {"label": "median distance between robots", "stroke": "rgb(30,140,70)", "width": 2})


def distance_data(t: np.ndarray, distance: np.ndarray) -> tuple[np.ndarray, ...]:
    return _padded(t, distance)


def fitness_series(generations: bool) -> tuple[dict[str, Any], ...]:
    return ({"label": x_label(generations)},
            {"label": "log10 |best f|", "stroke": "rgb(120,60,200)", "width": 2})


def log_fitness(best: np.ndarray) -> np.ndarray:
    """log10 |f| with 0 and non-finite values floored at 1e-300."""
    b = np.abs(np.asarray(best, dtype=float))
    b = np.where(np.isfinite(b) & (b > TINY), b, TINY)
    return np.log10(b)


def fitness_data(t: np.ndarray, best: np.ndarray) -> tuple[np.ndarray, ...]:
    return _padded(t, log_fitness(best))


def plain_scales(t: np.ndarray) -> dict[str, Any]:
    return {"x": _x_scale(t)}
