"""Rendering: ``rgb_array`` draws the arena headless (matplotlib's Agg, no display) with the app's
colours, legend and trails; ``human`` puts the same frames on a viser page."""

from __future__ import annotations

import urllib.request
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import shoal.rl
from shoal.app.kinds import fleet as app_fleet
from shoal.app.kinds import mai as app_mai
from shoal.app.kinds import sonar as app_sonar
from shoal.app.kinds import swarm as app_swarm
from shoal.rl.render import PALETTES


def _has(frame: np.ndarray, colour: tuple[int, int, int], tol: int = 2) -> int:
    return int(np.sum(np.all(np.abs(frame.astype(int) - np.array(colour)) <= tol, axis=-1)))


@pytest.mark.parametrize("preset", ["default", "course-dvc", "sonar-xb-pso", "slo-pso-sphere"])
def test_rgb_array_is_an_image_of_the_arena_in_the_apps_colours(preset, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)  # headless: no display, no Xvfb
    env = gym.make(f"shoal/{preset}-v0", render_mode="rgb_array", robots=6, steps=20)
    env.reset(seed=1)
    for _ in range(8):
        env.step(shoal.rl.baseline(env))
    frame = env.render()
    assert isinstance(frame, np.ndarray) and frame.dtype == np.uint8 and frame.ndim == 3 and frame.shape[2] == 3
    assert frame.mean() > 100 and frame.std() > 5, "never black, never blank"
    palette = PALETTES[env.unwrapped.scene.kind.name]
    assert _has(frame, palette.robot) > 20, "robots in the app's red"
    assert _has(frame, palette.trail) > 20, "trails in the app's trail colour"
    env.close()


def test_trails_grow_as_the_run_goes_on_and_start_again_on_reset():
    env = gym.make("shoal/default-v0", render_mode="rgb_array", robots=6, steps=40)
    env.reset(seed=2)
    trail = PALETTES["swarm"].trail
    first = _has(env.render(), trail)
    for _ in range(20):
        env.step(shoal.rl.baseline(env))
    later = _has(env.render(), trail)
    env.reset(seed=2)
    assert first == 0 < later and _has(env.render(), trail) == 0


def test_the_palettes_are_the_apps():
    """The environments and the app are separate layers; their colours are the same."""
    sw, fl, so, mai = PALETTES["swarm"], PALETTES["fleet"], PALETTES["sonar"], PALETTES["slo_swarm"]
    assert (sw.robot, sw.heading, sw.trail, sw.pbest, sw.gbest, sw.source) == (
        app_swarm.ROBOT, app_swarm.HEADING, app_swarm.TRAIL, app_swarm.PBEST, app_swarm.GBEST, app_swarm.SOURCE)
    assert (fl.robot, fl.collided, fl.heading, fl.trail, fl.pbest, fl.gbest, fl.source) == (
        app_fleet.ROBOT, app_fleet.COLLIDED, app_fleet.HEADING, app_fleet.TRAIL, app_fleet.PBEST, app_fleet.GBEST,
        app_fleet.SOURCE)
    extra = dict(fl.extra)
    assert (extra["start"], extra["layer"], extra["wall"], extra["obstacle_edge"]) == (
        app_fleet.START, app_fleet.LAYER, app_fleet.WALL, app_fleet.OBSTACLE_EDGE)
    assert (so.robot, so.heading, so.trail, so.pbest, so.gbest, so.source, dict(so.extra)["d_c"],
            dict(so.extra)["escort"]) == (app_sonar.ROBOT, app_sonar.HEADING, app_sonar.TRAIL, app_sonar.PBEST,
                                          app_sonar.GBEST, app_sonar.SOURCE, app_sonar.DC_RING, app_sonar.ESCORT)
    assert (mai.robot, mai.trail, dict(mai.extra)["neighbours"]) == (app_mai.ROBOT, app_mai.TRAIL, app_mai.EDGE)


def test_human_opens_a_viser_page_on_the_running_env_and_close_stops_it():
    env = gym.make("shoal/course-dvc-v0", render_mode="human", robots=4, steps=10)
    env.reset(seed=0)
    env.step(shoal.rl.baseline(env))
    assert env.render() is None
    viewer = env.unwrapped._renderer.viewer
    assert viewer is not None and viewer._image is not None
    with urllib.request.urlopen(viewer.address, timeout=10) as page:
        assert page.status == 200 and b"<html" in page.read(2000).lower()
    shown = np.array(viewer._image.image)
    assert shown.shape[-1] == 3 and shown.mean() > 100
    env.close()
    with pytest.raises(OSError):
        urllib.request.urlopen(viewer.address, timeout=2)


def test_check_env_with_its_render_modes():
    env = gym.make("shoal/sonar-xb-pso-v0", render_mode="rgb_array", robots=5, steps=5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_env(env.unwrapped)
