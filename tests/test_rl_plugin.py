"""A plug-in kind becomes an environment by registering its RLSpec (entry point group ``shoal.rl``):
the example plug-in's ``gather`` kind is ``shoal/gather-demo-v0`` and passes the same checks."""

from __future__ import annotations

from plugin_env import python

CHECK = """
import warnings
import gymnasium as gym, numpy as np
import shoal.rl
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test
assert "shoal/gather-demo-v0" in shoal.rl.ENV_IDS, shoal.rl.ENV_IDS
assert shoal.rl.RL_PLUGINS == ["example"]
env = gym.make("shoal/gather-demo-v0", robots=5, steps=6)
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    check_env(env.unwrapped, skip_render_check=True)
obs, _ = env.reset(seed=1)
assert set(obs) == {"position", "velocity", "heading", "active", "centroid"}
obs, reward, *_ = env.step(np.full((5, 2), 100.0))
assert np.all(np.linalg.norm(obs["velocity"], axis=-1) < 100.0), "no faster than gather.speed (plus noise)"
parallel_api_test(shoal.rl.parallel_env("gather-demo", robots=4, steps=5), num_cycles=5)
try:
    gym.make("shoal/gather-demo-v0", control="pso-params")
except ValueError as err:
    assert "no PSO coefficients" in str(err)
else:
    raise AssertionError("pso-params accepted for a kind without coefficients")
print("ok")
"""


def test_the_example_plugins_kind_is_an_environment(example_plugin):
    done = python(example_plugin, CHECK)
    assert done.returncode == 0 and done.stdout.strip().endswith("ok"), done.stdout + done.stderr[-3000:]


def test_without_plugins_only_the_built_in_kinds_are_environments(example_plugin):
    done = python(example_plugin, "import shoal.rl; print(shoal.rl.RL_PLUGINS, len(shoal.rl.ENV_IDS))",
                  SHOAL_PLUGINS="off")
    assert done.returncode == 0 and done.stdout.split() == ["[]", "30"], done.stdout + done.stderr[-2000:]
