"""The Chapter 4–5 fleet as an environment: robots with bodies in an obstacle world."""

from __future__ import annotations

import numpy as np

from shoal.engine.robots.laws import ROBOT_LAWS, rotational_energy_factor

from ..spec import Coefficients, Command, EnvScene, Part, RLSpec, common_parts, common_values
from .common import body_towards, world_towards


def _cost(scene: EnvScene) -> np.ndarray:
    e = scene.engine
    return e.cost(e.state.x)


def _arena(scene: EnvScene) -> tuple[float, float, float, float]:
    x0, y0, x1, y1 = (float(v) for v in scene.engine.world.bounds)
    return x0, y0, x1, y1


def _commanded(scene: EnvScene) -> np.ndarray:
    s = scene.engine.state
    return (s.cmd if s.commanded is None else s.commanded).copy()


def parts(scene: EnvScene) -> tuple[Part, ...]:
    r_s = float(scene.engine.params.sensing_range)
    return common_parts(scene) + (
        Part("sectors", (6,), 0.0, r_s, "the six-sector gaps s_1 … s_6 the DVC reads [m], R_s where a sector is empty"),
        Part("cost", (1,), 0.0, np.inf, "distance to the source, the cost of Algorithms 1–2 [m]"),
        Part("personal_best", (2,), -np.inf, np.inf, "the robot's personal best y [m]"),
        Part("global_best", (2,), -np.inf, np.inf, "the fleet's global best y_g [m]", per="swarm"),
        Part("best_fitness", (1,), 0.0, np.inf, "cost of y_g [m]", per="swarm"),
    )


def observe(scene: EnvScene) -> dict[str, np.ndarray]:
    e = scene.engine
    s = e.state
    return {**common_values(scene), "sectors": e.sense_now().gap, "cost": _cost(scene)[..., None],
            "personal_best": s.y, "global_best": s.yg, "best_fitness": s.best_fitness[:, None]}


def command(scene: EnvScene) -> Command:
    p = scene.engine.params
    law = ROBOT_LAWS[p.law]
    if law.body_frame:
        w = float(np.sqrt(0.5 * p.v_max**2 / rotational_energy_factor(p.rotational_energy, p.robot_radius)))  # [5.12]
        return Command("body", (0.0 if law.forward else -p.v_max, -w), (p.v_max, w), "m/s, rad/s")
    return Command("world", (-p.v_max, -p.v_max), (p.v_max, p.v_max))


def towards(scene: EnvScene, waypoint: np.ndarray) -> np.ndarray:
    e = scene.engine
    law = ROBOT_LAWS[e.params.law]
    if law.body_frame:
        return body_towards(e.state.x, e.state.heading, waypoint, e.dt, law.forward)
    return world_towards(e.state.x, waypoint, e.dt)


def _own(scene: EnvScene) -> np.ndarray:
    """ω, c1, c2 of the tick just done (the DVC's per robot)."""
    s = scene.engine.state
    R, N = s.x.shape[:2]
    if s.omega is None or s.c is None:
        p = scene.engine.params
        return np.stack([np.full((R, N), p.omega), np.full((R, N), p.c[0]), np.full((R, N), p.c[1])])
    return np.stack([s.omega, s.c[0], s.c[1]])


def coefficients(scene: EnvScene) -> Coefficients:
    p = scene.engine.params
    top = float(p.v_max)  # c_n adds at most c_n m/s a tick: the top speed bounds a useful one
    return Coefficients((0.0, 0.0, 0.0), (0.999, top, top), _own)


SPEC = RLSpec(
    "fleet", "Chapter 4–5 fleet", parts, observe,
    reward=lambda scene: -_cost(scene).mean(axis=1),
    robot_reward=lambda scene: -_cost(scene),
    terminated=lambda scene: ~np.any(scene.engine.state.status == 0, axis=1),
    robot_done=lambda scene: scene.engine.state.status != 0,
    commanded=_commanded,
    command=command, towards=towards, coefficients=coefficients,
    arena=_arena,
    progress=True,
    reward_text="the progress towards the source: how much the robots' mean distance to it (the cost of "
                "Algorithms 1–2) fell in the tick, in m; a robot's own: how much its distance fell",
    end_text="every robot disabled by a collision (ours: the thesis runs a fixed horizon); a disabled robot is done",
)
