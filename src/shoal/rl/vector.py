"""``num_envs`` seeds of a Shoal scene as one Gymnasium vector environment: one batched scene of
``runs = num_envs`` (the batched kernels step every run at once), not copies of an environment.

``gymnasium.make_vec("shoal/course-dvc-v0", num_envs=32, vectorization_mode="vector_entry_point")``
is a :class:`ShoalVectorEnv`. Environment i is run i of the reset's seed (``core/rng.py``), so
``reset(seed=S)`` gives environment i the run ``shoal run --seed S --runs N`` writes as run i.

Autoreset is Gymnasium's same-step mode: when an episode ends, its environment starts again in
the same step (run i of a seed drawn from the environment's generator; :mod:`shoal.rl.restart`),
the observation returned is the new episode's first, and ``info`` holds what the old one ended
with: ``final_obs`` and ``final_info`` (with the masks ``_final_obs``, ``_final_info``), and in
``final_info`` the episode's ``return``, ``length``, ``seed`` and whether it ended by the kind's
own rule (``terminated``) or at the horizon (``time_out``). ``info["time_out"]`` and
``info["terminated"]`` tell the two apart for every environment in every step.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .batch import Batch, Preset
from .env import SEEDS
from .render import RENDER_MODES, Renderer
from .spaces import action_space, observation_space


class ShoalVectorEnv(VectorEnv):
    """``num_envs`` runs of ``preset`` under ``control``; other keywords as :class:`~shoal.rl.env.ShoalEnv`."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": list(RENDER_MODES), "render_fps": 10}

    def __init__(self, preset: Preset = "default", num_envs: int = 1, *, control: str = "velocity",
                 render_mode: str | None = None, max_episode_steps: int | None = None, **overrides: Any) -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode: {render_mode!r}, choose from {list(RENDER_MODES)} or None")
        self.batch = Batch(preset, num_envs, control, max_episode_steps, overrides)
        self.num_envs = self.batch.runs
        self.single_observation_space = observation_space(self.batch)
        self.single_action_space = action_space(self.batch)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = render_mode
        self._renderer = Renderer(self.batch) if render_mode is not None else None
        self._returns = np.zeros(self.num_envs)

    @property
    def scene(self) -> Any:
        """The :class:`~shoal.api.Scene` underneath (``num_envs`` runs)."""
        return self.batch.scene

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        episode = seed if seed is not None else int(self.np_random.integers(SEEDS))
        self.batch.reset(episode)
        self._returns[:] = 0.0
        if self._renderer is not None:
            self._renderer.restart()
        return self.batch.observe(), {"seed": self.batch.seeds.copy()}

    def step(self, actions: Any) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        b = self.batch
        reward, terminated = b.step(actions)
        truncated = b.truncated(terminated)
        self._returns += reward
        obs = b.observe()
        info: dict[str, Any] = {"terminated": terminated.copy(), "time_out": truncated.copy(),
                                "step": b.elapsed.copy()}
        done = terminated | truncated
        if done.any():
            ended = np.flatnonzero(done)
            final_obs = np.full(self.num_envs, None, dtype=object)
            final_info = {"return": np.where(done, self._returns, 0.0), "length": np.where(done, b.elapsed, 0),
                          "seed": np.where(done, b.seeds, 0), "terminated": terminated.copy(),
                          "time_out": truncated.copy()}
            for i in ended:
                final_obs[i] = {k: v[i] for k, v in obs.items()}
            seeds = self.np_random.integers(SEEDS, size=ended.size) if ended.size < self.num_envs else \
                np.full(ended.size, self.np_random.integers(SEEDS))
            b.restart(ended, seeds)
            self._returns[ended] = 0.0
            obs = b.observe()
            info.update(final_obs=final_obs, _final_obs=done.copy(), final_info=final_info, _final_info=done.copy())
        if self._renderer is not None:
            self._renderer.record(restarted=done)
        return obs, reward, terminated, truncated, info

    def render(self) -> tuple[np.ndarray, ...] | None:
        """Run 0's arena (the one environment drawn) as an (H, W, 3) frame, in a tuple."""
        if self._renderer is None:
            return None
        frame = self._renderer.frame()
        if self.render_mode == "human":
            self._renderer.show(frame)
            return None
        return (frame,)

    def close_extras(self, **kwargs: Any) -> None:
        if self._renderer is not None:
            self._renderer.close()

    def __repr__(self) -> str:
        b = self.batch
        return (f"<ShoalVectorEnv {b.scene.scenario.name!r}: {self.num_envs} runs of {b.robots} robots "
                f"({b.scene.kind.label}), control {b.control.name!r}, {b.horizon} steps>")
