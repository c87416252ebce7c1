"""R environments as the R runs of one Shoal scene: the part every environment class shares.

A :class:`Batch` owns one :class:`~shoal.api.Scene` of ``runs`` runs (the batched kernels step
them together), the kind's :class:`~shoal.rl.spec.RLSpec` and a control mode. Environment i is
run i: on a reset with seed S it is run i of ``SeedSequence(S)`` (``core/rng.py``), the same run
``shoal run --seed S`` makes, and a run that restarts alone (:meth:`Batch.restart`) becomes run i
of its own new seed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from shoal.api.scene import Scene, scenario_of
from shoal.presets.models import Scenario

from .control import CONTROLS, Control
from .restart import restart_runs
from .spec import SPECS, Part, RLSpec

OBS_DTYPE = np.float32

Preset = str | Path | Mapping[str, Any] | Scenario


class Batch:
    """``runs`` environments of ``preset`` (a shipped name, a file, a dict or a scenario, with
    ``overrides`` as :func:`shoal.make` takes them) under a control mode, for ``horizon`` ticks an
    episode (default: the preset's ``sim.steps``)."""

    def __init__(self, preset: Preset, runs: int, control: str = "velocity", horizon: int | None = None,
                 overrides: Mapping[str, Any] | None = None) -> None:
        overrides = dict(overrides or {})
        if "runs" in overrides:
            raise ValueError("runs: an environment is one run; give num_envs to a vector env instead")
        if not isinstance(runs, (int, np.integer)) or runs < 1:
            raise ValueError(f"num_envs: must be an integer >= 1, got {runs!r}")
        self.scene = Scene(scenario_of(preset, runs=int(runs), **overrides), record=False)
        kind = self.scene.kind
        if kind.name not in SPECS or not hasattr(self.scene.engine, "steering"):
            raise ValueError(f"the {kind.label} ({kind.name!r}) is no environment: its engine takes no steering or "
                             "no RLSpec is registered for it (shoal.rl.SPECS.register)")
        self.spec: RLSpec = SPECS[kind.name]
        self.control: Control = CONTROLS.pick(control)
        steps = self.scene.scenario.sim.steps if horizon is None else horizon
        if not isinstance(steps, (int, np.integer)) or isinstance(steps, bool) or steps < 1:
            raise ValueError(f"max_episode_steps: must be an integer >= 1, got {steps!r}")
        self.horizon = int(steps)
        self.parts: tuple[Part, ...] = self.spec.parts(self.scene)
        self.command = self.spec.command(self.scene)
        if self.spec.coefficients is None and self.control.name == "pso-params":
            raise ValueError(f"control 'pso-params': the {kind.label} has no PSO coefficients; choose from "
                             f"{[c for c in CONTROLS if c != 'pso-params']}")
        self.coefficients = None if self.spec.coefficients is None else self.spec.coefficients(self.scene)
        self.low, self.high = self.control.bounds(self)
        R = self.runs
        self.elapsed = np.zeros(R, np.int64)  # ticks of each run's episode
        self.seeds = np.full(R, self.scene.scenario.sim.seed, np.int64)  # the seed each run's episode started from
        self.fresh = np.ones(R, bool)  # not stepped since its episode started
        self._level = self._levels()  # the headline metric now, of the swarm (R,) and its robots (R, N)
        self.robot_rewards = np.zeros((R, self.robots))  # each robot's reward of the last tick

    # ------------------------------------------------------------------ shapes
    @property
    def engine(self) -> Any:
        """The scene's engine (the kind's own class: its ``steering``, ``snapshot``, … by name)."""
        return self.scene.engine

    @property
    def runs(self) -> int:
        return int(self.scene.engine.runs)

    @property
    def robots(self) -> int:
        return int(self.scene.engine.robots)

    @property
    def d(self) -> int:
        return int(self.scene.state.x.shape[-1])

    @property
    def width(self) -> int:
        """Numbers in one robot's action."""
        return int(self.low.shape[0])

    # ------------------------------------------------------------------ episodes
    def reset(self, seed: int) -> None:
        """Every run from step 0 with ``seed`` (run i of it)."""
        self.scene.engine.reset(int(seed))
        self.elapsed[:] = 0
        self.seeds[:] = seed
        self.fresh[:] = True
        self._level = self._levels()

    def restart(self, runs: np.ndarray, seeds: np.ndarray) -> None:
        """Runs ``runs`` alone from step 0, run i with ``seeds[i]`` (the others go on)."""
        runs = np.asarray(runs, dtype=np.int64)
        if runs.size == self.runs and np.all(seeds == seeds[0]):
            self.reset(int(seeds[0]))
            return
        restart_runs(self.scene, runs, np.asarray(seeds, dtype=np.int64))
        self.elapsed[runs] = 0
        self.seeds[runs] = seeds
        self.fresh[runs] = True
        swarm, robots = self._levels()
        self._level[0][runs], self._level[1][runs] = swarm[runs], robots[runs]

    # ------------------------------------------------------------------ stepping
    def check(self, action: Any) -> np.ndarray:
        """``action`` as (R, N, m) floats, or a ``ValueError`` saying what it should be."""
        R, N, m = self.runs, self.robots, self.width
        try:
            a = np.asarray(action, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{self.control.name} action: numbers expected, got {type(action).__name__}") from None
        if self.control.per == "swarm" and (a.shape == (R, m) or (R == 1 and a.shape == (m,))):
            a = np.broadcast_to(a.reshape(R, 1, m), (R, N, m))  # one for every robot
        elif R == 1 and a.shape == (N, m):
            a = a[None]
        if a.shape != (R, N, m):
            want = (R, m) if self.control.per == "swarm" else (R, N, m)
            raise ValueError(f"{self.control.name} action: expected shape {want} (runs, …), got {a.shape}")
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{self.control.name} action: every value must be finite (got NaN or inf)")
        return a

    def step(self, action: Any) -> tuple[np.ndarray, np.ndarray]:
        """One tick of every run under ``action``; (reward (R,), terminated (R,))."""
        a = self.check(action)
        engine = self.engine
        engine.steering = self.control.steering(self, a)
        engine.step()
        self.elapsed += 1
        self.fresh[:] = False
        return self._rewards(), self.terminated()

    def _levels(self) -> tuple[np.ndarray, np.ndarray]:
        return (np.asarray(self.spec.reward(self.scene), dtype=float),
                np.asarray(self.spec.robot_reward(self.scene), dtype=float))

    def _rewards(self) -> np.ndarray:
        """The swarm's reward of the tick just done (R,); each robot's in :attr:`robot_rewards`."""
        level = self._levels()
        if self.spec.progress:
            swarm, self.robot_rewards = level[0] - self._level[0], level[1] - self._level[1]
        else:
            swarm, self.robot_rewards = level
        self._level = level
        return swarm

    def terminated(self) -> np.ndarray:
        return np.asarray(self.spec.terminated(self.scene), dtype=bool)

    def truncated(self, terminated: np.ndarray) -> np.ndarray:
        return (self.elapsed >= self.horizon) & ~terminated

    def observe(self) -> dict[str, np.ndarray]:
        """Every part of every run: (R, N, *shape) for a robot's part, (R, *shape) for the swarm's;
        new arrays each call."""
        values = self.spec.observe(self.scene)
        out = {}
        for part in self.parts:
            v = np.array(values[part.name], dtype=OBS_DTYPE)
            if part.name in self.spec.unheard and self.fresh.any():
                v[self.fresh] = 0.0
            out[part.name] = v
        return out
