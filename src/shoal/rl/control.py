"""The control modes, one registry entry each: what an action is and the steering it gives the engine.

* ``"velocity"``: each robot's velocity command (a world-frame velocity, or [v, w] for a robot that
  turns), limited by the engine as it limits its own law's (the robots' physical limits hold);
* ``"waypoint"``: a point for each robot to head for; the command is the one that reaches it in a
  tick, then limited the same way (so a far point means full speed towards it);
* ``"pso-params"``: ω, c1 and c2 of the kind's own law for the next tick (the law still decides the
  command): one triple for the swarm (a robot's own in a PettingZoo env).

An action is given to :meth:`Control.steering` robot by robot, (R, N, m); a triple for the swarm is
repeated for every robot first.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Literal

import numpy as np

from shoal.engine.core.registry import Registry
from shoal.engine.core.steering import Steering

if TYPE_CHECKING:
    from .batch import Batch


@dataclass(frozen=True)
class Control:
    """One control mode: the range of one robot's action (``per="swarm"``: one for all robots in a
    Gymnasium env) and the steering of a batch of them."""

    name: str
    label: str
    per: Literal["robot", "swarm"]
    bounds: Callable[[Batch], tuple[np.ndarray, np.ndarray]]  # low (m,), high (m,)
    steering: Callable[[Batch, np.ndarray], Steering]  # (R, N, m) → the next tick's steering
    text: str = ""


def _velocity_bounds(batch: Batch) -> tuple[np.ndarray, np.ndarray]:
    return np.array(batch.command.low, dtype=float), np.array(batch.command.high, dtype=float)


def _waypoint_bounds(batch: Batch) -> tuple[np.ndarray, np.ndarray]:
    x0, y0, x1, y1 = batch.spec.arena(batch.scene)
    lo, hi = [x0, y0], [x1, y1]
    d = batch.d
    return np.array([lo[j % 2] for j in range(d)], dtype=float), np.array([hi[j % 2] for j in range(d)], dtype=float)


def _towards(batch: Batch, waypoint: np.ndarray) -> Steering:
    return Steering(velocity=batch.spec.towards(batch.scene, waypoint))


def _coefficient_bounds(batch: Batch) -> tuple[np.ndarray, np.ndarray]:
    c = batch.coefficients
    assert c is not None  # (Batch refuses "pso-params" for a kind without coefficients)
    return np.array(c.low, dtype=float), np.array(c.high, dtype=float)


def _coefficients(batch: Batch, action: np.ndarray) -> Steering:
    return Steering(omega=action[..., 0], c=np.moveaxis(action[..., 1:3], -1, 0))


CONTROLS: Registry[Control] = Registry(
    "control mode",
    Control("velocity", "velocity per robot", "robot", _velocity_bounds,
            lambda batch, a: Steering(velocity=a),
            "each robot's velocity command (world frame, or [v, w] for a robot that turns), limited as the law's"),
    Control("waypoint", "waypoint per robot", "robot", _waypoint_bounds,
            _towards,
            "a point for each robot to head for, as fast as its limits allow"),
    Control("pso-params", "ω, c1, c2", "swarm", _coefficient_bounds, _coefficients,
            "the law's inertia ω and coefficients c1, c2 for the next tick"),
)
