"""The ``gather`` kind as a reinforcement-learning environment (``shoal/gather-demo-v0``).

Shoal's ``shoal.rl`` calls :func:`register` through this package's ``shoal.rl`` entry point: the
kind's :class:`~shoal.rl.spec.RLSpec` says what a robot observes (its own position, velocity and
heading, and the swarm's centroid), the reward (minus the spread), that nothing ends an episode
early, and the robots' command (a velocity of at most ``gather.speed``); it has no PSO coefficients.
"""

from __future__ import annotations

import numpy as np


def register() -> None:
    from shoal.rl.spec import SPECS, Command, Part, RLSpec, common_parts, common_values

    def spread(scene):
        x = scene.engine.state.x
        return np.linalg.norm(x - x.mean(axis=1, keepdims=True), axis=-1)

    def speed(scene):
        return float(scene.engine.params.speed)

    SPECS.register(RLSpec(
        "gather", "gather (example plug-in)",
        parts=lambda scene: common_parts(scene) + (
            Part("centroid", (2,), -np.inf, np.inf, "the swarm's centroid [m]", per="swarm"),),
        observe=lambda scene: {**common_values(scene), "centroid": scene.engine.state.x.mean(axis=1)},
        reward=lambda scene: -np.sqrt((spread(scene) ** 2).mean(axis=1)),
        robot_reward=lambda scene: -spread(scene),
        terminated=lambda scene: np.zeros(scene.engine.runs, bool),
        command=lambda scene: Command("world", (-speed(scene),) * 2, (speed(scene),) * 2),
        towards=lambda scene, w: (w - scene.engine.state.x) / scene.engine.dt,
        coefficients=None,  # no PSO law: "pso-params" is refused
        arena=lambda scene: (-scene.engine.params.area, -scene.engine.params.area, scene.engine.params.area,
                             scene.engine.params.area),
        commanded=lambda scene: scene.engine.state.u.copy(),
        reward_text="minus the root mean square distance to the centroid",
        end_text="none",
    ), replace=True)
