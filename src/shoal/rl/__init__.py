"""Shoal's scenes as reinforcement-learning environments (``pip install 'shoal[rl]'``).

``import shoal.rl`` registers ``shoal/<preset>-v0`` with Gymnasium for every shipped preset whose
kind is an environment, so that ::

    import gymnasium, shoal.rl
    env = gymnasium.make("shoal/course-dvc-v0", control="velocity", robots=6)
    envs = gymnasium.make_vec("shoal/course-dvc-v0", num_envs=32, vectorization_mode="vector_entry_point")
    zoo = shoal.rl.parallel_env("course-dvc")       # PettingZoo: one agent per robot
    action = shoal.rl.baseline(env)                  # what the thesis law would do

* :class:`ShoalEnv`: one run, the swarm as one agent; :class:`ShoalVectorEnv`: ``num_envs`` runs as
  one batched scene, with same-step autoreset; :class:`ShoalParallelEnv`: one agent per robot;
* control modes (:data:`CONTROLS`): ``"velocity"``, ``"waypoint"``, ``"pso-params"``;
* what each kind observes, its reward and its end rule: its :class:`RLSpec` in :data:`SPECS`
  (a plug-in kind registers one to become an environment);
* :func:`baseline`: the action of the scene's own law (Adapted PSO, XB-PSO, …) for comparison.

A plug-in kind becomes an environment with a steerable engine and an :class:`RLSpec`: its package
names a function that registers the spec in the entry-point group ``shoal.rl``
(:func:`~shoal.rl.registration.load_rl_plugins`), loaded here, before the presets are registered.
"""

from __future__ import annotations

from .baseline import baseline
from .batch import Batch
from .control import CONTROLS, Control
from .env import ShoalEnv
from .kinds import BUILT_IN
from .parallel import ShoalParallelEnv, parallel_env
from .registration import env_id, environment_presets, load_rl_plugins, register_presets
from .spec import SPECS, Coefficients, Command, Part, RLSpec
from .vector import ShoalVectorEnv

for _spec in BUILT_IN:
    if _spec.name not in SPECS:
        SPECS.register(_spec)

RL_PLUGINS = load_rl_plugins()
ENV_IDS = register_presets()

__all__ = ["CONTROLS", "ENV_IDS", "RL_PLUGINS", "SPECS", "Batch", "Coefficients", "Command", "Control", "Part",
           "RLSpec", "ShoalEnv", "ShoalParallelEnv", "ShoalVectorEnv", "baseline", "env_id", "environment_presets",
           "load_rl_plugins", "parallel_env", "register_presets"]
