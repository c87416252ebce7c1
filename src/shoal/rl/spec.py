"""What a scene kind declares to be an environment: one :class:`RLSpec` per kind name in :data:`SPECS`.

A kind whose engine can be steered (``engine.steering``, :mod:`shoal.engine.core.steering`) becomes
``shoal/<preset>-v0`` for each of its presets once its spec is registered: the four built-in kinds
have theirs (:mod:`shoal.rl.kinds`); a plug-in kind adds one with ``SPECS.register(RLSpec(...))``.
The spec says, from a running :class:`~shoal.api.Scene` (all arrays run-major, R runs of N robots):

* ``parts``: the observation, as named :class:`Part` s (a robot's own, or the swarm's), and
  ``observe``: their values;
* ``reward`` (R,) of the swarm and ``robot_reward`` (R, N) of each robot: the kind's headline metric,
  given as it is or (``progress``) as its change over the tick, for a metric whose level a run that
  ends early must not be rewarded for (the distance a fleet has left, the signal an acoustic swarm
  hears);
* ``terminated`` (R,): the kind's own end rule (``robot_done`` (R, N): a robot out of the run);
* ``command``: the frame and range of a robot's velocity command, and ``towards``: the command
  that takes a robot to a waypoint;
* ``coefficients``: the range of (ω, c1, c2) and the law's own values, for ``"pso-params"``;
* ``commanded``: the command each robot got in the tick just done (what the law decided: the
  baseline reads it after a look-ahead tick, :mod:`shoal.rl.baseline`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Literal, Protocol

import numpy as np

from shoal.engine.core.registry import Registry
from shoal.presets.kinds import SceneKind
from shoal.presets.models import Scenario


class EnvScene(Protocol):
    """What a spec reads: a :class:`~shoal.api.Scene`, whose engine is the kind's own class (its
    attributes are read by name)."""

    engine: Any
    scenario: Scenario
    kind: SceneKind

    @property
    def state(self) -> Any: ...


@dataclass(frozen=True)
class Part:
    """One entry of the observation: ``shape`` per robot (``per="robot"``: the env's array is
    (N, *shape)) or for the whole swarm, within [low, high]."""

    name: str
    shape: tuple[int, ...]
    low: float
    high: float
    description: str
    per: Literal["robot", "swarm"] = "robot"


@dataclass(frozen=True)
class Command:
    """A robot's velocity command: ``frame`` "world" (a velocity, one component per dimension) or
    "body" ([v, w]: speed along the heading, turn rate), each component within [low, high]."""

    frame: Literal["world", "body"]
    low: tuple[float, ...]
    high: tuple[float, ...]
    unit: str = "m/s"


@dataclass(frozen=True)
class Coefficients:
    """The ``"pso-params"`` action (ω, c1, c2): its range, and ω, c1, c2 as the kind's law sets them
    for the next tick ((R, N) each; None where the law has none the same for every robot)."""

    low: tuple[float, float, float]
    high: tuple[float, float, float]
    own: Callable[[EnvScene], np.ndarray]  # (3, R, N): ω, c1, c2 of the law for the tick (NaN: not known)


@dataclass(frozen=True)
class RLSpec:
    """A scene kind as an environment (see the module). ``name`` is the kind's (``SceneKind.name``)."""

    name: str
    label: str
    parts: Callable[[EnvScene], tuple[Part, ...]]
    observe: Callable[[EnvScene], dict[str, np.ndarray]]
    reward: Callable[[EnvScene], np.ndarray]
    robot_reward: Callable[[EnvScene], np.ndarray]
    terminated: Callable[[EnvScene], np.ndarray]
    command: Callable[[EnvScene], Command]
    towards: Callable[[EnvScene, np.ndarray], np.ndarray]
    coefficients: Callable[[EnvScene], Coefficients] | None  # None: no PSO coefficients ("pso-params" refused)
    arena: Callable[[EnvScene], tuple[float, float, float, float]]  # x0, y0, x1, y1 a waypoint lies in (run 0's)
    commanded: Callable[[EnvScene], np.ndarray]  # (R, N, k) each robot's command in the tick just done
    progress: bool = False  # the reward is the change of ``reward`` (and ``robot_reward``) over the tick
    reward_text: str = ""  # what the reward is, in words (the docs and the env's repr)
    end_text: str = ""  # what ends an episode (terminated), in words
    robot_done: Callable[[EnvScene], np.ndarray] | None = None  # (R, N) robots out of the run (a fleet's disabled)
    unheard: tuple[str, ...] = ()  # parts a restarted run has no value of until its first tick (zeros till then)


SPECS: Registry[RLSpec] = Registry("rl spec")


def common_parts(scene: EnvScene) -> tuple[Part, ...]:
    """What every robot observes of itself: position, velocity, heading, whether it is active."""
    d = scene.engine.state.x.shape[-1]
    return (Part("position", (d,), -np.inf, np.inf, "own position x [m]"),
            Part("velocity", (d,), -np.inf, np.inf, "own velocity u of the last tick [m/s]"),
            Part("heading", (1,), -np.pi, np.pi, "direction the robot faces [rad]"),
            Part("active", (1,), 0.0, 1.0, "1 while the robot is active, 0 once disabled"))


def common_values(scene: EnvScene) -> dict[str, np.ndarray]:
    s = scene.engine.state
    return {"position": s.x, "velocity": s.u, "heading": ((s.heading + np.pi) % (2.0 * np.pi) - np.pi)[..., None],
            "active": (s.status == 0)[..., None].astype(float)}
