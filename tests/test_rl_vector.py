"""shoal.rl's vector environment: num_envs seeds as one batched scene, with same-step autoreset that
tells time-outs from terminations, each restarted run being run i of its own new seed."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import shoal
import shoal.rl
from shoal.rl.vector import ShoalVectorEnv


def make(preset, n, **kw):
    return gym.make_vec(f"shoal/{preset}-v0", num_envs=n, vectorization_mode="vector_entry_point", **kw)


def test_make_vec_builds_one_batched_scene_not_copies():
    envs = make("course-dvc", 5, robots=4, steps=10)
    assert isinstance(envs, ShoalVectorEnv) and envs.num_envs == 5
    assert envs.scene.engine.runs == 5, "one engine of five runs"
    obs, info = envs.reset(seed=9)
    assert obs["position"].shape == (5, 4, 2) and envs.observation_space.contains(obs)
    ref = shoal.make("course-dvc", runs=5, seed=9, robots=4)
    assert np.array_equal(obs["position"], ref.state.x.astype(np.float32)), "env i is run i of the seed"
    actions = envs.action_space.sample()
    obs, reward, terminated, truncated, info = envs.step(actions)
    assert reward.shape == terminated.shape == truncated.shape == (5,)


def test_a_vector_env_steps_as_the_single_env_does_for_env_zero():
    envs = make("sonar-xb-pso", 3, robots=5, steps=10)
    env = gym.make("shoal/sonar-xb-pso-v0", robots=5, steps=10)
    obs_v, _ = envs.reset(seed=4)
    obs_1, _ = env.reset(seed=4)
    for _ in range(3):
        action = shoal.rl.baseline(envs)
        obs_v, r_v, *_ = envs.step(action)
        obs_1, r_1, *_ = env.step(action[0])
        assert r_v[0] == r_1
    assert all(np.array_equal(obs_v[k][0], obs_1[k]) for k in obs_1)


def test_time_outs_and_terminations_are_told_apart_and_envs_restart_in_the_same_step():
    envs = make("sonar-xb-pso", 3, robots=6, steps=400, acoustics={"snr0_db": 20.0})
    envs.reset(seed=2)
    for k in range(400):  # noqa: B007  (k is read after the loop)
        obs, reward, terminated, truncated, info = envs.step(shoal.rl.baseline(envs))
        if terminated.any():
            break
    assert terminated.any() and not truncated.any()
    i = int(np.flatnonzero(terminated)[0])
    assert info["terminated"][i] and not info["time_out"][i]
    assert info["_final_obs"][i] and info["final_info"]["length"][i] == k + 1
    assert info["final_info"]["terminated"][i] and not info["final_info"]["time_out"][i]
    b = envs.batch
    assert b.elapsed[i] == 0 and b.seeds[i] != 2, "restarted at once with a seed of its own"
    assert not obs["rays"][i].any(), "a restarted run has not listened yet"
    others = np.flatnonzero(~terminated)
    assert np.all(b.elapsed[others] == k + 1), "the others go on"
    fresh = shoal.make("sonar-xb-pso", runs=i + 1, seed=int(b.seeds[i]), robots=6, acoustics={"snr0_db": 20.0})
    assert np.array_equal(obs["position"][i], fresh.state.x[i].astype(np.float32)), "run i of its new seed"
    final = info["final_obs"][i]
    assert final["position"].shape == (6, 2) and not np.array_equal(final["position"], obs["position"][i])


def test_every_env_times_out_together_at_the_horizon_and_starts_again():
    envs = make("default", 4, robots=3, steps=5)
    envs.reset(seed=1)
    for _ in range(5):
        obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
    assert truncated.all() and not terminated.any() and info["time_out"].all()
    assert np.all(info["final_info"]["return"] != 0) and np.all(info["final_info"]["length"] == 5)
    assert np.all(envs.batch.elapsed == 0) and len(set(envs.batch.seeds.tolist())) == 1, "one new seed for all"


@pytest.mark.parametrize("preset", ["default", "course-dvc", "course-physics", "sonar-xb-pso", "slo-pso-sphere",
                                    "course-dvc-slo"])
def test_a_run_restarted_alone_is_run_i_of_its_seed_and_the_others_are_untouched(preset):
    envs = make(preset, 3, robots=4, steps=50)
    envs.reset(seed=7)
    b = envs.batch
    for _ in range(3):
        b.engine.step()
    b.restart(np.array([1]), np.array([99]))
    for _ in range(4):
        b.engine.step()
    alone = shoal.make(preset, runs=2, seed=99, robots=4)
    together = shoal.make(preset, runs=3, seed=7, robots=4)
    for _ in range(4):
        alone.engine.step()
    for _ in range(7):
        together.engine.step()
    assert np.array_equal(b.engine.state.x[1], alone.state.x[1])
    assert np.array_equal(b.engine.state.x[[0, 2]], together.state.x[[0, 2]])
