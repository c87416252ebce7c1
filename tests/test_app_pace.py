"""A shipped scene opens at a speed one can watch: the figure presets of Chapter 3 (100 steps)
last 20 s, not 5 (app/pace.py); the preset keeps its numbers, an upload its own speed."""

from __future__ import annotations

from shoal.app.pace import FIRST_RUN_SECONDS, paced
from shoal.app.preset_menu import PresetMenu
from shoal.presets.io import list_presets, load


def test_every_shipped_preset_opens_for_at_least_twenty_seconds_and_only_the_speed_changes():
    menu = PresetMenu(tuple(list_presets()))
    for name in list_presets():
        preset, opened = load(name), menu.scenario(name)
        assert opened.sim.steps / opened.view.steps_per_second >= FIRST_RUN_SECONDS - 1e-9, name
        assert opened.model_dump(exclude={"view"}) == preset.model_dump(exclude={"view"}), name
        assert opened.view.steps_per_second <= preset.view.steps_per_second
    assert menu.scenario("fig3-4a").view.steps_per_second == 5.0  # 100 steps: 20 s
    assert menu.scenario("default").view.steps_per_second == 20.0  # 600 steps: 30 s already


def test_an_upload_keeps_its_own_speed():
    menu = PresetMenu(tuple(list_presets()))
    fast = load("fig3-4a").model_copy(update={"name": "mine"})
    label = menu.add_upload(fast)
    assert menu.scenario(label).view.steps_per_second == 20.0
    assert paced(paced(load("fig3-5a"))) == paced(load("fig3-5a"))  # (once is enough)


def test_the_server_opens_its_shipped_scene_paced():
    from shoal.app.server import start_server

    server = start_server("fig3-5b", port=0)
    try:
        assert server.scenario.view.steps_per_second == 5.0
    finally:
        server.stop()
