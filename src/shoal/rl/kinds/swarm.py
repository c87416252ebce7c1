"""The Chapter 3 swarm as an environment: robots in free space on an objective."""

from __future__ import annotations

import numpy as np

from ..spec import Coefficients, Command, EnvScene, Part, RLSpec, common_parts, common_values
from .common import world_towards


def _sign(scene: EnvScene) -> float:
    return 1.0 if scene.engine.objective.maximise else -1.0


def parts(scene: EnvScene) -> tuple[Part, ...]:
    d = scene.engine.d
    return common_parts(scene) + (
        Part("fitness", (1,), -np.inf, np.inf, "objective f at the robot's position"),
        Part("personal_best", (d,), -np.inf, np.inf, "the robot's personal best y [m]"),
        Part("global_best", (d,), -np.inf, np.inf, "the swarm's global best y_g [m]", per="swarm"),
        Part("best_fitness", (1,), -np.inf, np.inf, "f(y_g), the best the swarm has found", per="swarm"),
    )


def observe(scene: EnvScene) -> dict[str, np.ndarray]:
    e = scene.engine
    s = e.state
    return {**common_values(scene), "fitness": e.objective(s.x)[..., None], "personal_best": s.y,
            "global_best": s.yg, "best_fitness": s.best_fitness[:, None]}


def _speed_bound(scene: EnvScene) -> float:
    """The largest U_j = ĉ/(1 − ω) [3.26] the policy sets (over its step changes)."""
    e = scene.engine
    starts = [0.0] + [seg.t_start for seg in getattr(e.policy, "segments", ())]
    bounds = []
    for t in starts:
        omega, c = e.policy.coefficients(t, e.dt, e.d)
        w = float(np.max(omega))
        bounds.append(float(np.sum(np.abs(c))) / (1.0 - w) if w < 1.0 else np.inf)
    bound = max(bounds)
    return bound if np.isfinite(bound) and e.law.adapted else 2.0 * scene.scenario.arena.half_size


def command(scene: EnvScene) -> Command:
    b = _speed_bound(scene)
    d = scene.engine.d
    return Command("world", (-b,) * d, (b,) * d, "m/s" if scene.engine.law.adapted else "m per tick")


def towards(scene: EnvScene, waypoint: np.ndarray) -> np.ndarray:
    e = scene.engine
    return world_towards(e.state.x, waypoint, e.dt if e.law.adapted else 1.0)  # [3.10] or [2.2]


def _own(scene: EnvScene) -> np.ndarray:
    e = scene.engine
    omega, c = e.policy.coefficients(e.t, e.dt, e.d)
    R, N = e.state.x.shape[:2]
    c = np.asarray(c, dtype=float)
    c = c.reshape(c.shape + (1,) * (3 - c.ndim))
    return np.stack([np.broadcast_to(np.asarray(omega, dtype=float), (R, N)),
                     *np.broadcast_to(c[:2], (2, R, N))])


def coefficients(scene: EnvScene) -> Coefficients:
    e = scene.engine
    omega, c = e.policy.coefficients(0.0, e.dt, e.d)
    top = max(2.0 * float(np.sum(np.abs(c))), 1e-6)
    return Coefficients((0.0, 0.0, 0.0), (0.999 if e.law.adapted else 1.0, top, top), _own)


def arena(scene: EnvScene) -> tuple[float, float, float, float]:
    h = scene.scenario.arena.half_size
    return (-h, -h, h, h)


SPEC = RLSpec(
    "swarm", "Chapter 3 swarm", parts, observe,
    reward=lambda scene: _sign(scene) * scene.engine.state.best_fitness,
    robot_reward=lambda scene: _sign(scene) * scene.engine.objective(scene.engine.state.x),
    terminated=lambda scene: np.zeros(scene.engine.runs, bool),
    commanded=lambda scene: scene.engine.state.u.copy(),
    command=command, towards=towards, coefficients=coefficients, arena=arena,
    reward_text="f(y_g), the best objective value the swarm has found (negated for a cost); a robot's own: "
                "f at its position",
    end_text="none: Chapter 3 runs a fixed horizon, so an episode is truncated at its last step",
)
