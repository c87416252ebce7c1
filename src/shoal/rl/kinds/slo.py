"""Mai's SLO swarm as an environment: robots that know each other only by estimated ranges."""

from __future__ import annotations

import numpy as np

from ..spec import Coefficients, Command, EnvScene, Part, RLSpec, common_parts, common_values
from .common import world_towards


def parts(scene: EnvScene) -> tuple[Part, ...]:
    n = scene.engine.robots
    return common_parts(scene) + (
        Part("fitness", (1,), -np.inf, np.inf, "objective f at the robot's position"),
        Part("personal_best", (2,), -np.inf, np.inf, "the personal best relative to the robot, P [3.13] [unit]"),
        Part("neighbours", (n, 2), -np.inf, np.inf, "the estimated vector x̂_ij to every robot j, from noisy ranges "
                                                     "and odometry (SLO) [unit]"),
        Part("in_range", (n,), 0.0, 1.0, "1 where robot j is in the neighbourhood N_i this generation"),
        Part("best_fitness", (1,), -np.inf, np.inf, "the best f of any generation so far", per="swarm"),
    )


def observe(scene: EnvScene) -> dict[str, np.ndarray]:
    s = scene.engine.state
    return {**common_values(scene), "fitness": s.f[..., None], "personal_best": s.P, "neighbours": s.est,
            "in_range": s.valid.astype(float), "best_fitness": s.best_fitness[:, None]}


def _area(scene: EnvScene) -> tuple[float, float]:
    return scene.engine.config.area()


def command(scene: EnvScene) -> Command:
    lo, hi = _area(scene)
    b = float(hi - lo)
    return Command("world", (-b, -b), (b, b), "unit per generation")


def _own(scene: EnvScene) -> np.ndarray:
    e = scene.engine
    R, N = e.state.x.shape[:2]
    law = e.spso
    return np.stack([np.full((R, N), law.inertia), np.full((R, N), law.c1), np.full((R, N), law.c2)])


def coefficients(scene: EnvScene) -> Coefficients:
    return Coefficients((0.0, 0.0, 0.0), (0.999, 3.0, 3.0), _own)


def _terminated(scene: EnvScene) -> np.ndarray:
    e = scene.engine
    return e.state.f.min(axis=1) <= e.config.threshold()


def _arena(scene: EnvScene) -> tuple[float, float, float, float]:
    lo, hi = _area(scene)
    return (lo, lo, hi, hi)


SPEC = RLSpec(
    "slo_swarm", "Mai's SLO swarm", parts, observe,
    reward=lambda scene: -scene.engine.state.f.min(axis=1),
    robot_reward=lambda scene: -scene.engine.state.f.copy(),
    terminated=_terminated,
    commanded=lambda scene: scene.engine.state.u.copy(),
    command=command, towards=lambda scene, w: world_towards(scene.engine.state.x, w, 1.0),
    coefficients=coefficients, arena=_arena,
    reward_text="minus this generation's best objective value min_i f(x_i); a robot's own: minus f at its position",
    end_text="the generation best at or below the quality threshold T (Mai Tab. 4.2), never for an objective "
             "without one",
)
