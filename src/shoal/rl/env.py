"""A Shoal scene as a Gymnasium environment: the whole swarm is one agent.

``gymnasium.make("shoal/course-dvc-v0", control="velocity")`` (after ``import shoal.rl``) is a
:class:`ShoalEnv`: one seeded run of the preset; an action commands every robot at once, the
observation is a ``Dict`` of every robot's parts (:mod:`shoal.rl.spec`), the reward the kind's
headline metric. ``reset(seed=S)`` starts run 0 of seed S, the run ``shoal run --seed S`` makes;
``reset()`` starts a new seed drawn from the environment's generator.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from .batch import Batch, Preset
from .render import RENDER_MODES, Renderer
from .spaces import action_space, observation_space

SEEDS = 2**31 - 1  # an episode's seed, when none is given, is drawn below this


class ShoalEnv(gym.Env):
    """One run of ``preset`` under ``control`` ("velocity", "waypoint" or "pso-params"); other
    keywords are :func:`shoal.make`'s overrides (``robots=8``, ``controller={...}``, …)."""

    metadata = {"render_modes": list(RENDER_MODES), "render_fps": 10}

    def __init__(self, preset: Preset = "default", *, control: str = "velocity", render_mode: str | None = None,
                 max_episode_steps: int | None = None, **overrides: Any) -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(f"render_mode: {render_mode!r}, choose from {list(RENDER_MODES)} or None")
        self.batch = Batch(preset, 1, control, max_episode_steps, overrides)
        self.observation_space = observation_space(self.batch)
        self.action_space = action_space(self.batch)
        self.render_mode = render_mode
        self._renderer = Renderer(self.batch) if render_mode is not None else None

    @property
    def scene(self) -> Any:
        """The :class:`~shoal.api.Scene` underneath (one run)."""
        return self.batch.scene

    def _obs(self) -> dict[str, np.ndarray]:
        return {k: v[0] for k, v in self.batch.observe().items()}

    def _info(self) -> dict[str, Any]:
        b = self.batch
        return {"seed": int(b.seeds[0]), "step": int(b.elapsed[0]), "t": float(b.scene.engine.t)}

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        episode = seed if seed is not None else int(self.np_random.integers(SEEDS))
        self.batch.reset(episode)
        if self._renderer is not None:
            self._renderer.restart()
        return self._obs(), self._info()

    def step(self, action: Any) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        reward, terminated = self.batch.step(action)
        truncated = self.batch.truncated(terminated)
        if self._renderer is not None:
            self._renderer.record()
            if self.render_mode == "human":
                self._renderer.show()
        return self._obs(), float(reward[0]), bool(terminated[0]), bool(truncated[0]), self._info()

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
        super().close()

    def __repr__(self) -> str:
        b = self.batch
        return (f"<ShoalEnv {b.scene.scenario.name!r}: {b.scene.kind.label}, {b.robots} robots, control "
                f"{b.control.name!r}, {b.horizon} steps>")
