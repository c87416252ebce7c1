"""A Shoal scene as a PettingZoo parallel environment: one agent per robot, all moving at once.

``shoal.rl.parallel_env("course-dvc", control="velocity")``: agents ``robot_0`` … ``robot_{N-1}``,
each with the same spaces, its own parts of the observation (:mod:`shoal.rl.spec`) beside the
swarm's, its own action (a velocity or a waypoint; in ``"pso-params"`` its own ω, c1, c2) and its
own reward. A robot the kind takes out of the run (a fleet's robot disabled by a collision) is
terminated and leaves ``agents``; the kind's end rule terminates every agent, the horizon
(``max_cycles``) truncates every agent.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from .batch import Batch, Preset
from .env import SEEDS
from .render import RENDER_MODES, Renderer
from .spaces import action_space, observation_space


class ShoalParallelEnv(ParallelEnv):
    """One run of ``preset`` with one agent per robot; keywords as :class:`~shoal.rl.env.ShoalEnv`
    (``max_cycles`` is the horizon)."""

    metadata = {"name": "shoal_v0", "render_modes": list(RENDER_MODES), "render_fps": 10, "is_parallelizable": True}

    def __init__(self, preset: Preset = "default", *, control: str = "velocity", render_mode: str | None = None,
                 max_cycles: int | None = None, **overrides: Any) -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode: {render_mode!r}, choose from {list(RENDER_MODES)} or None")
        self.batch = Batch(preset, 1, control, max_cycles, overrides)
        self.possible_agents = [f"robot_{i}" for i in range(self.batch.robots)]
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._obs_spaces = {a: observation_space(self.batch, robot=True) for a in self.possible_agents}
        self._act_spaces = {a: action_space(self.batch, robot=True) for a in self.possible_agents}
        self.metadata = {**self.metadata, "name": f"shoal_{self.batch.scene.scenario.name}_v0"}
        self.render_mode = render_mode
        self._renderer = Renderer(self.batch) if render_mode is not None else None
        self._rng = np.random.default_rng()

    @property
    def max_cycles(self) -> int:
        """The horizon: every agent is truncated after this many steps."""
        return self.batch.horizon

    @max_cycles.setter
    def max_cycles(self, value: int) -> None:
        if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < 1:
            raise ValueError(f"max_cycles: must be an integer >= 1, got {value!r}")
        self.batch.horizon = int(value)

    @property
    def scene(self) -> Any:
        return self.batch.scene

    def observation_space(self, agent: str) -> spaces.Space:
        """The same space object every time (PettingZoo seeds and compares it)."""
        return self._obs_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space:
        return self._act_spaces[agent]

    def _observations(self, agents: list[str]) -> dict[str, dict[str, np.ndarray]]:
        obs = self.batch.observe()
        robot = {p.name for p in self.batch.parts if p.per == "robot"}
        out = {}
        for a in agents:
            i = self._index[a]
            out[a] = {k: (v[0, i] if k in robot else v[0]) for k, v in obs.items()}
        return out

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, Any], dict[str, Any]]:
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        episode = seed if seed is not None else int(self._rng.integers(SEEDS))
        self.batch.reset(episode)
        self.agents = list(self.possible_agents)
        if self._renderer is not None:
            self._renderer.restart()
        info = {"seed": int(episode), "step": 0}
        return self._observations(self.agents), {a: dict(info) for a in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        b = self.batch
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"actions: none for {', '.join(missing)} (every live agent acts each step)")
        unknown = [a for a in actions if a not in self._index]
        if unknown:
            raise ValueError(f"actions: no agent {unknown[0]!r} (agents: robot_0 … robot_{b.robots - 1})")
        per_robot = np.zeros((1, b.robots, b.width))  # a robot out of the run does nothing with its row
        for a in self.agents:
            act = np.asarray(actions[a], dtype=float)
            if act.size != b.width:
                raise ValueError(f"actions[{a!r}]: expected {b.width} numbers, got shape {act.shape}")
            per_robot[0, self._index[a]] = act.reshape(-1)
        reward, terminated = b.step(per_robot)
        truncated = b.truncated(terminated)
        live = list(self.agents)
        robot_reward = b.robot_rewards[0]
        out_of_run = np.zeros(b.robots, bool) if b.spec.robot_done is None else \
            np.asarray(b.spec.robot_done(b.scene), dtype=bool)[0]
        obs = self._observations(live)
        rewards = {a: float(robot_reward[self._index[a]]) for a in live}
        terms = {a: bool(terminated[0] or out_of_run[self._index[a]]) for a in live}
        truncs = {a: bool(truncated[0]) and not terms[a] for a in live}
        info = {"step": int(b.elapsed[0]), "swarm_reward": float(reward[0])}
        infos = {a: dict(info) for a in live}
        self.agents = [a for a in live if not (terms[a] or truncs[a])]
        if self._renderer is not None:
            self._renderer.record()
            if self.render_mode == "human":
                self._renderer.show()
        return obs, rewards, terms, truncs, infos

    def render(self) -> np.ndarray | None:
        if self._renderer is None:
            return None
        frame = self._renderer.frame()
        if self.render_mode == "human":
            self._renderer.show(frame)
            return None
        return frame

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()

    def state(self) -> np.ndarray:
        """Every robot's position, velocity and heading, (N, 2d + 1)."""
        s = self.batch.scene.state
        return np.concatenate([s.x[0], s.u[0], s.heading[0][:, None]], axis=1).astype(np.float32)


def parallel_env(preset: Preset = "default", **kwargs: Any) -> ShoalParallelEnv:
    """The PettingZoo parallel environment of ``preset`` (see :class:`ShoalParallelEnv`)."""
    return ShoalParallelEnv(preset, **kwargs)
