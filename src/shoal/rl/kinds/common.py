"""What the built-in kinds' specs share: a world-frame or body-frame command towards a waypoint."""

from __future__ import annotations

import numpy as np


def wrap(angle: np.ndarray) -> np.ndarray:
    """Angles in [−π, π)."""
    return (np.asarray(angle, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


def world_towards(x: np.ndarray, waypoint: np.ndarray, dt: float) -> np.ndarray:
    """The velocity that reaches ``waypoint`` in one tick, (w − x)/Δt (the kind then limits it)."""
    return (waypoint - x) / dt


def body_towards(x: np.ndarray, heading: np.ndarray, waypoint: np.ndarray, dt: float, forward: bool) -> np.ndarray:
    """[v, w] towards ``waypoint``: turn by the bearing error in one tick, drive the part of the
    distance along the heading (not backwards for a robot that only drives forward)."""
    to = waypoint - x
    error = wrap(np.arctan2(to[..., 1], to[..., 0]) - heading)
    v = np.hypot(to[..., 0], to[..., 1]) * np.cos(error) / dt
    return np.stack([np.maximum(v, 0.0) if forward else v, error / dt], axis=-1)
