"""The thesis law as the baseline: an episode driven by ``shoal.rl.baseline`` writes the metrics
``shoal run`` writes for the same preset and seed, byte for byte, for a preset of each kind."""

from __future__ import annotations

import io
import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import shoal.rl
from shoal.engine.core.recorder import write_metrics

CASES = [("default", 6, 40), ("course-dvc", 6, 25), ("sonar-xb-pso", 6, 15), ("slo-pso-sphere", 8, 12)]


def shoal_run(tmp_path, preset: str, seed: int, steps: int, robots: int) -> str:
    out = tmp_path / "run"
    done = subprocess.run([sys.executable, "-m", "shoal", "run", preset, "--seed", str(seed), "--steps", str(steps),
                           "--set", f"sim.robots={robots}", "--out", str(out)], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return (out / "metrics.csv").read_text(encoding="utf-8")


def baseline_episode(preset: str, seed: int, steps: int, robots: int, control: str) -> str:
    env = gym.make(f"shoal/{preset}-v0", control=control, robots=robots, steps=steps)
    env.reset(seed=seed)
    scene = env.unwrapped.scene
    columns = type(scene.engine).COLUMNS
    csv = io.StringIO()
    write_metrics(csv, scene.row(), columns, header=True)
    for _ in range(steps):
        env.step(shoal.rl.baseline(env))
        write_metrics(csv, scene.row(), columns)
    return csv.getvalue()


@pytest.mark.parametrize("preset, robots, steps", CASES)
def test_a_baseline_episode_reproduces_shoal_runs_metrics_byte_for_byte(tmp_path, preset, robots, steps):
    want = shoal_run(tmp_path, preset, 11, steps, robots)
    assert baseline_episode(preset, 11, steps, robots, "velocity") == want
    if preset != "course-dvc":  # (DVC tunes every robot itself: one triple cannot say it)
        assert baseline_episode(preset, 11, steps, robots, "pso-params") == want


def test_another_action_makes_another_run(tmp_path):
    """The comparison can fail: steering away from the law changes the metrics."""
    env = gym.make("shoal/default-v0", robots=6, steps=5)
    env.reset(seed=11)
    env.step(shoal.rl.baseline(env) * 0.5)
    law = gym.make("shoal/default-v0", robots=6, steps=5)
    law.reset(seed=11)
    law.step(shoal.rl.baseline(law))
    assert not np.array_equal(env.unwrapped.scene.state.x, law.unwrapped.scene.state.x)


def test_the_baseline_changes_nothing_and_fits_each_env():
    env = gym.make("shoal/course-dvc-v0", robots=4, steps=5)
    env.reset(seed=0)
    before = env.unwrapped.scene.engine.snapshot()
    action = shoal.rl.baseline(env)
    assert action.shape == (4, 2) and env.unwrapped.scene.k == 0
    after = env.unwrapped.scene.engine.snapshot()
    assert np.array_equal(before["state"]["x"], after["state"]["x"]) and before["rngs"] == after["rngs"]
    envs = gym.make_vec("shoal/course-dvc-v0", num_envs=3, vectorization_mode="vector_entry_point", robots=4)
    envs.reset(seed=0)
    assert shoal.rl.baseline(envs).shape == (3, 4, 2)
    zoo = shoal.rl.parallel_env("course-dvc", robots=4)
    zoo.reset(seed=0)
    assert set(shoal.rl.baseline(zoo)) == set(zoo.agents)
    way = gym.make("shoal/course-dvc-v0", control="waypoint", robots=4)
    way.reset(seed=0)
    with pytest.raises(TypeError, match="not a Shoal environment"):
        shoal.rl.baseline(object())
    assert shoal.rl.baseline(way).shape == (4, 2)
