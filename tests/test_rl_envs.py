"""shoal.rl's Gymnasium environments: every registered env passes Gymnasium's own checker, and the
spaces, rewards, end rules and control modes do what they say (small swarms, short episodes)."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import shoal
import shoal.rl
from shoal.presets.io import shipped_names
from shoal.presets.kinds import kind_for

SMALL = {"robots": 6, "steps": 8}


def test_every_shipped_preset_with_robots_is_registered():
    with_robots = [n for n in shipped_names() if kind_for(shoal.scenario_of(n)).name in shoal.rl.SPECS]
    assert sorted(with_robots) == sorted(i.removeprefix("shoal/").removesuffix("-v0") for i in shoal.rl.ENV_IDS)
    assert {kind_for(shoal.scenario_of(n)).name for n in with_robots} == {"swarm", "fleet", "sonar", "slo_swarm"}
    for i in shoal.rl.ENV_IDS:
        assert gym.spec(i).vector_entry_point == "shoal.rl.vector:ShoalVectorEnv"


@pytest.mark.parametrize("env_id", shoal.rl.ENV_IDS)
def test_check_env_passes_on_every_registered_env(env_id):
    env = gym.make(env_id, **SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a checker's warning other than infinite bounds fails
        warnings.filterwarnings("ignore", message=".*infinity.*")
        check_env(env.unwrapped, skip_render_check=True)
    env.close()


@pytest.mark.parametrize("env_id", ["shoal/default-v0", "shoal/course-nonomni-v0", "shoal/sonar-xb-pso-nonomni-v0",
                                    "shoal/slo-pso-sphere-v0"])
@pytest.mark.parametrize("control", ["waypoint", "pso-params"])
def test_check_env_passes_in_the_other_control_modes(env_id, control):
    env = gym.make(env_id, control=control, **SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped, skip_render_check=True)


def test_the_observation_is_the_documented_dict_and_holds_the_kinds_sensing():
    def parts(preset, **kw):
        env = gym.make(f"shoal/{preset}-v0", **SMALL, **kw)
        obs, _ = env.reset(seed=0)
        return env, obs

    env, obs = parts("course-dvc")
    assert set(obs) == {"position", "velocity", "heading", "active", "sectors", "cost", "personal_best",
                        "global_best", "best_fitness"}
    assert obs["sectors"].shape == (6, 6) and np.all(obs["sectors"] <= 3.0) and np.all(obs["sectors"] >= 0)
    reading = env.unwrapped.scene.engine.sense_now()
    assert np.allclose(obs["sectors"], reading.gap[0]), "the DVC's six gaps where each robot stands"
    env, obs = parts("sonar-xb-pso")
    assert obs["rays"].shape == (6, 2, 2) and not obs["rays"].any(), "nothing heard before the first listen"
    obs, *_ = env.step(shoal.rl.baseline(env))
    assert np.allclose(np.linalg.norm(obs["rays"], axis=-1), 1.0, atol=1e-6), "a bearing and its mirror, unit"
    assert np.all(obs["intensity"] > 0)
    env, obs = parts("slo-pso-sphere")
    assert obs["neighbours"].shape == (6, 6, 2) and obs["in_range"].shape == (6, 6)
    s = env.unwrapped.scene.state
    assert np.allclose(obs["neighbours"], s.est[0]), "SLO's range-estimated vectors to the others"
    env, obs = parts("default")
    assert obs["global_best"].shape == (2,) and obs["best_fitness"].shape == (1,)


def test_rewards_are_the_kinds_headline_metrics():
    env = gym.make("shoal/course-dvc-v0", **SMALL)
    env.reset(seed=1)
    e = env.unwrapped.scene.engine
    before = np.linalg.norm(e.state.x[0] - e.source, axis=-1).mean()
    ret = sum(env.step(shoal.rl.baseline(env))[1] for _ in range(8))
    after = np.linalg.norm(e.state.x[0] - e.source, axis=-1).mean()
    assert ret == pytest.approx(before - after) and ret > 0.5, "the return is the fleet's progress to the source"
    env = gym.make("shoal/sonar-xb-pso-v0", **SMALL)
    env.reset(seed=1)
    e = env.unwrapped.scene.engine
    before = e.state.snr_db[0].mean()
    _, reward, *_ = env.step(shoal.rl.baseline(env))
    assert reward == pytest.approx(e.state.snr_db[0].mean() - before), "the rise of the signal level"
    env = gym.make("shoal/default-v0", **SMALL)
    env.reset(seed=1)
    _, reward, *_ = env.step(shoal.rl.baseline(env))
    assert reward == pytest.approx(-env.unwrapped.scene.engine.state.best_fitness[0]), "minus f(y_g) for a cost"
    env = gym.make("shoal/slo-pso-sphere-v0", **SMALL)
    env.reset(seed=1)
    _, reward, *_ = env.step(shoal.rl.baseline(env))
    assert reward == pytest.approx(-env.unwrapped.scene.engine.state.f[0].min()), "minus the generation's best"


def test_terminated_when_the_thesis_end_rule_holds_truncated_at_the_horizon():
    env = gym.make("shoal/sonar-xb-pso-v0", robots=6, steps=400, acoustics={"snr0_db": 20.0})
    env.reset(seed=2)
    for _ in range(400):
        _, _, terminated, truncated, _ = env.step(shoal.rl.baseline(env))
        if terminated or truncated:
            break
    e = env.unwrapped.scene.engine
    assert terminated and not truncated, "the CoM reached d_c"
    assert np.linalg.norm(e.state.x[0].mean(axis=0) - e.state.source[0]) <= e.params.dc
    env = gym.make("shoal/default-v0", robots=4, steps=5)
    env.reset(seed=0)
    ends = [env.step(env.action_space.sample())[2:4] for _ in range(5)]
    assert ends[-1] == (False, True) and all(e == (False, False) for e in ends[:-1])


def test_reset_with_a_seed_is_run_zero_of_that_seed_and_reset_without_draws_a_new_one():
    env = gym.make("shoal/course-dvc-v0", **SMALL)
    obs, info = env.reset(seed=42)
    ref = shoal.make("course-dvc", seed=42, robots=6)
    assert info["seed"] == 42 and np.array_equal(obs["position"], ref.state.x[0].astype(np.float32))
    obs2, info2 = env.reset()
    assert info2["seed"] != 42 and not np.array_equal(obs2["position"], obs["position"])


def test_velocity_commands_keep_the_physical_limits():
    env = gym.make("shoal/course-rpso-v0", **SMALL)
    env.reset(seed=3)
    v_max = env.unwrapped.scene.engine.params.v_max
    for _ in range(4):
        obs, *_ = env.step(np.full((6, 2), 50.0))
        assert np.all(np.linalg.norm(obs["velocity"], axis=-1) <= v_max * (1 + 1e-6))


def test_a_waypoint_is_headed_for_and_reached_when_near():
    env = gym.make("shoal/default-v0", control="waypoint", robots=3, steps=200)
    obs, _ = env.reset(seed=0)
    target = np.tile([5.0, 5.0], (3, 1))
    start = np.linalg.norm(obs["position"] - target, axis=-1)
    for _ in range(150):
        obs, *_ = env.step(target)
    assert np.all(np.linalg.norm(obs["position"] - target, axis=-1) < 0.2 * start)


def test_pso_params_set_the_laws_coefficients_for_the_tick():
    env = gym.make("shoal/default-v0", control="pso-params", robots=4, steps=10)
    env.reset(seed=0)
    env.step(np.array([0.25, 0.5, 0.125]))
    row = env.unwrapped.scene.row()
    assert row["omega"][0] == 0.25 and row["c_hat"][0] == 0.625


@pytest.mark.parametrize("action, message", [(np.full((6, 2), np.nan), "finite"), (np.zeros((5, 2)), "shape"),
                                             ("fast", "numbers")])
def test_a_bad_action_is_refused_by_name_and_changes_nothing(action, message):
    env = gym.make("shoal/course-dvc-v0", **SMALL)
    env.reset(seed=0)
    before = env.unwrapped.scene.state.x.copy()
    with pytest.raises(ValueError, match=message):
        env.unwrapped.step(action)
    assert np.array_equal(env.unwrapped.scene.state.x, before) and env.unwrapped.scene.k == 0


def test_a_kind_without_coefficients_or_a_run_count_is_refused_clearly():
    with pytest.raises(ValueError, match="control mode: unknown"):
        gym.make("shoal/default-v0", control="torque")
    with pytest.raises(ValueError, match="num_envs"):
        gym.make("shoal/default-v0", runs=4)
