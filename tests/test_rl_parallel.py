"""shoal.rl's PettingZoo environment: one agent per robot, simultaneous moves, the same spaces for
every agent; PettingZoo's own API and seed tests pass on a preset of each kind."""

from __future__ import annotations

import numpy as np
import pytest
from pettingzoo.test import parallel_api_test, parallel_seed_test

import shoal.rl

PRESETS = ["default", "course-dvc", "sonar-xb-pso-nonomni", "slo-pso-sphere"]


@pytest.mark.parametrize("preset", PRESETS)
@pytest.mark.parametrize("control", ["velocity", "pso-params"])
def test_parallel_api_test_passes(preset, control):
    parallel_api_test(shoal.rl.parallel_env(preset, control=control, robots=5, steps=12), num_cycles=12)


@pytest.mark.parametrize("preset", PRESETS)
def test_parallel_seed_test_passes(preset):
    parallel_seed_test(lambda: shoal.rl.parallel_env(preset, robots=5, steps=10), num_cycles=10)


def test_one_agent_per_robot_with_the_same_spaces_and_its_own_parts():
    env = shoal.rl.parallel_env("course-dvc", robots=4, steps=10)
    obs, infos = env.reset(seed=3)
    assert env.agents == ["robot_0", "robot_1", "robot_2", "robot_3"]
    spaces = [env.observation_space(a) for a in env.agents]
    assert all(s == spaces[0] for s in spaces) and len({id(s) for s in spaces}) == 4, "equal, one object each"
    assert all(env.action_space(a) == env.action_space("robot_0") for a in env.agents)
    x = env.scene.state.x[0]
    for i, a in enumerate(env.agents):
        assert np.array_equal(obs[a]["position"], x[i].astype(np.float32))
        assert obs[a]["sectors"].shape == (6,) and obs[a]["global_best"].shape == (2,)
    actions = {a: np.array([1.0, 0.0]) for a in env.agents}
    before = np.linalg.norm(env.scene.state.x[0] - env.scene.engine.source, axis=-1)
    obs, rewards, terms, truncs, infos = env.step(actions)
    after = np.linalg.norm(env.scene.state.x[0] - env.scene.engine.source, axis=-1)
    assert [rewards[a] for a in ["robot_0", "robot_1", "robot_2", "robot_3"]] == pytest.approx(list(before - after))


def test_a_disabled_robot_is_terminated_and_leaves_the_agents():
    env = shoal.rl.parallel_env("course-rpso", robots=6, steps=60)
    env.reset(seed=1)
    gone: set[str] = set()
    for _ in range(60):
        actions = {a: np.array([3.0, 0.0]) for a in env.agents}  # full speed ahead, into the obstacles
        obs, rewards, terms, truncs, infos = env.step(actions)
        gone |= {a for a, t in terms.items() if t}
        if gone:
            break
    status = env.scene.state.status[0]
    assert gone and all(status[int(a.split("_")[1])] != 0 for a in gone)
    assert not gone & set(env.agents)
    with pytest.raises(ValueError, match="none for"):
        env.step({})


def test_max_cycles_truncates_every_agent():
    env = shoal.rl.parallel_env("default", robots=3)
    env.max_cycles = 3
    env.reset(seed=0)
    for _ in range(3):
        obs, rewards, terms, truncs, infos = env.step({a: env.action_space(a).sample() for a in env.agents})
    assert all(truncs.values()) and env.agents == []
